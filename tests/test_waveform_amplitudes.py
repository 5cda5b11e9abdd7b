"""Co-orbital mode amplitudes (pnrotor.waveform.amplitudes, .nonspinning, .spin) against the PN energy flux
and their symmetries.

The flux carried by the modes of a quasi-circular binary, F = (1/16π) Σ_ℓm |ḣ_ℓm|² with ḣ_ℓm = −imΩ h_ℓm
(Ω = v³, units r h/M, M = 1; the amplitudes' own time dependence enters at 5PN), must reproduce the PN
flux F = (32/5) ν² v¹⁰ F̂(v) of pnrotor.pn.flux (Blanchet's Living Review Eq. (314), Marsat et al. 2014,
Bohé et al. 2015) coefficient by coefficient through the amplitude order: an independent check of every
amplitude's magnitude and of the relative phases of its terms, computed exactly from the amplitude table.
"""

import numpy as np
import pytest

from pnrotor.pn import flux, series
from pnrotor.waveform import amplitudes
from pnrotor.waveform.amplitudes import coorbital_modes
from pnrotor.waveform.layout import ell_m, mode_index

MASSES = [(10.0, 10.0), (30.0, 10.0), (50.0, 5.0)]


def mode_flux_series(m1, m2, order2, a1=0.0, a2=0.0, kappa=(1.0, 1.0), tides=amplitudes.NO_TIDES):
    """(F̂ coefficients of v^j, of v^j ln v), j ≤ order2, from the amplitudes' own table with aligned spins
    χᵢ = aᵢ ℓ̂ (and ``tides`` as amplitudes.table takes them): with H_ℓm = h₀ Σ_k v^k (A_k + B_k ln v),
    h₀ = 8√(π/5) ν v², the flux relative to (32/5) ν² v¹⁰ is F̂ = (1/8) Σ_ℓm m² |Σ_k v^k (A_k + B_k ln v)|²,
    exactly, as polynomials."""
    M = m1 + m2
    X1, X2 = m1 / M, m2 / M
    spins = bool(a1 or a2)
    rows, ks, qs, cs, parities = amplitudes.table(X1 * X2, X1 - X2, 8, order2, spins, tides)
    q = np.zeros(amplitudes.N_Q)
    q[0] = 1.0
    q[2 + 2] = X1 * X1 * a1 + X2 * X2 * a2                                   # S_ell
    q[5 + 2] = X2 * a2 - X1 * a1                                             # Sigma_ell
    q[8 + 2] = kappa[0] * X1 * X1 * a1 * a1 + 2 * X1 * X2 * a1 * a2 + kappa[1] * X2 * X2 * a2 * a2   # P_ellell
    A = np.zeros((len(ell_m(8)), order2 + 1), dtype=complex)
    B = np.zeros_like(A)
    for row, k, qi, c, parity in zip(rows, ks, qs, cs, parities):   # m ≥ 0; H_ℓ,−m from parity (−1)^ℓ H*_ℓm
        ell, m = ell_m(8)[row]
        for r, coef in ((row, c), (mode_index(ell, -m), parity * (-1) ** ell * np.conj(c)))[:2 if m else 1]:
            if qi == 1:
                B[r, k] += coef
            else:
                A[r, k] += coef * q[qi]
    f, flog = np.zeros(order2 + 1), np.zeros(order2 + 1)
    for row, (_, m) in enumerate(ell_m(8)):
        for k in range(order2 + 1):
            for kp in range(order2 + 1 - k):
                f[k + kp] += m * m * (A[row, k] * np.conj(A[row, kp])).real / 8
                flog[k + kp] += m * m * 2 * (B[row, k] * np.conj(A[row, kp])).real / 8
    return f, flog


def pn_flux_coefficients(m1, m2, order2, a1=0.0, a2=0.0, kappa=(1.0, 1.0)):
    C = flux.flux_series(m1 / (m1 + m2), *kappa)
    b = series.basis_values(a1, a2, a1 * a2, a1 * a1, a2 * a2)
    return (C[:, :, 0] @ b)[:order2 + 1], (C[:, :, 1] @ b)[:order2 + 1]


@pytest.mark.parametrize("m1, m2", MASSES)
def test_nonspinning_modes_carry_the_pn_flux_through_3_5pn(m1, m2):
    """Every coefficient of F̂ through v⁷, with the 3PN logarithm (the 2.5PN and 3.5PN imaginary parts,
    the tail's, do not reach the flux at these orders)."""
    f, flog = mode_flux_series(m1, m2, 7)
    g, glog = pn_flux_coefficients(m1, m2, 7)
    np.testing.assert_allclose(f, g, rtol=0, atol=1e-12 * np.abs(g).max())
    np.testing.assert_allclose(flog, glog, rtol=0, atol=1e-12)


@pytest.mark.parametrize("m1, m2", [(10.0, 10.0), (1.4, 1.4)])
def test_equal_mass_modes_carry_the_pn_flux_through_4pn(m1, m2):
    """The 4PN (2,2) term (Blanchet et al. 2023) with every other mode: at equal masses, where the odd-m modes vanish,
    every mode that reaches v⁸ of the flux is known (the 3.5PN terms of (2,1), (3,1), (3,3) that unequal masses need
    are not in the tables), so F̂ is reproduced through v⁸ with its logarithms, Blanchet et al. 2023's 4PN flux."""
    f, flog = mode_flux_series(m1, m2, 8)
    g, glog = pn_flux_coefficients(m1, m2, 8)
    np.testing.assert_allclose(f, g, rtol=0, atol=1e-12 * np.abs(g).max())
    np.testing.assert_allclose(flog, glog, rtol=0, atol=1e-12 * np.abs(glog).max())


def test_flux_in_the_test_mass_limit_is_black_hole_perturbation_theory():
    """ν → 0 of F̂ through 4.5PN against the flux of a particle on a circular orbit of a Schwarzschild black hole:
    Tagoshi & Sasaki 1994 (gr-qc/9405062) through v⁸ and Tanaka, Tagoshi & Sasaki 1996 (gr-qc/9602038) at v⁹,
    written as they are (γ, ln 2, ln 3 and ln v apart), an independent computation of the ν⁰ terms that
    Blanchet et al. 2023's 4PN and 4.5PN flux must reduce to."""
    g, pi, l2, l3 = 0.5772156649015329, np.pi, np.log(2.0), np.log(3.0)
    bhpt = {0: (1, 0), 2: (-1247 / 336, 0), 3: (4 * pi, 0), 4: (-44711 / 9072, 0), 5: (-8191 / 672 * pi, 0),
            6: (6643739519 / 69854400 - 1712 / 105 * g + 16 / 3 * pi ** 2 - 3424 / 105 * l2, -1712 / 105),
            7: (-16285 / 504 * pi, 0),
            8: (-323105549467 / 3178375200 + 232597 / 4410 * g - 1369 / 126 * pi ** 2 + 39931 / 294 * l2
                - 47385 / 1568 * l3, 232597 / 4410),
            9: (265978667519 / 745113600 * pi - 6848 / 105 * pi * g - 13696 / 105 * pi * l2, -6848 / 105 * pi)}
    f, flog = flux.nonspinning_flux_coefficients(0.0)
    for k in range(10):
        c, c_log = bhpt.get(k, (0, 0))
        assert f[k] == pytest.approx(c, rel=1e-14, abs=1e-14) and flog[k] == pytest.approx(c_log, rel=1e-14, abs=0)


@pytest.mark.parametrize("m1, m2", MASSES)
@pytest.mark.parametrize("kappa", [(1.0, 1.0), (3.0, 6.0)])
def test_aligned_spin_modes_carry_the_spin_orbit_and_spin_spin_flux(m1, m2, kappa):
    """Spin-orbit at 1.5PN and spin-spin, with the κ quadrupole-monopole terms, at 2PN."""
    for a1, a2 in ((0.7, -0.4), (0.0, 0.9), (-0.8, 0.0)):
        f, _ = mode_flux_series(m1, m2, 4, a1, a2, kappa)
        g, _ = pn_flux_coefficients(m1, m2, 4, a1, a2, kappa)
        np.testing.assert_allclose(f, g, rtol=0, atol=1e-13)


def test_nonprecessing_modes_have_reflection_symmetry_and_equal_mass_kills_odd_m():
    v = np.linspace(0.1, 0.4, 5)
    for chi in (None, (0.0, 0.0, 0.6)):
        c = None if chi is None else np.tile(chi, (v.size, 1))
        H = coorbital_modes(v, c, c, 30.0, 10.0, 8, 7)
        for ell, m in ell_m(8):
            np.testing.assert_allclose(H[mode_index(ell, -m)], (-1) ** ell * np.conj(H[mode_index(ell, m)]),
                                       rtol=0, atol=1e-15)
        E = coorbital_modes(v, c, c, 20.0, 20.0, 8, 7)
        for ell, m in ell_m(8):
            if m % 2:
                assert np.all(E[mode_index(ell, m)] == 0)
    assert np.all(coorbital_modes(v, None, None, 30.0, 10.0, 8, 7)[[mode_index(ell, 0) for ell in (2, 4, 6, 8)]] == 0)


def test_in_plane_spins_break_the_symmetry_by_the_antisymmetric_terms():
    """Precessing spins add terms with H_ℓ,−m = −(−1)^ℓ H*_ℓm (reflection through the orbital plane flips
    in-plane spin components of a pseudovector): H − (−1)^ℓ conj(H at −m) is twice them."""
    v = np.array([0.3])
    chi1, chi2 = np.array([[0.5, 0.2, 0.1]]), np.array([[-0.3, 0.4, 0.0]])
    H = coorbital_modes(v, chi1, chi2, 30.0, 10.0, 4, 4)
    flipped = coorbital_modes(v, chi1 * [-1, -1, 1], chi2 * [-1, -1, 1], 30.0, 10.0, 4, 4)
    for ell, m in ell_m(4):
        np.testing.assert_allclose(flipped[mode_index(ell, m)], (-1) ** ell * np.conj(H[mode_index(ell, -m)]),
                                   rtol=0, atol=1e-15)
    assert abs(H[mode_index(2, 1), 0] - np.conj(H[mode_index(2, -1), 0])) > 1e-4


def test_orders_and_modes_select_terms():
    v = np.array([0.3])
    full = coorbital_modes(v, None, None, 30.0, 10.0, 4, 7)
    newtonian = coorbital_modes(v, None, None, 30.0, 10.0, 2, 0)
    assert newtonian.shape == (5, 1) and full.shape == (21, 1)
    assert newtonian[mode_index(2, 2), 0] == pytest.approx(8 * np.sqrt(np.pi / 5) * 0.1875 * 0.09, rel=1e-15)
    assert np.count_nonzero(newtonian) == 2


def _summed_terms_reference(nu, delta, ell_max, order2, spins, constants):
    """The kernel's real terms summed the plain way, from table(): a dict of (ℓ, target, k, q) → sum, in the
    terms' order, its zero sums dropped, sorted (an independent route to what _real_terms must give)."""
    rows, ks, qs, cs, parities = amplitudes.table(nu, delta, ell_max, order2, spins)
    n_pow = 2 * ell_max + 1
    summed = {}
    for row, k, q, c, parity in zip(rows.tolist(), ks.tolist(), qs.tolist(), cs.tolist(), parities.tolist()):
        ell, m = ell_m(ell_max)[row]
        if constants is not None and q >= 2:
            c, q = c * constants[q], 0
        r = ell + m if parity > 0 else ell - m
        for part, target in ((c.real, r), (c.imag, n_pow + r)):
            if part:
                summed[(ell, target, k, q)] = summed.get((ell, target, k, q), 0.0) + part
    return sorted((key, value) for key, value in summed.items() if value)


@pytest.mark.parametrize("X1", [0.5, 0.75, 50 / 55, 0.999])
def test_kernel_terms_are_the_tables_terms_summed(X1):
    """_real_terms (the terms as the kernel adds them, built from a layout cached per options and the coefficients
    in one array) equals the plain per-term sum of table()'s terms bitwise, for every ℓ_max, amplitude order, spin
    content and spins folded into the coefficients (aligned runs); equal masses drop their vanishing odd-m sums."""
    rng = np.random.default_rng(7)
    nu, delta = X1 * (1 - X1), 2 * X1 - 1
    for ell_max in range(2, 9):
        for order2 in range(8):
            for spins, constants in ((False, None), (True, None), (True, tuple(rng.normal(size=amplitudes.N_Q)))):
                amplitudes._real_terms.cache_clear()
                ell_start, target, k, q, c, _ = amplitudes._real_terms(nu, delta, ell_max, order2, spins, constants)
                ell = np.repeat(np.arange(ell_max + 1), np.diff(ell_start))
                got = [((a, b, d, e), x) for a, b, d, e, x in zip(ell.tolist(), target.tolist(), k.tolist(),
                                                                    q.tolist(), c.tolist())]
                assert got == _summed_terms_reference(nu, delta, ell_max, order2, spins, constants), \
                    (ell_max, order2, spins, constants is not None)


def test_the_source_traversals_agree():
    """_source_values (the coefficients alone, per call) lists the coefficients of _source_terms (with their
    (ℓ, m, k, q, parity), which the cached layout reads) in the same order; nonspinning.terms with ell_max < 5
    gives the modes of ℓ ≤ 4 of the full table."""
    from pnrotor.waveform import nonspinning

    for nu, delta in ((0.25, 0.0), (0.1875, 0.5), (0.0099, 0.98)):
        full = nonspinning.terms(nu, delta)
        assert nonspinning.terms(nu, delta, 4) == {key: value for key, value in full.items() if key[0] <= 4}
        for ell_max in (2, 4, 5, 8):
            for spins in (False, True):
                values = amplitudes._source_values(nu, delta, ell_max, spins)
                assert values == [c for *_, c, _ in amplitudes._source_terms(nu, delta, ell_max, spins)]
