r"""Gragg–Bulirsch–Stoer extrapolation integrator in numba.

This module owns, as the solver protocol of :mod:`pnrotor.ode.common` asks, the extrapolation stepper (Gragg's
modified midpoint rule + Aitken–Neville polynomial extrapolation), its order and step-size control, the driver loop
(:func:`core`, one ``@njit`` function compiled for one explicit signature ``CORE_SIG`` on its first use, cached
across processes like the DOP853 core) and the Python entry point :func:`bulirsch_stoer`.

Algorithms (Hairer, Nørsett & Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer
1993, Sec. II.9, and Hairer's ODEX code; W. B. Gragg, SIAM J. Numer. Anal. 2, 384 (1965);
R. Bulirsch & J. Stoer, Numer. Math. 8, 1 (1966); P. Deuflhard, SIAM Review 27, 505 (1985)):

* Basic method: for a step H and an even number n of substeps, h = H/n, Gragg's rule
  z₀ = y₀, z₁ = z₀ + h f(t₀, z₀), z_{m+1} = z_{m−1} + 2h f(t₀ + m h, z_m) (m = 1..n−1), and
  T_{j,1} = z_n (no smoothing step).  Its error has an expansion in even powers of h.
* Step-number sequence n_j = 2, 4, 6, 8, … (Deuflhard's choice, ODEX's default); f(t₀, y₀) is
  shared, so building columns 1..j costs A_j = 1 + Σ_{i≤j} (n_i − 1) evaluations.
* Extrapolation (Aitken–Neville, eq. II.9.10):
  T_{j,k+1} = T_{j,k} + (T_{j,k} − T_{j−1,k}) / ((n_j/n_{j−k})² − 1); T_{j,j} has order 2j.
* Error of T_{j,j−1}: err_j = ‖T_{j,j} − T_{j,j−1}‖ in the RMS norm scaled by
  scᵢ = atolᵢ + rtolᵢ · max(|y₀ᵢ|, |T_{j,j,i}|) (as in DOP853); the solution advanced is T_{j,j}.
* Step size per column: H_j = H · clip(0.94 (0.65/err_j)^(1/(2j−1)), fac_min/4, 1/fac_min) with
  fac_min = 0.02^(1/(2j−1)) (ODEX's safety factors); work per unit step W_j = A_j / H_j.
* Order control with convergence monitor (Hairer II.9, "order and step size control"): with target
  column k, accept in column k−1, k or k+1 as soon as err ≤ 1; reject early in column k−1 if
  err_{k−1} > (n_k n_{k+1}/n_1²)², in column k if err_k > (n_{k+1}/n_1)², and in column k+1 if
  err_{k+1} > 1.  After acceptance the new target is the column with the smallest work per unit
  step among k−1, k, k+1 (with the factors 0.8 and 0.9 favouring the lower order); an order
  increase scales the step by A_{k+1}/A_k.  After a rejection neither the order nor the step may
  grow.  On the first step (and the step that lands on t_end) any column with err ≤ 1 is accepted.

Dense output and events are not implemented for this method (use :func:`pnrotor.ode.dop853`).

Smooth right-hand sides only.  The extrapolation and its error estimate rest on the even-power
expansion of Gragg's rule, which a jump or a kink of f inside a step breaks: the estimate can then
pass while T_{j,j} is wrong, and the run ends with status 0 and no warning.  Measured
(benchmarks/stress.py, ω reversing sign at t = 10.3 or ω = |t − 10.3| ê, six formulations, atol 1e-10):
max δ up to 0.3 across the jump and 3e-4 across the kink, where DOP853 stays within 1.1e-8.  Integrate
up to the discontinuity and restart from there.
"""

import math

import numpy as np
from numba import njit, types

from .common import (A1, A2, F8, FV_H, FV_T, FV_TFAIL, I1, I8, IV_NACC, IV_NANREJ, IV_NFEV, IV_NMOD, IV_NOUT, IV_NREJ,
                     IV_NSTEPS, IV_STATUS, OUT_FINAL, OUT_STEPS, OUT_TEVAL, after_step_function, all_finite, append_row,
                     assemble_result, common_inputs, entry_point, function_addresses, rhs_function, scaled,
                     select_initial_step, trivial_result)
from .result import STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW, STATUS_SUCCESS

K_MAX_DEFAULT = 9
"""Default number of extrapolation columns (ODEX's KM = 9: orders up to 18)."""

_SAFE_FAC = 0.94   # ODEX safe2
_SAFE_ERR = 0.65   # ODEX safe3
_FAC1 = 0.02       # ODEX fac1: fac_min = fac1^(1/(2j-1))
_FAC2 = 4.0        # ODEX fac2: the step may shrink by at most fac_min/fac2
_ORDER_DOWN = 0.8  # ODEX fac3
_ORDER_UP = 0.9    # ODEX fac4


@njit(cache=True, fastmath={'contract'})
def _gragg(rhs, t, y, f0, h_step, nsub, p, za, zb, ftmp):
    """Gragg's modified midpoint rule with nsub substeps over h_step; returns the buffer holding z_n."""
    n = y.size
    hs = h_step / nsub
    for i in range(n):
        za[i] = y[i]
        zb[i] = y[i] + hs * f0[i]
    two_hs = 2.0 * hs
    for mm in range(1, nsub):
        rhs(t + mm * hs, zb, p, ftmp)
        for i in range(n):
            za[i] = za[i] + two_hs * ftmp[i]
        za, zb = zb, za
    return zb


CORE_SIG = types.Tuple((A1, A2, I1, A1))(
    I1,                          # functions: rhs, after_step (pnrotor.ode.common.FUNCTIONS_LAYOUT)
    F8, A1, F8, A1,              # t0, y0, t_end, p
    A1, A1,                      # atol, rtol
    F8, F8, I8,                  # first_step (0: automatic), max_step, max_steps
    I8, I8, I8,                  # out_mode, k_max (columns), k_init (initial target column, 0-based)
)


@njit(cache=True)   # compiled for CORE_SIG by entry_point when first needed, not at import (~9 s cold)
def core(functions, t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps, out_mode, kmax, k_init):
    """The Bulirsch–Stoer driver loop, its right-hand side and hook given by address (the first two of
    ``FUNCTIONS_LAYOUT``).  Returns (t_out, y_out, ivals, fvals); the output buffers are over-allocated, their
    used length is ivals[IV_NOUT]."""
    rhs = rhs_function(functions[0], functions[1])
    after_step = after_step_function(functions[2], functions[3])
    n = y0.size
    direction = 1.0 if t_end > t0 else -1.0
    nseq = np.empty(kmax, dtype=np.int64)
    cost = np.empty(kmax)
    for j in range(kmax):
        nseq[j] = 2 * (j + 1)
        if j == 0:
            cost[j] = nseq[0]
        else:
            cost[j] = cost[j - 1] + nseq[j] - 1
    coef = np.zeros((kmax, kmax))
    for j in range(kmax):
        for m in range(1, j + 1):
            r = nseq[j] / nseq[j - m]
            coef[j, m] = 1.0 / (r * r - 1.0)
    tab = np.empty((kmax, n))
    za = np.empty(n)
    zb = np.empty(n)
    f0 = np.empty(n)
    ftmp = np.empty(n)
    hopt = np.zeros(kmax)
    work = np.zeros(kmax)
    ivals = np.zeros(10, dtype=np.int64)
    fvals = np.full(4, np.nan)

    cap = 64 if out_mode == OUT_STEPS else 1
    t_out = np.empty(cap)
    y_out = np.empty((cap, n))
    n_out = 0

    nfev = 0
    nsteps = 0
    nacc = 0
    nrej = 0
    nmod = 0
    status = STATUS_SUCCESS

    y = y0.copy()
    t = t0
    if out_mode == OUT_STEPS:
        t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)
    rhs(t, y, p, f0)
    nfev += 1
    k_targ = min(max(k_init, 1), kmax - 2)
    h_abs = 0.0
    if not all_finite(f0):
        status = STATUS_NONFINITE
        fvals[FV_TFAIL] = t
    elif first_step > 0.0:
        h_abs = first_step
    else:
        h_abs = select_initial_step(rhs, t, y, f0, p, t_end, max_step, 2 * k_targ, atol, rtol, za, ftmp)
        nfev += 1

    first = True
    prev_reject = False
    while status == STATUS_SUCCESS and direction * (t_end - t) > 0.0:
        min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        if h_abs < min_step:
            h_abs = min_step

        accepted = False
        acc_col = -1
        t_new = t
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
            last = False
            if direction * (t_new - t_end) >= 0.0:
                t_new = t_end
                last = True
            h = t_new - t
            h_abs = abs(h)
            nsteps += 1

            nonfinite = False
            acc_col = -1
            h_next = h_abs
            for j in range(k_targ + 2):
                z = _gragg(rhs, t, y, f0, h, nseq[j], p, za, zb, ftmp)
                nfev += nseq[j] - 1
                if not all_finite(z):
                    nonfinite = True
                    break
                # Aitken–Neville: tab[m] <- T_{j,m}, m = 0..j
                for i in range(n):
                    cur = z[i]
                    for m in range(1, j + 1):
                        old = tab[m - 1, i]
                        tab[m - 1, i] = cur
                        cur = cur + (cur - old) * coef[j, m]
                    tab[j, i] = cur
                if j == 0:
                    continue
                s = 0.0
                for i in range(n):
                    sc = atol[i] + rtol[i] * max(abs(y[i]), abs(tab[j, i]))
                    e = scaled(tab[j, i] - tab[j - 1, i], sc)
                    s += e * e
                err = math.sqrt(s / n)
                if not math.isfinite(err):
                    nonfinite = True
                    break
                expo = 1.0 / (2 * j + 1)
                facmin = _FAC1 ** expo
                if err == 0.0:
                    fac = 1.0 / facmin
                else:
                    fac = min(1.0 / facmin, max(facmin / _FAC2, _SAFE_FAC * (_SAFE_ERR / err) ** expo))
                hopt[j] = h_abs * fac
                work[j] = cost[j] / hopt[j]

                if (first or last) and err <= 1.0:
                    acc_col = j
                    break
                if j == k_targ - 1 and not prev_reject and not (first or last):
                    if err <= 1.0:
                        acc_col = j
                        break
                    q = nseq[k_targ] * nseq[k_targ + 1] / (nseq[0] * nseq[0])
                    if err > q * q:
                        k_targ = j
                        if k_targ > 1 and work[k_targ - 1] < _ORDER_DOWN * work[k_targ]:
                            k_targ -= 1
                        h_next = hopt[k_targ]
                        break
                if j == k_targ:
                    if err <= 1.0:
                        acc_col = j
                        break
                    q = nseq[j + 1] / nseq[0]
                    if err > q * q:
                        if k_targ > 1 and work[k_targ - 1] < _ORDER_DOWN * work[k_targ]:
                            k_targ -= 1
                        h_next = hopt[k_targ]
                        break
                if j == k_targ + 1:
                    if err <= 1.0:
                        acc_col = j
                    else:
                        if k_targ > 1 and work[k_targ - 1] < _ORDER_DOWN * work[k_targ]:
                            k_targ -= 1
                        h_next = hopt[k_targ]
                    break

            if acc_col >= 0:
                accepted = True
                break
            # rejected (by the convergence monitor, the final test, or non-finite values)
            nrej += 1
            prev_reject = True
            if nonfinite:
                ivals[IV_NANREJ] = 1
                h_abs = 0.25 * h_abs
            else:
                ivals[IV_NANREJ] = 0
                h_abs = min(h_next, 0.9 * h_abs)
        if not accepted:
            break

        # ---- accepted in column acc_col: order and step size for the next step
        nacc += 1
        j = acc_col
        if j == 1:
            k_new = min(2, kmax - 2)
        elif j <= k_targ:
            k_new = j
            if work[j - 1] < _ORDER_DOWN * work[j]:
                k_new = j - 1
            elif work[j] < _ORDER_UP * work[j - 1]:
                k_new = min(j + 1, kmax - 2)
        else:
            k_new = j - 1
            if j > 2 and work[j - 2] < _ORDER_DOWN * work[j - 1]:
                k_new = j - 2
            if work[j] < _ORDER_UP * work[k_new]:
                k_new = min(j, kmax - 2)
        if prev_reject:
            k_targ = min(k_new, j)
            h_abs = min(h_abs, hopt[k_targ])
            prev_reject = False
        else:
            if k_new <= j:
                h_abs = hopt[k_new]
            else:
                h_abs = hopt[j] * cost[k_new] / cost[j]
            k_targ = k_new
        k_targ = min(max(k_targ, 1), kmax - 2)
        first = False

        t = t_new
        for i in range(n):
            y[i] = tab[j, i]
        if after_step(t, y, p):
            nmod += 1
        if not all_finite(y):
            status = STATUS_NONFINITE
            fvals[FV_TFAIL] = t
            break
        if direction * (t_end - t) > 0.0:
            rhs(t, y, p, f0)
            nfev += 1
            if not all_finite(f0):
                status = STATUS_NONFINITE
                fvals[FV_TFAIL] = t
                break
        if out_mode == OUT_STEPS:
            t_out, y_out, n_out = append_row(t_out, y_out, n_out, t, y)

    if out_mode == OUT_FINAL:
        t_out, y_out, n_out = append_row(t_out, y_out, 0, t, y)

    ivals[IV_STATUS] = status
    ivals[IV_NFEV] = nfev
    ivals[IV_NSTEPS] = nsteps
    ivals[IV_NACC] = nacc
    ivals[IV_NREJ] = nrej
    ivals[IV_NMOD] = nmod
    ivals[IV_NOUT] = n_out
    fvals[FV_T] = t
    fvals[FV_H] = h_abs
    return t_out, y_out, ivals, fvals


def bulirsch_stoer(rhs, t0, y0, t_end, atol, rtol=0.0, args=(), first_step=None, max_step=np.inf,
                   max_steps=1_000_000, after_step=None, t_eval=None, dense=False, events=None,
                   n_events=0, k_max=K_MAX_DEFAULT):
    """Integrate dy/dt = rhs(t, y, p) from t0 to t_end with Gragg–Bulirsch–Stoer extrapolation.

    Parameters are as for :func:`pnrotor.ode.dop853` (same signatures, tolerances, error norm,
    ``after_step`` hook, status codes and :class:`OdeResult`), except:

    t_eval : None or 'final'
        ``None``: output every accepted step (and t0); ``'final'``: the final state only.  Output at
        arbitrary times needs dense output, which is not implemented for this method (ValueError).
    dense, events, n_events
        Not supported (ValueError if requested); use :func:`pnrotor.ode.dop853`.
    k_max : int
        Number of extrapolation columns, 4 ≤ k_max ≤ 12 (default 9: orders up to 2·k_max = 18).

    ``after_step`` may modify the state after an accepted step (return True); the next step starts
    with a fresh f(t, y) in any case, so no extra evaluation is counted.  ``nfev`` counts every
    evaluation: f(t₀, y₀) per step plus n_j − 1 per extrapolation column.
    """
    if dense:
        raise ValueError("dense output is not implemented for bulirsch_stoer (dense must be False); use dop853")
    if events is not None or n_events:
        raise ValueError("events are not implemented for bulirsch_stoer (events must be None); use dop853")
    c = common_inputs(rhs, t0, y0, t_end, atol, rtol, args, first_step, max_step, max_steps, t_eval, after_step)
    if c.mode == OUT_TEVAL:
        raise ValueError("t_eval arrays are not supported by bulirsch_stoer (no dense output); "
                         "use t_eval=None or 'final', or dop853")
    if isinstance(k_max, (bool, np.bool_)) or not isinstance(k_max, (int, np.integer)) or not 4 <= k_max <= 12:
        raise ValueError(f"k_max must be an integer in [4, 12], got {k_max!r}")
    if c.t_end == c.t0:
        return trivial_result(c.t0, c.y0, c.mode, c.t_eval, "Bulirsch-Stoer")

    # initial target column from the tolerance (Hairer's ODEX: k = -log10(tol)·0.6 + 1.5 columns)
    ymag = max(float(np.max(np.abs(c.y0))), 1.0)
    tol = float(np.mean(c.atol + c.rtol * np.abs(c.y0))) / ymag
    tol = min(max(tol, 1e-16), 1e-2)
    k_init = int(-math.log10(tol) * 0.6 + 1.5) - 1
    k_init = min(max(k_init, 1), int(k_max) - 2)

    t_out, y_out, iv, fv = entry_point(core, CORE_SIG)(
        function_addresses(c.rhs, c.after_step), c.t0, c.y0, c.t_end, c.p, c.atol, c.rtol, c.first_step, c.max_step,
        c.max_steps, c.mode, int(k_max), k_init)
    return assemble_result(t_out, y_out, iv, fv, "Bulirsch-Stoer")
