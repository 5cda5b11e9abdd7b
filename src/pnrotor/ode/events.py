r"""Terminal events of the ODE solvers: whether an event function crossed zero over a step, and where, on the
step's dense interpolant.

An event j of ``events(t, y, p, g)`` (:data:`~pnrotor.ode.common.EVENTS_SIG`) triggers over a step when gⱼ changes
sign between its ends in the event's direction (:func:`crossed`).  Its root is located on the step's interpolant in
Hairer's ``contd8`` form (:func:`pnrotor.ode.result.contd8`: eight coefficient vectors rc per step) with Brent's
method (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 4) to a few ulp of t
(:func:`locate_root`).  The DOP853 core calls both for its events, and :func:`pnrotor.evolve_many` for the nearer
targets it finds on a run's dense output (``pnrotor.pn.many._nearer_targets``).
"""

import numpy as np
from numba import njit

from .result import contd8

_EPS = np.finfo(np.float64).eps


@njit(cache=True)
def _event_value(events, p, j, t, t_old, h, rc, yint, gtmp):
    """Event j at t on the interpolant rc of the step from t_old of size h (``contd8``); yint, gtmp: scratch."""
    contd8(rc, (t - t_old) / h, yint)
    events(t, yint, p, gtmp)
    return gtmp[j]


@njit(cache=True, inline="always")
def crossed(g_old, g_new, direction):
    """Whether an event went from g_old to g_new across zero in its direction (> 0 upward only,
    < 0 downward only, 0 either): from below to ≥ 0, or from above to ≤ 0."""
    return ((g_old < 0.0 and g_new >= 0.0 and direction >= 0.0)
            or (g_old > 0.0 and g_new <= 0.0 and direction <= 0.0))


@njit(cache=True)
def locate_root(events, p, j, ta, tb, ga, gb, t_old, h, rc, yint, gtmp):
    """Root of event j on the step's interpolant between ta (value ga) and tb (value gb, of the
    opposite sign or zero), by Brent's method (inverse quadratic interpolation, secant, bisection).
    Returns t with |t − t*| ≲ 2 ulp(t) + 2 eps |h|.
    """
    a = ta
    b = tb
    fa = ga
    fb = gb
    if fb == 0.0:
        return b
    c = a
    fc = fa
    d = b - a
    e = d
    tol_abs = 4.0 * _EPS * abs(h)
    for _ in range(300):
        if (fb > 0.0) == (fc > 0.0):
            # b and c on the same side: take the bracket end from a
            c = a
            fc = fa
            d = b - a
            e = d
        if abs(fc) < abs(fb):
            a = b
            b = c
            c = a
            fa = fb
            fb = fc
            fc = fa
        tol1 = 2.0 * _EPS * abs(b) + 0.5 * tol_abs
        xm = 0.5 * (c - b)
        if abs(xm) <= tol1 or fb == 0.0:
            return b
        if abs(e) >= tol1 and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:
                pp = 2.0 * xm * s
                q = 1.0 - s
            else:
                qq = fa / fc
                r = fb / fc
                pp = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0))
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0)
            if pp > 0.0:
                q = -q
            else:
                pp = -pp
            if 2.0 * pp < min(3.0 * xm * q - abs(tol1 * q), abs(e * q)):
                e = d
                d = pp / q
            else:
                d = xm
                e = d
        else:
            d = xm
            e = d
        a = b
        fa = fb
        if abs(d) > tol1:
            b += d
        elif xm > 0.0:
            b += tol1
        else:
            b -= tol1
        fb = _event_value(events, p, j, b, t_old, h, rc, yint, gtmp)
    return b
