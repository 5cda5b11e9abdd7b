"""Tests of pnrotor.ode.bulirsch_stoer against independent references.

References: the exact Kepler orbit, exact solutions of linear systems (scipy.linalg.expm), the
harmonic oscillator, the first integral of the Lotka–Volterra system, and polynomial solutions
(which Gragg's rule with extrapolation integrates exactly).
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pnrotor.ode import STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_SUCCESS, bulirsch_stoer

from ode_problems import (W, add_to_first, assert_matches_expm, blow_up, kepler, kepler_exact, kepler_y0, linear, lotka_volterra,
                          nan_always, oscillator, ramp, random_linear)


def test_kepler_error_falls_with_atol():
    """Absolute tolerance only (rtol = 0, the paper's setting): the global error over two orbits
    of an e = 0.5 Kepler orbit stays within a modest multiple of atol and falls with it."""
    e = 0.5
    y0 = kepler_y0(e)
    T = 4 * np.pi
    errs, nfev = [], []
    tols = [1e-6, 1e-8, 1e-10, 1e-12]
    for tol in tols:
        r = bulirsch_stoer(kepler, 0.0, y0, T, atol=tol)
        assert r.status == STATUS_SUCCESS and r.success and r.t[-1] == T
        assert r.nsteps == r.naccepted + r.nrejected
        errs.append(np.max(np.abs(r.y - kepler_exact(r.t, e))))
        nfev.append(r.nfev)
    errs = np.array(errs)
    assert np.all(errs < 2000 * np.array(tols)), errs   # global error over ~20 steps of high order
    assert np.all(np.diff(errs) < 0), errs
    assert errs[0] / errs[-1] > 1e5, errs
    assert np.all(np.diff(nfev) > 0)


def test_oscillator_and_backward_kepler():
    r = bulirsch_stoer(oscillator, 0.0, [1.0, 0.0], 10.0, atol=1e-12, args=[W])
    exact = np.stack([np.cos(W * r.t), -W * np.sin(W * r.t)], axis=-1)
    assert np.max(np.abs(r.y - exact)) < 1e-10
    e = 0.5
    y_start = kepler_exact(3.0, e)[0]
    rb = bulirsch_stoer(kepler, 3.0, y_start, -2.5, atol=1e-12, rtol=1e-12)
    assert rb.status == 0 and rb.t[-1] == -2.5 and np.all(np.diff(rb.t) < 0)
    assert np.max(np.abs(rb.y - kepler_exact(rb.t, e))) < 1e-8


def test_lotka_volterra_first_integral():
    a, b, c, d = 1.5, 1.0, 1.0, 3.0
    y0 = np.array([10.0, 5.0])

    def V(y):
        return c * y[..., 0] - d * np.log(y[..., 0]) + b * y[..., 1] - a * np.log(y[..., 1])

    for tol, bound in [(1e-8, 1e-5), (1e-12, 1e-9)]:
        r = bulirsch_stoer(lotka_volterra, 0.0, y0, 15.0, atol=tol, rtol=tol, args=[a, b, c, d])
        assert r.status == 0
        assert np.max(np.abs(V(r.y) - V(y0))) < bound


@settings(max_examples=20, deadline=None)
@given(n=st.integers(1, 5), seed=st.integers(0, 2**32 - 1), T=st.floats(0.1, 3.0),
       backward=st.booleans())
def test_random_linear_systems_against_expm(n, seed, T, backward):
    """At every step."""
    A, y0 = random_linear(n, seed)
    r = bulirsch_stoer(linear, 0.0, y0, -T if backward else T, atol=1e-11, rtol=1e-11, args=A.ravel())
    assert_matches_expm(r, A, y0, T)


def test_final_only_output():
    e = 0.5
    y0 = kepler_y0(e)
    r = bulirsch_stoer(kepler, 0.0, y0, 2 * np.pi, atol=1e-10)
    rf = bulirsch_stoer(kepler, 0.0, y0, 2 * np.pi, atol=1e-10, t_eval="final")
    assert rf.t.shape == (1,) and rf.y.shape == (1, 4)
    np.testing.assert_array_equal(rf.y[0], r.y[-1])
    assert rf.nfev == r.nfev


def test_after_step_hook():
    """ramp: y0' = 1, y1' = y0 with δ added to y0 after every step: y1(t_N) = t_N²/2 + δ Σ k h_k
    exactly (the extrapolated midpoint rule integrates these polynomials exactly)."""
    delta = 0.01
    r = bulirsch_stoer(ramp, 0.0, [0.0, 0.0], 10.0, atol=1e-8, args=[delta], after_step=add_to_first,
                       max_step=0.5)
    assert r.status == 0
    N = r.naccepted
    assert r.n_modified == N
    h = np.diff(r.t)
    assert abs(r.y[-1, 0] - (r.t[-1] + N * delta)) < 1e-12
    assert abs(r.y[-1, 1] - (r.t[-1] ** 2 / 2 + delta * np.sum(np.arange(N) * h))) < 1e-11
    np.testing.assert_allclose(r.y[:, 0], r.t + delta * np.arange(N + 1), atol=1e-12)


def test_failures_terminate_with_status():
    r = bulirsch_stoer(nan_always, 0.0, [0.0], 5.0, atol=1e-8)
    assert r.status == STATUS_NONFINITE and not r.success and "NaN" in r.message
    r = bulirsch_stoer(blow_up, 0.0, [1.0], 2.0, atol=1e-8, rtol=1e-8)
    assert r.status < 0 and r.t[-1] < 1.0 + 1e-6 and r.nsteps < 100_000
    r = bulirsch_stoer(kepler, 0.0, kepler_y0(0.5), 100.0, atol=1e-12, max_steps=5)
    assert r.status == STATUS_MAX_STEPS and r.nsteps == 5 and "max_steps" in r.message


@pytest.mark.parametrize("kwargs, match", [
    (dict(t_eval=[0.0, 1.0]), "t_eval arrays are not supported"),
    (dict(dense=True), "dense output is not implemented"),
    (dict(events=kepler, n_events=1), "events are not implemented"),
    (dict(k_max=3), r"k_max must be an integer in \[4, 12\]"),
    (dict(atol=0.0), "atol must be > 0 where rtol = 0"),
    (dict(rtol=-1.0), "rtol must be >= 0"),
    (dict(y0=[np.nan, 0.0, 0.0, 1.0]), "y0 must be finite"),
    (dict(atol=[1e-8, 1e-8]), "atol must be a scalar or have shape"),
    (dict(max_steps=0), "max_steps must be >= 1"),
    (dict(t_end=np.inf), "t_end must be finite"),
])
def test_invalid_inputs(kwargs, match):
    call = dict(rhs=kepler, t0=0.0, y0=kepler_y0(0.5), t_end=1.0, atol=1e-8)
    call.update(kwargs)
    with pytest.raises(ValueError, match=match):
        bulirsch_stoer(**call)


def test_invalid_function():
    with pytest.raises(TypeError, match="numba-compiled"):
        bulirsch_stoer(lambda t, y, p, d: None, 0.0, [1.0], 1.0, atol=1e-8)


def test_importing_the_integrators_and_the_test_binary_compiles_nothing(cold_python):
    """In a fresh process with an empty numba cache, importing pnrotor.integrate (which imports both integrators)
    and pnrotor.analytic compiles neither driver loop nor the binary's right-hand sides: decorated with their
    signatures, the Bulirsch-Stoer core and the four right-hand sides compiled at import (25.1 s against 3.5 s
    for the two imports on a cold cache, for every `pnrotor verify`, which uses one method and one formulation);
    they are compiled on first use."""
    out = cold_python("import pnrotor.integrate, pnrotor.analytic as a\n"
                      "from pnrotor.ode.bulirsch_stoer import core as bs_core\n"
                      "from pnrotor.ode.dop853 import core as dop853_core\n"
                      "print(len(bs_core.overloads), len(dop853_core.overloads),\n"
                      "      sum(len(f.overloads) for f in a._RHS.values()))\n")
    assert out.split() == ["0", "0", "0"], out


def test_the_first_bulirsch_stoer_run_waits_for_no_dop853_compile(cold_python):
    """The CLI may compile the DOP853 core in another process (numba_cache.compile_aside); the first use of that core
    waits for it, the first Bulirsch-Stoer run (another core) did too (a review)."""
    out = cold_python("from pnrotor import numba_cache\n"
                      "waited = []\n"
                      "numba_cache.wait_for_aside = waited.append\n"
                      "from numba import njit\n"
                      "from pnrotor.ode import RHS_SIG, bulirsch_stoer, dop853\n"
                      "@njit(RHS_SIG)\n"
                      "def decay(t, y, p, dydt):\n"
                      "    dydt[0] = -y[0]\n"
                      "bulirsch_stoer(decay, 0.0, [1.0], 1.0, atol=1e-8)\n"
                      "print(waited)\n"
                      "dop853(decay, 0.0, [1.0], 1.0, atol=1e-8)\n"
                      "print(waited)\n", timeout=900)
    assert out.split("\n")[:2] == ["[]", "['core']"], out
