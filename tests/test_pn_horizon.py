"""The flux into black-hole horizons (``horizon_absorption=True``, pnrotor.pn.flux.horizon_rates): its test-mass limit
against black-hole perturbation theory, its comparable-mass nonspinning form against Nagar & Akcay 2012's, Alvi 2001's
tilted-horizon rates as a sum over the tidal field's harmonics, the orbit average against that sum averaged
numerically, the Schwarzschild limit at any tilt, the area theorem and superradiance; a run's energy balance, spins,
masses and ℓ̂ against those rates; evolve_many, batch tables and the CLI with the option; default runs bitwise as
before it."""

import math

import numpy as np
import pytest

from pnrotor import batch, hdf5
from pnrotor.cli import main
from pnrotor.pn import evolve, evolve_many, layout, rhs, system
from pnrotor.pn.energy import energy_series
from pnrotor.pn.flux import flux_series, horizon_rates
from pnrotor.pn.series import basis_values, evaluate, kmax_from_orders, truncate


def coefficients(X, a, chi_sq):
    """(c₅, c₈) of F̂_H = c₅v⁵ + c₈v⁸, from F̂_H and v ∂F̂_H/∂v at v = 1."""
    f, f_v, _, _ = horizon_rates(X, 0.25, 1.0, a, chi_sq)
    return (8 * f - f_v) / 3, (f_v - 5 * f) / 3


def mode_weights(chi):
    """A_m, m = 0, 1, 2: Teukolsky & Press's low-frequency ∏ₙ₌₁² (n²κ² + m²χ²)/4 (κ² = 1 − χ²)."""
    k2 = 1 - chi * chi
    return [(k2 + m * m * chi * chi) * (4 * k2 + m * m * chi * chi) / 4 for m in range(3)]


def harmonics(n, n_dot):
    """α_m = √(4π/15) Y₂ₘ(n̂) and their time derivatives for n̂ = ``n`` moving at ``n_dot``, in the frame whose z is the
    spin axis, m = −2 … 2."""
    (x, y, z), (xd, yd, zd) = n, n_dot
    w, wd = complex(x, y), complex(xd, yd)
    r2, r3 = math.sqrt(2), math.sqrt(3)
    alpha = {2: w * w / (2 * r2), 1: -z * w / r2, 0: (3 * z * z - 1) / (2 * r3)}
    dot = {2: w * wd / r2, 1: -(zd * w + z * wd) / r2, 0: 3 * z * zd / r3}
    for m in (1, 2):   # Y₂,₋ₘ = (−1)ᵐ Y₂ₘ*
        alpha[-m], dot[-m] = (-1) ** m * alpha[m].conjugate(), (-1) ** m * dot[m].conjugate()
    return alpha, dot


def mode_sum(X, nu, v, chi, n, n_dot):
    """(dm/dt, dS/dt) of the horizon at one instant, unaveraged: Σₘ C A_|m| [|α̇ₘ|² − mΩ_H Im(α̇ₘ αₘ*)] and
    Σₘ C A_|m| [m Im(α̇ₘ αₘ*) − m²Ω_H |αₘ|²], C = (16/5)ν²v¹²X⁴(1 + κ), Ω_H = χ/(2X(1 + κ)): each harmonic rotating
    at ω = Im(α̇ₘ αₘ*)/|αₘ|² absorbs ω(ω − mΩ_H) (Alvi 2001, Eq. (21), mode by mode)."""
    kappa = math.sqrt(1 - chi * chi)
    C, omega_h = 3.2 * nu * nu * v ** 12 * X ** 4 * (1 + kappa), chi / (2 * X * (1 + kappa))
    A = mode_weights(chi)
    alpha, dot = harmonics(n, n_dot)
    mdot = sdot = 0.0
    for m in range(-2, 3):
        rate = (dot[m] * alpha[m].conjugate()).imag
        mdot += C * A[abs(m)] * (abs(dot[m]) ** 2 - m * omega_h * rate)
        sdot += C * A[abs(m)] * (m * rate - m * m * omega_h * abs(alpha[m]) ** 2)
    return mdot, sdot


@pytest.mark.parametrize("q", [-0.9, -0.3, 0.0, 0.5, 0.9, 0.99])
def test_test_mass_limit_is_black_hole_perturbation_theory(q):
    """X → 1: a particle on a circular equatorial orbit of a Kerr black hole of spin q.  The v⁵ term is Tagoshi, Mano &
    Takasugi 1997's leading horizon flux −(1/4)(q + 3q³) (gr-qc/9711072); without spin the leading term is v⁸ with
    coefficient 1, Poisson & Sasaki 1995's Schwarzschild result (gr-qc/9412027); the small body (X → 0) absorbs
    nothing."""
    c5, c8 = coefficients(1.0, q, q * q)
    assert c5 == pytest.approx(-0.25 * (q + 3 * q ** 3), rel=1e-14, abs=1e-16)
    if q == 0.0:
        assert (c5, c8) == (0.0, 1.0)
    assert coefficients(0.0, q, q * q) == (0.0, 0.0)


@pytest.mark.parametrize("X1", [0.5, 0.75, 10 / 11])
def test_nonspinning_comparable_masses_are_nagar_and_akcay(X1):
    """Two nonspinning holes absorb (1 − 4ν + 2ν²) v⁸ of the Newtonian flux at leading order (Nagar & Akcay 2012,
    arXiv:1112.2840, the (2,2) horizon flux)."""
    nu = X1 * (1 - X1)
    total = coefficients(X1, 0.0, 0.0)[1] + coefficients(1 - X1, 0.0, 0.0)[1]
    assert total == pytest.approx(1 - 4 * nu + 2 * nu * nu, rel=1e-14, abs=0)


@pytest.mark.parametrize("chi", [0.3, 0.9, 0.999])
def test_alvi_tilted_horizon_is_the_sum_over_harmonics(chi):
    """With the companion at a fixed polar angle θ from the spin and turning about it at φ̇, Alvi 2001's Eq. (10) and
    (21), dm/dt = φ̇ I₀ (φ̇ − Ω_H), dS/dt = I₀ (φ̇ − Ω_H) with I₀ = C sin²θ (1 − ¾χ² + (15/4)χ² sin²θ) as
    PostNewtonian.jl writes it, equal the sum over harmonics of :func:`mode_sum` with Teukolsky & Press's m-weights
    (the weights pnrotor's orbit average takes, m = 0 included)."""
    X, nu, v, phidot = 0.7, 0.21, 0.35, 0.03
    kappa = math.sqrt(1 - chi * chi)
    C, omega_h = 3.2 * nu * nu * v ** 12 * X ** 4 * (1 + kappa), chi / (2 * X * (1 + kappa))
    for theta in np.linspace(0.1, math.pi - 0.1, 7):
        for phi in (0.0, 1.3):
            n = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
            n_dot = phidot * np.cross([0.0, 0.0, 1.0], n)
            s2 = math.sin(theta) ** 2
            I0 = C * s2 * (1 - 0.75 * chi * chi + 3.75 * chi * chi * s2)
            mdot, sdot = mode_sum(X, nu, v, chi, n, n_dot)
            assert mdot == pytest.approx(phidot * I0 * (phidot - omega_h), rel=1e-13, abs=0)
            assert sdot == pytest.approx(I0 * (phidot - omega_h), rel=1e-13, abs=0)


@pytest.mark.parametrize("X", [0.2, 0.9])
@pytest.mark.parametrize("chi", [0.3, 0.9, 0.999])
@pytest.mark.parametrize("iota", [0.0, 0.5, 1.2, math.pi / 2, 2.3, math.pi])
def test_orbit_average_is_the_mean_of_the_unaveraged_sum(X, chi, iota):
    """horizon_rates' dm/dt, dS/dt for a spin tilted by ι from ℓ̂ equal the mean of :func:`mode_sum` over 64 points of
    one circular orbit (n̂ turning about ℓ̂ at Ω = v³, so θ changes too): exact for the field's harmonics, which are
    trigonometric polynomials of degree ≤ 4 in the orbital phase; F̂_H is dm/dt over (32/5)ν²v¹⁰."""
    nu, v = X * (1 - X), 0.3
    ell = np.array([math.sin(iota), 0.0, math.cos(iota)])   # the spin along z
    e1 = np.array([math.cos(iota), 0.0, -math.sin(iota)])
    e2 = np.cross(ell, e1)
    sums = np.zeros(2)
    for phase in 2 * np.pi * np.arange(64) / 64:
        n = math.cos(phase) * e1 + math.sin(phase) * e2
        sums += mode_sum(X, nu, v, chi, n, v ** 3 * np.cross(ell, n))
    mdot, sdot = sums / 64
    f, _, s, m = horizon_rates(X, nu, v, chi * math.cos(iota), chi * chi)
    assert m == pytest.approx(mdot, rel=1e-12, abs=0) and s == pytest.approx(sdot, rel=1e-12, abs=0)
    assert f == pytest.approx(m / (6.4 * nu * nu * v ** 10), rel=1e-14, abs=0)


@pytest.mark.parametrize("iota", [0.0, 0.7, math.pi / 2, 2.5, math.pi])
def test_a_hole_of_vanishing_spin_absorbs_the_same_at_any_tilt(iota):
    """A Schwarzschild hole has no axis: dm/dt = (16/45) m⁶ ⟨Ė_ab Ė^ab⟩ (Poisson 2004, gr-qc/0407050) with
    E_ab = (m₂/b³)(δ_ab − 3n_a n_b) is (32/5) m₁⁶ m₂² v¹⁸, F̂_H = X⁴v⁸, whichever way a spin of 1e-9 points
    (Alvi's rigid rotation about the spin, evaluated at each instant, would average to |cos ι| of it)."""
    X, v = 0.6, 0.4
    f = horizon_rates(X, X * (1 - X), v, 1e-9 * math.cos(iota), 1e-18)[0]
    assert f == pytest.approx(X ** 4 * v ** 8, rel=1e-8, abs=0)


def test_area_theorem_and_superradiance():
    """Over random holes, tilts and v: dm − Ω_H dS ≥ 0 (the horizon's area never decreases: dm = Ω_H dS + (κ/8π) dA),
    and where the horizon turns faster than the orbit (Ω_H > Ω = v³) the spin's magnitude falls, dS/dt < 0; with the
    spin along ℓ̂ the hole then gives energy to the orbit (dm/dt < 0, superradiance)."""
    rng = np.random.default_rng(33)
    faster = 0
    for X, chi, c, v in zip(rng.uniform(0.05, 0.95, 2000), rng.uniform(0, 1, 2000), rng.uniform(-1, 1, 2000),
                            rng.uniform(0.05, 0.6, 2000)):
        kappa = math.sqrt(1 - chi * chi)
        omega_h = chi / (2 * X * (1 + kappa))
        _, _, s, m = horizon_rates(X, X * (1 - X), v, chi * c, chi * chi)
        assert m - omega_h * s >= -1e-15 * abs(m)
        if omega_h > v ** 3:
            faster += 1
            assert s < 0
            assert horizon_rates(X, X * (1 - X), v, chi, chi * chi)[3] < 0
    assert faster > 1000


# --------------------------------------------------------------------------------------------------
# runs
# --------------------------------------------------------------------------------------------------

TILTED = (50.0, 5.0, (0.9 * math.sin(math.pi / 3), 0.0, 0.9 * math.cos(math.pi / 3)), (0.2, -0.1, -0.3), 20.0)
"""q = 10, χ₁ = 0.9 tilted 60° from ℓ̂, χ₂ precessing too."""


@pytest.fixture(scope="module")
def tilted_run():
    return evolve(*TILTED, f_max=120.0, approximant="T1", pn_order=3.5, spin_orbit_order=3.5, spin_spin_order=3.0,
                  sampling=("per_orbit", 128), horizon_absorption=True)


def test_energy_balance_takes_the_horizon_flux(tilted_run):
    """T1 evaluates v̇ = (32ν/5) v⁹ (F̂ + F̂_H)/Ê′ as it is: a precessing run's v̇, from 128 samples per orbit (a
    second-order difference), equals that formula evaluated here in numpy at each sample's spins and ℓ̂, to a small
    part of the horizon flux's own share of v̇ there (0.02–0.26%); without the horizon flux it misses by that share."""
    run = tilted_run
    X1 = 50.0 / 55.0
    nu = X1 * (1 - X1)
    kmax = kmax_from_orders(3.5, 3.5, 3.0)
    F, E = truncate(flux_series(X1), kmax), truncate(energy_series(X1), kmax)
    a1, a2 = (np.einsum("ij,ij->i", c, run.ell_hat) for c in (run.chi1, run.chi2))
    s11, s22 = (np.einsum("ij,ij->i", c, c) for c in (run.chi1, run.chi2))
    b = basis_values(a1, a2, np.einsum("ij,ij->i", run.chi1, run.chi2), s11, s22)
    v = run.v
    Fv = np.array([evaluate(F, v[i], b[:, i]) for i in range(v.size)])
    Ep = np.array([sum(0.5 * (k + 2) * E[k, :, 0] @ b[:, i] * v[i] ** k
                       + 0.5 * ((k + 2) * math.log(v[i]) + 1) * (E[k, :, 1] @ b[:, i]) * v[i] ** k
                       for k in range(E.shape[0])) for i in range(v.size)])
    H = np.array([horizon_rates(X1, nu, v[i], a1[i], s11[i])[0] + horizon_rates(1 - X1, nu, v[i], a2[i], s22[i])[0]
                  for i in range(v.size)])
    vdot = np.gradient(run.v, run.t, edge_order=2)[2:-2]
    with_h, without = (32 * nu / 5 * v ** 9 * (Fv + h) / Ep for h in (H, 0.0))
    with_h, without = with_h[2:-2], without[2:-2]
    share = np.abs(with_h / without - 1)
    assert share.min() > 2e-4
    assert np.all(np.abs(vdot / with_h - 1) < 0.05 * share)
    assert np.all(np.abs(vdot / without - 1) > 0.5 * share)


def test_spins_and_masses_follow_the_rates(tilted_run):
    """Along the precessing run: each |χᵢ| changes at (dS/dt)/Xᵢ² − 2|χᵢ|(dm/dt)/Xᵢ of horizon_rates at the sample's
    state (the precession keeps |χᵢ|), from a second-order difference; each mass's change over the run, in stats, is
    the integral of dm/dt over the samples (trapezoids); the larger hole spins down and loses mass (Ω_H > Ω)."""
    run = tilted_run
    X1 = 50.0 / 55.0
    nu = X1 * (1 - X1)
    for chi, X, key in ((run.chi1, X1, "m1"), (run.chi2, 1 - X1, "m2")):
        size = np.linalg.norm(chi, axis=1)
        a = np.einsum("ij,ij->i", chi, run.ell_hat)
        rates = np.array([horizon_rates(X, nu, v, ai, si * si)[2:] for v, ai, si in zip(run.v, a, size)])
        expected = rates[:, 0] / X ** 2 - 2 * size * rates[:, 1] / X
        got = np.gradient(size, run.t, edge_order=2)
        assert np.max(np.abs(got - expected)[2:-2]) < 2e-3 * np.max(np.abs(expected))
        absorbed = np.sum(0.5 * (rates[1:, 1] + rates[:-1, 1]) * np.diff(run.t)) * 55.0
        assert run.stats[f"{key}_final_Msun"] - 55.0 * X == pytest.approx(absorbed, rel=1e-3, abs=0)
        assert run.stats[f"{key}_initial_Msun"] == 55.0 * X
    assert np.all(np.diff(np.linalg.norm(run.chi1, axis=1)) < 0) and run.stats["m1_final_Msun"] < 50.0


def test_the_orbit_gives_the_angular_momentum_the_horizons_take():
    """The precessing right-hand side, with horizon absorption: |L| dℓ̂/dt = −Σᵢ (dSᵢ/dt)⊥ (perpendicular to ℓ̂), with
    dSᵢ/dt = Xᵢ² dχᵢ/dt + 2Xᵢ (dmᵢ/dt) χᵢ the spins' own change (precession and absorption; the mass term rescales
    χᵢ and moves no angular momentum): J = |L|ℓ̂ + S₁ + S₂ keeps its direction, the orbit giving what the horizons
    absorb, to rounding of the absorbed torque's perpendicular part."""
    X1, v = 0.8, 0.45
    p = system.make_parameters(X1, "T4", kmax_from_orders(3.5, 3.5, 3.0), so_order=3.5, ss_order=3.0, horizon=True)
    chi1, chi2 = np.array([0.5, 0.3, 0.6]), np.array([-0.2, 0.4, 0.1])
    R = np.array([math.cos(0.2), math.sin(0.2) * 0.6, math.sin(0.2) * 0.8, 0.0])
    y = np.array([v, *chi1, *chi2, *R, 0.3, X1, 1 - X1])
    dy = np.empty_like(y)
    rhs.rhs_precessing(0.0, y, p, dy)
    w, x, yy, z = R
    ell = np.array([2 * (x * z + w * yy), 2 * (yy * z - w * x), w * w - x * x - yy * yy + z * z])
    q = dy[7:11]   # ω = 2 Ṙ R⁻¹ (vector part), dℓ̂/dt = ω × ℓ̂
    omega = 2 * np.array([-q[0] * x + q[1] * w - q[2] * z + q[3] * yy, -q[0] * yy + q[1] * z + q[2] * w - q[3] * x,
                          -q[0] * z - q[1] * yy + q[2] * x + q[3] * w])
    L = X1 * (1 - X1) / v * (1 + v * v * (p[layout.P_L] + v * v * p[layout.P_L + 1]))
    sdot = sum(X * X * dy[i:i + 3] + 2 * X * dy[j] * c for X, i, j, c in ((X1, 1, 12, chi1), (1 - X1, 4, 13, chi2)))
    total = L * np.cross(omega, ell) + sdot
    torque = sum(horizon_rates(X, X1 * (1 - X1), v, c @ ell, c @ c)[2] * c / np.linalg.norm(c)
                 for X, c in ((X1, chi1), (1 - X1, chi2)))
    perp = lambda u: u - (u @ ell) * ell  # noqa: E731
    assert np.linalg.norm(perp(torque)) > 1e-9
    assert np.linalg.norm(perp(total)) < 1e-6 * np.linalg.norm(perp(torque))


def test_aligned_spins_stay_aligned_and_the_dephasing_has_its_sign():
    """A hole spinning along ℓ̂ gives energy to the orbit (F_H < 0 at leading order): more orbits to the same
    frequency; against ℓ̂ it takes energy: fewer; in T1, T4 (F̂_H added to the numerator of v̇) and T5 (subtracted
    from its denominator) alike.  Aligned spins (and a nonspinning hole, spun up along ℓ̂) stay exactly along ℓ̂, ℓ̂
    stays put, and the run is on the precessing state."""
    kw = dict(sampling="final", f_max=200.0)
    for approximant in ("T1", "T4", "T5"):
        gain = {a: np.diff([evolve(50.0, 5.0, (0, 0, a), (0, 0, 0), 20.0, horizon_absorption=h, approximant=approximant,
                                   **kw).Phi[-1] for h in (False, True)])[0] for a in (0.9, -0.9)}
        assert gain[0.9] > 0.1 and gain[-0.9] < -0.1, approximant
    run = evolve(50.0, 5.0, (0, 0, 0.9), (0, 0, 0), 20.0, horizon_absorption=True, f_max=200.0)
    assert run.inputs["horizon_absorption"] is True and run.inputs["state"] == "precessing"
    assert np.all(run.chi1[:, :2] == 0) and np.all(run.chi2[:, :2] == 0) and np.all(run.ell_hat[:, :2] == 0)
    assert np.all(np.abs(run.ell_hat[:, 2] - 1) < 1e-15)   # ℓ̂ of the rotor, normalized
    assert 0 < run.chi2[-1, 2] < 1e-5 and run.chi1[-1, 2] < 0.9


def test_a_neutron_star_has_no_horizon():
    """An NSBH (Λ₂ = 600) with the option: the star's mass is exactly its initial one and its spin's magnitude changes
    only by the integration's error (~5e-12, as without the option), while the hole's change; the same binary with
    Λ₂ = 0 (two holes) has the small body absorb too (|χ₂| −1e-6)."""
    chi2 = (0.1, 0.0, 0.05)
    kw = dict(f_max=300.0, sampling="final", horizon_absorption=True)
    star = evolve(8.0, 1.4, (0.4, 0.0, 0.5), chi2, 30.0, lambda2=600.0, **kw)
    hole = evolve(8.0, 1.4, (0.4, 0.0, 0.5), chi2, 30.0, **kw)
    assert star.stats["m2_final_Msun"] == star.stats["m2_initial_Msun"] == 1.4
    assert abs(np.linalg.norm(star.chi2[-1]) - np.linalg.norm(chi2)) < 1e-10   # the integration's: ~5e-12
    assert hole.stats["m2_final_Msun"] != 1.4 and abs(np.linalg.norm(hole.chi2[-1]) - np.linalg.norm(chi2)) > 1e-7
    for run in (star, hole):
        assert run.stats["m1_final_Msun"] < 8.0 and np.linalg.norm(run.chi1[-1]) < math.hypot(0.4, 0.5)


def test_bad_input_names_the_option(capsys, tmp_path):
    with pytest.raises(ValueError, match="horizon_absorption must be True or False, got 'yes'"):
        evolve(50.0, 5.0, (0, 0, 0.8), (0, 0, 0), 20.0, horizon_absorption="yes")
    with pytest.raises(ValueError, match="horizon_absorption must be True or False, got 1"):
        evolve_many([50.0], [5.0], (0, 0, 0.8), (0, 0, 0), 20.0, horizon_absorption=1)
    with pytest.raises(ValueError, match="horizon_absorption needs the orbit-averaged precession"):
        evolve(50.0, 5.0, (0, 0, 0.8), (0, 0, 0), 20.0, horizon_absorption=True, precession="instantaneous")
    code = main(["evolve", "--m1", "50", "--m2", "5", "--f-ref", "20", "--horizon-absorption", "--precession",
                 "instantaneous", "-o", str(tmp_path / "x.h5")])
    out, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and "horizon_absorption needs" in err
    assert not (tmp_path / "x.h5").exists()
    path = tmp_path / "bad.csv"
    path.write_text("m1,m2,chi1,chi2,f_ref,horizon_absorption\n50,5,\"0,0,0.5\",\"0,0,0\",20,maybe\n")
    row, = batch.read_batch(path, {})
    assert row.error == "horizon_absorption must be true or false (or 1, 0), got 'maybe'"


# --------------------------------------------------------------------------------------------------
# evolve_many, batch tables, the CLI
# --------------------------------------------------------------------------------------------------

BINARIES = dict(m1=[50.0, 30.0, 12.0], m2=[5.0, 10.0, 12.0], chi1=[(0, 0, 0.9), TILTED[2], (0, 0, 0)],
                chi2=[(0, 0, 0), (0.2, -0.1, -0.3), (0, 0, 0)], f_ref=[30.0, 40.0, 60.0])


def test_evolve_many_and_population_tables_are_single_runs_bitwise(tmp_path):
    """evolve_many(…, horizon_absorption=True) gives bitwise each binary's evolve(…, sampling='final'), nonspinning,
    aligned and precessing alike, and so does a DataFrame with the column; a population table's horizon_absorption
    column selects it per row (one call per value), each row's state that of evolve, in chunks whose rows differ in
    it (the chunks' files are joined with the column stored per row)."""
    import pandas

    pop = evolve_many(**BINARIES, horizon_absorption=True)
    frame = evolve_many(pandas.DataFrame({**BINARIES, "horizon_absorption": True}))
    assert pop.inputs["horizon_absorption"] is True and frame.inputs["horizon_absorption"] is True
    rows = list(zip(*BINARIES.values()))
    for i, (m1, m2, c1, c2, f) in enumerate(rows):
        one = evolve(m1, m2, c1, c2, f, sampling="final", horizon_absorption=True)
        for name in ("t", "v", "Phi", "chi1", "chi2", "R", "ell_hat"):
            assert np.array_equal(getattr(pop, name)[i], getattr(one, name)[-1]), name
            assert np.array_equal(getattr(frame, name)[i], getattr(one, name)[-1]), name
    table = tmp_path / "rows.csv"
    table.write_text("m1,m2,chi1,chi2,f_ref,horizon_absorption\n" + "".join(
        f"{m1},{m2},\"{','.join(map(str, c1))}\",\"{','.join(map(str, c2))}\",{f},{h}\n"
        for (m1, m2, c1, c2, f), h in zip(rows, ("true", "0", "True"))))
    from pnrotor.batch import population

    population.run(table, tmp_path / "pop.h5", chunk=2)
    back = hdf5.read(tmp_path / "pop.h5")
    assert back.inputs["horizon_absorption"].tolist() == [True, False, True]
    for i, ((m1, m2, c1, c2, f), h) in enumerate(zip(rows, (True, False, True))):
        one = evolve(m1, m2, c1, c2, f, sampling="final", horizon_absorption=h)
        assert np.array_equal(back.chi1[i], one.chi1[-1]) and np.array_equal(back.Phi[i], one.Phi[-1])


def test_cli_option_writes_the_run_of_evolve(tmp_path, capsys):
    """--horizon-absorption: the file holds evolve(…, horizon_absorption=True)'s run bitwise (but wall times), the
    summary names the option and the masses at both ends, and the default name says 'horizon'."""
    code = main(["evolve", "--m1", "50", "--m2", "5", "--chi1", "0,0,0.9", "--f-ref", "60", "--f-min", "50",
                 "--horizon-absorption", "-o", str(tmp_path / "h.h5")])
    out, _ = capsys.readouterr()
    assert code == 0
    run = hdf5.read(tmp_path / "h.h5")
    direct = evolve(50.0, 5.0, (0, 0, 0.9), (0, 0, 0), 60.0, f_min=50.0, horizon_absorption=True)
    for name in ("t", "v", "Phi", "chi1", "chi2", "R"):
        assert np.array_equal(getattr(run, name), getattr(direct, name)), name
    s = direct.stats
    assert {k: s[k] for k in s if "Msun" in k} == {k: run.stats[k] for k in run.stats if "Msun" in k}
    assert s["m1_initial_Msun"] > 50.0 > s["m1_final_Msun"]   # at f_min before f_ref: more mass, it is given away
    assert ", horizon absorption\n" in out
    assert (f"  masses         m1 {s['m1_initial_Msun']:.9g} -> {s['m1_final_Msun']:.9g} Msun, m2 "
            f"{s['m2_initial_Msun']:.9g} -> {s['m2_final_Msun']:.9g} Msun (the horizons' absorption)") in out
    params = dict(m1=50.0, m2=5.0, chi1=(0, 0, 0.9), chi2=(0, 0, 0), f_ref=60.0, **batch.DEFAULTS)
    assert batch.default_name({**params, "horizon_absorption": True}).endswith("_horizon")
    assert "horizon" not in batch.default_name(params)
