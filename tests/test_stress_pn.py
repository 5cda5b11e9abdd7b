"""pnrotor.evolve at its physical extremes (benchmarks/stress_pn.py measures them; these guard them):
extreme mass ratios and spins, the up-down configuration, the end of the PN inspiral as a starting
point, the memory of sampling='final', and random binaries (hypothesis).

Every run is checked by :func:`check`: finite outputs, a documented termination name (module docstring
of pnrotor.pn.evolve), |χᵢ| conserved, R unit and finite, v increasing."""

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pnrotor import evolve
from pnrotor.pn.initial import MTSUN_SI

Z = np.array([0.0, 0.0, 1.0])
# the termination names of a forward run without f_max that reaches a physical end (pnrotor.pn.evolve)
PHYSICAL_ENDS = {"v_max", "energy_balance", "vdot_nonpositive", "vdot_divergent", "vdot_peak"}


def _angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def check(e, chi1, chi2, spin_tol=1e-10):
    """The invariants of every run; returns e."""
    for a in (e.t, e.t_seconds, e.v, e.Phi, e.chi1, e.chi2, e.R, e.ell_hat):
        assert np.all(np.isfinite(a))
    assert e.termination in PHYSICAL_ENDS | {"f_max"}
    for x, c in ((e.chi1, chi1), (e.chi2, chi2)):
        assert np.max(np.abs(np.linalg.norm(x, axis=1) - np.linalg.norm(c))) < spin_tol
    assert np.max(np.abs(np.linalg.norm(e.R, axis=1) - 1.0)) < 1e-14
    assert np.all(np.diff(e.v) > 0) and np.all(np.diff(e.t) > 0)
    return e


# --------------------------------------------------------------------------------------------------
# the end of the inspiral as a starting point
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("approximant", ["T1", "T5"])
@pytest.mark.parametrize("past", [1e-9, 1e-6, 1e-4])
def test_start_between_pole_guard_and_pole(approximant, past):
    """T1/T5 stop where the denominator of v̇ falls to 1e-3, before its pole.  Restarting just past that
    frequency used to integrate into the pole (~110 steps, half rejected): T5 then reported
    'vdot_nonpositive' and T1 a v that decreased.  Now: a ValueError naming f_ref."""
    e = evolve(30, 30, [0, 0, 0], [0, 0, 0], 20.0, approximant=approximant, sampling="final")
    assert e.termination == ("energy_balance" if approximant == "T1" else "vdot_divergent")
    with pytest.raises(ValueError, match="f_ref"):
        evolve(30, 30, [0, 0, 0], [0, 0, 0], e.f_gw[-1] * (1 + past), approximant=approximant)


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
@pytest.mark.parametrize("chi", [[0, 0, 0], [0.6, 0.0, 0.3], [0, 0, -0.99]])
@pytest.mark.parametrize("f_ref", [300.0, 500.0, 1000.0])
def test_f_ref_beyond_the_inspiral_is_a_value_error(approximant, chi, f_ref):
    """30 + 30 M☉: the inspiral ends near 50–185 Hz (measured), so these f_ref are all past it.  The error
    gives the bound (pnrotor.pn.ends.inspiral_end, a grid and bisection of the series in numpy); for
    nonspinning and aligned spins it is where the integrated run from 20 Hz ends (events located by DOP853),
    and just below it a run starts."""
    with pytest.raises(ValueError, match="f_ref") as info:
        evolve(30, 30, chi, [0, 0, 0], f_ref, approximant=approximant)
    bound = float(re.search(r"f_ref must be below (\S+) Hz", str(info.value)).group(1))
    end = evolve(30, 30, chi, [0, 0, 0], 20.0, approximant=approximant, sampling="final")
    if chi[0] == 0.0:
        assert bound == pytest.approx(end.f_gw[-1], rel=1e-5)
    check(evolve(30, 30, chi, [0, 0, 0], bound * (1 - 1e-5), approximant=approximant, sampling="final"), chi, [0, 0, 0])


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
def test_restart_just_before_the_end(approximant):
    """From the end state of a precessing run, restarted at 1 − 1e-6 of its end frequency: the same
    termination within a few steps (measured 1–9), or a ValueError naming f_ref (never a crash)."""
    c1, c2 = [0.6, 0.0, 0.3], [-0.3, 0.5, 0.1]
    e = evolve(30, 30, c1, c2, 20.0, approximant=approximant, sampling="final")
    assert e.termination in PHYSICAL_ENDS
    try:
        r = evolve(30, 30, e.chi1[-1], e.chi2[-1], e.f_gw[-1] * (1 - 1e-6), approximant=approximant,
                   ell_hat=e.ell_hat[-1], n_hat=e.n_hat[-1])
    except ValueError as exc:
        assert "f_ref" in str(exc)
    else:
        check(r, e.chi1[-1], e.chi2[-1])
        assert r.termination == e.termination and r.stats["nsteps"] < 20
        assert r.v[-1] == pytest.approx(e.v[-1], abs=1e-6)


# --------------------------------------------------------------------------------------------------
# mass ratio and spin extremes
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("q", [20, 100])
@pytest.mark.parametrize("chi1,chi2", [([0, 0, 0], [0, 0, 0]), ([0.6, 0.0, 0.3], [-0.3, 0.5, 0.1])])
def test_extreme_mass_ratio_terminates(q, chi1, chi2):
    """q + 1 M☉ from 20 Hz through the precessing state: a physical end, |χ| to 1e-11 (measured 8.6e-12),
    v past v_ref (at q = 100 the run starts at v = 0.315 and ends at 0.42–0.53)."""
    e = check(evolve(q, 1.0, chi1, chi2, 20.0, integrate_rotor=True), chi1, chi2, spin_tol=1e-11)
    assert e.termination in PHYSICAL_ENDS - {"v_max"}
    assert e.v[-1] > 0.4
    if not np.any(chi1):
        assert np.max(_angle(e.ell_hat, Z)) == 0.0


@pytest.mark.parametrize("approximant", ["T1", "T4", "T5"])
@pytest.mark.parametrize("label,chi1,chi2", [("aligned", [0, 0, 0.999], [0, 0, 0.999]),
                                             ("anti-aligned", [0, 0, -0.999], [0, 0, -0.999]),
                                             ("in-plane", [0.999, 0, 0], [0, 0.999, 0])])
def test_near_extremal_spins(approximant, label, chi1, chi2):
    """|χ| = 0.999 from 10 to 20 Hz and on: |χ| to 1e-11 (measured 2.1e-12); along ℓ̂ they stay put and
    ℓ̂ stays ẑ exactly, in the plane ℓ̂ swings (by 1.3 rad, measured)."""
    e = check(evolve(30, 10, chi1, chi2, 20.0, f_min=10.0, approximant=approximant, integrate_rotor=True),
              chi1, chi2, spin_tol=1e-11)
    swing = np.max(_angle(e.ell_hat, Z))
    if label == "in-plane":
        assert swing > 0.5
    else:
        assert swing < 1e-12
        assert np.max(np.abs(e.chi1 - chi1)) < 1e-12 and np.max(np.abs(e.chi2 - chi2)) < 1e-12


def _tilted(chi, tilt):
    return [abs(chi) * np.sin(tilt), 0.0, chi * np.cos(tilt)]


def test_up_down_exact_stays_aligned():
    """χ₁ = 0.9ẑ, χ₂ = −0.9ẑ exactly, through the precessing state: nothing moves (ℓ̂ to 1e-12)."""
    e = check(evolve(20, 10, [0, 0, 0.9], [0, 0, -0.9], 5.0, integrate_rotor=True), [0, 0, 0.9], [0, 0, -0.9])
    assert np.max(_angle(e.ell_hat, Z)) < 1e-12
    assert np.max(np.abs(e.chi1 - [0, 0, 0.9])) < 1e-12 and np.max(np.abs(e.chi2 - [0, 0, -0.9])) < 1e-12


@pytest.mark.parametrize("f_ref", [5.0, 20.0])
def test_up_down_instability_and_stable_neighbours(f_ref):
    """χ₁ tilted 1e-8 rad from ẑ, 20 + 10 M☉ (q = 0.5, χ = 0.9).  Up-down (heavier spin up, lighter down)
    is unstable for r < r_ud+ = (√χ₁ + √(qχ₂))⁴/(1 − q)² M = 27.6 M (Gerosa et al. 2015, arXiv:1506.03492):
    the misalignment grows (ℓ̂ opens to 4.9e-8–7.3e-8, χ₁'s tilt from ℓ̂ to 1e-7–1.6e-7, measured).  Up-up,
    down-up and χ₂ = 0 are stable: ℓ̂ stays within the 1e-8 (measured ≤ 6e-9)."""
    tilt = 1e-8

    def final_angles(chi1, chi2):
        e = check(evolve(20, 10, chi1, chi2, f_ref), chi1, chi2)
        return _angle(e.ell_hat[-1], Z), np.max(_angle(e.ell_hat, Z)), _angle(e.chi1[-1], e.ell_hat[-1])

    ell_end, _, chi_tilt = final_angles(_tilted(0.9, tilt), [0, 0, -0.9])
    assert ell_end > 3 * tilt and chi_tilt > 5 * tilt
    for chi1, chi2 in ((_tilted(0.9, tilt), [0, 0, 0.9]), (_tilted(0.9, tilt), [0, 0, 0]),
                       ([0, 0, -0.9], _tilted(0.9, tilt))):
        _, ell_max, _ = final_angles(chi1, chi2)
        assert ell_max < tilt


@pytest.mark.parametrize("tiny", [[1e-300, 1e-300, 1e-300], [0, 0, 1e-300], [1e-13, 0, 0]])
def test_tiny_spins_equal_zero_spins(tiny):
    """Spins of 1e-300 (and 1e-13 in the plane, which is integrated as precessing) give the phase of exactly
    zero spins to the last bit, without underflow trouble."""
    kw = dict(f_min=10.0, integrate_rotor=True)
    zero = evolve(30, 10, [0, 0, 0], [0, 0, 0], 20.0, **kw)
    e = check(evolve(30, 10, tiny, tiny, 20.0, **kw), tiny, tiny)
    assert len(e) == len(zero) and e.termination == zero.termination
    np.testing.assert_array_equal(e.Phi, zero.Phi)
    np.testing.assert_array_equal(e.v, zero.v)


# --------------------------------------------------------------------------------------------------
# binary neutron star from 10 Hz: the memory of sampling='final'
# --------------------------------------------------------------------------------------------------

def test_bns_final_sampling_keeps_one_sample():
    """1.4 + 1.4 M☉ from 10 Hz (1016 s, 1615 steps with these spins): sampling='final' returns the last
    state of sampling='steps' as a 1-sample history, and the numpy memory it allocates stays that of one
    sample (measured 21 kB peak vs 0.4 MB for 'steps')."""
    import tracemalloc
    chi = [0.05, 0.0, 0.02]
    evolve(1.4, 1.4, chi, chi, 200.0, sampling="final")        # compiled code loaded before measuring
    tracemalloc.start()
    fin = evolve(1.4, 1.4, chi, chi, 10.0, sampling="final")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    steps = check(evolve(1.4, 1.4, chi, chi, 10.0), chi, chi)
    assert len(fin) == 1 and fin.chi1.shape == (1, 3) and fin.R.shape == (1, 4)
    assert steps.stats["nsteps"] > 1000 and fin.stats["nsteps"] == steps.stats["nsteps"]
    assert fin.t_seconds[0] == steps.t_seconds[-1] > 1000.0
    np.testing.assert_array_equal(fin.R[0], steps.R[-1])
    assert peak < 100_000 < 136 * steps.stats["nsteps"]


def test_f_ref_past_the_peak_of_vdot_is_a_value_error():
    """Between the peak of ω̇ ∝ v²v̇ and the root of T4's flux ratio (v* = 0.6305) v̇ > 0 but ω̇ falls with
    v: no inspiral starts there."""
    e = evolve(30, 10, [0, 0, 0.999], [0, 0, 0.999], 20.0, approximant="T4", sampling="final")
    for f in (e.f_gw[-1] * (1 + 1e-6), e.f_gw[-1] * 1.1):
        with pytest.raises(ValueError, match="f_ref .* no longer accelerates"):
            evolve(30, 10, [0, 0, 0.999], [0, 0, 0.999], f, approximant="T4")


def _omega_dot_of_v(v, X1, chi, approximant, orders):
    """v²v̇(v) ∝ ω̇ for spins χ ẑ on both bodies, from the numpy series evaluator (not the numba event code)."""
    from pnrotor.pn.series import basis_values, evaluate, kmax_from_orders
    from pnrotor.pn.vdot import vdot_series
    N, D, _ = vdot_series(X1, approximant, kmax_from_orders(*orders))
    b = basis_values(chi, chi, chi * chi, chi * chi, chi * chi)
    return v ** 11 * evaluate(N, v, b) / evaluate(D, v, b)


@pytest.mark.parametrize("integrate_rotor", [False, True])
def test_t4_ends_at_the_peak_of_vdot_before_a_root_of_its_flux_ratio(integrate_rotor):
    """|χ| = 0.999 aligned, T4: N has a simple root at v* = 0.6305, where v̇ ∝ v* − v and v approaches v*
    only exponentially; before the 'vdot_peak' end the runs gained 27–52 rad there and their final Φ
    spread by 23 rad over atol 1e-10 … 1e-14.  Now they stop where ω̇ ∝ v²v̇ peaks (LAL's d²ω/dt² ≤ 0): at
    the maximum of an independent numpy evaluation of v²v̇(v), with a final Φ that agrees across atol."""
    runs = [evolve(30, 10, [0, 0, 0.999], [0, 0, 0.999], 20.0, approximant="T4", atol=atol, sampling="final",
                   integrate_rotor=integrate_rotor) for atol in (1e-10, 1e-12, 1e-14)]
    assert all(e.termination == "vdot_peak" for e in runs)
    phi = [e.Phi[-1] for e in runs]
    assert max(phi) - min(phi) < 1e-6
    v = np.linspace(0.55, 0.62, 70001)
    omega_dot = _omega_dot_of_v(v, 0.75, 0.999, "T4", (3.5, 3.5, 3.0))
    v_peak = v[np.argmax(omega_dot)]
    assert v_peak + 1e-6 < 0.6305 and all(abs(e.v[-1] - v_peak) < 2e-6 for e in runs)


# --------------------------------------------------------------------------------------------------
# random binaries
# --------------------------------------------------------------------------------------------------

@st.composite
def binaries(draw):
    """m in [1, 100] M☉ with q ≤ 20, isotropic spins with |χ| ≤ 0.99, f_ref in [10, 60] Hz lowered to
    v = 0.3 if above (below every end of the inspiral), one of T1/T4/T5."""
    m1 = draw(st.floats(1.0, 100.0))
    m2 = draw(st.floats(max(1.0, m1 / 20.0), 100.0))
    spins = []
    for _ in range(2):
        d = np.array(draw(st.tuples(*[st.floats(-1.0, 1.0)] * 3)))
        n = np.linalg.norm(d)
        spins.append(d / n * draw(st.floats(0.0, 0.99)) if n > 1e-3 else np.zeros(3))
    f_cap = 0.3 ** 3 / (math.pi * (m1 + m2) * MTSUN_SI)
    f_ref = min(draw(st.floats(10.0, 60.0)), f_cap)
    return m1, m2, spins[0], spins[1], f_ref, draw(st.sampled_from(["T1", "T4", "T5"]))


@settings(max_examples=100, deadline=None, derandomize=True)
@given(binaries())
def test_random_binaries(binary):
    """No exception, a physical end, |χᵢ| conserved, R unit and finite, v increasing (through :func:`check`)."""
    m1, m2, chi1, chi2, f_ref, approximant = binary
    e = evolve(m1, m2, chi1, chi2, f_ref, approximant=approximant)
    check(e, chi1, chi2)
    assert e.v[-1] > e.v[0]
