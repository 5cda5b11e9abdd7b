"""Where an inspiral ends: the first v at which the events of the PN system's end (1, 2, 5, 6: :mod:`pnrotor.pn.rhs`)
reach zero, below a run's start (:func:`earlier_end`, compiled, on the run's own events function) or at fixed spins
from low frequency (:func:`inspiral_end`, numpy): the bound on f_ref that a run past the end is refused with.
"""

import math

import numpy as np
from numba import njit

from ..ode.common import events_function
from .vdot import vdot_series
from .layout import DEN_EPS, EV_ENERGY, EV_POLE, EV_VDOT, EV_VDOT_PEAK, N_EVENTS, Y_V
from .rhs import vdot_peak
from .series import evaluate, v_derivative

_SCAN_FROM, _SCAN_STEP = 0.05, 0.045
"""The grid below v₀ on which :func:`earlier_end` looks for an end of the inspiral: from v = 0.05 in steps of
~0.045 in ln v (4.6% in v)."""


@njit(cache=True)
def earlier_end(c_addr, jit_addr, y0, p):
    """The first v below v₀ = y0[0] where event 1, 2, 5 or 6 of the system's events function (its addresses, as
    :data:`pnrotor.ode.common.FUNCTIONS_LAYOUT` gives them) at the state y0 with that v reaches zero, or 0.0: a v₀
    beyond it lies past the end of the inspiral even where the events are positive again at v₀ (a review found
    f_ref = 1000 Hz accepted for an aligned 30 + 10 M☉ binary whose inspiral ends at 455 Hz, while 600 Hz was
    refused).  Found on a geometric grid from 0.05 to v₀ (:data:`_SCAN_STEP`: a band of failing events narrower
    than 4.6% in v can be missed, as :func:`inspiral_end`'s finer grid can miss narrower ones) and refined by
    bisection to 1e-12.  The events are the run's own compiled function, called by address: one small kernel for
    every system."""
    v0 = y0[Y_V]
    if not v0 > _SCAN_FROM:
        return 0.0
    g = events_function(c_addr, jit_addr)
    y = y0.copy()
    values = np.empty(N_EVENTS)
    points = math.ceil(math.log(v0 / _SCAN_FROM) / _SCAN_STEP)
    ratio = (v0 / _SCAN_FROM) ** (1.0 / points)
    lo = hi = _SCAN_FROM
    for _ in range(points):
        if _past_end(g, y, p, values, hi):
            while lo < hi and hi - lo > 1e-12:   # lo passed (or is the grid's first point)
                mid = 0.5 * (lo + hi)
                if _past_end(g, y, p, values, mid):
                    hi = mid
                else:
                    lo = mid
            return hi
        lo, hi = hi, hi * ratio
    return 0.0


@njit(cache=True)
def _past_end(events, y, p, values, v):
    """Whether event 1, 2, 5 or 6 of ``events`` at the state y with y[0] set to v is ≤ 0."""
    y[Y_V] = v
    events(0.0, y, p, values)
    return not (values[EV_ENERGY] > 0.0 and values[EV_VDOT] > 0.0 and values[EV_POLE] > 0.0
                and values[EV_VDOT_PEAK] > 0.0)



def inspiral_end(X1, approximant, kmax, basis, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """The smallest v at which one of the events 1, 2, 5, 6 (module docstring) reaches zero with the spin
    invariants fixed at ``basis``: where an inspiral from low frequency ends (for precessing spins, as far
    as the spins at the start decide it), or 1.0 if none does below v = 1.  Found on a grid of 2000 values
    of v in [10⁻³, 1] and refined by bisection to 1e-12."""
    N, D, Ep = vdot_series(X1, approximant, kmax, kappa1, kappa2, lambda1, lambda2)
    Nv, Dv = v_derivative(N), v_derivative(D)

    def smallest(v):
        n, d = evaluate(N, v, basis), evaluate(D, v, basis)
        peak = vdot_peak.py_func(n, d, evaluate(Nv, v, basis), evaluate(Dv, v, basis))   # on arrays of v
        return np.minimum.reduce([evaluate(Ep, v, basis), n * d, d - DEN_EPS, peak])

    v = np.geomspace(1e-3, 1.0, 2000)
    bad = np.flatnonzero(smallest(v) <= 0.0)
    if bad.size == 0:
        return 1.0
    if bad[0] == 0:
        return v[0]
    lo, hi = v[bad[0] - 1], v[bad[0]]
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if smallest(np.array([mid]))[0] <= 0.0 else (mid, hi)
    return hi
