r"""Integration of an angular velocity to a rotor history: the public entry point of the verification mode.

This module owns :func:`integrate_angular_velocity`, which chooses the right-hand side for the given
ω and formulation (:mod:`pnrotor.formulations`, Secs. II–IV of Boyle 2016, arXiv:1604.08139), runs
one of the integrators of :mod:`pnrotor.ode` (DOP853 or Bulirsch–Stoer, as in the paper's Sec. V),
and returns the unit, sign-continuous rotors with the integrator's statistics as a
:class:`pnrotor.history.FrameHistory`. It implements no equation itself.
"""

import math
import time

import numpy as np
from numba.core.registry import CPUDispatcher

from pnrotor import formulations
from pnrotor import quaternion as quat
from pnrotor.history import FrameHistory
from pnrotor.ode import bulirsch_stoer, dop853

METHODS = {"DOP853": dop853, "Bulirsch-Stoer": bulirsch_stoer}
"""Integrators by their canonical names."""

_METHOD_NAMES = {"dop853": "DOP853", "bulirsch-stoer": "Bulirsch-Stoer", "bs": "Bulirsch-Stoer"}


def method_name(method):
    """The canonical name (a key of :data:`METHODS`) of ``method``, case-insensitive; 'BS' is accepted."""
    try:
        return _METHOD_NAMES[str(method).lower().replace("_", "-")]
    except KeyError:
        raise ValueError(f"unknown method {method!r}; choose DOP853 or Bulirsch-Stoer (BS)") from None


def _check_omega_value(w, where):
    w = np.asarray(w, dtype=np.float64)
    if w.shape != (3,) or not np.all(np.isfinite(w)):
        raise ValueError(f"omega({where!r}) must be three finite floats, got {w!r}")


def _integrand(omega, formulation, t0):
    """(rhs, leading parameters of p, ω over an array of times, description of ω) for ``omega``."""
    if hasattr(omega, "integrand"):
        rhs, p = omega.integrand(formulation)
        return rhs, p, omega.angular_velocity, omega.describe()
    if callable(omega):
        _check_omega_value(omega(t0), t0)

        def omega_at(ts):
            return np.array([omega(t) for t in ts], dtype=np.float64).reshape(len(ts), 3)

        name = getattr(omega, "__qualname__", repr(omega))
        if isinstance(omega, CPUDispatcher):
            return (formulations.rhs_for_numba_omega(formulation.derivative, omega), np.empty(0),
                    omega_at, {"omega": f"numba function {name}"})
        return (formulations.rhs_for_numba_omega(formulation.derivative,
                                                 formulations.numba_omega_from_python(omega)),
                np.empty(0), omega_at, {"omega": f"Python function {name}"})
    raise TypeError(f"omega must be a numba @njit function of t, a Python callable, or an object with an "
                    f"integrand() method such as PrecessingNutatingBinary; got {type(omega).__name__}")


def integrate_angular_velocity(omega, t_span, R0, formulation="rotor", method="DOP853", atol=1e-12, rtol=0.0,
                               t_eval=None, dense=False, *, damping=(0.01, 0.01), max_steps=1_000_000):
    """Integrate the angular velocity ω(t) from R(t_span[0]) = R0 and return the rotor history.

    Parameters
    ----------
    omega
        The angular velocity (inertial frame, ω = 2 Ṙ R⁻¹, eq:angular-velocity), one of

        * a :class:`pnrotor.analytic.PrecessingNutatingBinary` (or any object with its
          ``integrand``, ``angular_velocity`` and ``describe`` methods): cached right-hand sides,
          nothing compiled per process — the fast path;
        * a numba ``@njit`` function ``omega(t)`` returning three floats (an array or a tuple): the
          right-hand side composing it with the formulation is compiled once per process (~0.4 s),
          then runs as fast as the cached path;
        * a plain Python callable ``omega(t)`` returning three floats: called from the compiled
          integrator through numba's object mode, many times slower than the cached path.

        For the generator and vector formulations, a user's ω is also called from Python once per
        output interval, to make the rotor signs continuous (see :mod:`pnrotor.formulations`).
    t_span : (t0, t_end)
        Integration interval; t_end < t0 integrates backward.
    R0 : array_like (4,)
        Rotor at t0 (w, x, y, z), any nonzero norm; normalized.
    formulation : str
        One of :data:`pnrotor.formulations.FORMULATIONS`: 'rotor', 'generator', 'generator-noreset',
        'vectors3', 'vectors2', 'vectors-damped'.
    method : str
        'DOP853' or 'Bulirsch-Stoer' ('BS'), case-insensitive.  Bulirsch–Stoer needs a smooth ω: across a
        jump or kink it can return a wrong answer with no warning (:mod:`pnrotor.ode.bulirsch_stoer`).
    atol, rtol : float
        Tolerances on each state component (the paper uses rtol = 0, Sec. V-A).
    t_eval : None or array_like
        None: every accepted step. An array of times (DOP853 only): the 7th-order dense output there.
        Rotors are made sign-continuous from sample to sample (see :mod:`pnrotor.formulations`), so
        samples should resolve the rotation.
    dense : bool
        DOP853 only: keep the integrator's dense output of the evolved state in ``history.dense``
        (convert its values with ``pnrotor.formulations.get(formulation).to_rotors``).
    damping : (λ, μ)
        Damping rates of 'vectors-damped' (eq:vector-norm-damping, eq:vector-orthogonality-damping), finite
        and ≥ 0; their signs are flipped when integrating backward, so that constraint violations decay in the
        direction of integration. Rates well above the inverse step size make the system stiff.
    max_steps : int
        Maximum number of step attempts.

    Returns
    -------
    FrameHistory
        ``t``, unit rotors ``R`` (N, 4), sign-continuous from R0 at t0 (the solution's sign, also at samples
        that do not start at t0), the integrator's statistics,
        ``n_resets`` (generator resets, eq:generator_reset), ``status``/``message`` (0 = reached t_end),
        ``wall_time`` of the integration proper, and the inputs.

    Raises
    ------
    ValueError
        Unknown formulation or method, bad R0, t_span, tolerances, or ω values; options the method
        does not support (t_eval arrays or dense output with Bulirsch–Stoer).
    """
    form = formulations.get(formulation)
    method = method_name(method)
    if not all(np.ndim(x) == 0 and np.asarray(x).dtype.kind in "iuf" for x in (atol, rtol)):
        raise ValueError(f"atol and rtol must be numbers (one tolerance for every state component), got "
                         f"atol = {atol!r}, rtol = {rtol!r}")
    try:
        t0, t_end = (float(x) for x in t_span)
    except (TypeError, ValueError):
        raise ValueError(f"t_span must be a pair of numbers (t0, t_end), got {t_span!r}") from None
    if not (math.isfinite(t0) and math.isfinite(t_end)):
        raise ValueError(f"t_span must be finite, got {t_span!r}")
    R0 = np.array(R0, dtype=np.float64)
    if R0.shape != (4,) or not np.all(np.isfinite(R0)) or not np.any(R0):
        raise ValueError(f"R0 must be a finite nonzero quaternion (w, x, y, z), got {R0!r}")
    R0 = quat.normalize(R0)

    rhs, p_omega, omega_at, inputs = _integrand(omega, form, t0)
    p = np.array(p_omega, dtype=np.float64)
    if form.n_params:
        lam, mu = (float(x) for x in damping)
        if not (math.isfinite(lam) and math.isfinite(mu) and lam >= 0.0 and mu >= 0.0):
            raise ValueError(f"damping (λ, μ) must be finite and >= 0 (negative rates would make the constraint "
                             f"violations grow), got {damping!r}")
        # the damping terms vanish on the constraint surface and pull towards it in the direction of
        # integration; backward in time that takes −λ, −μ (with +λ, +μ violations would grow as e^{λ|t|})
        direction = 1.0 if t_end >= t0 else -1.0
        p = np.concatenate([p, [direction * lam, direction * mu]])
        inputs.update(damping_lambda=lam, damping_mu=mu)
    inputs.update(t0=t0, t_end=t_end, R0=R0)

    options = {"t_eval": t_eval} if t_eval is not None else {}
    if dense:
        options["dense"] = True
    start = time.perf_counter()
    res = METHODS[method](rhs, t0, form.initial_state(R0), t_end, atol, rtol, args=p,
                          after_step=form.after_step, max_steps=max_steps, **options)
    wall = time.perf_counter() - start

    return FrameHistory(
        t=res.t, R=form.rotors(res.y, R0, res.t, omega_at, t0), formulation=form.name, method=method,
        atol=float(atol), rtol=float(rtol), nfev=res.nfev, nsteps=res.nsteps, naccepted=res.naccepted,
        nrejected=res.nrejected, n_resets=res.n_modified, status=res.status, message=res.message,
        wall_time=wall, inputs=inputs, dense=res.dense)
