r"""Nonspinning co-orbital amplitudes (pnrotor.waveform.nonspinning, summed by amplitudes.coorbital_modes)
against LALSuite's ``SimInspiralPNMode{ℓ}{m}`` (Kidder 2008), the general leading-order mode formula, the
PN energy flux, the structure of the 1PN and tail corrections, and PostNewtonian.jl's 3.5PN (2,2) weight.

Notation: H_ℓm = h₀ Σ_k v^k (a_k + b_k ln v), h₀ = 8 √(π/5) ν v² (units r h / M, M = 1), LAL's signs
(h₂₂ = +|h₂₂| e^{−2iΦ}).

LAL: ``SimInspiralPNMode{ℓ}{m}(V, Φ, v0, m1, m2, r, O)`` returns Kidder's mode, the negative of LAL's
convention (``XLALCreateSimInspiralPNModeCOMPLEX16TimeSeriesLALConvention`` negates it), at twice-PN order
O = 0 … 6, with Blanchet's tail phase ψ = Φ − 3v³(1 − νv²/2) ln(v/v0)² expanded into the amplitude (the
ln(v/v0) terms).  Each sample is its own length-1 series with v0 = v, so every ln(v/v0) vanishes and LAL's
mode is h₀ Σ v^k (a_k + b_k ln v) e^{−imΦ} with Φ = 0 — the amplitude pnrotor uses with Φ (module
docstring of nonspinning.py); r = G M / c² makes LAL's strain equal to r h / M.

Measured (test_lal_pn_modes_agree_but_for_the_listed_differences): with the differences below applied to
our terms, LAL agrees to ≤ 8e-15 of max|H_ℓm| (≤ 1e-15 for most modes) for every ℓ ≤ 6, m ≥ 0, O = 0 … 6, ν = 0.25, 0.1875, 0.08;
without them the listed (mode, order) pairs — and no others — differ by more than 1e-10.  LAL's version
of each listed term, and which is right:

* no 3PN (v⁶) term in (2,1), (3,1), (3,2), (3,3), (4,1), (4,3), (5,1), (5,3), (5,5): Kidder 2008 predates
  Blanchet et al. 2008's 3PN modes (LAL: ``case 6:`` falls through to 2.5PN);
* (3,3) at v⁵: (123/110 − 1838/165 ν − 887/330 ν²) relative to the leading term, for + 887/330 ν²;
* (4,2) and (4,4) at v⁴: the 1PN correction with the opposite sign (LAL: ``re4 = 437./110. − …`` added
  to ``re2 = 1 − 3ν``, where the paper subtracts);
* (4,2) at v⁵: an extra i 8 (1 − 3ν) ln 2 relative to the leading term, copied from (4,4);
* (4,3): every term without the factor i (LAL: no ``* I`` in ``XLALSimInspiralPNMode43``), and its 1PN
  (v⁵) correction with the opposite sign, like (4,2) and (4,4) ((4,1)'s is right);
* (5,3): every term −√(2/3) times ours (LAL's prefactor −(9/20)√(2π/22));
* (6,4) at v⁶: (6,6)'s relative 1PN factor −(113/14 − 91/2 ν + 64 ν² − 39/2 ν³), copied;
* m = 0: (2,0) and (4,0) carry the constant Newtonian memory term, +(5/(14√6)) h₀ and +(1/(504√2)) h₀ in
  Kidder's sign (−… in LAL's convention; pnrotor omits the memory, nonspinning.py); ``SimInspiralPNMode60``
  returns the number 1.0 for every sample, whatever the masses and distance (a placeholder); (3,0) and
  (5,0) agree.

Ours is right in each case (tests below): the general leading-order formula settles (4,3) and (5,3); the
PN flux at 3PN rules out LAL's (3,3), (4,2) and (4,4) 1PN/2PN terms (each alone changes the v⁶ flux
coefficient); the 1PN coefficients of Damour, Iyer & Nagar's factorized ρ_ℓm rule out LAL's 1PN signs of
(4,2), (4,3), (4,4) and its (6,4); the first tail term of every mode carries 2m ln(m/2) (LAL's own (2,1), (3,1), (3,3), (4,4)
do), which vanishes for m = 2; and the 1PN relative correction of the mass-type modes of one ℓ is linear
in m² (LAL's own ℓ = 5 modes satisfy it), which LAL's (6,4) breaks.
"""

import math
from fractions import Fraction

import numpy as np
import pytest

from pnrotor.pn import flux, series
from pnrotor.waveform import nonspinning
from pnrotor.waveform.amplitudes import coorbital_modes
from pnrotor.waveform.layout import ell_m, mode_index

try:
    import lal
    import lalsimulation as ls
except ImportError:   # pragma: no cover
    lal = ls = None

needs_lal = pytest.mark.skipif(ls is None, reason="lalsuite not installed")

H0 = 8.0 * math.sqrt(math.pi / 5.0)
NUS = [0.25, 0.1875, 0.08]
V = np.array([0.05, 0.1, 0.2, 0.3, 0.4])
LN2 = math.log(2.0)


def masses(nu):
    """(X1, X2, δ) for ν, X1 ≥ X2."""
    delta = math.sqrt(1.0 - 4.0 * nu)
    return (1.0 + delta) / 2.0, (1.0 - delta) / 2.0, delta


def evaluate(series_, v, order2):
    """h₀ Σ_{k ≤ order2} v^k (a_k + b_k ln v) for one mode's [(k, a, b), …]."""
    total = np.zeros(v.size, dtype=complex)
    for k, a, b in series_:
        if k <= order2:
            total += v ** k * (a + b * np.log(v))
    return H0 * (v * v) * total   # ν = 1 here: callers multiply by ν


def leading(series_):
    k, a, _ = min(series_, key=lambda t: t[0])
    return k, a


# ---------------------------------------------------------------------------------------------- LAL

LAL_WITHOUT_3PN = [(2, 1), (3, 1), (3, 2), (3, 3), (4, 1), (4, 3), (5, 1), (5, 3), (5, 5)]


def lal_version(nu, delta):
    """Our terms with LAL's differences (module docstring) applied, ℓ ≤ 6, m ≥ 0, and the (k, a, b) of the
    m = 0 memory constants; returns (terms, changed) with changed = {(ℓ, m): lowest k LAL changes}."""
    ours = nonspinning.terms(nu, delta)
    t = {lm: list(s) for lm, s in ours.items() if lm[0] <= 6}
    changed = {}

    def change(lm, k):
        changed[lm] = min(k, changed.get(lm, k))

    for lm in LAL_WITHOUT_3PN:
        t[lm] = [term for term in t[lm] if term[0] != 6]
        change(lm, 6)
    # (3,3) v⁵: + 887/330 ν² → − 887/330 ν²
    t[3, 3] = [(k, a * (369 - 3676 * nu - 887 * nu ** 2) / (369 - 3676 * nu + 887 * nu ** 2) if k == 5 else a, b)
               for k, a, b in t[3, 3]]
    change((3, 3), 5)
    for lm in ((4, 2), (4, 4)):   # 1PN sign
        t[lm] = [(k, -a if k == 4 else a, b) for k, a, b in t[lm]]
        change(lm, 4)
    lead42 = leading(t[4, 2])[1]
    t[4, 2] = [(k, a + 8j * LN2 * lead42 if k == 5 else a, b) for k, a, b in t[4, 2]]
    t[4, 3] = [(k, (1j if k == 5 else -1j) * a, b) for k, a, b in t[4, 3]]   # no i, and the 1PN sign
    change((4, 3), 3)
    t[5, 3] = [(k, -math.sqrt(2 / 3) * a, b) for k, a, b in t[5, 3]]
    change((5, 3), 3)
    rel66 = dict((k, a) for k, a, _ in t[6, 6])
    lead64 = leading(t[6, 4])[1]
    t[6, 4] = [(k, lead64 * rel66[6] / rel66[4] if k == 6 else a, b) for k, a, b in t[6, 4]]
    change((6, 4), 6)
    t[2, 0] = [(0, -5 / (14 * math.sqrt(6)), 0)]
    t[4, 0] = [(0, -1 / (504 * math.sqrt(2)), 0)]
    change((2, 0), 0)
    change((4, 0), 0)
    for lm in ((5, 0), (6, 0)):
        t.setdefault(lm, [])
    return t, changed


def lal_mode(ell, m, v, m1, m2, order2):
    """LAL's H_ℓm (LAL's sign: minus Kidder's) at each v, with v0 = v, Φ = 0, r = G M / c²."""
    msun = lal.MSUN_SI
    r = lal.G_SI * (m1 + m2) * msun / lal.C_SI ** 2
    fn = getattr(ls, f"SimInspiralPNMode{ell}{m}")
    out = np.empty(v.size, dtype=complex)
    for j, vj in enumerate(v):
        series_v = lal.CreateREAL8TimeSeries("v", lal.LIGOTimeGPS(0), 0.0, 1.0, lal.DimensionlessUnit, 1)
        series_phi = lal.CreateREAL8TimeSeries("phi", lal.LIGOTimeGPS(0), 0.0, 1.0, lal.DimensionlessUnit, 1)
        series_v.data.data[:] = vj
        series_phi.data.data[:] = 0.0
        out[j] = -fn(series_v, series_phi, vj, m1 * msun, m2 * msun, r, order2).data.data[0]
    return out


@needs_lal
@pytest.mark.parametrize("nu", NUS)
def test_lal_pn_modes_agree_but_for_the_listed_differences(nu):
    X1, X2, delta = masses(nu)
    m1, m2 = 20.0 * X1, 20.0 * X2
    ours = nonspinning.terms(nu, delta)
    theirs, changed = lal_version(nu, delta)
    worst, differing = 0.0, set()
    for ell in range(2, 7):
        for m in range(0, ell + 1):
            for order2 in range(0, 7):
                h = lal_mode(ell, m, V, m1, m2, order2)
                if (ell, m) == (6, 0):   # a placeholder: 1.0 whatever the binary
                    assert np.all(h == -1.0)
                    continue
                expected = nu * evaluate(theirs[ell, m], V, order2)
                plain = nu * evaluate(ours.get((ell, m), []), V, order2)
                scale = max(np.abs(h).max(), np.abs(plain).max(), 1e-300)
                worst = max(worst, np.abs(h - expected).max() / scale)
                if np.abs(h - plain).max() > 1e-10 * scale:
                    differing.add((ell, m, order2))
    assert worst < 1e-13, worst
    predicted = {(ell, m, o) for (ell, m), k in changed.items() for o in range(k, 7)}
    if nu == 0.25:   # δ = 0: the odd-m modes vanish in both, so their differences do not show
        predicted = {(ell, m, o) for ell, m, o in predicted if m % 2 == 0}
    assert differing == predicted, sorted(differing ^ predicted)


# ------------------------------------------------------------------------------ leading order, all ℓ ≤ 8

def _double_factorial(n):
    return math.prod(range(n, 0, -2)) if n > 0 else 1


def _Y_equator(L, m):
    """Y_Lm(π/2, 0), Condon–Shortley, from P_L^m(0) = (−1)^{(L+m)/2} (L+m−1)!!/(L−m)!! (zero for L+m odd)."""
    if abs(m) > L:
        return 0.0
    if m < 0:
        return (-1) ** m * _Y_equator(L, -m)
    if (L + m) % 2:
        return 0.0
    p = (-1) ** ((L + m) // 2) * _double_factorial(L + m - 1) / _double_factorial(L - m)
    return math.sqrt((2 * L + 1) / (4 * math.pi) * math.factorial(L - m) / math.factorial(L + m)) * p


def newtonian_mode(ell, m, X1, X2):
    """(k, coefficient of h₀ v^k) of the leading term of H_ℓm, m ≠ 0, from the general formula for the
    Newtonian-order modes of a circular binary (Kidder 2008; in this form Damour, Iyer &
    Nagar 2009, arXiv:0811.2069): with ε = parity of ℓ + m,
    h_ℓm = (M ν / R) n_ℓm^(ε) c_{ℓ+ε}(ν) v^{ℓ+ε} Y^{ℓ−ε, −m}(π/2, Φ), c_n = X2^{n−1} + (−1)^n X1^{n−1},
    n^(0) = (im)^ℓ 8π/(2ℓ+1)!! √((ℓ+1)(ℓ+2)/(ℓ(ℓ−1))),
    n^(1) = −(im)^ℓ 16πi/(2ℓ+1)!! √((2ℓ+1)(ℓ+2)(ℓ²−m²)/((2ℓ−1)(ℓ+1)ℓ(ℓ−1))),
    in Blanchet's and Kidder's sign: LAL's (and ours) is the negative."""
    eps = (ell + m) % 2
    base = (1j * m) ** ell * math.pi / _double_factorial(2 * ell + 1)
    if eps == 0:
        n = 8 * base * math.sqrt((ell + 1) * (ell + 2) / (ell * (ell - 1)))
    else:
        n = -16j * base * math.sqrt((2 * ell + 1) * (ell + 2) * (ell * ell - m * m)
                                     / ((2 * ell - 1) * (ell + 1) * ell * (ell - 1)))
    c = X2 ** (ell + eps - 1) + (-1) ** (ell + eps) * X1 ** (ell + eps - 1)
    return ell + eps - 2, -n * c * _Y_equator(ell - eps, -m) / H0


@pytest.mark.parametrize("nu", [0.1875, 0.08, 0.01])
def test_leading_term_of_every_mode_is_the_general_newtonian_formula(nu):
    """Every (ℓ, m ≠ 0), ℓ ≤ 8, including all of ℓ = 7 and 8 (each of their terms is a leading term)."""
    X1, X2, delta = masses(nu)
    terms = nonspinning.terms(nu, delta)
    for ell in range(2, 9):
        for m in range(1, ell + 1):
            k, c = newtonian_mode(ell, m, X1, X2)
            if ell == 8 and m % 2:   # current-type ℓ = 8: v⁷, beyond 3PN, absent (nonspinning.py)
                assert (ell, m) not in terms
                continue
            k_ours, c_ours = leading(terms[ell, m])
            assert k_ours == k, (ell, m)
            assert c_ours == pytest.approx(c, rel=1e-14, abs=0), (ell, m)


def test_lal_43_and_53_normalizations_contradict_the_newtonian_formula():
    """LAL's leading (4,3) and (5,3) (measured in the LAL test: −i and −√(2/3) times ours) against the
    formula, which ours matches."""
    X1, X2, _ = masses(0.1875)
    assert newtonian_mode(4, 3, X1, X2)[1].real == pytest.approx(0, abs=1e-17)   # purely imaginary …
    assert abs(newtonian_mode(4, 3, X1, X2)[1].imag) > 1e-3                        # … LAL's is real
    ratio = (-math.sqrt(2 / 3) * leading(nonspinning.terms(0.1875, X1 - X2)[5, 3])[1]) / newtonian_mode(5, 3, X1, X2)[1]
    assert ratio == pytest.approx(-math.sqrt(2 / 3), rel=1e-14)


# ---------------------------------------------------------------------------------------- the PN flux

def flux_coefficients(terms, order2):
    """F̂_j, j ≤ order2: the energy flux (1/16π) Σ |ḣ_ℓm|² over (32/5) ν² v¹⁰ is (1/8) Σ_ℓm m² |Σ_k a_k v^k|²
    (both signs of m, the ln v parts left out)."""
    f = np.zeros(order2 + 1)
    for (ell, m), s in terms.items():
        if m == 0:
            continue
        for k, a, _ in s:
            for kp, ap, _ in s:
                if k + kp <= order2:
                    f[k + kp] += 2 * m * m * (a * np.conj(ap)).real / 8
    return f


@pytest.mark.parametrize("nu", NUS[1:])
def test_flux_at_3pn_rules_out_lal_33_42_44_terms(nu):
    """Our amplitudes give the PN flux (pnrotor.pn.flux: Blanchet's Living Review) through v⁶; each of LAL's
    (3,3) v⁵, (4,2) v⁴ and (4,4) v⁴ terms alone changes the v⁶ coefficient by > 1e-4."""
    X1, X2, delta = masses(nu)
    pn = (flux.flux_series(X1)[:, :, 0] @ series.basis_values(0.0, 0.0, 0.0, 0.0, 0.0))[:7]
    ours = nonspinning.terms(nu, delta)
    np.testing.assert_allclose(flux_coefficients(ours, 6), pn, rtol=0, atol=1e-13)
    theirs, _ = lal_version(nu, delta)
    for lm in ((3, 3), (4, 2), (4, 4)):
        swapped = dict(ours)
        swapped[lm] = theirs[lm] + [term for term in ours[lm] if term[0] == 6 and lm == (3, 3)]
        f = flux_coefficients(swapped, 6)
        np.testing.assert_allclose(f[:6], pn[:6], rtol=0, atol=1e-13)
        assert abs(f[6] - pn[6]) > 1e-4, lm


# --------------------------------------------------------------------------- structure of the terms

def test_first_tail_term_is_m_pi_plus_2i_m_ln_m_over_2():
    """Relative to the leading term, the tail term 1.5PN above it is mπ + i(r + 2m ln(m/2)) with r rational:
    checked as Re = mπ and Im − 2m ln(m/2) a fraction of denominator ≤ 1000, in the test-mass limit ν = 0
    (the ln(m/2) part multiplies the leading term, so it does not depend on ν).
    LAL's (4,2) adds 8(1 − 3ν) ln 2 (relative: 8 ln 2), breaking it."""
    checked = 0
    for ell in range(2, 9):
        for m in range(1, ell + 1):
            terms = nonspinning.terms(0.0, 1.0)
            s = dict((k, a) for k, a, _ in terms.get((ell, m), []))
            if not s:
                continue
            k0 = min(s)
            if k0 + 3 not in s:
                continue
            ratio = s[k0 + 3] / s[k0]
            assert ratio.real == pytest.approx(m * math.pi, rel=1e-14), (ell, m)
            rest = ratio.imag - 2 * m * math.log(m / 2)
            assert abs(rest - float(Fraction(rest).limit_denominator(1000))) < 1e-12, (ell, m, rest)
            lal_rest = rest + 8 * LN2
            if (ell, m) == (4, 2):
                assert abs(lal_rest - float(Fraction(lal_rest).limit_denominator(1000))) > 1e-10
            checked += 1
    assert checked == 12   # (2,1) (2,2) (3,1) (3,2) (3,3) (4,1) (4,2) (4,3) (4,4) (5,1) (5,3) (5,5)


def test_1pn_correction_of_mass_modes_is_linear_in_m_squared():
    """For one ℓ the relative 1PN correction of the mass-type modes (ℓ + m even) is A + B m²: checked where
    three m exist, ℓ = 5 (m = 1, 3, 5: LAL's own agree) and ℓ = 6 (m = 2, 4, 6), at several ν; LAL's (6,4),
    with (6,6)'s correction, breaks it."""
    for nu in (0.2, 0.1875, 0.08):
        terms = nonspinning.terms(nu, masses(nu)[2])

        def rel(ell, m, tab=terms):
            s = dict((k, a) for k, a, _ in tab[ell, m])
            k0 = min(s)
            return s[k0 + 2] / s[k0]

        for ell, (ma, mb, mc) in ((5, (1, 3, 5)), (6, (2, 4, 6))):
            t = (mb * mb - ma * ma) / (mc * mc - ma * ma)
            assert rel(ell, mb) == pytest.approx((1 - t) * rel(ell, ma) + t * rel(ell, mc), rel=1e-13)
        theirs, _ = lal_version(nu, masses(nu)[2])
        t = (16 - 4) / (36 - 4)
        lal64 = rel(6, 4, theirs)
        assert abs(lal64 - ((1 - t) * rel(6, 2) + t * rel(6, 6))) > 1e-3 * abs(lal64)


# 1PN coefficient of ρ_ℓm, h_ℓm = h_ℓm^N Ŝ T e^{iδ} ρ_ℓm^ℓ (Damour, Iyer & Nagar 2009, arXiv:0811.2069; also
# Pan et al. 2011, arXiv:1106.1021, App. A), ρ_ℓm = 1 + ρ₁ x + …, re-typed as rational functions of ν;
# Ŝ = Ĥ_eff = 1 − x/2 + … for ℓ + m even, Ŝ = ĵ = 1 + (3/2 + ν/6) x + … for ℓ + m odd; T and δ start at
# 1.5PN.  (5,5) is not re-typed here (the ℓ = 5 linear-in-m² test covers it).
RHO_1PN = {
    (2, 2): lambda n: 55 * n / 84 - Fraction(43, 42),
    (2, 1): lambda n: 23 * n / 84 - Fraction(59, 56),
    (3, 3): lambda n: 2 * n / 3 - Fraction(7, 6),
    (3, 2): lambda n: (320 * n ** 2 - 1115 * n + 328) / (270 * (3 * n - 1)),
    (3, 1): lambda n: -2 * n / 9 - Fraction(13, 18),
    (4, 4): lambda n: (1614 - 5870 * n + 2625 * n ** 2) / (1320 * (3 * n - 1)),
    (4, 3): lambda n: (160 * n ** 2 - 547 * n + 222) / (176 * (2 * n - 1)),
    (4, 2): lambda n: (1146 - 3530 * n + 285 * n ** 2) / (1320 * (3 * n - 1)),
    (4, 1): lambda n: (288 * n ** 2 - 1385 * n + 602) / (528 * (2 * n - 1)),
    (5, 4): lambda n: (33320 * n ** 3 - 127610 * n ** 2 + 96019 * n - 17448) / (13650 * (5 * n ** 2 - 5 * n + 1)),
    (5, 3): lambda n: (176 * n ** 2 - 850 * n + 375) / (390 * (2 * n - 1)),
    (5, 2): lambda n: (21980 * n ** 3 - 104930 * n ** 2 + 84679 * n - 15828) / (13650 * (5 * n ** 2 - 5 * n + 1)),
    (5, 1): lambda n: (8 * n ** 2 - 626 * n + 319) / (390 * (2 * n - 1)),
    (6, 6): lambda n: (273 * n ** 3 - 861 * n ** 2 + 602 * n - 106) / (84 * (5 * n ** 2 - 5 * n + 1)),
    (6, 4): lambda n: (133 * n ** 3 - 581 * n ** 2 + 462 * n - 86) / (84 * (5 * n ** 2 - 5 * n + 1)),
    (6, 2): lambda n: (49 * n ** 3 - 413 * n ** 2 + 378 * n - 74) / (84 * (5 * n ** 2 - 5 * n + 1)),
}


def rho_1pn(terms, ell, m, nu):
    s = dict((k, a) for k, a, _ in terms[ell, m])
    k0 = min(s)
    relative = (s[k0 + 2] / s[k0]).real
    source = 1.5 + nu / 6 if (ell + m) % 2 else -0.5
    return (relative - source) / ell


@pytest.mark.parametrize("nu_frac", [Fraction(1, 5), Fraction(3, 16), Fraction(2, 25)])
def test_1pn_corrections_against_the_factorized_rho(nu_frac):
    """Every 1PN correction of ℓ ≤ 6 but (5,5) against DIN's ρ_ℓm; LAL's (4,2), (4,3), (4,4), (6,4) fail."""
    nu = float(nu_frac)
    delta = masses(nu)[2]
    ours = nonspinning.terms(nu, delta)
    theirs, _ = lal_version(nu, delta)
    for lm, rho in RHO_1PN.items():
        expected = float(rho(nu_frac))
        assert rho_1pn(ours, *lm, nu) == pytest.approx(expected, rel=1e-13, abs=1e-15), lm
        if lm in ((4, 2), (4, 3), (4, 4), (6, 4)):
            assert abs(rho_1pn(theirs, *lm, nu) - expected) > 0.05, lm
        else:
            assert rho_1pn(theirs, *lm, nu) == pytest.approx(expected, rel=1e-13, abs=1e-15), lm


def test_3_5pn_22_against_postnewtonian_jl_weight_retyped():
    """(2,2) at v⁷, Faye et al. 2012: PostNewtonian.jl's form (mode_weights.jl, h₂₂ (v/c)^7),
    (−2iν(−501655 + 24396ν) + 15(−2173 + 2ν(−2495 + 560ν))π)/11340, re-typed in exact fractions with its
    −2459 replaced by Faye et al.'s −2495 (which the 3.5PN flux requires: test_waveform_amplitudes.py)."""
    for nu_frac in (Fraction(1, 4), Fraction(3, 16), Fraction(2, 25)):
        imag = -2 * nu_frac * (-501655 + 24396 * nu_frac) / 11340
        real_over_pi = 15 * (-2173 + 2 * nu_frac * (-2495 + 560 * nu_frac)) / Fraction(11340)
        nu = float(nu_frac)
        c7 = dict((k, a) for k, a, _ in nonspinning.terms(nu, masses(nu)[2])[2, 2])[7]
        assert c7.real == pytest.approx(float(real_over_pi) * math.pi, rel=1e-14)
        assert c7.imag == pytest.approx(float(imag), rel=1e-14)
        # and the paper's own grouping: −2173π/756 + (−2495π/378 + 14333i/162)ν + (40π/27 − 4066i/945)ν²
        assert real_over_pi == Fraction(-2173, 756) + Fraction(-2495, 378) * nu_frac + Fraction(40, 27) * nu_frac ** 2
        assert imag == Fraction(14333, 162) * nu_frac - Fraction(4066, 945) * nu_frac ** 2


# ------------------------------------------------------------------------------------------- symmetry

@pytest.mark.parametrize("order2", [0, 3, 6, 7])
def test_reflection_symmetry_and_equal_mass_odd_m_vanish(order2):
    v = np.linspace(0.05, 0.45, 7)
    H = coorbital_modes(v, None, None, 30.0, 10.0, 8, order2)
    for ell, m in ell_m(8):
        np.testing.assert_array_equal(H[mode_index(ell, -m)], (-1) ** ell * np.conj(H[mode_index(ell, m)]))
    E = coorbital_modes(v, None, None, 15.0, 15.0, 8, order2)
    for ell, m in ell_m(8):
        if m % 2:
            assert not np.any(E[mode_index(ell, m)]), (ell, m)
    # every even-m mode is present at equal mass once its leading order is reached (ℓ = 8 at v⁶)
    if order2 >= 6:
        assert all(np.all(E[mode_index(ell, m)] != 0) for ell, m in ell_m(8) if m and m % 2 == 0)


def test_order_truncation_keeps_exactly_the_terms_up_to_order():
    v = np.array([0.1, 0.3])
    X1, X2, delta = masses(0.1875)
    terms = nonspinning.terms(0.1875, delta)
    for order2 in range(8):
        H = coorbital_modes(v, None, None, 30.0, 10.0, 8, order2)
        for ell, m in ell_m(8):
            if m < 0:
                continue
            expected = 0.1875 * evaluate(terms.get((ell, m), []), v, order2)
            np.testing.assert_allclose(H[mode_index(ell, m)], expected, rtol=1e-14, atol=1e-18)
