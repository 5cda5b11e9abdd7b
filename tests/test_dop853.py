"""Tests of pnrotor.ode.dop853 against independent references.

References used: the exact Kepler orbit (Kepler's equation solved by Newton's method), exact
solutions of linear systems (scipy.linalg.expm), closed-form crossing times of a harmonic
oscillator, polynomial solutions that an order-8 method integrates exactly, the Runge–Kutta order
conditions, and scipy.integrate.solve_ivp(method='DOP853') for the step sequence.
"""

import math

import numpy as np
import pytest
import scipy
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit
from scipy.integrate import DOP853, solve_ivp
from scipy.linalg import expm

from pnrotor.ode import (AFTER_STEP_SIG, EVENTS_SIG, RHS_SIG, STATUS_EVENT, STATUS_MAX_STEPS, STATUS_NONFINITE,
                         STATUS_STEP_UNDERFLOW, STATUS_SUCCESS, DenseOutput, by_address, dop853, tableau)

from ode_problems import (W, add_to_first, assert_matches_expm, blow_up, kepler, kepler_exact, kepler_y0, linear, lotka_volterra,
                          nan_after_one, nan_always, never_modify, osc_events, osc_exact, oscillator, ramp,
                          random_linear, two_close_levels)


def scipy_fun(rhs, args):
    """The same numba right-hand side as a scipy-style f(t, y), so both solvers see identical f."""
    p = np.ascontiguousarray(args, dtype=float)

    def f(t, y):
        d = np.empty(y.size)
        rhs(t, np.ascontiguousarray(y, dtype=float), p, d)
        return d
    return f


# --------------------------------------------------------------------------------------------------
# coefficients
# --------------------------------------------------------------------------------------------------


def test_tableau_order_conditions():
    A, b, c = tableau.A[:12, :12], tableau.B, tableau.C[:12]
    # consistency of every stage of the extended tableau: row sums equal the nodes
    np.testing.assert_allclose(tableau.A.sum(axis=1), tableau.C, atol=2e-15)
    # quadrature conditions  Σ b c^k = 1/(k+1), k ≤ 7 (order 8), and violated for k = 8
    for k in range(8):
        assert abs(b @ c**k - 1 / (k + 1)) < 1e-14
    assert abs(b @ c**8 - 1 / 9) > 1e-6
    # a selection of higher trees (orders k + 2 and k + 3 ≤ 8):
    # Σ b A c^k = 1/((k+1)(k+2)),  Σ b c A c^k = 1/((k+1)(k+3))
    for k in range(7):
        assert abs(b @ (A @ c**k) - 1 / ((k + 1) * (k + 2))) < 1e-13
    for k in range(6):
        assert abs((b * c) @ (A @ c**k) - 1 / ((k + 1) * (k + 3))) < 1e-13
    assert abs((b * c) @ (A @ c**6) - 1 / (7 * 9)) > 1e-8  # order 9: not satisfied
    # the error estimators are differences of two consistent solutions
    assert abs(tableau.E5.sum()) < 1e-14 and abs(tableau.E3.sum()) < 1e-14
    # the 3rd-order embedded solution b − E3 satisfies Σ (b−E3) c^k = 1/(k+1) for k ≤ 2
    bhat = b - tableau.E3
    for k in range(3):
        assert abs(bhat @ c**k - 1 / (k + 1)) < 1e-14


def test_tableau_matches_scipy_transcription():
    """Our transcription of Hairer's constants equals scipy's (an independent transcription)."""
    from scipy.integrate._ivp import dop853_coefficients as ref

    np.testing.assert_array_equal(tableau.C, ref.C)
    np.testing.assert_array_equal(tableau.A, ref.A)
    np.testing.assert_array_equal(tableau.B, ref.B)
    np.testing.assert_array_equal(tableau.E5, ref.E5[:12])
    np.testing.assert_array_equal(tableau.E3, ref.E3[:12])
    np.testing.assert_array_equal(tableau.D, ref.D)


# --------------------------------------------------------------------------------------------------
# accuracy and convergence
# --------------------------------------------------------------------------------------------------


def test_convergence_order_fixed_steps():
    """Global error at t = 2π of the e = 0.3 Kepler orbit with N fixed steps falls like N^-8."""
    e = 0.3
    y0 = kepler_y0(e)
    T = 2 * np.pi
    errs = []
    Ns = np.array([48, 64, 96, 128])
    for N in Ns:
        h = T / N
        # a huge atol accepts every step; max_step = first_step = h fixes the step size
        r = dop853(kepler, 0.0, y0, T, atol=1e6, first_step=h, max_step=h, t_eval="final")
        assert r.status == STATUS_SUCCESS and r.nrejected == 0
        assert r.naccepted in (N, N + 1)  # the last step may be a sliver because of rounding of t
        errs.append(np.max(np.abs(r.y[-1] - kepler_exact(T, e)[0])))
    errs = np.array(errs)
    assert errs[-1] > 1e-13, errs  # still well above roundoff
    slope = -np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    pairwise = np.log(errs[1:-1] / errs[2:]) / np.log(Ns[2:] / Ns[1:-1])
    assert slope >= 7.5, (errs, slope)
    assert np.all(pairwise >= 7.5), (errs, pairwise)


def test_error_vs_nfev_slope_tolerance_sweep():
    """Tolerance proportionality: error vs work slope of DOP853 on Kepler (order ~8 ⇒ slope ≤ −7)."""
    e = 0.5
    y0 = kepler_y0(e)
    T = 2 * np.pi
    nfev, errs = [], []
    for tol in [1e-6, 1e-8, 1e-10, 1e-12]:
        r = dop853(kepler, 0.0, y0, T, atol=tol, rtol=tol, t_eval="final")
        nfev.append(r.nfev)
        errs.append(np.max(np.abs(r.y[-1] - y0)))
    slope = np.polyfit(np.log(nfev), np.log(errs), 1)[0]
    assert slope < -7.0, (nfev, errs, slope)
    assert errs[-1] < 1e-9


def test_kepler_accuracy_and_step_outputs():
    e = 0.5
    y0 = kepler_y0(e)
    r = dop853(kepler, 0.0, y0, 4 * np.pi, atol=1e-12, rtol=1e-12)
    assert r.success and r.status == 0 and r.message
    assert r.t[0] == 0.0 and r.t[-1] == 4 * np.pi
    assert np.all(np.diff(r.t) > 0)
    assert r.y.shape == (r.naccepted + 1, 4)
    np.testing.assert_array_equal(r.y[0], y0)
    assert np.max(np.abs(r.y - kepler_exact(r.t, e))) < 1e-9
    assert r.nsteps == r.naccepted + r.nrejected
    # 1 initial f, 1 for the initial-step estimate, 11 per attempted step, 1 (FSAL) per accepted
    assert r.nfev == 2 + 11 * r.nsteps + r.naccepted


def test_backward_integration_matches_exact():
    e = 0.5
    y_start = kepler_exact(3.0, e)[0]
    r = dop853(kepler, 3.0, y_start, -2.5, atol=1e-12, rtol=1e-12)
    assert r.status == 0 and r.t[-1] == -2.5
    assert np.all(np.diff(r.t) < 0)
    assert np.max(np.abs(r.y - kepler_exact(r.t, e))) < 1e-9
    # backward t_eval (decreasing) and dense output
    te = np.linspace(3.0, -2.5, 57)
    r2 = dop853(kepler, 3.0, y_start, -2.5, atol=1e-12, rtol=1e-12, t_eval=te, dense=True)
    np.testing.assert_array_equal(r2.t, te)
    assert np.max(np.abs(r2.y - kepler_exact(te, e))) < 1e-9
    tq = np.linspace(-2.5, 3.0, 401)
    assert np.max(np.abs(r2.dense(tq) - kepler_exact(tq, e))) < 1e-9


def test_rtol_zero_with_per_component_atol():
    """Two decoupled oscillators of amplitude 1e6 and 1e-6: per-component atol controls each."""
    A = np.zeros((4, 4))
    A[0, 1], A[1, 0] = 1.0, -1.0
    A[2, 3], A[3, 2] = 3.0, -3.0
    y0 = np.array([1e6, 0.0, 1e-6, 0.0])
    T = 10.0
    exact = expm(A * T) @ y0
    atol = np.array([1e-4, 1e-4, 1e-16, 1e-16])
    r = dop853(linear, 0.0, y0, T, atol=atol, rtol=0.0, args=A.ravel(), t_eval="final")
    err = np.abs(r.y[-1] - exact)
    assert np.all(err < 100 * atol), err
    # a scalar atol sized for the large component leaves the small one unresolved
    r1 = dop853(linear, 0.0, y0, T, atol=1e-4, rtol=0.0, args=A.ravel(), t_eval="final")
    assert np.abs(r1.y[-1, 2:] - exact[2:]).max() > 1e-13
    assert r1.nfev < r.nfev


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 5), seed=st.integers(0, 2**32 - 1), T=st.floats(0.1, 3.0),
       backward=st.booleans())
def test_random_linear_systems_against_expm(n, seed, T, backward):
    """At 7 t_eval points (dense output) and at t_end."""
    A, y0 = random_linear(n, seed)
    t_end = -T if backward else T
    te = np.linspace(0.0, t_end, 7)
    r = dop853(linear, 0.0, y0, t_end, atol=1e-11, rtol=1e-11, args=A.ravel(), t_eval=te)
    np.testing.assert_array_equal(r.t, te)
    assert_matches_expm(r, A, y0, T)


# --------------------------------------------------------------------------------------------------
# agreement with scipy's DOP853
# --------------------------------------------------------------------------------------------------

SCIPY_CONTROLLER = dict(safety=0.9, min_factor=0.2, max_factor=10.0)


@pytest.mark.parametrize("problem", ["kepler", "lotka_volterra"])
def test_same_steps_as_scipy(problem):
    """With scipy's controller constants and initial step, DOP853 takes the same steps as scipy.

    Both codes evaluate the same f (the same numba function).  The stage sums differ only in
    summation order (scipy uses BLAS dot products), i.e. by ~1 ulp.  The error estimate is a
    difference of O(1) numbers that cancels down to ~tol, so those ulps change err by ~eps/tol
    relatively, and the step sizes by 1/8 of that: at tol = 1e-10 the step sizes agree to ~1e-7
    (1e-5 asserted), not to 1e-12.  Counts agree exactly and the final states (both codes land
    exactly on t_end) to ~1e-14.
    """
    if problem == "kepler":
        rhs, args, y0, T = kepler, np.empty(0), kepler_y0(0.5), 6 * np.pi
    else:
        rhs, args, y0, T = lotka_volterra, np.array([1.5, 1.0, 1.0, 3.0]), np.array([10.0, 5.0]), 15.0
    tol = 1e-10
    f = scipy_fun(rhs, args)
    h0 = DOP853(f, 0.0, y0, T, rtol=tol, atol=tol).h_abs
    s = solve_ivp(f, (0.0, T), y0, method="DOP853", rtol=tol, atol=tol)
    r = dop853(rhs, 0.0, y0, T, atol=tol, rtol=tol, args=args, first_step=h0, **SCIPY_CONTROLLER)
    assert s.status == 0 and r.status == 0
    # counts: scipy spends 12 evaluations on every attempt (2 more at the start); we skip the FSAL
    # evaluation of rejected attempts and, with first_step given, the initial-step estimate
    n_attempts_scipy = (s.nfev - 2) // 12
    assert (s.nfev - 2) % 12 == 0
    assert len(r.t) == len(s.t)
    assert r.nsteps == n_attempts_scipy
    assert r.nfev == s.nfev - r.nrejected - 1
    assert r.nrejected > 0  # the comparison covers rejected steps too
    np.testing.assert_allclose(np.diff(r.t), np.diff(s.t), rtol=1e-5, atol=0)
    np.testing.assert_allclose(r.t, s.t, rtol=1e-6, atol=0)
    assert np.max(np.abs(r.y[-1] - s.y[:, -1])) <= 1e-12 * np.max(np.abs(s.y[:, -1]))
    # intermediate states differ only through the slightly different output times
    ydot = np.array([f(t, y) for t, y in zip(s.t, s.y.T)])
    dev = np.abs(r.y - s.y.T) - np.abs(ydot) * np.abs(r.t - s.t)[:, None]
    assert np.max(dev) < 1e-12 * np.max(np.abs(s.y))

    # our automatic initial step is scipy's (same algorithm): same run without first_step
    r_auto = dop853(rhs, 0.0, y0, T, atol=tol, rtol=tol, args=args, **SCIPY_CONTROLLER)
    np.testing.assert_allclose(r_auto.t, r.t, rtol=1e-12, atol=0)
    assert r_auto.nfev == r.nfev + 1


def test_single_steps_replay_scipy():
    """From each of scipy's accepted states, one DOP853 step of scipy's size reproduces scipy's
    next state to roundoff (checks the 8th-order formula exactly, independent of the controller)."""
    e = 0.7
    y0 = kepler_y0(e)
    f = scipy_fun(kepler, np.empty(0))
    s = solve_ivp(f, (0.0, 2 * np.pi), y0, method="DOP853", rtol=1e-9, atol=1e-9)
    worst = 0.0
    for i in range(len(s.t) - 1):
        # a huge atol accepts the step; t_end = scipy's next time makes it exactly one step
        r = dop853(kepler, s.t[i], s.y[:, i], s.t[i + 1], atol=1e9, first_step=s.t[i + 1] - s.t[i],
                   t_eval="final")
        assert r.naccepted == 1 and r.t[-1] == s.t[i + 1]
        worst = max(worst, np.max(np.abs(r.y[-1] - s.y[:, i + 1]) / np.max(np.abs(s.y[:, i + 1]))))
    assert worst < 1e-14, worst


# --------------------------------------------------------------------------------------------------
# output modes and dense output
# --------------------------------------------------------------------------------------------------


def test_dense_output_error_at_tolerance_level():
    e = 0.5
    y0 = kepler_y0(e)
    T = 4 * np.pi
    tol = 1e-10
    r = dop853(kepler, 0.0, y0, T, atol=tol, rtol=tol, dense=True)
    assert isinstance(r.dense, DenseOutput)
    node_err = np.max(np.abs(r.y - kepler_exact(r.t, e)))
    tq = np.sort(np.random.default_rng(1).uniform(0, T, 5000))
    dense_err = np.max(np.abs(r.dense(tq) - kepler_exact(tq, e)))
    assert dense_err < 2 * node_err + 10 * tol, (dense_err, node_err)
    # it interpolates: exact at the step points, scalar and array calls agree, shape conventions
    np.testing.assert_allclose(r.dense(r.t), r.y, rtol=0, atol=1e-14)
    assert r.dense(1.234).shape == (4,)
    assert r.dense(np.zeros((3, 2))).shape == (3, 2, 4)
    np.testing.assert_array_equal(r.dense(1.234), r.dense(np.array([1.234]))[0])
    assert r.dense.t_min == 0.0 and r.dense.t_max == T
    with pytest.raises(ValueError, match="interval"):
        r.dense(T + 1e-3)
    # the 7th-order interpolant is much better than the local error of a cubic Hermite would be:
    # compare with the midpoints of the largest steps
    h = np.diff(r.t)
    k = np.argsort(h)[-5:]
    mids = r.t[k] + 0.5 * h[k]
    assert np.max(np.abs(r.dense(mids) - kepler_exact(mids, e))) < 2 * node_err + 10 * tol
    # dense=True costs 3 extra evaluations per step
    r0 = dop853(kepler, 0.0, y0, T, atol=tol, rtol=tol)
    assert r.nfev == r0.nfev + 3 * r0.naccepted


def test_t_eval_uses_interpolation_without_changing_steps():
    e = 0.5
    y0 = kepler_y0(e)
    T = 2 * np.pi
    te = np.linspace(0, T, 301)
    r0 = dop853(kepler, 0.0, y0, T, atol=1e-10, rtol=1e-10)
    r = dop853(kepler, 0.0, y0, T, atol=1e-10, rtol=1e-10, t_eval=te)
    assert r.naccepted == r0.naccepted and r.nrejected == r0.nrejected  # steps not shortened
    np.testing.assert_array_equal(r.t, te)
    assert np.max(np.abs(r.y - kepler_exact(te, e))) < 1e-8
    np.testing.assert_array_equal(r.y[-1], r0.y[-1])  # t_end is a step end: no interpolation
    # only steps containing an output point pay for the dense stages
    assert r.nfev <= r0.nfev + 3 * r0.naccepted
    # final-state mode: same steps, one row, no extra evaluations
    rf = dop853(kepler, 0.0, y0, T, atol=1e-10, rtol=1e-10, t_eval="final")
    assert rf.t.shape == (1,) and rf.y.shape == (1, 4) and rf.nfev == r0.nfev
    np.testing.assert_array_equal(rf.y[0], r0.y[-1])
    # an empty t_eval records nothing
    re = dop853(kepler, 0.0, y0, T, atol=1e-10, rtol=1e-10, t_eval=np.array([]))
    assert re.t.shape == (0,) and re.y.shape == (0, 4) and re.nfev == r0.nfev


def test_max_step_respected():
    r = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-6, args=[W], max_step=0.1)
    assert np.max(np.diff(r.t)) <= 0.1 + 1e-15
    assert np.max(np.abs(r.y - osc_exact(r.t))) < 1e-5


# --------------------------------------------------------------------------------------------------
# events
# --------------------------------------------------------------------------------------------------


def test_event_located_to_near_machine_precision():
    r = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-13, args=[W], events=osc_events, n_events=2)
    assert r.status == STATUS_EVENT and r.success
    assert r.event_index == 0
    t_star = math.acos(0.5) / W
    assert abs(r.t_event - t_star) < 1e-10
    assert abs(r.y_event[0] - 0.5) < 1e-12
    np.testing.assert_allclose(r.y_event, osc_exact(r.t_event), atol=1e-11)
    # the output ends at the event
    assert r.t[-1] == r.t_event
    np.testing.assert_array_equal(r.y[-1], r.y_event)


def test_functions_by_address_give_the_same_run():
    """by_address(f, sig) (the compiled address, for functions that cannot raise) integrates exactly as the
    dispatcher f, events included; a function of another signature is refused."""
    kw = dict(atol=1e-12, args=[W], n_events=2, dense=True)
    a = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, events=osc_events, **kw)
    b = dop853(by_address(oscillator, RHS_SIG), 0.0, [1.0, 0.0], 10.0, events=by_address(osc_events, EVENTS_SIG),
               **kw)
    assert a.status == b.status == STATUS_EVENT and a.nfev == b.nfev
    np.testing.assert_array_equal(a.y, b.y)
    np.testing.assert_array_equal(a.t, b.t)
    with pytest.raises(TypeError, match="rhs must have the signature"):
        dop853(by_address(never_modify, AFTER_STEP_SIG), 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W])


@njit(RHS_SIG, cache=True)
def _raising_rhs(t, y, p, dydt):
    if t > 1.0:
        raise ValueError("rhs refused t > 1")
    dydt[0] = y[1]
    dydt[1] = -y[0]


@njit(EVENTS_SIG, cache=True)
def _raising_events(t, y, p, g):
    if t > 2.0:
        raise ValueError("events refused t > 2")
    g[0] = 1.0


@njit(AFTER_STEP_SIG, cache=True)
def _raising_after_step(t, y, p):
    if t > 3.0:
        raise ValueError("after_step refused t > 3")
    return False


def test_exceptions_raised_by_a_users_functions_reach_the_caller():
    """A dispatcher is called through its jit entry inside the core, so its exception propagates (with its
    message) from dop853 and bulirsch_stoer alike; the same function by_address would not (documented)."""
    from pnrotor.ode import bulirsch_stoer

    with pytest.raises(ValueError, match="rhs refused t > 1"):
        dop853(_raising_rhs, 0.0, [1.0, 0.0], 10.0, atol=1e-10)
    with pytest.raises(ValueError, match="rhs refused t > 1"):
        bulirsch_stoer(_raising_rhs, 0.0, [1.0, 0.0], 10.0, atol=1e-10)
    with pytest.raises(ValueError, match="events refused t > 2"):
        dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-10, args=[W], events=_raising_events, n_events=1)
    with pytest.raises(ValueError, match="after_step refused t > 3"):
        dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-10, args=[W], after_step=_raising_after_step)
    with pytest.raises(ValueError, match="after_step refused t > 3"):
        bulirsch_stoer(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-10, args=[W], after_step=_raising_after_step)


def test_a_recompiled_dispatcher_is_looked_up_again():
    """The addresses of a dispatcher are cached with its overload: after recompile() (new code, the old may be
    freed) a run uses the new overload's and gives the same result."""
    @njit(RHS_SIG)
    def rhs(t, y, p, dydt):
        dydt[0] = y[1]
        dydt[1] = -p[0] * y[0]

    from pnrotor.ode.common import _CHECKED

    a = dop853(rhs, 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W])
    first = _CHECKED[rhs]["rhs"]
    rhs.recompile()
    b = dop853(rhs, 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W])
    assert _CHECKED[rhs]["rhs"][0] is rhs.overloads[tuple(RHS_SIG.args)] is not first[0]
    np.testing.assert_array_equal(a.y, b.y)


def test_a_cfunc_is_refused_and_by_address_checks_its_function():
    """A @cfunc cannot pass an exception back (numba prints it and the run goes on with wrong numbers): refused with
    a TypeError naming the argument; by_address refuses what is not an @njit function of its signature."""
    from numba import cfunc

    with pytest.raises(TypeError, match="rhs must be an @njit function, not a @cfunc"):
        dop853(cfunc(RHS_SIG)(oscillator.py_func), 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W])
    with pytest.raises(TypeError, match="by_address takes an @njit function"):
        by_address(cfunc(RHS_SIG)(oscillator.py_func), RHS_SIG)
    with pytest.raises(TypeError, match="by_address.s function must be a numba @njit function compilable"):
        by_address(oscillator, AFTER_STEP_SIG)
    with pytest.raises(TypeError, match="by_address takes a numba signature"):
        by_address(oscillator, "void(float64, float64[::1], float64[::1], float64[::1])")


def test_event_direction_and_zero_at_start():
    """Forward: g0 = cos(Wt) − ½ falls through 0 at acos(½)/W and rises at (2π − acos ½)/W;
    g1 = y' = −W sin(Wt) is exactly 0 at t0 (must not trigger), rises through 0 at π/W and falls
    at 2π/W."""
    def run(direction):
        return dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-13, args=[W], events=osc_events,
                      n_events=2, event_direction=direction)
    r = run(-1)  # scalar: both decreasing only
    assert r.event_index == 0 and abs(r.t_event - math.acos(0.5) / W) < 1e-10
    r = run([+1, 0])  # g1 in either direction: its first crossing at π/W, not the zero at t0
    assert r.event_index == 1 and abs(r.t_event - math.pi / W) < 1e-10
    r = run([+1, -1])
    assert r.event_index == 0 and abs(r.t_event - (2 * math.pi - math.acos(0.5)) / W) < 1e-10
    r = run([-1, -1])
    assert r.event_index == 0 and abs(r.t_event - math.acos(0.5) / W) < 1e-10
    r = run([0, +1])  # both directions for g0: the first crossing wins
    assert r.event_index == 0 and abs(r.t_event - math.acos(0.5) / W) < 1e-10


def test_event_backward_direction_is_in_integration_order():
    """Backward from 0 (t decreasing): g0 = cos(Wt) − ½ falls through 0 at −acos(½)/W and rises at
    −(2π − acos ½)/W; g1 = −W sin(Wt) > 0 just below 0, falls through 0 at −π/W, rises at −2π/W.
    Directions refer to the order of integration."""
    def run(direction):
        return dop853(oscillator, 0.0, [1.0, 0.0], -10.0, atol=1e-13, args=[W], events=osc_events,
                      n_events=2, event_direction=direction)
    r = run([-1, 0])
    assert r.event_index == 0 and abs(r.t_event + math.acos(0.5) / W) < 1e-10
    r = run([+1, -1])
    assert r.event_index == 1 and abs(r.t_event + math.pi / W) < 1e-10
    r = run([+1, +1])
    assert r.event_index == 0 and abs(r.t_event + (2 * math.pi - math.acos(0.5)) / W) < 1e-10
    np.testing.assert_allclose(r.y_event, osc_exact(r.t_event), atol=1e-11)


def test_earliest_of_several_events_in_one_step_wins():
    # y crosses 0.5 before 0.49; listing 0.49 first must not make it win.  Large steps (loose atol)
    # so that both crossings fall into one step.
    r = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-3, args=[W], events=two_close_levels,
               n_events=2)
    assert r.event_index == 1
    assert abs(r.y_event[0] - 0.5) < 1e-12  # the root of the interpolant itself is exact


def test_event_with_t_eval_stops_outputs():
    te = np.linspace(0, 10, 101)
    r = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W], events=osc_events, n_events=2,
               t_eval=te)
    assert r.status == STATUS_EVENT
    np.testing.assert_array_equal(r.t, te[te <= r.t_event])
    np.testing.assert_allclose(r.y, osc_exact(r.t), atol=1e-10)
    rf = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W], events=osc_events, n_events=2,
                t_eval="final")
    assert rf.t[0] == rf.t_event and np.array_equal(rf.y[0], rf.y_event)


# --------------------------------------------------------------------------------------------------
# after_step hook
# --------------------------------------------------------------------------------------------------


def test_after_step_modification_counted_and_fsal_reevaluated():
    """ramp: y0' = 1, y1' = y0.  The hook adds δ to y0 after every step, so on step k (from t_k,
    h_k) y0 = t + kδ and the exact update is y1 += ∫ y0 = h_k (t_k + h_k/2) + kδ h_k.  DOP853 is
    exact for these polynomials, so y1(t_N) = t_N²/2 + δ Σ_k k h_k to roundoff, but only if the
    derivative is re-evaluated after each modification (a stale FSAL stage would be off by δ)."""
    delta = 0.01
    r = dop853(ramp, 0.0, [0.0, 0.0], 10.0, atol=1e-8, args=[delta], after_step=add_to_first,
               max_step=0.5)
    assert r.status == 0
    N = r.naccepted
    assert r.n_modified == N
    assert r.nfev == 2 + 11 * r.nsteps + r.naccepted + r.n_modified
    h = np.diff(r.t)
    k = np.arange(N)
    t_N = r.t[-1]
    assert abs(r.y[-1, 0] - (t_N + N * delta)) < 1e-12
    assert abs(r.y[-1, 1] - (t_N**2 / 2 + delta * np.sum(k * h))) < 1e-11
    # outputs at step ends are the modified states
    np.testing.assert_allclose(r.y[:, 0], r.t + delta * np.arange(N + 1), atol=1e-12)

    # a hook that returns False costs nothing and counts nothing
    r0 = dop853(ramp, 0.0, [0.0, 0.0], 10.0, atol=1e-8, args=[delta], after_step=never_modify,
                max_step=0.5)
    assert r0.n_modified == 0 and r0.nfev == 2 + 11 * r0.nsteps + r0.naccepted


def test_after_step_dense_output_refers_to_premodification_state():
    delta = 0.25
    r = dop853(ramp, 0.0, [0.0, 0.0], 2.0, atol=1e-8, args=[delta], after_step=add_to_first,
               max_step=0.5, dense=True)
    # inside step k the interpolant follows y0 = t + kδ; at the step boundaries (right-continuous)
    # it gives the modified state the next step started from
    for k in range(r.naccepted):
        tm = 0.5 * (r.t[k] + r.t[k + 1])
        assert abs(r.dense(tm)[0] - (tm + k * delta)) < 1e-12
    np.testing.assert_allclose(r.dense(r.t[:-1])[:, 0], r.y[:-1, 0], atol=1e-12)
    # at t_end: the last interpolant's end, i.e. before the final modification
    assert abs(r.dense(r.t[-1])[0] - (r.y[-1, 0] - delta)) < 1e-12


# --------------------------------------------------------------------------------------------------
# failures
# --------------------------------------------------------------------------------------------------


def test_nonfinite_rhs_inside_steps_ends_with_underflow_message():
    r = dop853(nan_after_one, 0.0, [0.0], 5.0, atol=1e-8)
    assert r.status == STATUS_STEP_UNDERFLOW and not r.success
    assert "NaN" in r.message and "t = " in r.message
    assert 0.99 < r.t[-1] <= 1.0
    assert abs(r.y[-1, 0] - r.t[-1]) < 1e-12


def test_nonfinite_rhs_at_start():
    r = dop853(nan_always, 0.0, [0.0], 5.0, atol=1e-8)
    assert r.status == STATUS_NONFINITE and not r.success
    assert "NaN" in r.message and r.nsteps == 0


@pytest.mark.parametrize("solver", ["dop853", "bulirsch_stoer"])
def test_pure_relative_tolerance_with_a_state_component_at_zero(solver):
    """atol = 0 with rtol > 0 is allowed; a component that starts at 0 (y' = 0 of the oscillator) made a
    bare ZeroDivisionError (the initial step's and the error's scales are 0 there)."""
    from pnrotor.ode import bulirsch_stoer

    call = dop853 if solver == "dop853" else bulirsch_stoer
    r = call(oscillator, 0.0, [1.0, 0.0], 10.0, atol=0.0, rtol=1e-10, args=(W,))
    assert r.status == STATUS_SUCCESS
    np.testing.assert_allclose(r.y[-1], osc_exact(10.0), rtol=0, atol=1e-7)


def test_overflowing_error_norms_end_at_once():
    """atol = 1e-300 overflows the scaled norms: the initial step was NaN and max_steps went by at t0 (11
    million evaluations); now a step underflow once the rejected steps have shrunk it from 1e-6 to the
    ulps of t (~660 of them).  A huge state gave a zero initial step and a ZeroDivisionError."""
    r = dop853(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-300, args=(W,))
    assert r.status == STATUS_STEP_UNDERFLOW and r.nfev < 10_000 and "at or near zero" in r.message
    big = dop853(oscillator, 0.0, [1e150, 0.0], 10.0, atol=1e-8, rtol=1e-8, args=(W,))
    assert big.status == STATUS_SUCCESS
    np.testing.assert_allclose(big.y[-1] / 1e150, osc_exact(10.0), rtol=0, atol=1e-6)


def test_blow_up_terminates():
    r = dop853(blow_up, 0.0, [1.0], 2.0, atol=1e-8, rtol=1e-8)
    # the numerical solution lags the singularity by a hair; it cannot get far past it
    assert r.status < 0 and 0.999 < r.t[-1] < 1.0 + 1e-6
    assert r.nsteps < 100_000
    # away from the singularity (where the problem is well conditioned) the solution is right
    ok = r.t < 0.99
    assert ok.sum() > 10
    np.testing.assert_allclose(r.y[ok, 0], 1 / (1 - r.t[ok]), rtol=1e-6)


def test_max_steps():
    r = dop853(kepler, 0.0, kepler_y0(0.5), 100.0, atol=1e-12, max_steps=50)
    assert r.status == STATUS_MAX_STEPS and r.nsteps == 50
    assert "max_steps" in r.message
    assert r.t[-1] < 100.0


def test_t_end_equal_t0():
    r = dop853(kepler, 1.0, kepler_y0(0.5), 1.0, atol=1e-8)
    assert r.status == 0 and r.nfev == 0
    np.testing.assert_array_equal(r.y, kepler_y0(0.5)[None])


# --------------------------------------------------------------------------------------------------
# input validation
# --------------------------------------------------------------------------------------------------

Y0 = [1.0, 0.0]


@pytest.mark.parametrize("kwargs, match", [
    (dict(atol=0.0), "atol must be > 0 where rtol = 0"),
    (dict(atol=-1e-8, rtol=1e-6), "atol must be >= 0"),
    (dict(atol=[1e-8, 0.0]), "component 1"),
    (dict(atol=1e-8, rtol=-1e-3), "rtol must be >= 0"),
    (dict(atol=[1e-8, 1e-8, 1e-8]), "atol must be a scalar or have shape"),
    (dict(atol=np.nan), "atol must be finite"),
    (dict(atol=1e-8, y0=[1.0, np.nan]), "y0 must be finite"),
    (dict(atol=1e-8, y0=[[1.0, 0.0]]), "y0 must be a 1-D array"),
    (dict(atol=1e-8, y0=[]), "at least one component"),
    (dict(atol=1e-8, y0=[1j, 0]), "y0 must be real"),
    (dict(atol=1e-8, t0=np.inf), "t0 must be finite"),
    (dict(atol=1e-8, t_end=np.nan), "t_end must be finite"),
    (dict(atol=1e-8, t0="a"), "t0 must be a finite real number"),
    (dict(atol=1e-8, t_eval=[0.0, 11.0]), r"t_eval must lie within \[t0, t_end\]"),
    (dict(atol=1e-8, t_eval=[0.0, 2.0, 1.0]), "t_eval must be sorted"),
    (dict(atol=1e-8, t_eval=[np.nan]), "t_eval must be finite"),
    (dict(atol=1e-8, t_eval="all"), "t_eval must be None, 'final'"),
    (dict(atol=1e-8, max_steps=0), "max_steps must be >= 1"),
    (dict(atol=1e-8, max_steps=1.5), "max_steps must be an integer"),
    (dict(atol=1e-8, max_step=0.0), "max_step must be > 0"),
    (dict(atol=1e-8, first_step=-0.1), "first_step must be > 0"),
    (dict(atol=1e-8, first_step=20.0), "first_step must not exceed"),
    (dict(atol=1e-8, safety=1.5), r"safety must be in \(0.0, 1.0\]"),
    (dict(atol=1e-8, min_factor=0.0), "min_factor must be in"),
    (dict(atol=1e-8, min_factor=1.0), r"min_factor must be in \(0.0, 1.0\)"),
    (dict(atol=1e-8, max_factor=0.5), "max_factor must be >= 1"),
    (dict(atol=1e-8, args=[[1.0], [2.0]]), "args must be a scalar or a 1-D sequence"),
    (dict(atol=1e-8, events=osc_events), "n_events must be >= 1"),
    (dict(atol=1e-8, n_events=2), "n_events must be 0 when no events"),
    (dict(atol=1e-8, events=osc_events, n_events=2, event_direction=[2, 0]), "event_direction values"),
    (dict(atol=1e-8, events=osc_events, n_events=2, event_direction=[1, 0, 1]), "event_direction must be"),
])
def test_invalid_inputs(kwargs, match):
    call = dict(rhs=oscillator, t0=0.0, y0=Y0, t_end=10.0, args=[W])
    call.update(kwargs)
    with pytest.raises(ValueError, match=match):
        dop853(**call)


def test_invalid_functions():
    with pytest.raises(TypeError, match="numba-compiled"):
        dop853(lambda t, y, p, d: None, 0.0, Y0, 1.0, atol=1e-8)

    @njit("void(float64, float64[:], float64[:], float64[:])")
    def wrong_layout(t, y, p, d):
        d[:] = 0.0

    with pytest.raises(TypeError, match="RHS_SIG"):
        dop853(wrong_layout, 0.0, Y0, 1.0, atol=1e-8)
    with pytest.raises(TypeError, match="after_step"):
        dop853(oscillator, 0.0, Y0, 1.0, atol=1e-8, args=[W], after_step=oscillator)


def test_lazy_njit_rhs_is_accepted():
    @njit
    def lazy(t, y, p, d):
        d[0] = -y[0]

    r = dop853(lazy, 0.0, [1.0], 1.0, atol=1e-12, t_eval="final")
    assert abs(r.y[0, 0] - math.exp(-1.0)) < 1e-11


def test_scipy_version_has_dop853():
    # the scipy comparison above relies on scipy's DOP853 (present since 1.4)
    assert tuple(int(x) for x in scipy.__version__.split(".")[:2]) >= (1, 4)


def test_compensated_summation_keeps_long_sums_exact():
    """y' = 0.1 from y = 1000 over 10⁵ steps of 0.01: every step adds 0.001, which float64 cannot add to 1000
    without rounding.  The compensated update (module docstring) ends on 1100 exactly; a plain y + h Σ bⱼkⱼ
    ended 2.3e-9 away (measured before it was compensated)."""
    @njit(RHS_SIG)
    def constant(t, y, p, dydt):
        dydt[0] = 0.1

    r = dop853(constant, 0.0, [1000.0], 1000.0, atol=1e-10, max_step=0.01, t_eval="final")
    assert r.nsteps > 99_999
    assert abs(r.y[-1, 0] - 1100.0) <= np.spacing(1100.0)


def test_the_core_has_one_compiled_signature_whatever_the_callers_pass():
    """The core is compiled for CORE_SIG only and called through that entry point: a user's dispatcher
    as rhs adds no overload (one would be cached with a reference to the user's module, which another
    process could not import: a batch then failed every row with ModuleNotFoundError)."""
    from pnrotor.ode.common import entry_point
    from pnrotor.ode.dop853 import CORE_SIG, core

    @njit(RHS_SIG)
    def decay(t, y, p, dydt):
        dydt[0] = -y[0]

    r = dop853(decay, 0.0, [1.0], 1.0, atol=1e-10)
    assert abs(r.y[-1, 0] - math.exp(-1.0)) < 1e-9
    assert entry_point(core, CORE_SIG) is not core
    assert list(core.overloads) == [tuple(CORE_SIG.args)]
