"""Right-hand sides, hooks and exact solutions shared by the tests of pnrotor.ode (DOP853 and
Bulirsch–Stoer) and by benchmarks/bench_ode.py: each problem once, with its exact answer."""

import math

import numpy as np
from numba import njit

from pnrotor.ode import AFTER_STEP_SIG, EVENTS_SIG, RHS_SIG


@njit(RHS_SIG, cache=True)
def kepler(t, y, p, dydt):
    r2 = y[0] * y[0] + y[1] * y[1]
    r3 = r2 * math.sqrt(r2)
    dydt[0] = y[2]
    dydt[1] = y[3]
    dydt[2] = -y[0] / r3
    dydt[3] = -y[1] / r3


@njit(RHS_SIG, cache=True)
def lotka_volterra(t, y, p, dydt):
    dydt[0] = p[0] * y[0] - p[1] * y[0] * y[1]
    dydt[1] = p[2] * y[0] * y[1] - p[3] * y[1]


@njit(RHS_SIG, cache=True)
def oscillator(t, y, p, dydt):
    """y'' = −w² y with w = p[0]; solution y = cos(w t), y' = −w sin(w t) from (1, 0)."""
    dydt[0] = y[1]
    dydt[1] = -p[0] * p[0] * y[0]


@njit(RHS_SIG, cache=True)
def linear(t, y, p, dydt):
    """y' = A y with A = p reshaped to (n, n), row-major."""
    n = y.size
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += p[i * n + j] * y[j]
        dydt[i] = s


@njit(RHS_SIG, cache=True)
def ramp(t, y, p, dydt):
    """y0' = 1, y1' = y0: polynomial solutions, integrated exactly by an order-8 method."""
    dydt[0] = 1.0
    dydt[1] = y[0]


@njit(RHS_SIG, cache=True)
def nan_after_one(t, y, p, dydt):
    dydt[0] = 1.0 if t <= 1.0 else math.nan


@njit(RHS_SIG, cache=True)
def nan_always(t, y, p, dydt):
    dydt[0] = math.nan


@njit(RHS_SIG, cache=True)
def blow_up(t, y, p, dydt):
    """y' = y², y(0) = 1: y = 1/(1 − t) blows up at t = 1."""
    dydt[0] = y[0] * y[0]


@njit(AFTER_STEP_SIG, cache=True)
def add_to_first(t, y, p):
    """Add p[0] to y[0] after every accepted step."""
    y[0] += p[0]
    return True


@njit(AFTER_STEP_SIG, cache=True)
def never_modify(t, y, p):
    return False


@njit(EVENTS_SIG, cache=True)
def osc_events(t, y, p, g):
    g[0] = y[0] - 0.5   # position crosses 1/2
    g[1] = y[1]         # velocity crosses 0 (it is exactly 0 at t0 = 0)


@njit(EVENTS_SIG, cache=True)
def two_close_levels(t, y, p, g):
    g[0] = y[0] - 0.49
    g[1] = y[0] - 0.5


def kepler_exact(t, e):
    """Kepler orbit with a = GM = 1 starting at pericentre: (x, y, vx, vy) at times t."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    M = np.mod(t, 2 * np.pi)
    E = M + e * np.sin(M)
    for _ in range(60):
        E = E - (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
    Edot = 1.0 / (1 - e * np.cos(E))
    b = np.sqrt(1 - e * e)
    return np.stack([np.cos(E) - e, b * np.sin(E), -np.sin(E) * Edot, b * np.cos(E) * Edot], axis=-1)


def kepler_y0(e):
    return np.array([1 - e, 0.0, 0.0, np.sqrt((1 + e) / (1 - e))])


W = 2.0


def osc_exact(t):
    t = np.asarray(t, dtype=float)
    return np.stack([np.cos(W * t), -W * np.sin(W * t)], axis=-1)


def random_linear(n, seed):
    """A random n×n matrix A and initial state y0, entries uniform in [−1, 1]."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, (n, n)), rng.uniform(-1, 1, n)


def assert_matches_expm(r, A, y0, T):
    """Every output (t, y) of the successful result r of y' = A y (``linear``) equals expm(A t) y0 to 1e-8
    times the growth bound of errors, e^{‖A‖∞ T}."""
    from scipy.linalg import expm

    assert r.status == 0
    scale = np.exp(np.abs(A).sum(axis=1).max() * T)
    for tk, yk in zip(r.t, r.y):
        np.testing.assert_allclose(yk, expm(A * tk) @ y0, rtol=0, atol=1e-8 * scale)
