r"""What pnrotor's ODE solvers share: the signatures of the functions they call, the passing of compiled functions
to their cores by address, the numba kernels every core uses, the checks of the arguments every solver takes and
the assembly of their results.  A solver imports this module, :mod:`~pnrotor.ode.result` and, if it locates
events, :mod:`~pnrotor.ode.events`; never another solver.

A solver module (:mod:`pnrotor.ode.dop853`, :mod:`pnrotor.ode.bulirsch_stoer`) provides

* ``CORE_SIG``, one explicit numba signature, and ``core``, its driver loop: an ``@njit(cache=True)`` function
  compiled for ``CORE_SIG`` on its first use (:func:`entry_point`), not at import, and the same compiled code for
  every right-hand side.  Its arguments are ``functions`` (int64 addresses in the order of
  :data:`FUNCTIONS_LAYOUT`, from :func:`function_addresses`; a solver without events reads the first four), t0, y0,
  t_end, p, atol, rtol (per component), first_step (0: automatic), max_step, max_steps, then its own, among them the
  output mode (``OUT_STEPS``, ``OUT_TEVAL`` or ``OUT_FINAL``).  It returns a tuple of t_out, y_out (over-allocated:
  rows up to ``ivals[IV_NOUT]``), its statistics ``ivals`` (int64, indexed by the ``IV_*`` constants, the status a
  ``STATUS_*`` code of :mod:`~pnrotor.ode.result`) and ``fvals`` (float64, ``FV_*``), and any outputs of its own
  (DOP853's dense output and event state);
* a Python entry named after the method, ``name(rhs, t0, y0, t_end, atol, rtol, args, first_step, max_step,
  max_steps, t_eval, after_step, …)``: the arguments of :func:`common_inputs` checked there (a ValueError or
  TypeError naming the bad one), a ValueError for an option the method does not implement, :func:`trivial_result`
  when t_end == t0, else :func:`assemble_result` of its core's outputs: an :class:`~pnrotor.ode.result.OdeResult`.

Function types: a core takes the right-hand side and hooks by the addresses of their compiled code (one int64
array, ``FUNCTIONS_LAYOUT``), checked against the explicit signatures below before the call, and calls them inside
as first-class ``numba.types.FunctionType`` values (:data:`rhs_function`, …); numba caches such a driver across
processes (a driver taking a dispatcher or closure is recompiled in every process).  Calling
:func:`~pnrotor.ode.dop853.dop853` has a fixed cost (argument checks), which ``benchmarks/bench_ode.py`` measures.
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

from .result import STATUS_MESSAGES, STATUS_STEP_UNDERFLOW, STATUS_SUCCESS, OdeResult

# --------------------------------------------------------------------------------------------------
# signatures of user functions and of the cores; the cores' output modes and statistics
# --------------------------------------------------------------------------------------------------

RHS_SIG = types.void(types.float64, types.float64[::1], types.float64[::1], types.float64[::1])
"""``rhs(t, y, p, dydt)``: write dy/dt at (t, y) with parameters p into ``dydt``."""

AFTER_STEP_SIG = types.boolean(types.float64, types.float64[::1], types.float64[::1])
"""``after_step(t, y, p) -> bool``: may modify y in place after an accepted step; return True if it did."""

EVENTS_SIG = types.void(types.float64, types.float64[::1], types.float64[::1], types.float64[::1])
"""``events(t, y, p, g)``: fill g[0..m-1] with the m event functions at (t, y)."""

# numba types of the cores' arguments (CORE_SIG of each solver)
F8 = types.float64
I8 = types.int64
B1 = types.boolean
A1 = types.float64[::1]
A2 = types.float64[:, ::1]
A3 = types.float64[:, :, ::1]
I1 = types.int64[::1]

# output modes of the cores
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


def default_hook(name):
    """The no-op hook ``name`` ('after_step' or 'events') in its cheapest form for passing to a core."""
    return by_address(*{"after_step": (no_after_step, AFTER_STEP_SIG), "events": (no_events, EVENTS_SIG)}[name])


# --------------------------------------------------------------------------------------------------
# calling the cores cheaply
# --------------------------------------------------------------------------------------------------
#
# The cores take their functions as one int64 array of addresses, FUNCTIONS_LAYOUT, and turn each pair into
# a first-class function inside (`function_of`).  Declared as FunctionType arguments instead, every call
# of a core from Python unboxed each function through numba's Python helpers (a module import, two
# unpickled signatures and two Python calls per function), many times the cost of the address array.


def function_of(sig):
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


rhs_function = function_of(RHS_SIG)
after_step_function = function_of(AFTER_STEP_SIG)
events_function = function_of(EVENTS_SIG)
FUNCTIONS_LAYOUT = ("rhs", "after_step", "events")
"""The cores' ``functions`` argument: for each of these in turn, its (cfunc wrapper, jit entry or 0) addresses."""


class _FunctionAddress:
    """A compiled numba function as the cores take it: its ``addresses`` (:func:`function_of`, from
    :func:`addresses`) and the function itself, which keeps the compiled code alive during a call."""

    def __init__(self, f, sig, addresses):
        self._function = f
        self._sig = sig
        self.addresses = addresses


def addresses(f, sig, raises):
    """(cfunc wrapper address, jit entry address or 0) of f compiled for sig; ``raises``: keep the jit entry, so
    that an exception raised inside reaches the caller (without it the call goes through the cfunc wrapper)."""
    from numba.experimental.function_type import _get_jit_address, _get_wrapper_address

    return _get_wrapper_address(f, sig), _get_jit_address(f, sig) if raises else 0


_BY_ADDRESS = {}


def by_address(f, sig):
    """The ``@njit`` function ``f`` with signature ``sig`` in its cheapest form for :func:`~pnrotor.ode.dop853.dop853`
    and :func:`~pnrotor.ode.bulirsch_stoer.bulirsch_stoer`: its compiled address, looked up once (a dispatcher costs 5-13 µs more per
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
        entry = _BY_ADDRESS[key] = (sig, _FunctionAddress(f, sig, addresses(f, sig, raises=False)))
    return entry[1]


def function_addresses(*functions):
    """The cores' ``functions`` array (FUNCTIONS_LAYOUT) of :class:`_FunctionAddress` values."""
    return np.array([a for f in functions for a in f.addresses], dtype=np.int64)


_ENTRY_POINTS = {}


def entry_point(core, sig, aside=None):
    """The compiled entry point of a solver's core for its one signature ``sig`` (or the dispatcher), compiled or
    loaded from numba's cache on first use.  ``aside``: what :func:`pnrotor.numba_cache.compile_aside` calls the
    core, if the CLI may be compiling it in another process; that compilation is then awaited first, so that
    this one loads it."""
    ep = _ENTRY_POINTS.get(core)
    if ep is None:
        if aside is not None and not core.overloads:
            from pnrotor import numba_cache

            numba_cache.wait_for_aside(aside)
        try:
            core.compile(sig)
            ep = core.overloads[tuple(sig.args)].entry_point
        except Exception:  # pragma: no cover - numba internals changed
            ep = core
        _ENTRY_POINTS[core] = ep
    return ep


# --------------------------------------------------------------------------------------------------
# numba kernels the cores share
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def all_finite(x):
    for i in range(x.size):
        if not math.isfinite(x[i]):
            return False
    return True


@njit(cache=True)
def append_row(t_out, y_out, n_out, t, y):
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
def scaled(x, sc):
    """x / sc for an error scale sc = atol + rtol |y| ≥ 0.  sc = 0 (atol = 0 where y = 0, a pure relative
    tolerance) allows no error: a zero x is none, any other an infinite one (the step is rejected)."""
    if sc > 0.0:
        return x / sc
    return 0.0 if x == 0.0 else math.inf


@njit(cache=True)
def _rms_scaled(x, y, atol, rtol):
    """RMS of x / (atol + rtol |y|) (:func:`scaled`)."""
    s = 0.0
    for i in range(x.size):
        r = scaled(x[i], atol[i] + rtol[i] * abs(y[i]))
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
        r = scaled(f1[i] - f0[i], atol[i] + rtol[i] * abs(y0[i]))
        s += r * r
    d2 = math.sqrt(s / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    if not h1 > 0.0:   # the norms overflowed, or are infinite (a zero tolerance where the state is 0)
        h1 = h0
    return min(100.0 * h0, h1, interval, max_step)

# --------------------------------------------------------------------------------------------------
# the Python entries' checks and result assembly
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
more than a call of :func:`_jit_function` that finds them here; a recompiled dispatcher has a new overload."""


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
            known = (f.overloads[tuple(sig.args)], addresses(f, sig, raises=True))
            try:
                _CHECKED.setdefault(f, {})[name] = known
            except TypeError:  # pragma: no cover
                pass
        return _FunctionAddress(f, sig, known[1])
    if isinstance(f, CFunc):   # its C wrapper prints an exception raised inside and returns: a wrong run, not an error
        raise TypeError(f"{name} must be an @njit function, not a @cfunc (an exception raised inside a @cfunc cannot "
                        f"reach the caller); use @njit({_sig_label(sig)}, cache=True)")
    if isinstance(f, _FunctionAddress):
        # the identity test spares comparing signatures in the usual case
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


def trivial_result(t0, y0, mode, t_eval, method):
    """t_end == t0: nothing to integrate."""
    if mode == OUT_TEVAL:
        t = t_eval.copy()
        y = np.repeat(y0[None, :], t.size, axis=0)
    else:
        t = np.array([t0])
        y = y0[None, :].copy()
    return OdeResult(t, y, 0, 0, 0, 0, 0, STATUS_SUCCESS, "t_end == t0: nothing to integrate.", method=method)


class Inputs(NamedTuple):
    """The arguments both integrators take, checked and converted (:func:`common_inputs`)."""

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


def common_inputs(rhs, t0, y0, t_end, atol, rtol, args, first_step, max_step, max_steps, t_eval, after_step):
    """Check and convert what :func:`~pnrotor.ode.dop853.dop853` and :func:`~pnrotor.ode.bulirsch_stoer.bulirsch_stoer`
    share
    (their docstrings say what each must be) → :class:`Inputs`; a ValueError or TypeError naming the first
    bad one."""
    t0 = _finite_scalar(t0, "t0")
    t_end = _finite_scalar(t_end, "t_end")
    y0 = _validate_state(y0)
    atol_a, rtol_a = _validate_tolerances(atol, rtol, y0.size)
    p = _validate_args(args)
    fs, ms, max_steps = _validate_steps(first_step, max_step, max_steps, t0, t_end)
    mode, te = _validate_t_eval(t_eval, t0, t_end)
    rhs_f = _jit_function(rhs, RHS_SIG, "rhs")
    after_f = default_hook("after_step") if after_step is None else _jit_function(after_step, AFTER_STEP_SIG,
                                                                                       "after_step")
    return Inputs(rhs_f, after_f, t0, y0, t_end, p, atol_a, rtol_a, fs, ms, max_steps, mode, te)


def event_inputs(events, n_events, event_direction):
    """(events function or the no-op hook, m, direction per event) from a solver's event arguments (those of
    :func:`~pnrotor.ode.dop853.dop853`)."""
    if isinstance(n_events, (bool, np.bool_)) or not isinstance(n_events, (int, np.integer)) or n_events < 0:
        raise ValueError(f"n_events must be an integer >= 0, got {n_events!r}")
    n_events = int(n_events)
    if events is None:
        if n_events != 0:
            raise ValueError("n_events must be 0 when no events function is given")
        if event_direction is not None:
            raise ValueError("event_direction given without an events function")
        events_f = default_hook("events")
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


def controller(safety, min_factor, max_factor):
    """(safety, min_factor, max_factor) checked: 0 < safety ≤ 1, 0 < min_factor < 1 ≤ max_factor."""
    safety = _positive_factor(safety, "safety", 0.0, 1.0)
    min_factor = _positive_factor(min_factor, "min_factor", 0.0, 1.0, hi_open=True)  # < 1: rejections shrink h
    max_factor = _finite_scalar(max_factor, "max_factor")
    if max_factor < 1.0:
        raise ValueError(f"max_factor must be >= 1, got {max_factor!r}")
    return safety, min_factor, max_factor


def assemble_result(t_out, y_out, iv, fv, method, **extra):
    """The :class:`OdeResult` of a core's outputs (its rows up to the output count, counters, status)."""
    status = int(iv[IV_STATUS])
    nout = int(iv[IV_NOUT])
    return OdeResult(
        t=t_out[:nout].copy(), y=y_out[:nout].copy(), nfev=iv[IV_NFEV], nsteps=iv[IV_NSTEPS],
        naccepted=iv[IV_NACC], nrejected=iv[IV_NREJ], n_modified=iv[IV_NMOD], status=status,
        message=_status_message(status, iv, fv), method=method, **extra)
