r"""DOP853: Dormand–Prince explicit Runge–Kutta 8(5,3) integrator in numba.

This module owns

* the function signatures that right-hand sides and hooks must be compiled with (``RHS_SIG``,
  ``AFTER_STEP_SIG``, ``EVENTS_SIG``) and the default no-op hooks;
* the DOP853 stepper, step-size controller, dense output, event location and driver loop, all in
  one ``@njit`` function compiled for one explicit signature (:func:`_dop853_core`, ``_CORE_SIG``) on
  first use, so that it is compiled once per machine and loaded from numba's cache afterwards, whatever
  right-hand side is passed;
* the Python entry point :func:`dop853` (input validation, result assembly).

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
  exponent 1/8, the same algorithm as scipy's ``select_initial_step`` for this method.
* Dense output: Hairer's 7th-order continuous extension (three extra stages, ``contd8``), computed
  only on steps where it is needed (t_eval points inside the step, ``dense=True``, or an event).
* Events: sign changes of g between the ends of an accepted step (respecting the requested
  direction) are located on the dense interpolant with Brent's method (R. P. Brent, *Algorithms
  for Minimization without Derivatives*, 1973, ch. 4) to a few ulp of t; all events are terminal.

Floating point: the stage and interpolation sums are compiled with ``fastmath={'contract'}``, i.e.
LLVM may fuse a·b + c into one FMA instruction (halves the arithmetic of a step; results then differ
from an unfused evaluation by rounding only).  No other fast-math flag is used.

Function types: the core takes the right-hand side and hooks by the addresses of their compiled code
(one int64 array, ``FUNCTIONS_LAYOUT``), checked against the explicit signatures below before the call, and
calls them inside as first-class ``numba.types.FunctionType`` values; numba caches such a driver across
processes (a driver taking a dispatcher or closure is recompiled in every process).  An indirect call of a
no-op right-hand side with its three array arguments measured ~6 ns here.  Calling :func:`dop853` has a
fixed cost of ~0.05 ms (argument checks; a short oscillator run 48-52 µs with its right-hand side
by address, 57-65 µs as a dispatcher, measured), see ``benchmarks/bench_ode.py``.
"""

import math
import weakref
from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.core.ccallback import CFunc
from numba.core.registry import CPUDispatcher
from numba.core.typing.templates import Signature
from numba.extending import intrinsic

from . import tableau as _tab
from .result import (STATUS_EVENT, STATUS_MAX_STEPS, STATUS_MESSAGES, STATUS_NONFINITE,
                     STATUS_STEP_UNDERFLOW, STATUS_SUCCESS, DenseOutput, OdeResult, contd8)

# --------------------------------------------------------------------------------------------------
# signatures of user functions and of the core
# --------------------------------------------------------------------------------------------------

RHS_SIG = types.void(types.float64, types.float64[::1], types.float64[::1], types.float64[::1])
"""``rhs(t, y, p, dydt)``: write dy/dt at (t, y) with parameters p into ``dydt``."""

AFTER_STEP_SIG = types.boolean(types.float64, types.float64[::1], types.float64[::1])
"""``after_step(t, y, p) -> bool``: may modify y in place after an accepted step; return True if it did."""

EVENTS_SIG = types.void(types.float64, types.float64[::1], types.float64[::1], types.float64[::1])
"""``events(t, y, p, g)``: fill g[0..m-1] with the m event functions at (t, y)."""

_f8 = types.float64
_i8 = types.int64
_b1 = types.boolean
_A1 = types.float64[::1]
_A2 = types.float64[:, ::1]
_A3 = types.float64[:, :, ::1]
_I1 = types.int64[::1]

# output modes of the core
OUT_STEPS = 0  # every accepted step (and t0)
OUT_TEVAL = 1  # at the requested times
OUT_FINAL = 2  # the final state only

# indices into the integer and float statistics returned by the cores
IV_STATUS, IV_NFEV, IV_NSTEPS, IV_NACC, IV_NREJ, IV_NMOD, IV_EVENT, IV_NOUT, IV_NSEG, IV_NANREJ = range(10)
FV_T, FV_TEVENT, FV_H, FV_TFAIL = range(4)


@njit(AFTER_STEP_SIG, cache=True)
def no_after_step(t, y, p):
    """Default ``after_step``: leaves the state alone."""
    return False


@njit(EVENTS_SIG, cache=True)
def no_events(t, y, p, g):
    """Default ``events``: no event functions."""
    return


# --------------------------------------------------------------------------------------------------
# calling the cores cheaply
# --------------------------------------------------------------------------------------------------
#
# The cores take their functions as one int64 array of addresses, FUNCTIONS_LAYOUT, and turn each pair into
# a first-class function inside (`_function_of`).  Declared as FunctionType arguments instead, every call
# of a core from Python unboxed each function through numba's Python helpers (a module import, two
# unpickled signatures and two Python calls per function): ~17-21 µs per call for three functions, against
# ~0.7 µs for the address array (measured with a one-evaluation driver of either form).


def _function_of(sig):
    """A numba intrinsic ``(c_addr, jit_addr) -> FunctionType(sig)``: the first-class function whose cfunc
    wrapper is at ``c_addr`` and whose numba-ABI entry is at ``jit_addr`` (0 for none).  numba calls
    ``jit_addr`` when it is set (exceptions raised inside propagate to the caller), else ``c_addr``
    (``numba.core.lowering``, first-class function calls); the Python object slot stays null."""
    fty = types.FunctionType(sig)

    @intrinsic
    def function(typingctx, c_addr, jit_addr):
        def codegen(context, builder, signature, args):
            f = cgutils.create_struct_proxy(fty)(context, builder)   # zero-filled: py_addr null
            ptr = context.get_value_type(types.voidptr)
            f.c_addr = builder.inttoptr(args[0], ptr)
            f.jit_addr = builder.inttoptr(args[1], ptr)
            return f._getvalue()

        return fty(types.int64, types.int64), codegen

    return function


_rhs_function = _function_of(RHS_SIG)
_after_step_function = _function_of(AFTER_STEP_SIG)
_events_function = _function_of(EVENTS_SIG)
FUNCTIONS_LAYOUT = ("rhs", "after_step", "events")
"""The cores' ``functions`` argument: for each of these in turn, its (cfunc wrapper, jit entry or 0) addresses."""


class _FunctionAddress:
    """A compiled numba function as the cores take it: its ``addresses`` (:func:`_function_of`, from
    :func:`_addresses`) and the function itself, which keeps the compiled code alive during a call."""

    def __init__(self, f, sig, addresses):
        self._function = f
        self._sig = sig
        self.addresses = addresses


def _addresses(f, sig, raises):
    """(cfunc wrapper address, jit entry address or 0) of f compiled for sig; ``raises``: keep the jit entry, so
    that an exception raised inside reaches the caller (without it the call goes through the cfunc wrapper)."""
    from numba.experimental.function_type import _get_jit_address, _get_wrapper_address

    return _get_wrapper_address(f, sig), _get_jit_address(f, sig) if raises else 0


_BY_ADDRESS = {}


def by_address(f, sig):
    """The ``@njit`` function ``f`` with signature ``sig`` in its cheapest form for :func:`dop853` and
    :func:`~pnrotor.ode.bulirsch_stoer`: its compiled address, looked up once (a dispatcher costs 5-13 µs more per
    call, its checks and cached addresses: dop853 on a short oscillator run 57-65 µs against 51-52).  Only for
    functions that cannot raise (no ``raise``, and ``error_model='numpy'`` so that a division by zero gives
    inf or nan): the call goes through the cfunc wrapper, so an exception inside would not reach the caller.
    The address is the code compiled when ``by_address`` first saw ``f``: after ``f.recompile()`` it still runs that
    code (numba keeps it), where ``f`` itself would run the new one."""
    # keyed by id(sig): hashing a numba signature costs ~1.3 µs (the lookup now 0.15 µs); the entry keeps sig
    # alive, so its id is not reused
    key = (f, id(sig))
    entry = _BY_ADDRESS.get(key)
    if entry is None:
        if not isinstance(f, CPUDispatcher):
            raise TypeError(f"by_address takes an @njit function, got {type(f).__name__}")
        if not isinstance(sig, Signature):
            raise TypeError(f"by_address takes a numba signature (pnrotor.ode.RHS_SIG, AFTER_STEP_SIG or EVENTS_SIG), "
                            f"got {sig!r}")
        _check_dispatcher(f, sig, "by_address's function")
        entry = _BY_ADDRESS[key] = (sig, _FunctionAddress(f, sig, _addresses(f, sig, raises=False)))
    return entry[1]


def _function_addresses(*functions):
    """The cores' ``functions`` array (FUNCTIONS_LAYOUT) of :class:`_FunctionAddress` values."""
    return np.array([a for f in functions for a in f.addresses], dtype=np.int64)


def _default_hook(name):
    """The no-op hook ``name`` in its cheapest form for passing to a core."""
    return by_address(*{"after_step": (no_after_step, AFTER_STEP_SIG), "events": (no_events, EVENTS_SIG)}[name])


_ENTRY_POINTS = {}


def _entry_point(core, sig):
    """The compiled entry point of a core for its one signature ``sig`` (or the dispatcher), compiled or loaded
    from numba's cache on first use; for the DOP853 core, a compilation of it that the CLI started in another
    process (:func:`pnrotor.numba_cache.compile_aside`) is awaited first, so that this one loads it."""
    ep = _ENTRY_POINTS.get(core)
    if ep is None:
        if core is _dop853_core and not core.overloads:
            from pnrotor import numba_cache

            numba_cache.wait_for_aside("core")
        try:
            core.compile(sig)
            ep = core.overloads[tuple(sig.args)].entry_point
        except Exception:  # pragma: no cover - numba internals changed
            ep = core
        _ENTRY_POINTS[core] = ep
    return ep


def compile_core():
    """Compile the DOP853 core into numba's cache (or load it): what :func:`pnrotor.numba_cache.compile_aside`
    runs in another process."""
    _entry_point(_dop853_core, _CORE_SIG)


def compile_core_parts():
    """Compile two callees of the DOP853 core into numba's cache (or load them), for the types the core calls them
    with: what a process that started :func:`compile_core` in another one (the CLI on a cold cache,
    :func:`pnrotor.numba_cache.compile_aside`) does first.  That process meets them last, ~7-9 s into the core's
    compile, and loads them from the cache instead of compiling them, ~2 s less of its work: without this its
    compile ended ~4-5 s after everything else of a cold run had compiled (numba's compile events of both processes,
    a cold ``pnrotor evolve``).  Only a saving: if it fails, the core's process compiles them as before."""
    try:
        _locate_root.compile((types.FunctionType(EVENTS_SIG), _A1, _i8, _f8, _f8, _f8, _f8, _f8, _f8, _A2, _A1, _A1))
        _append_segment.compile((_A1, _A1, _A3, _i8, _f8, _f8, _A2))
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
_EPS = np.finfo(np.float64).eps


@njit(cache=True)
def _all_finite(x):
    for i in range(x.size):
        if not math.isfinite(x[i]):
            return False
    return True


@njit(cache=True)
def _copy(dst, src):
    """dst[:] = src for 1-D arrays, as a plain loop (cheaper to compile than slice assignment)."""
    for i in range(src.size):
        dst[i] = src[i]


@njit(cache=True)
def _append_row(t_out, y_out, n_out, t, y):
    """Store (t, y) as output row n_out, doubling the buffers when full; returns buffers and count."""
    n = y.size
    if n_out == t_out.size:
        cap = 2 * n_out
        new_t = np.empty(cap)
        new_y = np.empty((cap, n))
        for k in range(n_out):
            new_t[k] = t_out[k]
            for i in range(n):
                new_y[k, i] = y_out[k, i]
        t_out = new_t
        y_out = new_y
    t_out[n_out] = t
    for i in range(n):
        y_out[n_out, i] = y[i]
    return t_out, y_out, n_out + 1


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


@njit(cache=True)
def _scaled(x, sc):
    """x / sc for an error scale sc = atol + rtol |y| ≥ 0.  sc = 0 (atol = 0 where y = 0, a pure relative
    tolerance) allows no error: a zero x is none, any other an infinite one (the step is rejected)."""
    if sc > 0.0:
        return x / sc
    return 0.0 if x == 0.0 else math.inf


@njit(cache=True)
def _rms_scaled(x, y, atol, rtol):
    """RMS of x / (atol + rtol |y|) (:func:`_scaled`)."""
    s = 0.0
    for i in range(x.size):
        r = _scaled(x[i], atol[i] + rtol[i] * abs(y[i]))
        s += r * r
    return math.sqrt(s / x.size)


@njit(cache=True)
def select_initial_step(rhs, t0, y0, f0, p, t_end, max_step, order, atol, rtol, y1, f1):
    """Hairer's starting step size (Solving ODEs I, Sec. II.4), RMS norms; costs one evaluation.

    Uses ``y1`` and ``f1`` as scratch.  ``order`` is the order q of the error estimate: the step is
    ( 0.01 / max(‖f0‖, ‖f″‖) )^(1/(q+1)), bounded by 100 h₀, the interval length and max_step.
    """
    n = y0.size
    interval = abs(t_end - t0)
    direction = 1.0 if t_end >= t0 else -1.0
    d0 = _rms_scaled(y0, y0, atol, rtol)
    d1 = _rms_scaled(f0, y0, atol, rtol)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    if not 0.0 < h0 < math.inf:   # the norms overflowed (a tolerance near zero)
        h0 = 1e-6
    h0 = min(h0, interval)
    for i in range(n):
        y1[i] = y0[i] + h0 * direction * f0[i]
    rhs(t0 + h0 * direction, y1, p, f1)
    s = 0.0
    for i in range(n):
        r = _scaled(f1[i] - f0[i], atol[i] + rtol[i] * abs(y0[i]))
        s += r * r
    d2 = math.sqrt(s / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    if not h1 > 0.0:   # the norms overflowed, or are infinite (a zero tolerance where the state is 0)
        h1 = h0
    return min(100.0 * h0, h1, interval, max_step)


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
        e3 = _scaled(e3, sc)
        e5 = _scaled(e5, sc)
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


@njit(cache=True)
def _event_value(events, p, j, t, t_old, h, rc, yint, gtmp):
    contd8(rc, (t - t_old) / h, yint)
    events(t, yint, p, gtmp)
    return gtmp[j]


@njit(cache=True, inline="always")
def _crossed(g_old, g_new, direction):
    """Whether an event went from g_old to g_new across zero in its direction (> 0 upward only,
    < 0 downward only, 0 either): from below to ≥ 0, or from above to ≤ 0."""
    return ((g_old < 0.0 and g_new >= 0.0 and direction >= 0.0)
            or (g_old > 0.0 and g_new <= 0.0 and direction <= 0.0))


@njit(cache=True)
def _locate_root(events, p, j, ta, tb, ga, gb, t_old, h, rc, yint, gtmp):
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


_CORE_SIG = types.Tuple((_A1, _A2, _A1, _A1, _A3, _I1, _A1, _A1))(
    _I1,                         # functions (FUNCTIONS_LAYOUT)
    _f8, _A1, _f8, _A1,          # t0, y0, t_end, p
    _A1, _A1,                    # atol, rtol (per component)
    _f8, _f8, _i8,               # first_step (0: automatic), max_step, max_steps
    _A1, _i8, _b1,               # t_eval, out_mode, want_dense
    _i8, _A1,                    # n_events, event_direction
    _f8, _f8, _f8,               # safety, min_factor, max_factor
)


@njit(cache=True)   # compiled for _CORE_SIG by _entry_point when first needed, not at import
def _dop853_core(functions, t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps, t_eval, out_mode,
                 want_dense, n_events, ev_dir, safety, min_factor, max_factor):
    """The DOP853 driver loop, with its right-hand side and hooks given by address (FUNCTIONS_LAYOUT).
    Returns (t_out, y_out, seg_t, seg_h, seg_coef, ivals, fvals, y_event); the output and dense buffers are
    over-allocated, their used lengths are ivals[IV_NOUT], ivals[IV_NSEG]."""
    rhs = _rhs_function(functions[0], functions[1])
    after_step = _after_step_function(functions[2], functions[3])
    events = _events_function(functions[4], functions[5])
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
    # the counters passed to _append_row/_append_segment start as np.int64(0), not 0: a literal 0 makes
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
        t_out, y_out, n_out = _append_row(t_out, y_out, n_out, t, y)
    elif out_mode == OUT_TEVAL:
        while k_ev < t_eval.size and t_eval[k_ev] == t:
            t_out, y_out, n_out = _append_row(t_out, y_out, n_out, t, y)
            k_ev += 1

    h_abs = 0.0
    if not _all_finite(K[0]):
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
        if not (_all_finite(ynew) and _all_finite(K[12])):
            status = STATUS_NONFINITE
            fvals[FV_TFAIL] = t_new
            break

        # events: sign changes between the ends of the step
        ev_j = -1
        if n_events > 0:
            events(t_new, ynew, p, g_new)
            for j in range(n_events):
                if _crossed(g_old[j], g_new[j], ev_dir[j]):
                    ev_j = j
                    break

        need_dense = want_dense or ev_j >= 0 or (
            out_mode == OUT_TEVAL and k_ev < t_eval.size and direction * (t_eval[k_ev] - t_new) < 0.0)
        if need_dense:
            _dense_coefficients(rhs, t, y, ynew, h, p, K, ys, rc)
            nfev += 3
            if not _all_finite(rc.reshape(rc.size)):
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
                if _crossed(g_old[j], g_new[j], ev_dir[j]):
                    tr = _locate_root(events, p, j, t, t_new, g_old[j], g_new[j], t, h, rc, yint, gtmp)
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
                t_out, y_out, n_out = _append_row(t_out, y_out, n_out, t, y)
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
            if not (_all_finite(y) and _all_finite(K[0])):
                status = STATUS_NONFINITE
                fvals[FV_TFAIL] = t
                break
            if n_events > 0:
                events(t, y, p, g_new)
        if n_events > 0:
            _copy(g_old, g_new)

        # outputs at the step end (state after after_step)
        if out_mode == OUT_STEPS:
            t_out, y_out, n_out = _append_row(t_out, y_out, n_out, t, y)
        elif out_mode == OUT_TEVAL:
            while k_ev < t_eval.size and t_eval[k_ev] == t:
                t_out, y_out, n_out = _append_row(t_out, y_out, n_out, t, y)
                k_ev += 1

    if out_mode == OUT_FINAL:
        t_out, y_out, n_out = _append_row(t_out, y_out, np.int64(0), t, y)

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


# --------------------------------------------------------------------------------------------------
# Python entry point: validation and result assembly (shared with the Bulirsch–Stoer driver)
# --------------------------------------------------------------------------------------------------


def _finite_scalar(x, name):
    if isinstance(x, (bool, np.bool_)):
        raise ValueError(f"{name} must be a finite real number, got {x!r}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite real number, got {x!r}") from None
    if np.ndim(x) != 0:
        raise ValueError(f"{name} must be a scalar, got an array of shape {np.shape(x)}")
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v!r}")
    return v


def _real_array(x, name):
    try:
        arr = np.asarray(x)
    except Exception:  # pragma: no cover - exotic inputs
        raise ValueError(f"{name} must be an array of real numbers") from None
    if arr.dtype.kind == "c":
        raise ValueError(f"{name} must be real, got complex values")
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name} must be an array of real numbers, got dtype {arr.dtype}")
    return np.array(arr, dtype=np.float64, order="C")  # always a private, writable copy


def _validate_state(y0):
    y = _real_array(y0, "y0")
    if y.ndim != 1:
        raise ValueError(f"y0 must be a 1-D array, got shape {y.shape}")
    if y.size == 0:
        raise ValueError("y0 must have at least one component")
    if not np.all(np.isfinite(y)):
        raise ValueError("y0 must be finite (it contains NaN or inf)")
    return y


def _validate_tolerances(atol, rtol, n):
    if isinstance(atol, float) and isinstance(rtol, float):  # fast path for plain scalars
        if math.isfinite(atol) and math.isfinite(rtol) and rtol >= 0 and (atol > 0 or (atol == 0 and rtol > 0)):
            return np.full(n, atol), np.full(n, rtol)
    a = _real_array(atol, "atol")
    r = _real_array(rtol, "rtol")
    for name, v in (("atol", a), ("rtol", r)):
        if v.ndim > 1 or (v.ndim == 1 and v.size != n):
            raise ValueError(f"{name} must be a scalar or have shape ({n},) like y0, got shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{name} must be finite")
    a = np.ascontiguousarray(np.broadcast_to(a, (n,)), dtype=np.float64).copy()
    r = np.ascontiguousarray(np.broadcast_to(r, (n,)), dtype=np.float64).copy()
    if np.any(r < 0):
        raise ValueError(f"rtol must be >= 0, got {r.min()!r}")
    if np.any(a < 0):
        raise ValueError(f"atol must be >= 0, got {a.min()!r}")
    bad = (a <= 0) & (r == 0)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise ValueError(f"atol must be > 0 where rtol = 0 (component {i} has atol = {a[i]!r}, rtol = 0)")
    return a, r


def _validate_args(args):
    p = _real_array(args, "args")
    if p.ndim > 1:
        raise ValueError(f"args must be a scalar or a 1-D sequence of floats, got shape {p.shape}")
    return np.ascontiguousarray(p.reshape(-1))


def _validate_steps(first_step, max_step, max_steps, t0, t_end):
    if first_step is None:
        fs = 0.0
    else:
        fs = _finite_scalar(first_step, "first_step")
        if fs <= 0:
            raise ValueError(f"first_step must be > 0, got {fs!r}")
        if t_end != t0 and fs > abs(t_end - t0):
            raise ValueError(f"first_step must not exceed |t_end - t0| = {abs(t_end - t0)!r}, got {fs!r}")
    try:
        ms = float(max_step)
    except (TypeError, ValueError):
        raise ValueError(f"max_step must be a positive number or inf, got {max_step!r}") from None
    if not ms > 0:  # also catches NaN
        raise ValueError(f"max_step must be > 0 (inf allowed), got {ms!r}")
    if isinstance(max_steps, (bool, np.bool_)) or not isinstance(max_steps, (int, np.integer)):
        raise ValueError(f"max_steps must be an integer >= 1, got {max_steps!r}")
    if max_steps < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps!r}")
    return fs, ms, int(max_steps)


def _validate_t_eval(t_eval, t0, t_end):
    """Returns (out_mode, t_eval array)."""
    if t_eval is None:
        return OUT_STEPS, np.empty(0)
    if isinstance(t_eval, str):
        if t_eval == "final":
            return OUT_FINAL, np.empty(0)
        raise ValueError(f"t_eval must be None, 'final' or an array of times, got {t_eval!r}")
    te = _real_array(t_eval, "t_eval")
    if te.ndim != 1:
        raise ValueError(f"t_eval must be a 1-D array, got shape {te.shape}")
    if not np.all(np.isfinite(te)):
        raise ValueError("t_eval must be finite")
    lo, hi = min(t0, t_end), max(t0, t_end)
    if te.size and (te.min() < lo or te.max() > hi):
        raise ValueError(f"t_eval must lie within [t0, t_end] = [{t0!r}, {t_end!r}]")
    direction = 1.0 if t_end >= t0 else -1.0
    if te.size > 1 and np.any(direction * np.diff(te) < 0):
        order = "increasing" if direction > 0 else "decreasing"
        raise ValueError(f"t_eval must be sorted in the direction of integration ({order})")
    return OUT_TEVAL, te


_CHECKED = weakref.WeakKeyDictionary()
"""dispatcher -> {argument name: (its overload for that signature, its addresses)}: looking the addresses up costs
~50 µs, a call of :func:`_jit_function` that finds them 2.6 µs (measured); a recompiled dispatcher has a new overload."""


def _jit_function(f, sig, name):
    """f checked for a core's argument ``name`` of signature ``sig`` → its :class:`_FunctionAddress` (a
    dispatcher's keeps its jit entry: exceptions it raises propagate)."""
    if isinstance(f, CPUDispatcher):
        try:
            known = _CHECKED.get(f, {}).get(name)
        except TypeError:  # pragma: no cover - not weak-referenceable
            known = None
        if known is None or f.overloads.get(tuple(sig.args)) is not known[0]:
            _check_dispatcher(f, sig, name)
            known = (f.overloads[tuple(sig.args)], _addresses(f, sig, raises=True))
            try:
                _CHECKED.setdefault(f, {})[name] = known
            except TypeError:  # pragma: no cover
                pass
        return _FunctionAddress(f, sig, known[1])
    if isinstance(f, CFunc):   # its C wrapper prints an exception raised inside and returns: a wrong run, not an error
        raise TypeError(f"{name} must be an @njit function, not a @cfunc (an exception raised inside a @cfunc cannot "
                        f"reach the caller); use @njit({_sig_label(sig)}, cache=True)")
    if isinstance(f, _FunctionAddress):
        # the identity test spares comparing signatures (~0.9 µs, measured) in the usual case
        if f._sig is not sig and f._sig != sig:
            raise TypeError(f"{name} must have the signature {sig}; got a function of signature {f._sig}")
        return f
    raise TypeError(f"{name} must be a numba-compiled function, e.g. decorated with "
                    f"@njit({_sig_label(sig)}, cache=True); got {type(f).__name__}")


def _check_dispatcher(f, sig, name):
    """Raise TypeError unless the dispatcher f has (or can compile) exactly the signature sig."""
    existing = f.overloads.get(tuple(sig.args))
    if existing is not None:
        if existing.signature.return_type != sig.return_type:
            raise TypeError(
                f"{name} must return {sig.return_type} (signature {sig}), but it returns "
                f"{existing.signature.return_type}; compile it with @njit({_sig_label(sig)})")
        return
    try:
        f.compile(sig)
    except Exception as exc:
        raise TypeError(
            f"{name} must be a numba @njit function compilable with the signature {sig} "
            f"(e.g. @njit({_sig_label(sig)}, cache=True)): {exc}") from None


_SIG_LABELS = {id(RHS_SIG): "pnrotor.ode.RHS_SIG", id(AFTER_STEP_SIG): "pnrotor.ode.AFTER_STEP_SIG",
               id(EVENTS_SIG): "pnrotor.ode.EVENTS_SIG"}


def _sig_label(sig):
    """How to write ``sig`` in a decorator: its public name if it is one of the three, else itself."""
    return _SIG_LABELS.get(id(sig), f"'{sig}'")


def _positive_factor(x, name, lo, hi, lo_open=True, hi_open=False):
    v = _finite_scalar(x, name)
    ok_lo = v > lo if lo_open else v >= lo
    ok_hi = v < hi if hi_open else v <= hi
    if not (ok_lo and ok_hi):
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        raise ValueError(f"{name} must be in {lb}{lo}, {hi}{rb}, got {v!r}")
    return v


def _status_message(status, iv, fv):
    msg = STATUS_MESSAGES[status]
    if status < 0 and math.isfinite(fv[FV_TFAIL]):
        msg = msg.rstrip(".") + f" (at t = {float(fv[FV_TFAIL])!r})."
    if status == STATUS_STEP_UNDERFLOW and iv[IV_NANREJ]:
        msg += (" The last error estimate was NaN or infinite: the right-hand side produced non-finite values, or"
                " a tolerance at or near zero (atol = 0 where the state is 0) allowed no error.")
    return msg


def _trivial_result(t0, y0, mode, t_eval, method):
    """t_end == t0: nothing to integrate."""
    if mode == OUT_TEVAL:
        t = t_eval.copy()
        y = np.repeat(y0[None, :], t.size, axis=0)
    else:
        t = np.array([t0])
        y = y0[None, :].copy()
    return OdeResult(t, y, 0, 0, 0, 0, 0, STATUS_SUCCESS, "t_end == t0: nothing to integrate.", method=method)


class _Inputs(NamedTuple):
    """The arguments both integrators take, checked and converted (:func:`_common_inputs`)."""

    rhs: object
    after_step: object
    t0: float
    y0: np.ndarray
    t_end: float
    p: np.ndarray
    atol: np.ndarray
    rtol: np.ndarray
    first_step: float
    max_step: float
    max_steps: int
    mode: int
    t_eval: np.ndarray


def _common_inputs(rhs, t0, y0, t_end, atol, rtol, args, first_step, max_step, max_steps, t_eval, after_step):
    """Check and convert what :func:`dop853` and :func:`~pnrotor.ode.bulirsch_stoer.bulirsch_stoer` share
    (their docstrings say what each must be) → :class:`_Inputs`; a ValueError or TypeError naming the first
    bad one."""
    t0 = _finite_scalar(t0, "t0")
    t_end = _finite_scalar(t_end, "t_end")
    y0 = _validate_state(y0)
    atol_a, rtol_a = _validate_tolerances(atol, rtol, y0.size)
    p = _validate_args(args)
    fs, ms, max_steps = _validate_steps(first_step, max_step, max_steps, t0, t_end)
    mode, te = _validate_t_eval(t_eval, t0, t_end)
    rhs_f = _jit_function(rhs, RHS_SIG, "rhs")
    after_f = _default_hook("after_step") if after_step is None else _jit_function(after_step, AFTER_STEP_SIG,
                                                                                       "after_step")
    return _Inputs(rhs_f, after_f, t0, y0, t_end, p, atol_a, rtol_a, fs, ms, max_steps, mode, te)


def _event_inputs(events, n_events, event_direction):
    """(events function or the no-op hook, m, direction per event) from :func:`dop853`'s event arguments."""
    if isinstance(n_events, (bool, np.bool_)) or not isinstance(n_events, (int, np.integer)) or n_events < 0:
        raise ValueError(f"n_events must be an integer >= 0, got {n_events!r}")
    n_events = int(n_events)
    if events is None:
        if n_events != 0:
            raise ValueError("n_events must be 0 when no events function is given")
        if event_direction is not None:
            raise ValueError("event_direction given without an events function")
        events_f = _default_hook("events")
    else:
        if n_events < 1:
            raise ValueError("n_events must be >= 1 when an events function is given")
        events_f = _jit_function(events, EVENTS_SIG, "events")
    if event_direction is None:
        return events_f, n_events, np.zeros(max(n_events, 1))
    ed = _real_array(event_direction, "event_direction")
    if ed.ndim > 1 or (ed.ndim == 1 and ed.size != n_events):
        raise ValueError(f"event_direction must be a scalar or have shape ({n_events},), got shape {ed.shape}")
    ed = np.broadcast_to(ed, (n_events,))
    if not np.all((ed == -1.0) | (ed == 0.0) | (ed == 1.0)):
        raise ValueError("event_direction values must be -1, 0 or +1")
    return events_f, n_events, np.ascontiguousarray(ed, dtype=np.float64).copy()


def _controller(safety, min_factor, max_factor):
    """(safety, min_factor, max_factor) checked: 0 < safety ≤ 1, 0 < min_factor < 1 ≤ max_factor."""
    safety = _positive_factor(safety, "safety", 0.0, 1.0)
    min_factor = _positive_factor(min_factor, "min_factor", 0.0, 1.0, hi_open=True)  # < 1: rejections shrink h
    max_factor = _finite_scalar(max_factor, "max_factor")
    if max_factor < 1.0:
        raise ValueError(f"max_factor must be >= 1, got {max_factor!r}")
    return safety, min_factor, max_factor


def _result(t_out, y_out, iv, fv, method, **extra):
    """The :class:`OdeResult` of a core's outputs (its rows up to the output count, counters, status)."""
    status = int(iv[IV_STATUS])
    nout = int(iv[IV_NOUT])
    return OdeResult(
        t=t_out[:nout].copy(), y=y_out[:nout].copy(), nfev=iv[IV_NFEV], nsteps=iv[IV_NSTEPS],
        naccepted=iv[IV_NACC], nrejected=iv[IV_NREJ], n_modified=iv[IV_NMOD], status=status,
        message=_status_message(status, iv, fv), method=method, **extra)


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
    c = _common_inputs(rhs, t0, y0, t_end, atol, rtol, args, first_step, max_step, max_steps, t_eval, after_step)
    safety, min_factor, max_factor = _controller(safety, min_factor, max_factor)
    events_f, n_events, ev_dir = _event_inputs(events, n_events, event_direction)
    dense = bool(dense)
    if c.t_end == c.t0:
        if dense:
            raise ValueError("dense=True needs t_end != t0 (there is no step to interpolate)")
        return _trivial_result(c.t0, c.y0, c.mode, c.t_eval, "DOP853")

    return _integrate(c.rhs, c.after_step, events_f, c.t0, c.y0, c.t_end, c.p, c.atol, c.rtol, c.first_step,
                      c.max_step, c.max_steps, c.t_eval, c.mode, dense, n_events, ev_dir, safety, min_factor,
                      max_factor)


def _integrate(rhs, after_step, events, t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps, t_eval,
               mode, dense, n_events, ev_dir, safety, min_factor, max_factor):
    """:func:`dop853` after its checks: the core called with arguments already of its declared types (t_end ≠ t0,
    functions by address or checked dispatchers, contiguous float64 arrays, ``mode`` an ``OUT_*`` code) →
    :class:`OdeResult`.  :func:`pnrotor.pn.evolve.integrate_half` calls it directly with inputs its settings
    stage has checked, which saves the 20–40 µs of :func:`dop853`'s validation per half (measured)."""
    t_out, y_out, seg_t, seg_h, seg_c, iv, fv, y_ev = _entry_point(_dop853_core, _CORE_SIG)(
        _function_addresses(rhs, after_step, events), t0, y0, t_end, p, atol, rtol, first_step, max_step, max_steps,
        t_eval, mode, dense, n_events, ev_dir, safety, min_factor, max_factor)
    nseg = int(iv[IV_NSEG])
    dense_out = None
    if dense and nseg > 0:
        dense_out = DenseOutput(seg_t[:nseg].copy(), seg_h[:nseg].copy(), seg_c[:nseg].copy(), fv[FV_T])
    ev = int(iv[IV_STATUS]) == STATUS_EVENT
    return _result(t_out, y_out, iv, fv, "DOP853", t_event=float(fv[FV_TEVENT]) if ev else None,
                   y_event=y_ev.copy() if ev else None, event_index=int(iv[IV_EVENT]) if ev else None,
                   dense=dense_out)
