"""Physics of pnrotor.pn.evolve: invariants, the quadrupole chirp, total angular momentum, reversibility,
termination and output sampling.  Measured values are quoted in the comments (lalsuite-free)."""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from pnrotor.pn import evolve
from pnrotor.pn.initial import MTSUN_SI

Z = np.array([0.0, 0.0, 1.0])


def _angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


# --------------------------------------------------------------------------------------------------
# invariants
# --------------------------------------------------------------------------------------------------

def test_solar_mass_in_seconds_is_astropy_s_and_lalsuite_s():
    """MTSUN_SI, written out in pnrotor.pn.initial, is astropy's GM☉/c³ exactly and LALSuite's to 1 ulp."""
    from astropy import constants as const
    lal = pytest.importorskip("lal")
    assert MTSUN_SI == float((const.GM_sun / const.c ** 3).si.value)
    assert abs(MTSUN_SI - lal.MTSUN_SI) <= np.spacing(MTSUN_SI)


def test_quantities_are_converted_like_floats_in_solar_masses_and_hertz():
    """Masses and frequencies as astropy Quantities give the same run as floats in M☉ and Hz."""
    import astropy.units as u
    a = evolve(30.0, 10.0, [0.1, 0.2, 0.3], [0.0, 0.0, 0.0], 20.0, sampling="final")
    b = evolve(30.0 * u.M_sun, (10.0 * u.M_sun).to(u.kg), [0.1, 0.2, 0.3], [0.0, 0.0, 0.0], 0.02 * u.kHz,
               sampling="final")
    np.testing.assert_allclose(b.R, a.R, rtol=0, atol=1e-9)
    assert b.inputs["m1_Msun"] == 30.0 and b.inputs["f_ref_Hz"] == 20.0
    assert b.inputs["m2_Msun"] == pytest.approx(10.0, rel=1e-14)


@pytest.mark.parametrize("chi1,chi2", [([0, 0, 0], [0, 0, 0]), ([0, 0, 0.9], [0, 0, -0.5])])
def test_aligned_runs_keep_ell_fixed(chi1, chi2):
    """Through the *precessing* state (integrate_rotor=True) ℓ̂ stays ẑ to 1e-12 (measured 4.4e-16)
    and the spins do not move; the aligned state [v, Φ] gives the same v, Φ, R (measured 5e-11)."""
    e = evolve(30, 10, chi1, chi2, 20.0, f_min=12.0, integrate_rotor=True, sampling=1 / 4096)
    assert e.inputs["state"] == "precessing"
    assert np.max(np.abs(e.ell_hat - Z)) < 1e-12
    assert np.max(np.abs(e.chi1 - chi1)) == 0.0 and np.max(np.abs(e.chi2 - chi2)) == 0.0
    a = evolve(30, 10, chi1, chi2, 20.0, f_min=12.0, sampling=1 / 4096)
    assert a.inputs["state"] == "aligned"
    assert np.all(a.ell_hat == np.broadcast_to(Z, a.ell_hat.shape)) or np.max(np.abs(a.ell_hat - Z)) < 1e-15
    n = min(len(a), len(e))
    assert len(a) == len(e)
    assert np.max(np.abs(a.Phi[:n] - e.Phi[:n])) < 1e-9
    assert np.max(np.abs(a.R[:n] - e.R[:n])) < 1e-9


@pytest.mark.parametrize("sampling", ["steps", "final", 1 / 4096, ("per_orbit", 3)])
def test_aligned_runs_give_constant_spins_and_ell_as_views(tmp_path, sampling):
    """An aligned run's χ₁, χ₂, ℓ̂ are read-only (N, 3) views of one row: ℓ̂ equals R ẑ R⁻¹ of every sample (an
    independent formula, to rounding), the spins are (χᵢ·ℓ̂)ℓ̂ of the inputs, evolve_many's final state has the same
    rows bitwise, and an HDF5 round trip gives them back."""
    from pnrotor import hdf5
    from pnrotor.pn import evolve_many

    ell = np.array([0.6, 0.0, 0.8])
    n = np.array([0.8, 0.0, -0.6])
    chi1, chi2 = 0.5 * ell, -0.3 * ell
    run = evolve(30, 10, chi1, chi2, 20.0, f_min=15.0, ell_hat=ell, n_hat=n, sampling=sampling)
    assert run.inputs["state"] == "aligned"
    N = len(run)
    for x in (run.chi1, run.chi2, run.ell_hat):
        assert x.shape == (N, 3) and not x.flags.writeable
    w, x, y, z = run.R.T
    from_R = np.column_stack((2 * (x * z + w * y), 2 * (y * z - w * x), w * w - x * x - y * y + z * z))
    assert np.max(np.abs(from_R - run.ell_hat)) < 1e-15
    np.testing.assert_allclose(run.chi1, np.broadcast_to(np.dot(chi1, ell) * ell, (N, 3)), rtol=0, atol=1e-16)
    np.testing.assert_allclose(run.chi2, np.broadcast_to(np.dot(chi2, ell) * ell, (N, 3)), rtol=0, atol=1e-16)
    if sampling == "final":
        many = evolve_many([30.0], [10.0], [chi1], [chi2], [20.0], ell_hat=ell, n_hat=n)
        for a, b in ((many.chi1, run.chi1), (many.chi2, run.chi2), (many.ell_hat, run.ell_hat)):
            np.testing.assert_array_equal(a, b)
    hdf5.write(tmp_path / "run.h5", run)
    back = hdf5.read(tmp_path / "run.h5")
    for a, b in ((back.chi1, run.chi1), (back.chi2, run.chi2), (back.ell_hat, run.ell_hat)):
        np.testing.assert_array_equal(a, b)


def test_spin_magnitudes_conserved():
    """Near-extremal precessing spins: | |χᵢ(t)| − |χᵢ(0)| | < 1e-10 (measured 1.2e-13, 2.1e-12)."""
    c1, c2 = np.array([0.7, 0.0, 0.7]), np.array([0.0, 0.99, 0.0])
    e = evolve(30, 10, c1, c2, 20.0, f_min=10.0)
    assert np.max(np.abs(np.linalg.norm(e.chi1, axis=1) - np.linalg.norm(c1))) < 1e-10
    assert np.max(np.abs(np.linalg.norm(e.chi2, axis=1) - 0.99)) < 1e-10
    assert np.max(np.abs(np.linalg.norm(e.R, axis=1) - 1.0)) < 1e-14


def test_leading_order_chirp_is_the_quadrupole_formula():
    """pn_order = 0: v(t) = (v₀⁻⁸ − 256νt/5)^(−1/8), Φ(v) = −(v⁻⁵ − v₀⁻⁵)/(32ν), and the time between
    two frequencies is τ(f₁) − τ(f₂) with τ = (5/256) M (πMf)^(−8/3)/ν (measured 2e-13, 1e-12 rad,
    6e-14 s)."""
    nu = 0.25
    e = evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, f_min=10.0, f_max=200.0, pn_order=0)
    v0 = e.inputs["v_ref"]
    vt = (v0 ** -8 - 256 * nu / 5 * e.t) ** (-1 / 8)
    assert np.max(np.abs(e.v / vt - 1)) < 1e-11
    assert np.max(np.abs(e.Phi + (e.v ** -5 - v0 ** -5) / (32 * nu))) < 1e-9
    M = 20 * MTSUN_SI
    tau = lambda f: 5 / 256 * M * (math.pi * M * f) ** (-8 / 3) / nu   # noqa: E731
    assert e.t_seconds[-1] - e.t_seconds[0] == pytest.approx(tau(10.0) - tau(200.0), rel=1e-12)
    assert e.termination == "f_max" and e.stats["termination_backward"] == "f_min"
    assert e.f_gw[0] == pytest.approx(10.0, rel=1e-12) and e.f_gw[-1] == pytest.approx(200.0, rel=1e-12)


@pytest.mark.parametrize("m1,m2,chi1,chi2,max_drift", [
    (30.0, 10.0, [0.6, 0.0, 0.3], [0.0, 0.0, 0.0], 0.02),      # measured 0.0124 rad
    (10.0, 10.0, [0.5, 0.2, 0.3], [0.5, 0.2, 0.3], 0.01),      # measured 0.0055 rad
])
def test_total_angular_momentum_direction_simple_precession(m1, m2, chi1, chi2, max_drift):
    """Simple precession (spin-orbit only), 10 → 100 Hz: ℓ̂ swings by 0.36–0.63 rad about Ĵ, while Ĵ
    (J = |L|ℓ̂ + S₁ + S₂, |L| as in the model) moves only 0.006–0.012 rad — and that drift is exactly
    radiation reaction along ℓ̂: J(t) = J(0) + ∫ d|L|/dt ℓ̂ dt to 1.4e-7 rad (quadrature-limited)."""
    e = evolve(m1, m2, chi1, chi2, 20.0, f_min=10.0, f_max=100.0, sampling=1 / 4096, spin_spin_order=-1)
    X1 = m1 / (m1 + m2)
    X2 = 1 - X1
    nu = X1 * X2
    v = e.v
    L = nu / v * (1 + (1.5 + nu / 6) * v ** 2 + (27 / 8 - 19 * nu / 8 + nu ** 2 / 24) * v ** 4)
    J = L[:, None] * e.ell_hat + X1 ** 2 * e.chi1 + X2 ** 2 * e.chi2
    Jh = J / np.linalg.norm(J, axis=1)[:, None]
    drift = _angle(Jh, Jh[0]).max()
    swing = _angle(e.ell_hat, e.ell_hat[0]).max()
    assert drift < max_drift
    assert swing > 20 * drift
    Jp = J[0] + cumulative_simpson(np.gradient(L, e.t, edge_order=2)[:, None] * e.ell_hat, x=e.t, axis=0,
                                   initial=0)
    assert _angle(Jh, Jp / np.linalg.norm(Jp, axis=1)[:, None]).max() < 1e-6


def test_forward_then_backward_returns_to_start():
    """15 → 60 Hz forward, then from the final state back to 15 Hz: spins, ℓ̂, n̂ return to 2e-12,
    Φ and t to 1e-12 and 6e-11 M."""
    c1, c2 = [0.5, 0.1, 0.3], [0.0, 0.4, -0.2]
    e1 = evolve(30, 10, c1, c2, 15.0, f_max=60.0, sampling="final")
    assert e1.termination == "f_max" and len(e1) == 1
    e2 = evolve(30, 10, e1.chi1[-1], e1.chi2[-1], e1.f_gw[-1], f_min=15.0, ell_hat=e1.ell_hat[-1],
                n_hat=e1.n_hat[-1])
    assert e2.stats["termination_backward"] == "f_min"
    assert e2.f_gw[0] == pytest.approx(15.0, rel=1e-13)
    np.testing.assert_allclose(e2.chi1[0], c1, atol=1e-10)
    np.testing.assert_allclose(e2.chi2[0], c2, atol=1e-10)
    np.testing.assert_allclose(e2.ell_hat[0], Z, atol=1e-10)
    np.testing.assert_allclose(e2.n_hat[0], [1, 0, 0], atol=1e-10)
    assert abs(e2.Phi[0] + e1.Phi[-1]) < 1e-9
    assert abs(e2.t[0] + e1.t[-1]) < 1e-8 * abs(e1.t[-1])


def test_coprecessing_and_orbital_rotor_agree():
    """The two rotor formulations (R_p with R = R_p e^{Φẑ/2}, or the full orbital R) give the same
    frame: n̂ to 1e-7 over ~60 orbits (the orbital one integrates the orbital motion itself)."""
    kw = dict(f_max=80.0, sampling=1 / 2048)
    a = evolve(30, 10, [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], 20.0, rotor="coprecessing", **kw)
    b = evolve(30, 10, [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], 20.0, rotor="orbital", **kw)
    assert len(a) == len(b)
    assert np.max(_angle(a.n_hat, b.n_hat)) < 1e-7
    assert np.max(_angle(a.ell_hat, b.ell_hat)) < 1e-8
    assert np.max(np.abs(a.chi1 - b.chi1)) < 1e-8
    assert b.stats["naccepted"] > 2 * a.stats["naccepted"]


# --------------------------------------------------------------------------------------------------
# termination
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("approximant,reason", [("T4", "energy_balance"), ("T1", "energy_balance"),
                                                ("T5", "vdot_divergent")])
def test_termination_reasons(approximant, reason):
    e = evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, approximant=approximant)
    assert e.termination == reason
    assert e.stats["termination_backward"] == "not_integrated"
    assert e.stats["termination_message"]


def test_termination_v_max_and_step_limit():
    e = evolve(30, 10, [0, 0, 0.9], [0, 0, -0.5], 20.0)     # T4 with these spins keeps E' > 0 up to v = 1
    assert e.termination == "v_max" and e.v[-1] == pytest.approx(1.0, abs=1e-10)
    e = evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, max_steps=5)
    assert e.termination == "max_steps"


def test_termination_spin_magnitude_event():
    """The |χ| > 1 event fires when |χ|² exceeds 1 + 1e-10 (fed here through the event function)."""
    from pnrotor.pn import layout, rhs, system
    from pnrotor.pn.series import kmax_from_orders
    p = system.make_parameters(0.5, "T4", kmax_from_orders(3.5, 3, 3), so_order=3.0, ss_order=3.0)
    g = np.empty(layout.N_EVENTS)
    y = np.concatenate(([0.3], [0, 0, 1 + 1e-9], [0, 0, 0.5], [1, 0, 0, 0], [0]))
    rhs.events_precessing(0.0, y, p, g)
    assert g[layout.EV_SPIN1] < 0 < g[layout.EV_SPIN2]


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
def test_vdot_peak_event_is_the_v_derivative_of_omega_dot(approximant):
    """Event 6 is v⁻¹⁰ D² ∂(v²v̇)/∂v/(32ν/5) at fixed spins and ℓ̂ (ω̇ = 3v²v̇/M, LAL's d²ω/dt² test):
    checked against a central difference of v²v̇ from the right-hand side, for a precessing state and for
    the aligned (folded) one."""
    from pnrotor.pn import layout, rhs, system
    from pnrotor.pn.vdot import vdot_series
    from pnrotor.pn.series import basis_values, eval_at, kmax_from_orders
    X1, v = 0.7, 0.35
    kmax = kmax_from_orders(3.5, 3.5, 3)
    c1, c2 = np.array([0.3, -0.4, 0.5]), np.array([0.0, 0.2, -0.6])
    y = np.concatenate(([v], c1, c2, [0.9, 0.1, -0.3, 0.2], [0.0]))
    y[7:11] /= np.linalg.norm(y[7:11])
    ell = np.array(rhs._ell_hat(*y[7:11]))
    bvals = basis_values(ell @ c1, ell @ c2, c1 @ c2, c1 @ c1, c2 @ c2)
    N, D, _ = vdot_series(X1, approximant, kmax)
    for aligned in (False, True):
        p = system.make_parameters(X1, approximant, kmax, so_order=3.5, ss_order=3.0,
                                   aligned_basis=bvals if aligned else None)
        f, events, state = ((rhs.rhs_aligned, rhs.events_aligned, np.array([v, 0.0])) if aligned
                            else (rhs.rhs_precessing, rhs.events_precessing, y))

        def vdot(x):
            s, d = state.copy(), np.empty(state.size)
            s[0] = x
            f(0.0, s, p, d)
            return x * x * d[0]

        h = 1e-5
        fd = (vdot(v + h) - vdot(v - h)) / (2 * h)
        g = np.empty(layout.N_EVENTS)
        events(0.0, state, p, g)
        expected = fd * eval_at(D, v, bvals) ** 2 / (v ** 10 * p[layout.P_VDOT0])
        assert g[layout.EV_VDOT_PEAK] == pytest.approx(expected, rel=1e-7)


def test_right_hand_sides_and_events_cannot_raise():
    """Compiled with error_model='numpy', so evolve may pass them by address (an exception would be lost
    there): at v = 0 and with R = 0 they give inf/nan, which the integrator reports as 'nonfinite', where
    the default error model raises ZeroDivisionError."""
    from pnrotor.pn import layout, rhs, system
    from pnrotor.pn.series import kmax_from_orders
    p = system.make_parameters(0.5, "T1", kmax_from_orders(3.5, 3, 3), so_order=3.0, ss_order=3.0)
    cases = ((rhs.rhs_aligned, rhs.events_aligned, np.array([0.0, 0.0])),
             (rhs.rhs_precessing, rhs.events_precessing, np.concatenate(([0.0], [0.1] * 6, [0.0] * 4, [0.0]))),
             (rhs.rhs_precessing_instantaneous, None, np.concatenate(([0.3], [0.1] * 6, [0.0] * 4, [0.0]))))
    for f, events, y in cases:
        d = np.empty(y.size)
        f(0.0, y, p, d)
        assert not np.all(np.isfinite(d))
        if events is not None:
            g = np.empty(layout.N_EVENTS)
            events(0.0, y, p, g)
            assert not np.all(np.isfinite(g))


def test_invalid_inputs():
    with pytest.raises(ValueError):
        evolve(10, 10, [0, 0, 1.2], [0, 0, 0], 20.0)
    with pytest.raises(ValueError):
        evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, f_min=30.0)
    with pytest.raises(ValueError):
        evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, ell_hat=(0, 0, 1), n_hat=(0, 0.5, 0.8))
    with pytest.raises(ValueError):
        evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, approximant="T3")
    with pytest.raises(ValueError):
        evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, pn_order=3.2)
    with pytest.raises(ValueError):
        evolve(10, 10, [0, 0, 0], [0, 0, 0], 2000.0)           # beyond the end of the T4 inspiral


@pytest.mark.parametrize("atol", [1e-6, 1e-10])
def test_maximal_spins_are_not_ended_by_the_tolerance(atol):
    """|χᵢ| = 1 is allowed and conserved by the equations; the integration's drift of a few atol made a fixed
    1e-10 margin end such runs as 'spin_magnitude' (at atol 1e-6 forward at 21 Hz instead of 197 Hz)."""
    run = evolve(30.0, 10.0, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 20.0, f_min=10.0, atol=atol)
    assert run.termination == "energy_balance" and run.stats["termination_backward"] == "f_min"
    assert run.f_gw[-1] > 190.0


@pytest.mark.parametrize("approximant, atol, sampling", [("T1", 1e-3, "steps"), ("T4", 1000.0, "steps"),
                                                        ("T4", 1000.0, 1 / 4096)])
def test_loose_tolerances_never_give_non_finite_samples(approximant, atol, sampling):
    """A step accepted just before a terminal event can have stages of its interpolant past it, where the
    right-hand side diverges: the event's state came out NaN (with termination energy_balance) until such a
    step was rejected as a non-finite one is."""
    chi = ((0.6, 0.0, 0.2), (0.0, -0.4, 0.1)) if approximant == "T1" else ((0, 0, 0), (0, 0, 0))
    run = evolve(30.0, 10.0, *chi, 20.0 if approximant == "T1" else 100.0, approximant=approximant, atol=atol,
                 sampling=sampling)
    assert run.termination == "energy_balance"
    for name in ("t", "v", "Phi", "chi1", "chi2", "R", "ell_hat"):
        assert np.all(np.isfinite(getattr(run, name))), name


def test_astropy_quantities():
    from astropy import units as u
    a = evolve(10 * u.M_sun, 1.98847e31 * u.kg, [0, 0, 0], [0, 0, 0], 0.02 * u.kHz, sampling=0.5 * u.ms)
    b = evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, sampling=5e-4)
    assert a.inputs["m2_Msun"] == pytest.approx(10.0, rel=1e-4)
    assert a.inputs["f_ref_Hz"] == 20.0 and a.inputs["sampling_value"] == 5e-4
    assert len(a) == len(b)
    for kw, name in ((dict(m1=10 * u.s), "m1"), (dict(f_ref=20 * u.m), "f_ref")):
        with pytest.raises(ValueError, match=f"{name} must be a finite positive .*not convertible"):
            evolve(**{**dict(m1=10, m2=10, chi1=[0, 0, 0], chi2=[0, 0, 0], f_ref=20.0), **kw})


# --------------------------------------------------------------------------------------------------
# sampling
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("forward", [True, False])
def test_per_orbit_times_are_the_roots_of_the_interpolated_phase(forward):
    """pnrotor.pn.sampling._phase_times (Newton in θ on each segment's polynomial, compiled) against scipy's brentq on
    the DenseOutput's Φ(t), target by target, on a precessing run's forward and backward halves: the same times to
    brentq's accuracy (~1e-15); a target at a step boundary gives that boundary, one rounded past the end the end itself."""
    from scipy.optimize import brentq

    from pnrotor.pn.evolve import OPTIONS, build_system, integrate_half
    from pnrotor.pn.sampling import _phase_times
    from pnrotor.pn.settings import settings

    s = settings(30.0, 10.0, (0.5, 0.1, 0.3), (0.0, 0.4, -0.2), 20.0, **{**OPTIONS, "f_min": 10.0})
    res, _ = integrate_half(s, build_system(s), forward, None, True)
    d, i = res.dense, 11
    phi = lambda t: d(t)[i]   # noqa: E731
    end = res.y[-1, i]
    targets = np.linspace(0.0, end, 97)[1:-1]
    boundary = d.coef[5, 0, i]   # Φ where the sixth step starts
    targets = np.sort(np.append(targets, boundary))[:: 1 if forward else -1]
    t = _phase_times(d, i, targets)
    lo, hi = sorted((d.t_min, d.t_max))
    for tq, target in zip(t, targets):
        root = brentq(lambda x: phi(x) - target, lo, hi, xtol=1e-300, rtol=9e-16)
        assert abs(tq - root) <= 2e-15 * abs(root), (target, tq, root)
    assert t[np.flatnonzero(targets == boundary)[0]] == d.seg_t[5]
    assert np.all(np.diff(t) * d.direction > 0)
    past = _phase_times(d, i, np.array([end + 1e-9 * d.direction * abs(end)]))
    assert past[0] == d.t_max


def test_per_orbit_runs_use_the_one_compiled_root_finder():
    """The per-orbit kernel compiled ahead by compile_output_kernel (beside the DOP853 core, on a cold cache) has
    the types every run gives it: precessing and aligned, forward and backward, one compiled signature."""
    from pnrotor.pn.sampling import _phase_roots

    for args in ((30, 10, [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], 100.0), (1.4, 1.4, [0, 0, 0.1], [0, 0, 0], 300.0)):
        evolve(*args, f_min=0.8 * args[4], sampling=("per_orbit", 3))
    assert len(_phase_roots.signatures) == 1


@pytest.mark.parametrize("sampling", [1 / 4096, ("per_orbit", 4)])
def test_a_half_without_a_step_samples_as_steps_does(sampling):
    """A run whose integration takes no step (a step underflow at once) gives its one state at t = 0 under uniform
    and per-orbit sampling as under 'steps' (it raised AttributeError: no dense output); a forward half without a
    step beside a backward half with steps gives the backward samples and the initial state, as when the forward
    half had steps."""
    import dataclasses

    from pnrotor.pn.evolve import OPTIONS, build_system, integrate_half
    from pnrotor.pn.sampling import sample
    from pnrotor.pn.settings import settings

    args = (1.4, 1.4, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], 30.0)
    for kw in ({}, {"f_min": 25.0}):
        steps = evolve(*args, atol=1e-200, **kw)
        run = evolve(*args, atol=1e-200, sampling=sampling, **kw)
        assert len(run) == len(steps) == 1 and run.termination == "step_underflow"
        for name in ("t", "v", "Phi", "chi1", "chi2", "R", "ell_hat"):
            np.testing.assert_array_equal(getattr(run, name), getattr(steps, name))
    s = settings(30.0, 10.0, (0.5, 0.1, 0.3), (0.0, 0.4, -0.2), 100.0,
                 **{**OPTIONS, "f_min": 70.0, "sampling": sampling})
    system = build_system(s)
    backward, _ = integrate_half(s, system, False, None, True)
    forward, _ = integrate_half(s, system, True, None, True)
    stuck, _ = integrate_half(dataclasses.replace(s, atol=1e-200), system, True, None, True)
    assert stuck.dense is None and backward.dense is not None
    t_all, rows_all = sample(s, forward, backward)
    t, rows = sample(s, stuck, backward)
    assert t[-1] == 0.0 and len(t) > 2
    np.testing.assert_array_equal(t, t_all[:len(t)])
    for got, full in zip(rows, rows_all):
        np.testing.assert_array_equal(got, full[:len(t)])


def test_sampling_modes_agree():
    args = (30, 10, [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], 20.0)
    kw = dict(f_min=15.0)
    steps = evolve(*args, **kw)
    dt = 1 / 4096
    uni = evolve(*args, sampling=("dt", dt), **kw)
    orb = evolve(*args, sampling={"per_orbit": 16}, **kw)
    fin = evolve(*args, sampling="final", **kw)
    # every mode has the same shapes
    for e in (steps, uni, orb, fin):
        assert e.chi1.shape == (len(e), 3) and e.R.shape == (len(e), 4) and e.ell_hat.shape == (len(e), 3)
        assert np.all(np.diff(e.t) > 0) if len(e) > 1 else True
    # the uniform grid is k Δt with t = 0 at f_ref, ascending, inside the integrated interval
    k = np.round(uni.t_seconds / dt)
    np.testing.assert_allclose(uni.t_seconds, k * dt, rtol=0, atol=1e-12)
    assert np.all(np.diff(k) == 1) and 0 in k
    i0 = int(np.nonzero(k == 0)[0][0])
    assert uni.v[i0] == steps.inputs["v_ref"] and uni.Phi[i0] == 0.0
    assert steps.t[0] <= uni.t[0] < steps.t[0] + dt / steps.inputs["M_seconds"]
    # per-orbit samples sit at Φ = 2πj/16
    j = orb.Phi / (2 * np.pi / 16)
    np.testing.assert_allclose(j, np.round(j), atol=1e-9)
    assert np.all(np.diff(np.round(j)) == 1)
    # same end state in every mode
    for e in (uni, orb):
        assert e.t[-1] <= steps.t[-1]
    assert fin.t[0] == steps.t[-1]
    np.testing.assert_array_equal(fin.R[0], steps.R[-1])
    np.testing.assert_array_equal(fin.chi1[0], steps.chi1[-1])
    # the dense output between steps agrees with a finer integration
    fine = evolve(*args, atol=1e-14, sampling=("dt", dt), **kw)
    assert len(fine) == len(uni)
    assert np.max(np.abs(fine.Phi - uni.Phi)) < 1e-7
    assert np.max(_angle(fine.ell_hat, uni.ell_hat)) < 1e-9


def test_rotor_is_unit_sign_continuous_and_consistent():
    e = evolve(30, 10, [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], 20.0, f_min=15.0, sampling=1 / 4096)
    np.testing.assert_allclose(np.linalg.norm(e.R, axis=1), 1.0, atol=1e-15)
    assert np.min(np.sum(e.R[1:] * e.R[:-1], axis=1)) > 0.9     # no sign flips between samples
    # n̂ at t = 0 is the input, and n̂ ⟂ ℓ̂ everywhere
    i0 = int(np.argmin(np.abs(e.t)))
    np.testing.assert_allclose(e.n_hat[i0], [1, 0, 0], atol=1e-15)
    assert np.max(np.abs(np.sum(e.n_hat * e.ell_hat, axis=1))) < 1e-14
    # n̂ rotates about ℓ̂ at Φ̇: the angle between successive n̂ ≈ ΔΦ
    dPhi = np.diff(e.Phi)
    ang = _angle(e.n_hat[1:], e.n_hat[:-1])
    np.testing.assert_allclose(ang, dPhi, rtol=1e-2)   # (precession of the plane adds a little)


def test_instantaneous_precession_is_the_averaged_one_plus_nutation():
    """precession='instantaneous' (Ω = v³ℓ̂ + ϖn̂, Bohé+ 2013) against 'averaged_varpi' (Ω_ℓ = ⟨ϖn̂⟩),
    spin-orbit only: ℓ̂ nutates about the averaged one at twice the orbital frequency with amplitude
    ϖ_max/(4ω); as both start from the same ℓ̂ the difference reaches ϖ_max/(2ω) = v³|Σ wᵢχᵢ⊥|/2 early
    on (measured 0.0062 rad vs 0.0067 predicted for this q = 3 case).  Spin magnitudes stay constant."""
    from pnrotor.pn.precession import varpi_coefficients
    args = (30, 10, [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], 20.0)
    kw = dict(sampling=1 / 4096, f_max=25.0, spin_spin_order=-1, spin_orbit_order=1.5)
    a = evolve(*args, precession="averaged_varpi", precession_phase_shift=False, **kw)
    b = evolve(*args, precession="instantaneous", **kw)
    assert b.inputs["rotor"] == "orbital" and b.stats["naccepted"] > 3 * a.stats["naccepted"]
    v0 = a.inputs["v_ref"]
    w1 = varpi_coefficients(0.75, 0.25)[0]
    w2 = varpi_coefficients(0.25, 0.75)[0]
    perp = lambda c: np.asarray(c) - np.dot(c, Z) * Z      # noqa: E731
    predicted = v0 ** 3 * np.linalg.norm(w1 * perp(args[2]) + w2 * perp(args[3])) / 2
    measured = _angle(a.ell_hat[:2000], b.ell_hat[:2000]).max()
    assert 0.7 * predicted < measured < 1.3 * predicted
    assert np.max(np.abs(np.linalg.norm(b.chi1, axis=1) - np.linalg.norm(args[2]))) < 1e-10


@pytest.mark.parametrize("block", ["small", "near pi/2 multiples", "large", "beyond the reduction"])
def test_half_angle_cos_sin_is_within_an_ulp_of_the_exact_values(block):
    """The sampling kernel's cos(Φ/2), sin(Φ/2) (fdlibm's reduction and polynomials, vectorized) against mpmath
    at 120 bits, block by block as the kernel takes them: within 1.2e-16 (an ulp of values in [0.5, 1); libm is
    within 5.6e-17, ours 1.10e-16 seen).  The last block holds a Φ beyond the reduction's range (libm's path)."""
    import mpmath

    from pnrotor.pn.sampling import _BLOCK, _REDUCTION_LIMIT, _half_angle_cos_sin
    rng = np.random.default_rng(7)
    ph = {"small": np.concatenate(([0.0, -0.0, 5e-324, 1e-300], rng.uniform(-1e-3, 1e-3, 28),
                                   rng.uniform(-10.0, 10.0, 32))),
          "near pi/2 multiples": np.arange(-32, 32) * math.pi + rng.choice([-1, 0, 1], 64) * 1e-12,
          "large": rng.uniform(-2.0, 2.0, _BLOCK) * 0.999 * _REDUCTION_LIMIT,
          "beyond the reduction": np.concatenate(([2.0 * _REDUCTION_LIMIT], rng.uniform(-1e4, 1e4, 63)))}[block]
    cs = np.empty((2, _BLOCK))
    _half_angle_cos_sin(ph, cs, ph.size)
    with mpmath.workprec(120):
        exact = np.array([[float(f(mpmath.mpf(float(x)) / 2)) for x in ph] for f in (mpmath.cos, mpmath.sin)])
    assert np.max(np.abs(cs[:, :ph.size] - exact)) <= 1.2e-16


def test_output_kernel_matches_the_integrators_dense_output():
    """The sampling kernel's dense evaluation equals pnrotor.ode's DenseOutput at the same times."""
    from pnrotor.ode import dop853
    from pnrotor.pn import sampling as ev
    from pnrotor.pn import rhs, system
    from pnrotor.pn.series import kmax_from_orders
    p = system.make_parameters(0.75, "T4", kmax_from_orders(3.5, 3, 3), so_order=3.0, ss_order=3.0)
    y0 = np.concatenate(([0.25], [0.5, 0.1, 0.3], [0.0, 0.4, -0.2], [1.0, 0.0, 0.0, 0.0], [0.0]))
    r = dop853(rhs.rhs_precessing, 0.0, y0, 3000.0, 1e-12, args=p, dense=True)
    tq = np.linspace(0.0, 3000.0, 777)
    hist = ev.allocate_history(tq.size)
    ev.fill_history(ev.MODE_ORBITAL, r.dense.seg_t, r.dense.seg_h, r.dense.coef, tq, False, ev.NO_Y,
                     np.array([1.0, 0, 0, 0]), Z, np.zeros(3), np.zeros(3), 0, *hist)
    Y = r.dense(tq)
    # equal up to the rounding of fused multiply-adds (the ODE kernel contracts, ours need not) and, for
    # R, of two ways of normalizing (a few ulp of 1: 2 ulp seen)
    np.testing.assert_allclose(hist[0], Y[:, 0], rtol=1e-15, atol=0)
    np.testing.assert_allclose(hist[1], Y[:, 11], rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(hist[2], Y[:, 1:4], rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(hist[4], Y[:, 7:11] / np.linalg.norm(Y[:, 7:11], axis=1)[:, None], rtol=0, atol=5e-16)


def test_tolerance_convergence_is_not_floored_by_round_off():
    """A BNS from 40 Hz to 400 Hz (~5000 rad of phase): runs at atol 1e-14 and 5e-16 agree in the frame at
    400 Hz to 9e-13 rad (angle of R_a R_b⁻¹ from its vector part).  Without DOP853's compensated summation
    the round-off of Φ ~ 5e3 at every step left them 3.0e-11 apart (measured)."""
    args = (1.4, 1.4, [0.02, 0.01, 0.03], [0.0, -0.03, 0.02], 40.0)
    a, b = (evolve(*args, f_max=400.0, atol=atol, sampling="final") for atol in (1e-14, 5e-16))
    w1, v1, w2, v2 = a.R[-1, 0], a.R[-1, 1:], b.R[-1, 0], b.R[-1, 1:]
    vec = w2 * v1 - w1 * v2 - np.cross(v1, v2)    # vector part of R_a R_b⁻¹ (unit rotors)
    assert a.Phi[-1] > 4000.0
    assert 2.0 * math.asin(np.linalg.norm(vec)) < 1e-11
