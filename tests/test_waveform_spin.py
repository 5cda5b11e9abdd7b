"""Spin terms of the co-orbital amplitudes (pnrotor.waveform.spin) against LALSuite, PostNewtonian.jl and symmetry.

* Through 1.5PN, LALSuite's ``SimInspiralSpinPNMode2m/3m/4m`` (Arun et al. 2009, App. B), fed L̂N = ẑ, E1 = x̂:
  their inertial modes are then H_ℓm e^{−imΦ} with n̂ = cos Φ x̂ + sin Φ ŷ; the spin part is isolated by
  subtracting LALSuite's modes with zero spins.  ℓ = 2 agrees to ~1e-16 of |H₂₂|; LALSuite's ℓ = 3 spin terms
  are exactly twice ours (its χ_s is χ₁ + χ₂, its ℓ = 2 function's is (χ₁ + χ₂)/2), which LALSuite's
  IMRPhenomXHM PN amplitude (Mishra et al. 2016, χ_s = (χ₁ + χ₂)/2) confirms on (3,2); ℓ = 4 has no spin terms
  in either through 1.5PN.
* The 2PN terms (beyond LALSuite): PostNewtonian.jl's ``mode_weights.jl`` re-typed below in its own form
  (dimensionful S, Σ, S₀^± of Buonanno, Faye & Hinderer 2013 Eq. (3.4) with κ, symmetrized as it does it),
  against the module's coefficient table.
* The reflection relation H_ℓ,−m(χ_n, χ_λ, χ_ℓ) = (−1)^ℓ H*_ℓm(−χ_n, −χ_λ, χ_ℓ), and aligned spins.
"""

import cmath
import math

import numpy as np
import pytest
from helpers import needs, reference

from pnrotor.waveform.layout import mode_index
from pnrotor.waveform.amplitudes import coorbital_modes
from pnrotor.waveform.spin import terms

lal, ls = reference("lal"), reference("lalsimulation")
needs_lal = needs("lal", "lalsimulation")

NUS = (0.25, 0.1875, 0.08)
VS = (0.2, 0.3, 0.4)
H0 = 8.0 * math.sqrt(math.pi / 5.0)
LAL_MODES = {} if ls is None else {2: ls.SimInspiralSpinPNMode2m, 3: ls.SimInspiralSpinPNMode3m,
                                   4: ls.SimInspiralSpinPNMode4m}


def _delta(nu):
    return math.sqrt(1.0 - 4.0 * nu)


def _spins(rng, n):
    """n random spins, all components, |χ| ≤ 1."""
    c = rng.normal(size=(n, 3))
    return c / np.linalg.norm(c, axis=1)[:, None] * rng.uniform(0.0, 1.0, (n, 1)) ** (1 / 3)


def _samples(rng, per_v=4):
    v = np.repeat(VS, per_v)
    return v, _spins(rng, v.size), _spins(rng, v.size)


def ours(v, nu, chi1, chi2, order2, ell_max=4, kappa1=1.0, kappa2=1.0):
    """The spin part of pnrotor's H_ℓm (n_modes, N): the amplitudes with these spins minus those without."""
    d = _delta(nu)
    m1, m2 = (1 + d) / 2, (1 - d) / 2
    v = np.asarray(v, dtype=float)
    return (coorbital_modes(v, chi1, chi2, m1, m2, ell_max, order2, kappa1, kappa2)
            - coorbital_modes(v, None, None, m1, m2, ell_max, order2))


def _series(x):
    s = lal.CreateREAL8TimeSeries("s", lal.LIGOTimeGPS(0), 0.0, 1.0, lal.DimensionlessUnit, x.size)
    s.data.data[:] = x
    return s


def lal_modes(v, phi, nu, chi1, chi2, ampO, ell):
    """LALSuite's inertial modes of ℓ (units r h / M) with L̂N = ẑ, E1 = x̂, orbital phase phi, spins along x, y, z."""
    d = _delta(nu)
    m1, m2 = (1.0 + d) / 2 * lal.MSUN_SI, (1.0 - d) / 2 * lal.MSUN_SI
    zero, one = np.zeros(v.size), np.ones(v.size)
    frame = [_series(a) for a in (zero, zero, one, one, zero, zero)]
    spins = [_series(np.ascontiguousarray(c[:, a])) for c in (chi1, chi2) for a in range(3)]
    out = LAL_MODES[ell](_series(v), _series(phi), *frame, *spins, m1, m2, lal.MRSUN_SI, ampO)
    node = out[-1] if isinstance(out, (tuple, list)) else out
    modes = {}
    while node is not None:
        modes[(node.l, node.m)] = node.mode.data.data.copy()
        node = node.next
    return modes


def lal_spin_part(v, phi, nu, chi1, chi2, ampO, ell):
    full = lal_modes(v, phi, nu, chi1, chi2, ampO, ell)
    bare = lal_modes(v, phi, nu, 0 * chi1, 0 * chi2, ampO, ell)
    return {lm: full[lm] - bare[lm] for lm in full}


def _scale(nu, v):
    """|H₂₂| of the nonspinning binary at leading order, per sample."""
    return H0 * nu * v ** 2


def _lal_differences(nu, ampO, phi_of_v=None, seed=0):
    """max_samples |ours − LAL| / |H₂₂| for every (ℓ, m), and the same with ours doubled for ℓ = 3."""
    rng = np.random.default_rng(seed + int(1000 * nu) + 10 * ampO)
    v, c1, c2 = _samples(rng)
    phi = np.zeros(v.size) if phi_of_v is None else phi_of_v(v, rng)
    # co-orbital components: n̂ = cos Φ x̂ + sin Φ ŷ, λ̂ = −sin Φ x̂ + cos Φ ŷ
    cp, sp = np.cos(phi), np.sin(phi)
    co1, co2 = (np.stack([cp * c[:, 0] + sp * c[:, 1], -sp * c[:, 0] + cp * c[:, 1], c[:, 2]], axis=1) for c in (c1, c2))
    H = ours(v, nu, co1, co2, ampO)
    diff, diff_doubled = {}, {}
    for ell in (2, 3, 4):
        theirs = lal_spin_part(v, phi, nu, c1, c2, ampO, ell)
        for m in range(-ell, ell + 1):
            mine = H[mode_index(ell, m)] * np.exp(-1j * m * phi)
            diff[(ell, m)] = np.max(np.abs(mine - theirs[(ell, m)]) / _scale(nu, v))
            diff_doubled[(ell, m)] = np.max(np.abs(2 * mine - theirs[(ell, m)]) / _scale(nu, v))
    return diff, diff_doubled


@needs_lal
@pytest.mark.parametrize("ampO", [0, 1, 2, 3])
@pytest.mark.parametrize("nu", NUS)
def test_spin_terms_match_lal_coorbital(nu, ampO):
    """Φ = 0: LALSuite's inertial modes are the co-orbital H_ℓm.  ℓ = 2, 4 agree; ℓ = 3 is LALSuite's twice ours."""
    diff, doubled = _lal_differences(nu, ampO)
    for (ell, m), d in diff.items():
        if ell != 3:
            assert d < 1e-13, ((ell, m), d)
        else:
            assert doubled[(ell, m)] < 1e-13, ((ell, m), doubled[(ell, m)])


@needs_lal
@pytest.mark.parametrize("nu", NUS)
def test_spin_terms_match_lal_rotated_phase(nu):
    """Φ ≠ 0: LALSuite's h_ℓm = H_ℓm(χ·n̂, χ·λ̂, χ·ℓ̂) e^{−imΦ}, n̂ = cos Φ E1 + sin Φ (L̂N × E1)."""
    diff, doubled = _lal_differences(nu, 3, phi_of_v=lambda v, rng: rng.uniform(0, 2 * np.pi, v.size), seed=7)
    for (ell, m), d in diff.items():
        assert (doubled[(ell, m)] if ell == 3 else d) < 1e-13, ((ell, m), d, doubled[(ell, m)])


@needs_lal
@pytest.mark.parametrize("nu", NUS)
def test_lal_l3_spin_terms_are_twice_the_formula(nu):
    """The disagreement, measured: at 1.5PN LALSuite's ℓ = 3 spin terms are 2.000… times ours, for every m
    (their difference is as large as ours, ~1e-3–1e-2 of |H₂₂| at v = 0.4), while the ℓ = 2 spin terms (same
    paper, same χ_s notation) agree: ``SpinPNMode3m`` sets Ssx = S1x + S2x, ``SpinPNMode2m`` (S1x + S2x)/2."""
    rng = np.random.default_rng(3)
    v, c1, c2 = _samples(rng)
    H = ours(v, nu, c1, c2, 3)
    theirs = lal_spin_part(v, np.zeros(v.size), nu, c1, c2, 3, 3)
    for m in (-3, -2, -1, 1, 2, 3):
        mine = H[mode_index(3, m)]
        big = np.abs(mine) > 1e-6 * _scale(nu, v)
        assert big.any()
        np.testing.assert_allclose(theirs[(3, m)][big] / mine[big], 2.0, rtol=1e-11)
        assert np.max(np.abs(theirs[(3, m)] - mine) / _scale(nu, v)) > 1e-4
    # the (3,0) spin term starts at 2PN: none in either at 1.5PN
    assert np.all(theirs[(3, 0)] == 0) and np.all(H[mode_index(3, 0)] == 0)


def test_l3_aligned_spin_orbit_term_matches_phenomxhm_pn_amplitude():
    """An independent source for the factor: LALSuite's IMRPhenomXHM (32) PN amplitude, from Mishra et al. 2016,
    is (−1 + 3ν) x + (−4 χ_s ν) x^{3/2} with χ_s = (χ₁ + χ₂)/2 (LALSimIMRPhenomXHM_internals.c): the ratio of
    the 1.5PN spin term of H₃₂ to its 1PN term is 4 ν χ_s v / (1 − 3ν) — ours, not LALSuite's SpinPNMode3m."""
    from pnrotor.waveform import nonspinning
    for nu in NUS:
        v = np.array([0.3])
        c1, c2 = np.array([[0.0, 0.0, 0.7]]), np.array([[0.0, 0.0, -0.2]])
        newtonian = dict((k, a) for k, a, _ in nonspinning.terms(nu, _delta(nu))[(3, 2)])[2] * H0 * nu * v ** 4
        spin = ours(v, nu, c1, c2, 3)[mode_index(3, 2)]
        chi_s = (0.7 - 0.2) / 2
        np.testing.assert_allclose(spin / newtonian, 4 * nu * chi_s * v / (1 - 3 * nu), rtol=1e-13)


# ---- PostNewtonian.jl (src/pn_expressions/mode_weights.jl), re-typed in its own variables ---------------------

def _s0(M1, M2, k1, k2, S1, S2, sign):
    """S₀^± of Buonanno, Faye & Hinderer 2013, Eq. (3.4), with κ (complex for κ₁κ₂ > 1)."""
    M = M1 + M2
    root = cmath.sqrt(1 - k1 * k2)
    kr = (k1 / k2) ** 0.25
    return (M / M1) * kr * cmath.sqrt(1 + sign * root) * S1 + (M / M2) / kr * cmath.sqrt(1 - sign * root) * S2


def postnewtonian_jl(v, M1, M2, chi1, chi2, k1=1.0, k2=1.0, ell_max=4, pn_order2=4):
    """The spin terms of PostNewtonian.jl's h! for one sample, masses M1 + M2 = M ≠ 1 allowed: {(ℓ, m): value}."""
    M = M1 + M2
    nu, d = M1 * M2 / M ** 2, (M1 - M2) / M
    S1, S2 = np.asarray(chi1) * M1 ** 2, np.asarray(chi2) * M2 ** 2
    S = S1 + S2
    Sg = M * (np.asarray(chi2) * M2 - np.asarray(chi1) * M1)
    Sn, Sl, Sz = S
    Gn, Gl, Gz = Sg
    P = [_s0(M1, M2, k1, k2, S1[a], S2[a], +1) for a in range(3)]
    Q = [_s0(M1, M2, k1, k2, S1[a], S2[a], -1) for a in range(3)]
    Pn, Pl, Pz = P
    Qn, Ql, Qz = Q
    h0 = 2 * nu * v ** 2 * math.sqrt(16 * math.pi / 5)
    I = 1j
    r = math.sqrt

    def series(*pairs):
        return h0 * sum(v ** k * c for k, c in pairs if k <= pn_order2)

    h = {}
    sym = {
        (2, 0): series((4, (Pn * Qn - Pl * Ql) / (r(6) * M ** 4))),
        (2, 1): series((2, I * Gz / (2 * M ** 2)), (4, I * (-86 * Sz * d + Gz * (139 * nu - 79)) / (42 * M ** 2))),
        (2, 2): series((3, -(6 * Sz + 2 * Gz * d) / (3 * M ** 2)),
                       (4, (12 * Pz * Qz + 10 * Pl * Ql - 22 * Pn * Qn - 15 * I * (Pn * Ql + Pl * Qn)) / (12 * M ** 4))),
        (3, 1): series((4, r(14) * I * (Sz * d - 5 * Gz * (3 * nu - 1)) / (336 * M ** 2))),
        (3, 2): series((3, 2 * r(35) * (Sz + Gz * d) / (21 * M ** 2))),
        (3, 3): series((4, 3 * r(210) * I * (7 * Sz * d - 3 * Gz * (3 * nu - 1)) / (112 * M ** 2))),
        (4, 1): series((4, r(10) * I * (Sz * d - 3 * Gz * nu + Gz) / (336 * M ** 2))),
        (4, 3): series((4, 9 * r(70) * I * (-Sz * d + 3 * Gz * nu - Gz) / (112 * M ** 2))),
    }
    for (ell, m), x in sym.items():
        h[(ell, m)] = x
        if m:
            h[(ell, -m)] = (-1) ** ell * np.conj(x)
    anti = {
        (2, 0): series((2, r(6) * I * Gn / (6 * M ** 2)), (4, r(6) * I * (255 * Sn * d - Gn * (506 * nu - 45)) / (126 * M ** 2))),
        (2, 1): series((3, (4 * I * Sl + 25 * Sn + 4 * I * Gl * d + 13 * Gn * d) / (6 * M ** 2)),
                       (4, -3 * (Pn * Qz + Pz * Qn) / (4 * M ** 4))),
        (2, 2): series((2, -(Gl + I * Gn) / (2 * M ** 2)),
                       (4, (19 * Sl * d + 182 * I * Sn * d - 43 * Gl * nu + 5 * Gl - 280 * I * Gn * nu + 98 * I * Gn) / (84 * M ** 2))),
        (3, 0): series((4, r(42) * (-17 * Sl * d + Gl * (35 * nu - 9)) / (168 * M ** 2))),
        (3, 1): series((3, r(14) * (I * Sl + Sn + d * (I * Gl + Gn)) / (21 * M ** 2))),
        (3, 2): series((4, r(35) * (-Gl * (83 * nu - 17) + 4 * I * Gn * (55 * nu - 13) + 25 * d * (Sl - 4 * I * Sn)) / (168 * M ** 2))),
        (3, 3): series((3, r(210) * I * (Sl + I * Sn + d * (Gl + I * Gn)) / (21 * M ** 2))),
        (4, 0): series((4, r(2) * I * (Sn * d - 3 * Gn * nu + Gn) / (168 * M ** 2))),
        (4, 2): series((4, r(5) * (-13 * Gl * (3 * nu - 1) + 14 * I * Gn * (3 * nu - 1) + d * (13 * Sl - 14 * I * Sn)) / (168 * M ** 2))),
        (4, 4): series((4, 9 * r(35) * (-3 * Gl * nu + Gl - I * Gn * (3 * nu - 1) + d * (Sl + I * Sn)) / (56 * M ** 2))),
    }
    for (ell, m), x in anti.items():
        h[(ell, m)] = h.get((ell, m), 0) + x
        if m:
            h[(ell, -m)] = h.get((ell, -m), 0) - (-1) ** ell * np.conj(x)
    return {lm: x for lm, x in h.items() if lm[0] <= ell_max}


@pytest.mark.parametrize("kappas", [(1.0, 1.0), (4.3, 7.1), (1.0, 0.6)])
@pytest.mark.parametrize("nu", NUS)
def test_matches_postnewtonian_jl_retyped(nu, kappas):
    """Every term through 2PN (2PN spin-orbit and spin-spin included, κ too) against PostNewtonian.jl's
    expressions re-typed in its variables, at total mass 2.7 (so M ≠ 1 exercises its M powers)."""
    rng = np.random.default_rng(int(nu * 1e4) + int(10 * kappas[1]))
    M = 2.7
    X1 = (1 + _delta(nu)) / 2
    for v in VS:
        c1, c2 = _spins(rng, 1), _spins(rng, 1)
        for order2 in (2, 3, 4, 7):
            H = ours(np.array([v]), nu, c1, c2, order2, 4, *kappas)[:, 0]
            ref = postnewtonian_jl(v, X1 * M, (1 - X1) * M, c1[0], c2[0], *kappas, pn_order2=order2)
            for ell in (2, 3, 4):
                for m in range(-ell, ell + 1):
                    assert abs(H[mode_index(ell, m)] - ref.get((ell, m), 0)) < 1e-15 * H0 * nu * v ** 2, (ell, m, order2)


def test_2pn_terms_are_present_and_sizable():
    """The 2PN spin terms (absent from LALSuite) do contribute: order2 = 4 minus order2 = 3 is nonzero in every
    mode that has one, and order2 = 4 … 7 add nothing more (no spin terms beyond 2PN are implemented)."""
    rng = np.random.default_rng(11)
    v, c1, c2 = _samples(rng, 2)
    nu = 0.1875
    h3, h4, h7 = (ours(v, nu, c1, c2, k) for k in (3, 4, 7))
    np.testing.assert_allclose(h4, h7, rtol=0, atol=1e-16)
    for ell, m in [(2, 0), (2, 1), (2, 2), (3, 0), (3, 1), (3, 2), (3, 3), (4, 0), (4, 1), (4, 2), (4, 3), (4, 4)]:
        for mm in (m, -m):
            assert np.max(np.abs(h4[mode_index(ell, mm)] - h3[mode_index(ell, mm)])) > 1e-7, (ell, mm)


def _reflect(c):
    return c * np.array([-1.0, -1.0, 1.0])


def test_reflection_through_orbital_plane():
    """Spins are pseudovectors: the reflected binary has (−χ_n, −χ_λ, χ_ℓ), and h_ℓm → (−1)^ℓ h*_ℓ,−m, so
    H_ℓ,−m(χ) = (−1)^ℓ H*_ℓm(reflected χ) for every term (κ ≠ 1 too); not (−1)^ℓ H*_ℓm(χ) once spins precess."""
    rng = np.random.default_rng(5)
    v, c1, c2 = _samples(rng)
    for nu in NUS:
        for kappas in ((1.0, 1.0), (3.0, 5.0)):
            H = ours(v, nu, c1, c2, 4, 4, *kappas)
            R = ours(v, nu, _reflect(c1), _reflect(c2), 4, 4, *kappas)
            worst_plain = 0.0
            for ell in (2, 3, 4):
                for m in range(-ell, ell + 1):
                    np.testing.assert_allclose(H[mode_index(ell, -m)], (-1) ** ell * np.conj(R[mode_index(ell, m)]),
                                               rtol=0, atol=1e-16)
                    worst_plain = max(worst_plain, np.max(np.abs(H[mode_index(ell, -m)]
                                                                 - (-1) ** ell * np.conj(H[mode_index(ell, m)]))))
            assert worst_plain > 1e-4


def test_parity_labels_match_the_quantities():
    """Symmetric terms use only quantities even in the in-plane components, antisymmetric ones only odd ones."""
    even_q = {"S_ell", "Sigma_ell", "P_nn", "P_lambdalambda", "P_ellell", "Q_nlambda"}
    for nu in NUS:
        symmetric, antisymmetric = terms(nu, _delta(nu))
        assert symmetric and antisymmetric
        for group, even in ((symmetric, True), (antisymmetric, False)):
            for ell, m, k, name, c in group:
                assert (name in even_q) == even, (ell, m, k, name)
                assert 2 <= ell <= 4 and 0 <= m <= ell and 2 <= k <= 4


@pytest.mark.parametrize("nu", NUS)
def test_aligned_spins(nu):
    """Spins along ℓ̂: no m = 0 or ℓ = 4 even-m terms, H_ℓ,−m = (−1)^ℓ H*_ℓm, H_ℓm real for even m and imaginary
    for odd m; and the terms in χ_s, χ_a = (χ₁ ± χ₂)/2 (re-derived by hand from S_ℓ, Σ_ℓ, P_ℓℓ):
    H₂₁ ∋ −i (χ_a + δ χ_s)/2 v², H₂₂ ∋ −(4/3)[(1 − ν) χ_s + δ χ_a] v³ + (χ_s + δ χ_a)² v⁴ (κ = 1),
    H₃₂ ∋ (4/3) √(5/7) ν χ_s v³."""
    d = _delta(nu)
    rng = np.random.default_rng(2)
    v = np.array(VS)
    z1, z2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    c1 = np.stack([0 * z1, 0 * z1, z1], axis=1)
    c2 = np.stack([0 * z2, 0 * z2, z2], axis=1)
    H = ours(v, nu, c1, c2, 4)
    for ell in (2, 3, 4):
        for m in range(-ell, ell + 1):
            h = H[mode_index(ell, m)]
            np.testing.assert_allclose(H[mode_index(ell, -m)], (-1) ** ell * np.conj(h), rtol=0, atol=1e-17)
            part = h.imag if m % 2 == 0 else h.real
            assert np.all(part == 0), (ell, m)
            if m == 0 or (ell == 4 and m % 2 == 0):
                assert np.all(h == 0), (ell, m)
    xs, xa = (z1 + z2) / 2, (z1 - z2) / 2
    h0 = H0 * nu * v ** 2
    np.testing.assert_allclose(ours(v, nu, c1, c2, 2)[mode_index(2, 1)], h0 * v ** 2 * -0.5j * (xa + d * xs),
                               rtol=0, atol=1e-15 * h0.max())
    np.testing.assert_allclose(H[mode_index(2, 2)], h0 * (-4 / 3 * ((1 - nu) * xs + d * xa) * v ** 3
                                                          + (xs + d * xa) ** 2 * v ** 4), rtol=0, atol=1e-15 * h0.max())
    np.testing.assert_allclose(ours(v, nu, c1, c2, 3)[mode_index(3, 2)], h0 * 4 / 3 * math.sqrt(5 / 7) * nu * xs * v ** 3,
                               rtol=0, atol=1e-15 * h0.max())
