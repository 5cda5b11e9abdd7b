"""PN coefficients, series algebra and the numba right-hand sides, checked against independent forms.

* orbit-averaged spin² energy/flux (pnrotor.pn.energy/flux) reduce, for aligned spins, to the
  aligned-spin form of Bohé, Faye, Marsat & Porter 2015 (arXiv:1501.01529) Eqs. (3.33) and (4.14)
  in the variables s_ℓ, σ_ℓ, κ± — an independent transcription (PostNewtonian.jl's);
* the TaylorT4 re-expansion reproduces the published TaylorT4 coefficients: nonspinning, Buonanno,
  Iyer, Ochsner, Pan & Sathyaprakash 2009 (arXiv:0907.0700) Eq. (3.6); spin-orbit, Marsat et al.
  2014 (arXiv:1307.6793) Eq. (4.10a); 2PN spin-spin, Racine, Buonanno & Kidder 2009 (arXiv:0812.4413)
  Eqs. (5.15)-(5.17) (closed forms as in LALSuite's LALSimInspiralPNCoefficients.c);
* the leading-order orbital precession equals the orbit average of Bohé et al. 2013's ϖ n̂;
* the numba RHS agrees with the numpy reference formulas.
"""

import math

import numpy as np
import pytest

from pnrotor.pn import energy, ends, flux, layout, precession, rhs, series, system
from pnrotor.pn.series import (B_A1, B_A1A1, B_A1A2, B_A2, B_A2A2, B_ONE, B_S11, B_S12, B_S22, basis_values,
                               evaluate, kmax_from_orders)
from pnrotor.pn.vdot import vdot_series

RNG = np.random.default_rng(20240611)
GAMMA = 0.57721566490153286061


def _aligned_spin_squared(X1, chi1, chi2, k1, k2):
    """Bohé+ 2015 Eqs. (3.33) (energy) and (4.14) (flux), aligned spins: {k: (E_k, F_k)}."""
    X2 = 1 - X1
    nu = X1 * X2
    d = X1 - X2
    s = X1 ** 2 * chi1 + X2 ** 2 * chi2
    sig = X2 * chi2 - X1 * chi1
    kp, km = k1 + k2, k1 - k2
    E4 = s ** 2 * (-kp - 2) + s * sig * (-d * kp - 2 * d + km) + sig ** 2 * (d * km / 2 - kp / 2 + (kp + 2) * nu)
    E6 = (s ** 2 * (-5 * d * km / 3 - 25 * kp / 6 + 50 / 9 + (5 * kp / 6 + 5 / 3) * nu)
          + s * sig * (-5 * d * kp / 2 + 25 * d / 3 + 5 * km / 2 + (5 * d * kp / 6 + 5 * d / 3 + 35 * km / 6) * nu)
          + sig ** 2 * (5 * d * km / 4 - 5 * kp / 4 + 5 + (5 * d * km / 4 + 5 * kp / 4 - 10) * nu
                        + (-5 * kp / 6 - 5 / 3) * nu ** 2))
    F4 = s ** 2 * (2 * kp + 4) + s * sig * (2 * d * kp + 4 * d - 2 * km) + sig ** 2 * (
        -d * km + kp + 1 / 16 + (-2 * kp - 4) * nu)
    F6 = (s ** 2 * (41 * d * km / 16 - 271 * kp / 112 - 5239 / 504 + (-43 * kp / 4 - 43 / 2) * nu)
          + s * sig * (-279 * d * kp / 56 - 817 * d / 56 + 279 * km / 56 + (-43 * d * kp / 4 - 43 * d / 2 + km / 2) * nu)
          + sig ** 2 * (279 * d * km / 112 - 279 * kp / 112 - 25 / 8 + (45 * d * km / 16 + 243 * kp / 112 + 344 / 21) * nu
                        + (43 * kp / 4 + 43 / 2) * nu ** 2))
    return {4: (E4, F4), 6: (E6, F6)}


@pytest.mark.parametrize("trial", range(6))
def test_averaged_spin_squared_reduces_to_aligned_form(trial):
    X1 = RNG.uniform(0.05, 0.95)
    c1, c2 = RNG.uniform(-1, 1, 2)
    k1, k2 = RNG.uniform(1, 10, 2)
    E = energy.energy_series(X1, k1, k2)
    F = flux.flux_series(X1, k1, k2)
    b = basis_values(c1, c2, c1 * c2, c1 * c1, c2 * c2)
    ref = _aligned_spin_squared(X1, c1, c2, k1, k2)
    for k, (e_ref, f_ref) in ref.items():
        e = np.dot(E[k, 3:, 0], b[3:])
        f = np.dot(F[k, 3:, 0], b[3:])
        assert e == pytest.approx(e_ref, rel=1e-12, abs=1e-12)
        assert f == pytest.approx(f_ref, rel=1e-12, abs=1e-12)


def test_lalsuite_flux_qm_typo_is_what_differs():
    """LALSuite's XLALSimInspiralPNFlux_6PNQMS1OS1OCoeffAvg has the constant 129/80; the aligned form
    (above) requires 129/8.  Show it: the (ℓ̂·χ₁)² coefficient at v⁶ with κ₁ = 1 equals the LAL closed
    form with 129/8, not with 129/80."""
    X1 = 0.6
    F = flux.flux_series(X1, 1.0, 1.0)
    ours = F[6, B_A1A1, 0] / X1 ** 4                      # per (ℓ̂·S₁)², S₁ = X₁²χ₁
    m = X1
    lal_self = -23.9 / (1.6 * m * m) + 2.93 / 1.44 / m + 2.99 / 1.44
    lal_qm_typo = -8.37 / (1.12 * m * m) - 13.5 / (1.6 * m) + 12.9 / 8.0
    lal_qm_fixed = -8.37 / (1.12 * m * m) - 13.5 / (1.6 * m) + 129.0 / 8.0
    assert ours == pytest.approx(lal_self + lal_qm_fixed, rel=1e-13)
    assert abs(ours - (lal_self + lal_qm_typo)) == pytest.approx(129 / 8 - 129 / 80, rel=1e-12)


@pytest.mark.parametrize("nu", [0.25, 0.1875, 0.0826, 0.01])
def test_taylor_t4_nonspinning_coefficients(nu):
    """Our series ratio F̂/Ê′ vs the TaylorT4 ω̇ coefficients of arXiv:0907.0700, Eq. (3.6)."""
    X1 = 0.5 * (1 + math.sqrt(1 - 4 * nu))
    kmax = kmax_from_orders(3.5, -1, -1)
    N, D, _ = vdot_series(X1, "T4", kmax)
    assert np.all(D[1:] == 0) and D[0, 0, 0] == 1.0
    pi2 = math.pi ** 2
    ref = {
        2: -(743 / 336 + 11 * nu / 4),
        3: 4 * math.pi,
        4: 34103 / 18144 + 13661 * nu / 2016 + 59 * nu ** 2 / 18,
        5: -(4159 / 672 + 189 * nu / 8) * math.pi,
        6: (16447322263 / 139708800 - 1712 * GAMMA / 105 + 16 * pi2 / 3 - 856 / 105 * math.log(16)
            + (-56198689 / 217728 + 451 * pi2 / 48) * nu + 541 * nu ** 2 / 896 - 5605 * nu ** 3 / 2592),
        7: (-4415 / 4032 + 358675 * nu / 6048 + 91495 * nu ** 2 / 1512) * math.pi,
    }
    assert N[0, B_ONE, 0] == 1.0 and N[1, B_ONE, 0] == 0.0
    for k, val in ref.items():
        assert N[k, B_ONE, 0] == pytest.approx(val, rel=1e-13), k
    assert N[6, B_ONE, 1] == pytest.approx(-1712 / 105, rel=1e-14)   # ln v
    assert np.all(N[8:] == 0)


@pytest.mark.parametrize("X1", [0.5, 0.75, 10 / 11, 0.2])
def test_taylor_t4_spin_coefficients(X1):
    """Spin-orbit (Marsat+ 2014 Eq. (4.10a)) and 2PN spin-spin (Racine+ 2009) TaylorT4 coefficients,
    closed forms per S₁ = X₁²χ₁ (as tabulated in LALSuite)."""
    X2 = 1 - X1
    nu = X1 * X2
    N, _, _ = vdot_series(X1, "T4", kmax_from_orders(3.5, 3.0, 2.0))
    m = X1
    # spin-orbit: coefficient of ℓ̂·S₁
    assert N[3, B_A1, 0] / m ** 2 == pytest.approx(-19 / 6 - 25 / (4 * m), rel=1e-13)
    assert N[5, B_A1, 0] / m ** 2 == pytest.approx(-809 / (84 * m) + 13795 / 1008 - 527 * m / 24 - 79 * m * m / 6,
                                                   rel=1e-13)
    assert N[6, B_A1, 0] / m ** 2 == pytest.approx(math.pi * (-37 / 3 - 151 / (6 * m)), rel=1e-13)
    assert np.all(N[7, B_A1:B_A2 + 1] == 0)        # 3.5PN spin-orbit truncated (so_order = 3)
    # 2PN spin-spin, orbit averaged (QM with κ = 1 plus self-spin)
    assert N[4, B_S12, 0] / (X1 * X2) ** 2 == pytest.approx(-247 / (48 * nu), rel=1e-13)
    assert N[4, B_A1A2, 0] / (X1 * X2) ** 2 == pytest.approx(721 / (48 * nu), rel=1e-13)
    assert N[4, B_S11, 0] / m ** 4 == pytest.approx(7 / (96 * m * m) - 2.5 / (m * m), rel=1e-13)
    assert N[4, B_A1A1, 0] / m ** 4 == pytest.approx(-1 / (96 * m * m) + 7.5 / (m * m), rel=1e-13)
    assert np.all(N[6, B_S12:] == 0)               # 3PN spin² truncated (ss_order = 2)


def test_series_division_inverts_multiplication():
    kmax = kmax_from_orders(4.5, 4.0, 3.0)
    D = series.new_series()
    N = series.new_series()
    D[0, 0, 0] = 1.0
    D[1:] = RNG.normal(size=D[1:].shape)
    N[:] = RNG.normal(size=N.shape)
    D[:, :, 1][:6] = 0.0   # logarithms only from v⁶ on, as in the PN series
    N[:, :, 1][:6] = 0.0
    series.truncate(D, kmax)
    series.truncate(N, kmax)
    Q = series.divide(N, D, kmax)
    back = series.multiply(Q, D, kmax)
    np.testing.assert_allclose(back, N, atol=1e-9)


def test_energy_derivative_matches_finite_difference():
    E = energy.energy_series(0.7, 2.0, 3.0)
    Ep = energy.energy_derivative_series(E)
    b = basis_values(0.3, -0.2, 0.1, 0.5, 0.4)
    nu = 0.7 * 0.3
    Efull = lambda v: -(nu * v * v / 2) * evaluate(E, v, b)       # noqa: E731
    for v in (0.1, 0.3, 0.45):
        h = 1e-5
        fd = (Efull(v + h) - Efull(v - h)) / (2 * h)
        assert -nu * v * evaluate(Ep, v, b) == pytest.approx(fd, rel=1e-8)


def test_spin_orbit_precession_matches_lalsuite_closed_forms():
    """Bohé+ 2013 Eq. (4.5) (LO, NLO, NNLO) vs the per-body closed forms tabulated in LALSuite."""
    for X in (0.2, 0.5, 0.8, 0.95):
        s0, s2, s4 = precession.spin_orbit_precession(X, 1 - X)
        assert s0 == pytest.approx(1.5 - X - X * X / 2, rel=1e-14)
        assert s2 == pytest.approx(9 / 8 - X / 2 + 7 * X ** 2 / 12 - 7 * X ** 3 / 6 - X ** 4 / 24, rel=1e-13)
        assert s4 == pytest.approx(X ** 6 / 48 - 3 * X ** 5 / 8 - 39 * X ** 4 / 16 - 23 * X ** 3 / 6
                                   + 181 * X ** 2 / 16 - 51 * X / 8 + 27 / 16, rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("trial", range(4))
def test_leading_order_orbital_precession_is_averaged_varpi(trial):
    """Ω_ℓ at LO equals ⟨ϖ n̂⟩ = ½ v⁶ (7 S⊥ + 3δ Σ⊥), Bohé+ 2013 Eqs. (4.1), (4.4) with ⟨(a·n̂)n̂⟩ = ½a⊥."""
    X1 = RNG.uniform(0.1, 0.9)
    X2 = 1 - X1
    v = RNG.uniform(0.1, 0.4)
    c1, c2 = RNG.normal(size=3) * 0.4, RNG.normal(size=3) * 0.4
    ell = RNG.normal(size=3)
    ell /= np.linalg.norm(ell)
    om = precession.orbital_precession_vector(v, c1, c2, ell, X1, so_order=1.5, ss_order=-1)
    S = X1 ** 2 * c1 + X2 ** 2 * c2
    Sig = X2 * c2 - X1 * c1
    perp = lambda a: a - np.dot(a, ell) * ell      # noqa: E731
    np.testing.assert_allclose(om, 0.5 * v ** 6 * (7 * perp(S) + 3 * (X1 - X2) * perp(Sig)), rtol=1e-12, atol=1e-20)


def _rotor_from_frame(ell, n):
    from pnrotor.pn.initial import frame_rotor
    return frame_rotor(ell, n)


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
@pytest.mark.parametrize("rotor", ["coprecessing", "orbital"])
def test_numba_rhs_matches_numpy_reference(approximant, rotor):
    X1 = 0.7
    k1, k2 = 1.5, 3.0
    so, ss = 3.5, 3.0
    kmax = kmax_from_orders(3.5, so, ss)
    p = system.make_parameters(X1, approximant, kmax, so_order=so, ss_order=ss, kappa1=k1, kappa2=k2,
                               rotor=rotor, phase_shift=True)
    ell = np.array([0.3, -0.2, 0.9])
    ell /= np.linalg.norm(ell)
    n = np.cross(ell, [1.0, 0.0, 0.0])
    n /= np.linalg.norm(n)
    R = _rotor_from_frame(ell, n) * 1.7            # unnormalized on purpose
    c1 = np.array([0.4, 0.3, -0.2])
    c2 = np.array([-0.1, 0.5, 0.6])
    v = 0.31
    y = np.concatenate(([v], c1, c2, R, [2.0]))
    dy = np.empty(12)
    rhs.rhs_precessing(0.0, y, p, dy)

    N, D, _ = vdot_series(X1, approximant, kmax, k1, k2)
    b = basis_values(ell @ c1, ell @ c2, c1 @ c2, c1 @ c1, c2 @ c2)
    vdot = 32 * X1 * (1 - X1) / 5 * v ** 9 * evaluate(N, v, b) / evaluate(D, v, b)
    assert dy[0] == pytest.approx(vdot, rel=1e-13)
    om1, om2 = precession.spin_precession_vectors(v, c1, c2, ell, X1, k1, k2, so, ss)
    np.testing.assert_allclose(dy[1:4], np.cross(om1, c1), rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(dy[4:7], np.cross(om2, c2), rtol=1e-12, atol=1e-18)
    w1, w2 = precession.phase_shift_weights(X1, 1 - X1)
    u = w1 * (c1 - (c1 @ ell) * ell) + w2 * (c2 - (c2 @ ell) * ell)
    phidot = v ** 3 - 0.25 * (u @ u) * v ** 9
    assert dy[11] == pytest.approx(phidot, rel=1e-14)
    Om = precession.orbital_precession_vector(v, c1, c2, ell, X1, k1, k2, so, ss)
    if rotor == "orbital":
        Om = Om + phidot * ell
    # dR/dt = ½ (0, Ω) R
    w, r = R[0], R[1:]
    expect = 0.5 * np.concatenate(([-Om @ r], w * Om + np.cross(Om, r)))
    np.testing.assert_allclose(dy[7:11], expect, rtol=1e-12, atol=1e-20)


def test_aligned_rhs_matches_precessing_rhs_for_aligned_spins():
    X1 = 0.75
    kmax = kmax_from_orders(3.5, 3.0, 3.0)
    c1, c2 = np.array([0, 0, 0.6]), np.array([0, 0, -0.3])
    b = basis_values(0.6, -0.3, -0.18, 0.36, 0.09)
    pa = system.make_parameters(X1, "T4", kmax, so_order=3.0, ss_order=3.0, aligned_basis=b)
    pp = system.make_parameters(X1, "T4", kmax, so_order=3.0, ss_order=3.0)
    ya = np.array([0.3, 1.0])
    yp = np.concatenate(([0.3], c1, c2, [1.0, 0, 0, 0], [1.0]))
    da, dp = np.empty(2), np.empty(12)
    rhs.rhs_aligned(0.0, ya, pa, da)
    rhs.rhs_precessing(0.0, yp, pp, dp)
    assert da[0] == pytest.approx(dp[0], rel=1e-14)
    assert da[1] == dp[11]
    assert np.all(dp[1:11] == 0.0)


def _omega_from_rdot(R, Rdot):
    """Ω with Ṙ = ½ (0, Ω) R: (0, Ω) = 2 Ṙ R⁻¹ = 2 Ṙ R̄ / |R|²."""
    w, x, y, z = R
    a, b, c, d = Rdot
    m = R @ R
    # vector part of Ṙ R̄
    vx = -a * x + b * w - c * z + d * y
    vy = -a * y + b * z + c * w - d * x
    vz = -a * z - b * y + c * x + d * w
    return 2.0 * np.array([vx, vy, vz]) / m


def test_instantaneous_precession_averages_to_averaged_model():
    """Averaged over the orbital phase, the instantaneous spin precession (n̂-dependent spin-spin terms)
    equals the orbit-averaged one, and the instantaneous frame velocity v³ℓ̂ + ϖn̂ averages to
    v³ℓ̂ + ⟨ϖn̂⟩ (the 'averaged_varpi' Ω_ℓ without the spin-spin torque)."""
    from pnrotor.pn.initial import frame_rotor
    X1, k1, k2 = 0.7, 2.0, 4.0
    kmax = kmax_from_orders(3.5, 3.5, 3.0)
    common = dict(so_order=3.5, ss_order=3.0, kappa1=k1, kappa2=k2)
    p_inst = system.make_parameters(X1, "T4", kmax, rotor="orbital", **common)
    p_avg = system.make_parameters(X1, "T4", kmax, rotor="coprecessing", omega_l="varpi", **common)
    p_so = system.make_parameters(X1, "T4", kmax_from_orders(3.5, 3.5, -1), rotor="coprecessing", omega_l="varpi",
                                  so_order=3.5, ss_order=-1, kappa1=k1, kappa2=k2)
    ell = np.array([0.2, 0.3, 0.9])
    ell /= np.linalg.norm(ell)
    n0 = np.cross(ell, [1.0, 0, 0])
    n0 /= np.linalg.norm(n0)
    R0 = frame_rotor(ell, n0)
    c1, c2 = np.array([0.4, -0.3, 0.2]), np.array([0.1, 0.5, -0.6])
    v = 0.33
    K = 64
    chidot = np.zeros(6)
    om = np.zeros(3)
    for j in range(K):
        phi = 2 * np.pi * j / K
        rot = np.array([np.cos(phi / 2), 0, 0, np.sin(phi / 2)])
        w, x, y, z = R0
        c, s = rot[0], rot[3]
        R = np.array([w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s])
        y_ = np.concatenate(([v], c1, c2, R, [phi]))
        dy = np.empty(12)
        rhs.rhs_precessing_instantaneous(0.0, y_, p_inst, dy)
        chidot += dy[1:7] / K
        om += _omega_from_rdot(R, dy[7:11]) / K
    ya = np.concatenate(([v], c1, c2, R0, [0.0]))
    da = np.empty(12)
    rhs.rhs_precessing(0.0, ya, p_avg, da)
    np.testing.assert_allclose(chidot, da[1:7], rtol=1e-12, atol=1e-16)
    ds = np.empty(12)
    rhs.rhs_precessing(0.0, ya, p_so, ds)
    om_so = _omega_from_rdot(R0, ds[7:11])
    np.testing.assert_allclose(om - v ** 3 * ell, om_so, rtol=1e-12, atol=1e-18)


@pytest.mark.parametrize("nu", [0.25, 0.1, 0.01])
def test_4pn_energy_matches_lalsuite_closed_form(nu):
    """Our 4PN binding-energy coefficient (Blanchet 2014 Eq. (233)) vs LALSuite's
    XLALSimInspiralPNEnergy_8PNCoeff / _8PNLogCoeff (arXiv:1305.4884; an independent transcription)."""
    e, elog = energy.nonspinning_energy_coefficients(nu)
    pi2 = math.pi ** 2
    lal = (-39.69 / 1.28 + (-123.671 / 5.76 + 9.037 / 1.536 * pi2 + 1792.0 / 15.0 * math.log(2) + 89.6 / 1.5 * GAMMA) * nu
           + (-498.449 / 3.456 + 31.57 / 5.76 * pi2) * nu ** 2 + 3.01 / 17.28 * nu ** 3 + 7.7 / 3110.4 * nu ** 4)
    assert e[8] == pytest.approx(lal, rel=1e-13)
    assert elog[8] == pytest.approx(896.0 / 15.0 * nu, rel=1e-15)


def test_test_mass_flux_matches_tagoshi_sasaki():
    """ν → 0 limit of the 4PN and 4.5PN flux: the black-hole-perturbation coefficients of Tagoshi &
    Sasaki 1994 (Prog. Theor. Phys. 92, 745), written with ln x = 2 ln v (the numbers as recalled from
    that paper, an independent check of the ν⁰ part of our transcription of arXiv:2304.11186)."""
    f, flog = flux.nonspinning_flux_coefficients(0.0)
    ln2, ln3 = math.log(2), math.log(3)
    assert f[8] == pytest.approx(-323105549467 / 3178375200 + 232597 * GAMMA / 4410 - 1369 * math.pi ** 2 / 126
                                 + 39931 * ln2 / 294 - 47385 * ln3 / 1568, rel=1e-13)
    assert flog[8] == pytest.approx(232597 / 4410, rel=1e-15)
    assert f[9] == pytest.approx(math.pi * (265978667519 / 745113600 - 6848 * GAMMA / 105 - 13696 * ln2 / 105), rel=1e-13)
    assert flog[9] == pytest.approx(-6848 * math.pi / 105, rel=1e-15)


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
def test_spin_independent_parts_of_a_population_are_bitwise_those_of_each_binary(approximant):
    """evolve_many builds the mass-ratio parts of p for many binaries in one pass of numpy; each row must be
    bitwise what one binary's Python floats give (a power written x ** k would differ: numpy's is not libm's
    pow on CPUs with AVX-512), else evolve_many and evolve would part."""
    rng = np.random.default_rng(11)
    X1 = rng.uniform(0.5, 0.995, 400)
    k1, k2 = rng.uniform(1.0, 20.0, 400), rng.uniform(1.0, 20.0, 400)
    kmax = kmax_from_orders(3.5, 3.5, 3.0)
    for rotor, shift, omega_l in (("coprecessing", True, "torque"), ("orbital", False, "varpi")):
        many = system.spin_independent_parts(X1, k1, k2, approximant, kmax, 3.5, 3.0, rotor, shift, omega_l)
        for i in range(0, 400, 7):
            one = system.spin_independent_parts(float(X1[i]), float(k1[i]), float(k2[i]), approximant, kmax, 3.5,
                                                3.0, rotor, shift, omega_l)
            for a, b in zip(one, many):
                np.testing.assert_array_equal(a[0], b[i])


@pytest.mark.parametrize("spins", ["precessing", "aligned"])
def test_the_start_rows_of_a_population_are_bitwise_those_of_each_binary(spins):
    """evolve_many builds the parameter vectors and start checks of a whole population in one call of
    system.start_rows (evolve.build_rows), evolve those of its one binary by make_parameters and earlier_end
    (evolve.build_system): each row must be bitwise the other's (p, y0, the spin invariants, the start checks),
    whatever the order of the rows taken from the spin-independent parts."""
    from pnrotor.pn.evolve import OPTIONS, build_rows, build_system, population_parts
    from pnrotor.pn.settings import Checked, population_settings, settings
    rng = np.random.default_rng(12)
    n = 40
    m1, m2 = rng.uniform(5.0, 40.0, n), rng.uniform(1.0, 20.0, n)
    c1, c2 = rng.uniform(-0.5, 0.5, (n, 3)), rng.uniform(-0.5, 0.5, (n, 3))
    ell = np.array([0.6, 0.0, 0.8])
    if spins == "aligned":
        c1, c2 = c1[:, 2:] * ell, c2[:, 2:] * ell
    options = {**OPTIONS, "sampling": "final", "kappa1": 4.0, "kappa2": 2.0, "ell_hat": ell, "n_hat": (0.0, 1.0, 0.0)}
    ss = [settings(m1[i], m2[i], c1[i], c2[i], 20.0, **{**options, "f_max": 200.0 + i}) for i in range(n)]
    assert {s.spin_content for s in ss} == {spins}
    order = rng.permutation(n)             # row i from row order[i] of the parts
    X1 = np.empty(n)
    X1[order] = [s.X1 for s in ss]
    parts = population_parts(ss[0], X1, np.full(n, 4.0), np.full(n, 2.0))
    o = Checked(*(getattr(ss[0], name) for name in Checked._fields))
    rows = population_settings(o, m1, m2, c1, c2, np.full(n, 20.0), np.full(n, np.nan), 200.0 + np.arange(n),
                               np.tile(ell, (n, 1)), np.tile([0.0, 1.0, 0.0], (n, 1)), np.full(n, 4.0), np.full(n, 2.0))
    assert rows.valid.all()
    rhs, events, P, Y0, bases, checks = build_rows(o, rows, parts, order)
    assert Y0.shape[1] == (2 if spins == "aligned" else 12) and np.all(checks[:, :4] > 0.0)
    for i, s in enumerate(ss):
        one = build_system(s)
        assert (one.rhs, one.events) == (rhs, events)
        for a, b in ((one.p, P[i]), (one.y0, Y0[i]), (one.basis, bases[i])):
            np.testing.assert_array_equal(a, b)
        p, at_v0 = system.make_parameters(
            s.X1, s.approximant, one.kmax, so_order=s.spin_orbit_order, ss_order=s.spin_spin_order, kappa1=4.0,
            kappa2=2.0, v_end=s.v_max, spin_tol=layout.spin_tolerance(s.atol, s.rtol),
            phase_shift=s.precession_phase_shift, aligned_basis=bases[i] if spins == "aligned" else None,
            basis=bases[i], v_check=s.v0)
        np.testing.assert_array_equal(checks[i], [*at_v0, ends.earlier_end(*events.addresses, one.y0, p)])


def test_a_population_member_past_the_end_of_its_inspiral_gets_evolves_message():
    """build_rows' start checks refuse what build_system refuses (f_ref past the end of the inspiral, found at v0 or
    below it), with its message, and leave the others of the population."""
    from pnrotor.pn import evolve, evolve_many
    f_ref = [20.0, 1000.0, 600.0, 30.0]
    pop = evolve_many(30.0, 10.0, [0, 0, 0.5], [0, 0, -0.3], f_ref)
    assert pop.termination.tolist() == ["energy_balance", "invalid", "invalid", "energy_balance"]
    for i in (1, 2):
        with pytest.raises(ValueError) as refusal:
            evolve(30.0, 10.0, [0, 0, 0.5], [0, 0, -0.3], f_ref[i])
        assert pop.message[i] == str(refusal.value) and "past the end" in pop.message[i]
