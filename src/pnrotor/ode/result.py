r"""Result type of the ODE integrators and the DOP853 dense output.

This module owns

* :class:`OdeResult` — what :func:`pnrotor.ode.dop853` and :func:`pnrotor.ode.bulirsch_stoer`
  return (output times and states, counters, status code and message, event data, dense output);
* the status codes (``STATUS_*``) shared by both integrators;
* :class:`DenseOutput` — the piecewise 7th-order continuous extension of DOP853 over all accepted
  steps, and the numba kernel :func:`contd8` that evaluates one step's interpolant.

The interpolant of one step from (t₀, y₀) to (t₀ + h, y₁) is Hairer's ``contd8`` (Hairer, Nørsett &
Wanner, *Solving ODEs I*, 2nd ed., Sec. II.6 (dense output) and II.10, and the DOP853 code): with
θ = (t − t₀)/h and θ' = 1 − θ,

    y(t) = r₁ + θ(r₂ + θ'(r₃ + θ(r₄ + θ'(r₅ + θ(r₆ + θ'(r₇ + θ r₈)))))),

where r₁..r₈ are the eight coefficient vectors stored per step (see :mod:`pnrotor.ode.tableau`).
It is exact at both ends (θ = 0 gives y₀, θ = 1 gives y₁ up to one rounding) and of order 7.
"""

import numpy as np
from numba import njit

# --------------------------------------------------------------------------------------------------
# status codes
# --------------------------------------------------------------------------------------------------

STATUS_SUCCESS = 0
"""The integration reached ``t_end``."""
STATUS_EVENT = 1
"""A terminal event occurred; the integration stopped at ``t_event``."""
STATUS_MAX_STEPS = -1
"""``max_steps`` step attempts were made before reaching ``t_end``."""
STATUS_STEP_UNDERFLOW = -2
"""The step size fell below 10 units in the last place of t (the error test could not be met)."""
STATUS_NONFINITE = -3
"""The state or its derivative became NaN or infinite."""

STATUS_MESSAGES = {
    STATUS_SUCCESS: "The integration reached t_end.",
    STATUS_EVENT: "A terminal event occurred.",
    STATUS_MAX_STEPS: "Reached max_steps step attempts before t_end.",
    STATUS_STEP_UNDERFLOW: "Required step size is less than 10 units in the last place of t.",
    STATUS_NONFINITE: "The state or the right-hand side became NaN or infinite.",
}


# --------------------------------------------------------------------------------------------------
# result
# --------------------------------------------------------------------------------------------------


class OdeResult:
    """Result of an integration.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Output times (every accepted step including t0, the requested ``t_eval``, or the final time
        only — see the integrator's ``t_eval``).
    y : ndarray, shape (N, n)
        States at ``t`` (row i is y(t[i])).
    nfev : int
        Right-hand-side evaluations, including the initial-step estimate, FSAL re-evaluations after
        ``after_step`` modified the state, and the extra stages of the dense output.
    nsteps : int
        Attempted steps (accepted + rejected).
    naccepted, nrejected : int
        Accepted and rejected steps.
    n_modified : int
        Accepted steps after which ``after_step`` reported that it modified the state.
    status : int
        ``0`` reached t_end, ``1`` terminal event, ``-1`` max_steps reached, ``-2`` step-size
        underflow, ``-3`` non-finite state or derivative (see the ``STATUS_*`` constants).
    message : str
        Human-readable description of the status, with the time at which a failure happened.
    success : bool
        ``status >= 0``.
    t_event : float or None
        Time of the terminal event (``status == 1``), else None.
    y_event : ndarray (n,) or None
        State at ``t_event`` (from the dense interpolant), else None.
    event_index : int or None
        Index of the event function that triggered, else None.
    dense : DenseOutput or None
        Continuous solution over [t0, t_final] when ``dense=True`` was requested.
    method : str
        ``"DOP853"`` or ``"Bulirsch-Stoer"``.
    """

    __slots__ = (
        "t", "y", "nfev", "nsteps", "naccepted", "nrejected", "n_modified", "status", "message",
        "t_event", "y_event", "event_index", "dense", "method",
    )

    def __init__(self, t, y, nfev, nsteps, naccepted, nrejected, n_modified, status, message,
                 t_event=None, y_event=None, event_index=None, dense=None, method=""):
        self.t = t
        self.y = y
        self.nfev = int(nfev)
        self.nsteps = int(nsteps)
        self.naccepted = int(naccepted)
        self.nrejected = int(nrejected)
        self.n_modified = int(n_modified)
        self.status = int(status)
        self.message = message
        self.t_event = t_event
        self.y_event = y_event
        self.event_index = event_index
        self.dense = dense
        self.method = method

    @property
    def success(self):
        """True if the integration reached t_end or stopped at a terminal event."""
        return self.status >= 0

    def __repr__(self):
        ev = "" if self.t_event is None else f", t_event={self.t_event!r}, event_index={self.event_index}"
        return (f"OdeResult(method={self.method!r}, status={self.status}, message={self.message!r}, "
                f"len(t)={len(self.t)}, nfev={self.nfev}, nsteps={self.nsteps}, "
                f"naccepted={self.naccepted}, nrejected={self.nrejected}, n_modified={self.n_modified}{ev})")


# --------------------------------------------------------------------------------------------------
# dense output
# --------------------------------------------------------------------------------------------------


@njit(cache=True, fastmath={'contract'})
def contd8(rc, theta, out):
    """Evaluate one step's DOP853 interpolant at θ = (t − t₀)/h into ``out``.

    ``rc`` is the (8, n) array of coefficient vectors r₁..r₈ of that step.
    """
    th1 = 1.0 - theta
    for i in range(out.size):
        out[i] = rc[0, i] + theta * (rc[1, i] + th1 * (rc[2, i] + theta * (rc[3, i] + th1 * (
            rc[4, i] + theta * (rc[5, i] + th1 * (rc[6, i] + theta * rc[7, i]))))))


@njit(cache=True)   # compiled on first use (at import it cost every process 0.3 s on a cold cache)
def _dense_eval(seg_t, seg_h, coef, direction, tq, out):
    """Evaluate the piecewise interpolant at the times ``tq`` into the rows of ``out``.

    Segment i covers [seg_t[i], seg_t[i] + seg_h[i]] in the direction of integration; a time on a
    boundary between two segments is evaluated on the later one (right-continuous).
    """
    nseg = seg_t.size
    for q in range(tq.size):
        s = direction * tq[q]
        # binary search: last segment whose start is <= t (in the direction of integration)
        lo = 0
        hi = nseg - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if direction * seg_t[mid] <= s:
                lo = mid
            else:
                hi = mid - 1
        theta = (tq[q] - seg_t[lo]) / seg_h[lo]
        contd8(coef[lo], theta, out[q])


class DenseOutput:
    """Continuous DOP853 solution over [t_min, t_max]: one 7th-order interpolant per accepted step.

    Call it with a scalar time (returns shape (n,)) or an array of times (returns shape (len(t), n)).
    Times outside the integrated interval raise ValueError.  At a boundary between two steps the
    later step's interpolant is used, i.e. the value is the state the next step started from.

    If ``after_step`` modified the state after a step, that step's interpolant joins the states
    *before* the modification (the next one starts from the modified state), so the output has a
    jump there, exactly where the integrator's state jumped.

    Attributes: ``t_min``, ``t_max`` (in the order of integration: t_min = t0), ``ts`` (step start
    times plus the final time), ``seg_h`` (step sizes), ``coef`` (nseg, 8, n).
    """

    def __init__(self, seg_t, seg_h, coef, t_final):
        self.seg_t = np.ascontiguousarray(seg_t, dtype=np.float64)
        self.seg_h = np.ascontiguousarray(seg_h, dtype=np.float64)
        self.coef = np.ascontiguousarray(coef, dtype=np.float64)
        if self.seg_t.size == 0:
            raise ValueError("DenseOutput needs at least one step")
        self.t_min = float(self.seg_t[0])
        self.t_max = float(t_final)
        self.direction = 1.0 if self.seg_h[0] > 0 else -1.0
        self.n = self.coef.shape[2]

    @property
    def ts(self):
        """Step boundaries: the start of every step followed by the final time."""
        return np.append(self.seg_t, self.t_max)

    def __call__(self, t):
        t_arr = np.asarray(t, dtype=np.float64)
        scalar = t_arr.ndim == 0
        tq = np.ascontiguousarray(t_arr.reshape(-1))
        if not np.all(np.isfinite(tq)):
            raise ValueError("DenseOutput: t must be finite")
        lo, hi = min(self.t_min, self.t_max), max(self.t_min, self.t_max)
        if tq.size and (tq.min() < lo or tq.max() > hi):
            raise ValueError(f"DenseOutput: t must lie in the integrated interval [{lo!r}, {hi!r}]")
        out = np.empty((tq.size, self.n))
        _dense_eval(self.seg_t, self.seg_h, self.coef, self.direction, tq, out)
        if scalar:
            return out[0]
        return out.reshape(t_arr.shape + (self.n,))

    def __repr__(self):
        return f"DenseOutput(t_min={self.t_min!r}, t_max={self.t_max!r}, steps={self.seg_t.size}, n={self.n})"
