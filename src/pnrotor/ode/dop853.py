r"""DOP853: Dormand–Prince explicit Runge–Kutta 8(5,3) integrator in numba.

This module owns, as the solver protocol of :mod:`pnrotor.ode.common` asks,

* the DOP853 stepper, step-size controller, dense output and driver loop, all in one ``@njit`` function
  compiled for one explicit signature (:func:`core`, ``CORE_SIG``) on first use, so that it is compiled once per
  machine and loaded from numba's cache afterwards, whatever right-hand side is passed; its events are located by
  :mod:`pnrotor.ode.events`;
* the Python entry point :func:`dop853` (its checks and result assembly are :mod:`pnrotor.ode.common`'s), and
  :func:`run_core`, the same without the checks.

Algorithms (Hairer, Nørsett & Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
Springer 1993, Sec. II.4 (step-size control, initial step), II.6 (dense output), II.10 (DOP853), and
Hairer's published DOP853 Fortran code; coefficients in :mod:`pnrotor.ode.tableau`):

* One step: the 12-stage 8th-order formula y₁ = y₀ + h Σ bⱼ kⱼ; the next step's first stage is
  f(t₀ + h, y₁) (FSAL), evaluated only for accepted steps, so a step costs 11 evaluations plus one
  if accepted.
* Compensated summation of the solution (Kahan; Hairer, Lubich & Wanner, *Geometric Numerical
  Integration*, Sec. VIII.5): the state is carried as y + yc, the update y₁ + yc₁ = y₀ + (h Σ bⱼ kⱼ + yc₀)
  by Knuth's TwoSum, so the rounding of y₀ + increment, ~ulp(y) per step, does not accumulate (for an
  inspiral with Φ ~ 10⁴ rad it set a floor of ~1e-9 rad on the phase, benchmarks/bench_pn_precision.py).
  The stages, error estimate, dense output and outputs use y; the time needs no compensation, since
  h = t₁ − t₀ is the exact difference of the two representable times.
* Error: err5 = Σ E5ⱼ kⱼ, err3 = Σ E3ⱼ kⱼ, scaled componentwise by
  scᵢ = atolᵢ + rtolᵢ · max(|y₀ᵢ|, |y₁ᵢ|), and combined as
  err = |h| · ‖err5‖² / √(n (‖err5‖² + 0.01 ‖err3‖²)) with ‖·‖² the sum of squares (Hairer's form;
  equal to the RMS form used by scipy).  The step is accepted if err < 1.
* Controller: h_new = h · clip(safety · err^(−1/8), min_factor, max_factor) (err = 0 gives
  max_factor); after a rejection within the same step the factor is capped at 1.  Defaults are
  Hairer's (safety 0.9, fac1 = 1/3, fac2 = 6); scipy uses 0.9, 0.2, 10.  The step size is clipped to
  max_step and so that the last step ends exactly on t_end.  A step below 10 ulp(t) is a failure.
* Initial step: Hairer's automatic choice (Sec. II.4, "starting step size") with RMS norms and
  exponent 1/8, the same algorithm as scipy's ``select_initial_step`` for this method
  (:func:`pnrotor.ode.common.select_initial_step`).
* Dense output: Hairer's 7th-order continuous extension (three extra stages, ``contd8``), computed
  only on steps where it is needed (t_eval points inside the step, ``dense=True``, or an event).
* Events: sign changes of g between the ends of an accepted step (respecting the requested
  direction) are located on the dense interpolant with Brent's method (R. P. Brent, *Algorithms
  for Minimization without Derivatives*, 1973, ch. 4) to a few ulp of t (:mod:`pnrotor.ode.events`); all events
  are terminal.

Floating point: the stage and interpolation sums are compiled with ``fastmath={'contract'}``, i.e.
LLVM may fuse a·b + c into one FMA instruction (halves the arithmetic of a step; results then differ
from an unfused evaluation by rounding only).  No other fast-math flag is used.

The right-hand side and hooks reach the core by the addresses of their compiled code (:mod:`pnrotor.ode.common`).
"""

import math

import numpy as np
from numba import njit, types

from . import tableau as _tab
from .common import (A1, A2, A3, B1, EVENTS_SIG, F8, FV_H, FV_T, FV_TEVENT, FV_TFAIL, I1, I8, IV_EVENT, IV_NACC,
                     IV_NANREJ, IV_NFEV, IV_NMOD, IV_NOUT, IV_NREJ, IV_NSEG, IV_NSTEPS, IV_STATUS, OUT_FINAL, OUT_STEPS,
                     OUT_TEVAL, after_step_function, all_finite, append_row, assemble_result, common_inputs,
                     controller, entry_point, event_inputs, events_function, function_addresses, rhs_function, scaled,
                     select_initial_step, trivial_result)
from .events import crossed, locate_root
from .result import (STATUS_EVENT, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW, STATUS_SUCCESS,
                     DenseOutput, contd8)


def compile_core():
    """Compile the DOP853 core into numba's cache (or load it): what :func:`pnrotor.numba_cache.compile_aside`
    runs in another process (as ``'core'``, which :func:`~pnrotor.ode.common.entry_point` awaits in this one)."""
    entry_point(core, CORE_SIG, "core")


def compile_core_parts():
    """Compile two callees of the DOP853 core into numba's cache (or load them), for the types the core calls them
    with: what a process that started :func:`compile_core` in another one (the CLI on a cold cache,
    :func:`pnrotor.numba_cache.compile_aside`) does first.  That process meets them last, ~7-9 s into the core's
    compile, and loads them from the cache instead of compiling them, ~2 s less of its work: without this its
    compile ended ~4-5 s after everything else of a cold run had compiled (numba's compile events of both processes,
    a cold ``pnrotor evolve``).  Only a saving: if it fails, the core's process compiles them as before."""
    try:
        locate_root.compile((types.FunctionType(EVENTS_SIG), A1, I8, F8, F8, F8, F8, F8, F8, A2, A1, A1))
        _append_segment.compile((A1, A1, A3, I8, F8, F8, A2))
    except Exception:  # pragma: no cover - numba internals changed
        pass


# --------------------------------------------------------------------------------------------------
# numba kernels (compiled into the core)
# --------------------------------------------------------------------------------------------------

_C = _tab.C
_A = _tab.A
_B = _tab.B
_E5 = _tab.E5
_D = _tab.D
_BHH0 = _tab.B[0] - _tab.E3[0]
_BHH8 = _tab.B[8] - _tab.E3[8]
_BHH11 = _tab.B[11] - _tab.E3[11]
_EXPO = _tab.ERROR_EXPONENT


@njit(cache=True)
def _copy(dst, src):
    """dst[:] = src for 1-D arrays, as a plain loop (cheaper to compile than slice assignment)."""
    for i in range(src.size):
        dst[i] = src[i]



@njit(cache=True)
def _append_segment(seg_t, seg_h, seg_c, nseg, t, h, rc):
    """Store one step's dense-output coefficients, doubling the buffers when full."""
    n = rc.shape[1]
    if nseg == seg_t.size:
        cap = 2 * nseg
        new_t = np.empty(cap)
        new_h = np.empty(cap)
        new_c = np.empty((cap, 8, n))
        for k in range(nseg):
            new_t[k] = seg_t[k]
            new_h[k] = seg_h[k]
            for r in range(8):
                for i in range(n):
                    new_c[k, r, i] = seg_c[k, r, i]
        seg_t = new_t
        seg_h = new_h
        seg_c = new_c
    seg_t[nseg] = t
    seg_h[nseg] = h
    for r in range(8):
        for i in range(n):
            seg_c[nseg, r, i] = rc[r, i]
    return seg_t, seg_h, seg_c, nseg + 1


@njit(cache=True, fastmath={'contract'})
def _dop853_step(rhs, t, y, yc, h, p, K, ys, ynew, ycnew, atol, rtol):
    """One DOP853 step from (t, y) with step h; K[0] must hold f(t, y).

    Fills K[1..11] and ynew + ycnew = y + yc + h Σ bⱼ kⱼ, compensated (module docstring); returns the
    error norm err (< 1: accept).
    The FSAL stage K[12] = f(t + h, ynew) is not evaluated here.  The stages are read as K[j, i], not
    through row views kⱼ = K[j]: the views cost ~7 ns each per step (per-step overhead over the bare 12
    evaluations on Kepler 340 → 235 ns, benchmarks/bench_ode.py; same results bitwise).
    """
    n = y.size
    A = _A
    C = _C
    for i in range(n):
        ys[i] = y[i] + h * (A[1, 0] * K[0, i])
    rhs(t + C[1] * h, ys, p, K[1])
    for i in range(n):
        ys[i] = y[i] + h * (A[2, 0] * K[0, i] + A[2, 1] * K[1, i])
    rhs(t + C[2] * h, ys, p, K[2])
    for i in range(n):
        ys[i] = y[i] + h * (A[3, 0] * K[0, i] + A[3, 2] * K[2, i])
    rhs(t + C[3] * h, ys, p, K[3])
    for i in range(n):
        ys[i] = y[i] + h * (A[4, 0] * K[0, i] + A[4, 2] * K[2, i] + A[4, 3] * K[3, i])
    rhs(t + C[4] * h, ys, p, K[4])
    for i in range(n):
        ys[i] = y[i] + h * (A[5, 0] * K[0, i] + A[5, 3] * K[3, i] + A[5, 4] * K[4, i])
    rhs(t + C[5] * h, ys, p, K[5])
    for i in range(n):
        ys[i] = y[i] + h * (A[6, 0] * K[0, i] + A[6, 3] * K[3, i] + A[6, 4] * K[4, i] + A[6, 5] * K[5, i])
    rhs(t + C[6] * h, ys, p, K[6])
    for i in range(n):
        ys[i] = y[i] + h * (A[7, 0] * K[0, i] + A[7, 3] * K[3, i] + A[7, 4] * K[4, i] + A[7, 5] * K[5, i]
                            + A[7, 6] * K[6, i])
    rhs(t + C[7] * h, ys, p, K[7])
    for i in range(n):
        ys[i] = y[i] + h * (A[8, 0] * K[0, i] + A[8, 3] * K[3, i] + A[8, 4] * K[4, i] + A[8, 5] * K[5, i]
                            + A[8, 6] * K[6, i] + A[8, 7] * K[7, i])
    rhs(t + C[8] * h, ys, p, K[8])
    for i in range(n):
        ys[i] = y[i] + h * (A[9, 0] * K[0, i] + A[9, 3] * K[3, i] + A[9, 4] * K[4, i] + A[9, 5] * K[5, i]
                            + A[9, 6] * K[6, i] + A[9, 7] * K[7, i] + A[9, 8] * K[8, i])
    rhs(t + C[9] * h, ys, p, K[9])
    for i in range(n):
        ys[i] = y[i] + h * (A[10, 0] * K[0, i] + A[10, 3] * K[3, i] + A[10, 4] * K[4, i] + A[10, 5] * K[5, i]
                            + A[10, 6] * K[6, i] + A[10, 7] * K[7, i] + A[10, 8] * K[8, i] + A[10, 9] * K[9, i])
    rhs(t + C[10] * h, ys, p, K[10])
    for i in range(n):
        ys[i] = y[i] + h * (A[11, 0] * K[0, i] + A[11, 3] * K[3, i] + A[11, 4] * K[4, i] + A[11, 5] * K[5, i]
                            + A[11, 6] * K[6, i] + A[11, 7] * K[7, i] + A[11, 8] * K[8, i] + A[11, 9] * K[9, i]
                            + A[11, 10] * K[10, i])
    rhs(t + C[11] * h, ys, p, K[11])

    B = _B
    E5 = _E5
    err5 = 0.0
    err3 = 0.0
    for i in range(n):
        bk = (B[0] * K[0, i] + B[5] * K[5, i] + B[6] * K[6, i] + B[7] * K[7, i] + B[8] * K[8, i]
              + B[9] * K[9, i] + B[10] * K[10, i] + B[11] * K[11, i])
        d = h * bk + yc[i]
        yn = y[i] + d
        r = yn - y[i]   # TwoSum (Knuth): yn + the rounding error of y + d, exactly
        ycnew[i] = (y[i] - (yn - r)) + (d - r)
        ynew[i] = yn
        sc = atol[i] + rtol[i] * max(abs(y[i]), abs(yn))
        e3 = bk - _BHH0 * K[0, i] - _BHH8 * K[8, i] - _BHH11 * K[11, i]
        e5 = (E5[0] * K[0, i] + E5[5] * K[5, i] + E5[6] * K[6, i] + E5[7] * K[7, i] + E5[8] * K[8, i]
              + E5[9] * K[9, i] + E5[10] * K[10, i] + E5[11] * K[11, i])
        e3 = scaled(e3, sc)
        e5 = scaled(e5, sc)
        err3 += e3 * e3
        err5 += e5 * e5
    deno = err5 + 0.01 * err3
    if deno <= 0.0:
        deno = 1.0
    return abs(h) * err5 / math.sqrt(n * deno)


@njit(cache=True, fastmath={'contract'})
def _dense_coefficients(rhs, t, y, ynew, h, p, K, ys, rc):
    """Three extra stages K[13..15] and the eight interpolation vectors rc (Hairer's contd8).

    Needs K[0..12] of the accepted step (K[12] = f(t + h, ynew)).
    """
    n = y.size
    A = _A
    for s in range(13, 16):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += A[s, j] * K[j, i]
            ys[i] = y[i] + h * acc
        rhs(t + _C[s] * h, ys, p, K[s])
    D = _D
    for i in range(n):
        dy = ynew[i] - y[i]
        bsp = h * K[0, i] - dy
        rc[0, i] = y[i]
        rc[1, i] = dy
        rc[2, i] = bsp
        rc[3, i] = dy - h * K[12, i] - bsp
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += D[r, j] * K[j, i]
            rc[4 + r, i] = h * acc


CORE_SIG = types.Tuple((A1, A2, A1, A1, A3, I1, A1, A1))(
    I1,                          # functions (FUNCTIONS_LAYOUT)
    F8, A1, F8, A1,              # t0, y0, t_end, p
    A1, A1,                      # atol, rtol (per component)
    F8, F8, I8,                  # first_step (0: automatic), max_step, max_steps
    A1, I8, B1,                  # t_eval, out_mode, want_dense
    I8, A1,                      # n_events, event_direction
    F8, F8, F8,                  # safety, min_factor, max_factor
)


@njit(cache=True)   # compiled for CORE_SIG by entry_point when first needed, not at import
def core(functions, t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps, t_eval, out_mode, want_dense,
         n_events, ev_dir, safety, min_factor, max_factor):
    """The DOP853 driver loop, with its right-hand side and hooks given by address (FUNCTIONS_LAYOUT).
    Returns (t_out, y_out, seg_t, seg_h, seg_coef, ivals, fvals, y_event); the output and dense buffers are
    over-allocated, their used lengths are ivals[IV_NOUT], ivals[IV_NSEG]."""
    rhs = rhs_function(functions[0], functions[1])
    after_step = after_step_function(functions[2], functions[3])
    events = events_function(functions[4], functions[5])
    n = y0.size
    direction = 1.0 if t_end > t0 else -1.0
    K = np.empty((16, n))
    y = y0.copy()
    ynew = np.empty(n)
    yc = np.zeros(n)      # compensation: the state is y + yc (module docstring)
    ycnew = np.empty(n)
    ys = np.empty(n)
    yint = np.empty(n)
    rc = np.empty((8, n))
    m = max(n_events, 1)
    g_old = np.zeros(m)
    g_new = np.zeros(m)
    gtmp = np.zeros(m)
    ivals = np.zeros(10, dtype=np.int64)
    fvals = np.full(4, np.nan)
    y_event = np.full(n, np.nan)

    # output buffers (grown by doubling)
    if out_mode == OUT_STEPS:
        cap = 64
    elif out_mode == OUT_TEVAL:
        cap = max(t_eval.size, 1)
    else:
        cap = 1
    t_out = np.empty(cap)
    y_out = np.empty((cap, n))
    # the counters passed to append_row/_append_segment start as np.int64(0), not 0: a literal 0 makes
    # numba's type inference compile those helpers twice (for Literal[int](0), then int64)
    n_out = np.int64(0)
    k_ev = 0  # next t_eval index
    dcap = 64 if want_dense else 1
    seg_t = np.empty(dcap)
    seg_h = np.empty(dcap)
    seg_c = np.empty((dcap, 8, n))
    nseg = np.int64(0)

    nfev = 0
    nsteps = 0
    nacc = 0
    nrej = 0
    nmod = 0
    status = STATUS_SUCCESS
    event_index = -1
    t_event = np.nan

    t = t0
    rhs(t, y, p, K[0])
    nfev += 1
    if n_events > 0:
        events(t, y, p, g_old)

    # outputs at t0
    if out_mode == OUT_STEPS:
        t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)
    elif out_mode == OUT_TEVAL:
        while k_ev < t_eval.size and t_eval[k_ev] == t:
            t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)
            k_ev += 1

    h_abs = 0.0
    if not all_finite(K[0]):
        status = STATUS_NONFINITE
        fvals[FV_TFAIL] = t
    else:
        if first_step > 0.0:
            h_abs = first_step
        else:
            h_abs = select_initial_step(rhs, t, y, K[0], p, t_end, max_step, 7, atol, rtol, ys, K[1])
            nfev += 1

    while status == STATUS_SUCCESS and direction * (t_end - t) > 0.0:
        min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step

        # ---- attempt steps until one is accepted
        rejected = False
        accepted = False
        t_new = t
        h = 0.0
        while True:
            if not h_abs >= min_step:   # NaN too
                status = STATUS_STEP_UNDERFLOW
                fvals[FV_TFAIL] = t
                break
            if nsteps >= max_steps:
                status = STATUS_MAX_STEPS
                fvals[FV_TFAIL] = t
                break
            h = h_abs * direction
            t_new = t + h
            if direction * (t_new - t_end) > 0.0:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
            nsteps += 1
            err = _dop853_step(rhs, t, y, yc, h, p, K, ys, ynew, ycnew, atol, rtol)
            nfev += 11
            if err < 1.0:
                if err == 0.0:
                    factor = max_factor
                else:
                    factor = min(max_factor, max(min_factor, safety * err ** (-_EXPO)))
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                accepted = True
                break
            # rejected (NaN err counts as rejected: shrink as much as allowed)
            if math.isfinite(err):
                factor = max(min_factor, safety * err ** (-_EXPO))
                ivals[IV_NANREJ] = 0
            else:
                factor = min_factor
                ivals[IV_NANREJ] = 1
            h_abs *= factor
            rejected = True
            nrej += 1
        if not accepted:
            break

        # ---- accepted step from (t, y) to (t_new, ynew)
        nacc += 1
        rhs(t_new, ynew, p, K[12])
        nfev += 1
        if not (all_finite(ynew) and all_finite(K[12])):
            status = STATUS_NONFINITE
            fvals[FV_TFAIL] = t_new
            break

        # events: sign changes between the ends of the step
        ev_j = -1
        if n_events > 0:
            events(t_new, ynew, p, g_new)
            for j in range(n_events):
                if crossed(g_old[j], g_new[j], ev_dir[j]):
                    ev_j = j
                    break

        need_dense = want_dense or ev_j >= 0 or (
            out_mode == OUT_TEVAL and k_ev < t_eval.size and direction * (t_eval[k_ev] - t_new) < 0.0)
        if need_dense:
            _dense_coefficients(rhs, t, y, ynew, h, p, K, ys, rc)
            nfev += 3
            if not all_finite(rc.reshape(rc.size)):
                # a stage of the interpolant left the right-hand side's domain (e.g. past a terminal event of
                # the PN system, where it diverges): the step is rejected, as for a non-finite error, so that no
                # event or sample comes from a non-finite interpolant
                nacc -= 1
                nrej += 1
                ivals[IV_NANREJ] = 1
                h_abs = abs(h) * min_factor
                if h_abs < min_step:
                    status = STATUS_STEP_UNDERFLOW
                    fvals[FV_TFAIL] = t
                    break
                continue
        if want_dense:
            seg_t, seg_h, seg_c, nseg = _append_segment(seg_t, seg_h, seg_c, nseg, t, h, rc)

        if ev_j >= 0:
            # locate every triggered event; keep the earliest
            t_best = t_new
            for j in range(ev_j, n_events):
                if crossed(g_old[j], g_new[j], ev_dir[j]):
                    tr = locate_root(events, p, j, t, t_new, g_old[j], g_new[j], t, h, rc, yint, gtmp)
                    if direction * (tr - t_best) < 0.0 or event_index < 0:
                        t_best = tr
                        event_index = j
            t_event = t_best
            contd8(rc, (t_event - t) / h, y_event)
            if out_mode == OUT_TEVAL:
                while k_ev < t_eval.size and direction * (t_eval[k_ev] - t_event) <= 0.0:
                    contd8(rc, (t_eval[k_ev] - t) / h, y_out[n_out])
                    t_out[n_out] = t_eval[k_ev]
                    n_out += 1
                    k_ev += 1
            t = t_event
            _copy(y, y_event)
            status = STATUS_EVENT
            if out_mode == OUT_STEPS:
                t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)
            break

        # t_eval points strictly inside the step: interpolate
        if out_mode == OUT_TEVAL:
            while k_ev < t_eval.size and direction * (t_eval[k_ev] - t_new) < 0.0:
                contd8(rc, (t_eval[k_ev] - t) / h, y_out[n_out])
                t_out[n_out] = t_eval[k_ev]
                n_out += 1
                k_ev += 1

        # advance; FSAL
        t = t_new
        _copy(y, ynew)
        _copy(yc, ycnew)
        _copy(K[0], K[12])
        if after_step(t, y, p):
            yc[:] = 0.0   # the hook set the state to y
            nmod += 1
            rhs(t, y, p, K[0])
            nfev += 1
            if not (all_finite(y) and all_finite(K[0])):
                status = STATUS_NONFINITE
                fvals[FV_TFAIL] = t
                break
            if n_events > 0:
                events(t, y, p, g_new)
        if n_events > 0:
            _copy(g_old, g_new)

        # outputs at the step end (state after after_step)
        if out_mode == OUT_STEPS:
            t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)
        elif out_mode == OUT_TEVAL:
            while k_ev < t_eval.size and t_eval[k_ev] == t:
                t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)
                k_ev += 1

    if out_mode == OUT_FINAL:
        t_out, y_out, n_out = append_row(t_out, y_out, np.int64(0), t, y)

    ivals[IV_STATUS] = status
    ivals[IV_NFEV] = nfev
    ivals[IV_NSTEPS] = nsteps
    ivals[IV_NACC] = nacc
    ivals[IV_NREJ] = nrej
    ivals[IV_NMOD] = nmod
    ivals[IV_EVENT] = event_index
    ivals[IV_NOUT] = n_out
    ivals[IV_NSEG] = nseg
    fvals[FV_T] = t
    if status == STATUS_EVENT:
        fvals[FV_TEVENT] = t_event
    fvals[FV_H] = h_abs
    return t_out, y_out, seg_t, seg_h, seg_c, ivals, fvals, y_event


def dop853(rhs, t0, y0, t_end, atol, rtol=0.0, args=(), first_step=None, max_step=np.inf,
           max_steps=1_000_000, t_eval=None, dense=False, after_step=None, events=None, n_events=0,
           event_direction=None, safety=0.9, min_factor=1.0 / 3.0, max_factor=6.0):
    """Integrate dy/dt = rhs(t, y, p) from t0 to t_end with DOP853 (explicit Runge–Kutta 8(5,3)).

    Parameters
    ----------
    rhs : numba function
        ``rhs(t, y, p, dydt)`` writing dy/dt into ``dydt``; compile it with
        ``@njit(RHS_SIG, cache=True)``, or ``@njit(cache=True)``: it is then compiled for ``RHS_SIG`` on its
        first use (and cached) instead of at import.
    t0, t_end : float
        Initial and final time; t_end < t0 integrates backward.
    y0 : array_like, shape (n,)
        Initial state (finite).
    atol, rtol : float or array_like (n,)
        Absolute and relative tolerances; the local error of component i is measured against
        atolᵢ + rtolᵢ · max(|y₀ᵢ|, |y₁ᵢ|) in the RMS norm.  ``rtol = 0`` (absolute error control
        only, the default) requires atol > 0; atolᵢ = 0 is allowed where rtolᵢ > 0.
    args : sequence of float
        Parameters, passed to rhs (and hooks) as the contiguous float64 array ``p``.
    first_step : float, optional
        Initial step size (> 0, ≤ |t_end − t0|); default: Hairer's automatic choice.
    max_step : float
        Upper bound on |h| (default inf).
    max_steps : int
        Maximum number of step attempts (accepted + rejected) before giving up (status −1).
    t_eval : None, 'final' or array_like
        ``None``: output every accepted step (including t0).  An array of times sorted in the
        direction of integration within [t0, t_end]: output there, using the 7th-order dense output
        for times inside a step (steps are never shortened to hit them).  ``'final'``: output only
        the final state (t_end, or the event time) — the cheapest mode, no dense output is built.
    dense : bool
        Return a :class:`DenseOutput` covering [t0, t_final] in ``result.dense`` (costs 3 extra
        evaluations per step).
    after_step : numba function, optional
        ``after_step(t, y, p) -> bool`` (``AFTER_STEP_SIG``), called after each accepted step; it may
        modify y in place and must then return True.  The derivative is then re-evaluated at the new
        state (counted in nfev) and the step counted in ``n_modified``.  Outputs at step ends are the
        modified states; the dense interpolant and t_eval points strictly inside a step refer to the
        states before the modification.  Not called at t0 nor at a terminal event.
    events : numba function, optional
        ``events(t, y, p, g)`` (``EVENTS_SIG``) filling g[0..n_events-1].  All events are terminal:
        when some gⱼ changes sign between the ends of an accepted step (from < 0 to ≥ 0 or from > 0
        to ≤ 0, in the order of integration) the root is located on the dense interpolant to a few
        ulp, the integration stops there, and ``t_event``, ``y_event``, ``event_index`` are set
        (earliest root if several).  A g that is exactly 0 at the start of a step (e.g. at t0) does
        not trigger; two sign changes within one step cancel and are not seen.
    n_events : int
        Number of event functions m (≥ 1 when events is given).
    event_direction : None, int or array_like (m,)
        Per event: +1 only increasing crossings (− → +), −1 only decreasing, 0 both (default).
    safety, min_factor, max_factor : float
        Controller: h_new = h · clip(safety · err^(−1/8), min_factor, max_factor), with
        0 < safety ≤ 1, 0 < min_factor < 1 ≤ max_factor.  Defaults are Hairer's DOP853 values
        (0.9, 1/3, 6); scipy's DOP853 uses (0.9, 0.2, 10), with which the two codes take the same
        steps (up to rounding in the error estimate).

    Returns
    -------
    OdeResult
        ``status``: 0 reached t_end, 1 terminal event, −1 max_steps reached, −2 step size underflow,
        −3 non-finite state or derivative.  Outputs up to the failure point are returned.

    Raises
    ------
    ValueError
        Invalid inputs (the message names the parameter and the allowed range).
    TypeError
        rhs/after_step/events not numba-compiled functions of the right signature.
    """
    c = common_inputs(rhs, t0, y0, t_end, atol, rtol, args, first_step, max_step, max_steps, t_eval, after_step)
    safety, min_factor, max_factor = controller(safety, min_factor, max_factor)
    events_f, n_events, ev_dir = event_inputs(events, n_events, event_direction)
    dense = bool(dense)
    if c.t_end == c.t0:
        if dense:
            raise ValueError("dense=True needs t_end != t0 (there is no step to interpolate)")
        return trivial_result(c.t0, c.y0, c.mode, c.t_eval, "DOP853")

    return run_core(c.rhs, c.after_step, events_f, c.t0, c.y0, c.t_end, c.p, c.atol, c.rtol, c.first_step,
                    c.max_step, c.max_steps, c.t_eval, c.mode, dense, n_events, ev_dir, safety, min_factor, max_factor)


def run_core(rhs, after_step, events, t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps, t_eval,
             mode, dense, n_events, ev_dir, safety, min_factor, max_factor):
    """:func:`dop853` after its checks: the core called with arguments already of its declared types (t_end ≠ t0,
    functions by address or checked dispatchers, contiguous float64 arrays, ``mode`` an ``OUT_*`` code) →
    :class:`OdeResult`.  :func:`pnrotor.pn.evolve.integrate_half` calls it directly with inputs its settings
    stage has checked, which saves :func:`dop853`'s validation per half."""
    t_out, y_out, seg_t, seg_h, seg_c, iv, fv, y_ev = entry_point(core, CORE_SIG, "core")(
        function_addresses(rhs, after_step, events), t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps,
        t_eval, mode, dense, n_events, ev_dir, safety, min_factor, max_factor)
    nseg = int(iv[IV_NSEG])
    dense_out = None
    if dense and nseg > 0:
        dense_out = DenseOutput(seg_t[:nseg].copy(), seg_h[:nseg].copy(), seg_c[:nseg].copy(), fv[FV_T])
    ev = int(iv[IV_STATUS]) == STATUS_EVENT
    return assemble_result(t_out, y_out, iv, fv, "DOP853", t_event=float(fv[FV_TEVENT]) if ev else None,
                           y_event=y_ev.copy() if ev else None, event_index=int(iv[IV_EVENT]) if ev else None,
                           dense=dense_out)
