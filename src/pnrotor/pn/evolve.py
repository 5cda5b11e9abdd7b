r"""``evolve``: integrate the post-Newtonian system backward and forward from f_ref → :class:`Evolution`.

One run is four stages, each a function that the others (and later callers such as a batch of
binaries or waveform modes) can compose:

1. :func:`pnrotor.pn.settings.settings`: inputs checked and in geometric units (:mod:`pnrotor.pn.initial`),
   t = 0 at the reference GW frequency f_ref, Φ(0) = 0, n̂(0) = ``n_hat``, ℓ̂(0) = ``ell_hat``
   → :class:`~pnrotor.pn.settings.Settings`;
2. :func:`build_system`: the right-hand side — :func:`~pnrotor.pn.rhs.rhs_aligned` (state [v, Φ]) for
   nonspinning and aligned-spin binaries, :func:`~pnrotor.pn.rhs.rhs_precessing` (state
   [v, χ₁, χ₂, R, Φ]) otherwise or when ``integrate_rotor=True`` (or
   :func:`~pnrotor.pn.rhs.rhs_precessing_instantaneous` with ``precession='instantaneous'``) — its
   events, parameter vector and initial state, and the check that f_ref is inside the inspiral
   → :class:`System` (:func:`build_rows` for many binaries at once);
3. :func:`integrate_half`: DOP853 backward to f_min (if given) and forward to f_max or to termination,
   each with terminal events; both halves share t = 0;
4. :func:`pnrotor.pn.sampling.sample`: the two halves stitched into one history, from the integrator's
   steps or its 7th-order dense output (never by shortening steps) → :class:`Evolution`.

Termination reasons (``Evolution.termination`` for the forward half, ``stats['termination_backward']``):

* ``'f_max'`` / ``'f_min'`` — v reached the requested end frequency;
* ``'v_max'`` — v reached 1 (no f_max given and nothing else stopped the inspiral first);
* ``'energy_balance'`` — E′(v) ≥ 0: the binding energy no longer decreases with v;
* ``'vdot_nonpositive'`` — v̇ ≤ 0; a safety net: where N or D of v̇ = K v⁹N/D falls to zero, event 6
  or the pole guard fires first, so only a change of the spins could end a run here;
* ``'vdot_peak'`` — ∂(v²v̇)/∂v ≤ 0 at the current spins: the orbital frequency's rate ω̇ = 3v²v̇/M
  stopped increasing (LALSuite's d²ω/dt² ≤ 0, its code 1026; the well-defined end where T4's flux ratio
  approaches a root and v would creep towards it forever, :mod:`pnrotor.pn.rhs` event 6);
* ``'vdot_divergent'`` — the denominator of v̇ (T5: the re-expanded Ê′/F̂) fell to 1e-3, just before
  the pole where v̇ → ∞ (for T1 the denominator is Ê′ itself and this is reported as
  ``'energy_balance'``);
* ``'spin_magnitude'`` — |χᵢ|² exceeded 1 by more than 1000 (atol + rtol), at least 1e-10 and at most 1e-3:
  far more than the integration's drift (:func:`pnrotor.pn.layout.spin_tolerance`);
* ``'nonfinite'``, ``'max_steps'``, ``'step_underflow'`` — integrator failures;
* ``'time_limit'`` — the generous time bound (4τ_N + 10⁴ M forward) was reached (should not happen);
* ``'not_integrated'`` — backward half only, when no f_min was given.
"""

import functools
import inspect
import math
import time
import warnings
from dataclasses import dataclass

import numpy as np

from ..ode import EVENTS_SIG, RHS_SIG, by_address
from ..ode.common import OUT_FINAL, OUT_STEPS, controller, default_hook
from ..ode.dop853 import run_core
from ..ode.result import (STATUS_EVENT, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW,
                          STATUS_SUCCESS)
from .. import approximants
from . import ends, layout, rhs, system
from . import initial as _ini
from .sampling import compile_output_kernel, sample
from .series import basis_values, kmax_from_orders
from .settings import settings
from pnrotor.results.runs import Evolution

TERMINATION_MESSAGES = {
    "f_max": "v reached the requested end frequency f_max",
    "f_min": "v reached the requested start frequency f_min",
    "v_max": "v reached v_max = 1",
    "energy_balance": "E'(v) >= 0: the PN binding energy stopped decreasing (energy balance breaks down)",
    "vdot_nonpositive": "dv/dt <= 0: the PN energy balance gives no inspiral",
    "vdot_peak": "d2(omega)/dt2 <= 0: the orbital frequency stopped accelerating (LALSuite's code 1026)",
    "vdot_divergent": "dv/dt diverges: the denominator of the approximant's dv/dt reached zero",
    "spin_magnitude": "|chi_i| exceeded 1",
    "nonfinite": "the state or its derivative became non-finite",
    "max_steps": "the integrator reached its step limit",
    "step_underflow": "the integrator's step size underflowed",
    "time_limit": "the time bound of the integration was reached before any termination condition",
    "not_integrated": "this half was not integrated (no f_min given)",
}

CONTROLLER = dict(safety=0.85, max_factor=4.0)
"""DOP853 step-size controller for the inspiral.  With Hairer's defaults (0.9, 6) the accelerating chirp
makes every few steps a rejection (18–57 of 116–216 attempts in the LALSuite comparison cases); with
(0.85, 4) there are none and the runs cost 10–35% fewer evaluations (benchmarks/bench_pn.py)."""
CONTROLLER_ARGS = controller(CONTROLLER["safety"], 1.0 / 3.0, CONTROLLER["max_factor"])
"""(safety, min_factor, max_factor) as :func:`pnrotor.ode.dop853` would check them (min_factor its default)."""


# ---------------------------------------------------------------------------------------------------
# stage 2: the specialized system
# ---------------------------------------------------------------------------------------------------

@dataclass(eq=False)
class System:
    """The compiled problem of one run: right-hand side and events (by address, see
    :func:`pnrotor.ode.by_address`), parameter vector ``p`` (:func:`pnrotor.pn.system.make_parameters`),
    initial state ``y0``, and what the forward and backward halves need to stop: the PN truncation
    ``kmax`` and spin invariants ``basis`` at f_ref (for the bound on f_ref in the error message)."""

    rhs: object
    events: object
    p: np.ndarray
    y0: np.ndarray
    kmax: np.ndarray
    basis: np.ndarray


def build_system(s):
    """The :class:`System` of :class:`~pnrotor.pn.settings.Settings` ``s``; a ValueError if f_ref is at or
    past the end of the inspiral (the terminal events only fire on crossing zero, so none may start there)."""
    kmax = kmax_of(s)
    rhs, events = _functions(s.use_aligned, s.precession)
    bvals, y0 = _start(s)
    p, at_v0 = system.make_parameters(
        s.X1, s.approximant, kmax, so_order=s.spin_orbit_order, ss_order=s.spin_spin_order, kappa1=s.kappa1,
        kappa2=s.kappa2, lambda1=s.lambda1, lambda2=s.lambda2, v_end=s.v_max, spin_tol=layout.spin_tolerance(s.atol, s.rtol), rotor=s.rotor,
        phase_shift=s.precession_phase_shift,
        aligned_basis=bvals if s.use_aligned else None, omega_l=_omega_l(s), basis=bvals, v_check=s.v0,
        horizon=s.horizon_absorption)
    check_start(s, kmax, bvals, *at_v0, ends.earlier_end(*events.addresses, y0, p))
    return System(rhs, events, p, y0, kmax, bvals)


def kmax_of(s):
    """The PN truncation of settings ``s`` (:func:`pnrotor.pn.series.kmax_from_orders`)."""
    return kmax_from_orders(s.pn_order, s.spin_orbit_order, s.spin_spin_order, s.tidal_order)


def _functions(use_aligned, precession):
    """(right-hand side, events) of a run, by address: :func:`~pnrotor.pn.rhs.rhs_aligned` (state [v, Φ]) if
    ``use_aligned`` (its Settings' flag: nonspinning and aligned spins), else :func:`~pnrotor.pn.rhs.rhs_precessing`
    (state [v, χ₁, χ₂, R, Φ]; or :func:`~pnrotor.pn.rhs.rhs_precessing_instantaneous` with
    ``precession='instantaneous'``)."""
    if use_aligned:
        f, events = rhs.rhs_aligned, rhs.events_aligned
    else:
        f = rhs.rhs_precessing_instantaneous if precession == "instantaneous" else rhs.rhs_precessing
        events = rhs.events_precessing
    # they cannot raise (error_model='numpy'), so they may go to the integrator by address
    return by_address(f, RHS_SIG), by_address(events, EVENTS_SIG)


def _invariants(x1, y1, z1, x2, y2, z2, lx, ly, lz):
    """The spin invariants (:func:`~pnrotor.pn.series.basis_values`) of χ₁, χ₂ and ℓ̂ by components: floats (one
    binary, cheaper than np.dot), or arrays (n,) → (9, n), elementwise the same numbers."""
    return basis_values(lx * x1 + ly * y1 + lz * z1, lx * x2 + ly * y2 + lz * z2, x1 * x2 + y1 * y2 + z1 * z2,
                        x1 * x1 + y1 * y1 + z1 * z1, x2 * x2 + y2 * y2 + z2 * z2)


def _start(s):
    """(spin invariants at f_ref, initial state of the right-hand side of :func:`_functions`) of settings ``s``."""
    (x1, y1, z1), (x2, y2, z2), (lx, ly, lz) = s.chi1.tolist(), s.chi2.tolist(), s.ell_hat.tolist()   # floats
    bvals = _invariants(x1, y1, z1, x2, y2, z2, lx, ly, lz)
    if s.use_aligned:
        return bvals, np.array([s.v0, 0.0])
    if s.horizon_absorption:   # [v, χ₁, χ₂, R, Φ, m₁, m₂], the masses in units of M at f_ref
        return bvals, np.array([s.v0, x1, y1, z1, x2, y2, z2, *s.R0.tolist(), 0.0, s.X1, 1.0 - s.X1])
    return bvals, np.array([s.v0, x1, y1, z1, x2, y2, z2, *s.R0.tolist(), 0.0])   # [v, χ₁, χ₂, R, Φ]


def build_rows(o, b, parts, rows):
    """What :func:`build_system` builds and checks, for binaries that share :class:`~pnrotor.pn.settings.Checked`
    ``o`` and their right-hand side (all on the [v, Φ] system, ``use_aligned``, or none), in one compiled call
    (:func:`pnrotor.pn.system.start_rows`: ``evolve_many``): b holds their rows of
    :class:`~pnrotor.pn.settings.Binaries`, binary i from row rows[i] of the spin-independent ``parts``
    (:func:`population_parts`) → (right-hand side, events, parameter vectors P (n, P_SIZE), initial states Y0
    (n, size), spin invariants (n, 9), start checks (n, 5): ``check_start(s, kmax, invariants, *checks)`` raises
    for binary i what build_system would).  Bitwise build_system's numbers (tests/test_pn_coefficients.py)."""
    aligned = bool(b.aligned[0])
    rhs, events = _functions(aligned, o.precession)
    bases = np.ascontiguousarray(_invariants(*b.chi1.T, *b.chi2.T, *b.ell_hat.T).T)
    zeros = np.zeros((b.v0.size, 1))
    masses = [b.X1[:, None], 1.0 - b.X1[:, None]] if o.horizon_absorption else []
    Y0 = np.concatenate([b.v0[:, None], zeros] if aligned else [b.v0[:, None], b.chi1, b.chi2, b.R0, zeros, *masses],
                        axis=1)
    P, checks = np.zeros((b.v0.size, layout.P_SIZE)), np.empty((b.v0.size, 5))
    system.start_rows(*parts, rows, bases, aligned, b.v_max, layout.spin_tolerance(o.atol, o.rtol), *events.addresses,
                    Y0, P, checks)
    return rhs, events, P, Y0, bases, checks


def _omega_l(s):
    return "varpi" if s.precession == "averaged_varpi" else "torque"


def population_parts(s, X1, kappa1, kappa2, lambda1=0.0, lambda2=0.0):
    """:func:`pnrotor.pn.system.spin_independent_parts` of binaries with the model options of settings ``s``
    and arrays X1, κ₁, κ₂, Λ₁, Λ₂ (row i is what :func:`build_rows` takes for binary i)."""
    return system.spin_independent_parts(X1, kappa1, kappa2, s.approximant, kmax_of(s),
                                       s.spin_orbit_order, s.spin_spin_order, s.rotor, s.precession_phase_shift,
                                       _omega_l(s), lambda1, lambda2, s.horizon_absorption)


def check_start(s, kmax, bvals, n0, d0, e0, peak0, ended):
    """A ValueError naming f_ref and its bound if N, D, Ê′ or event 6 at v₀ say the inspiral has ended, or if one
    of them does at a lower v (``ended``, :func:`pnrotor.pn.ends.earlier_end`)."""
    why = ended_at(n0, d0, e0, peak0)
    if why or ended:   # the bound: the first end on inspiral_end's grid or on the start check's, whichever is lower
        v_end = min(ends.inspiral_end(s.X1, s.approximant, kmax, bvals, s.kappa1, s.kappa2, s.lambda1, s.lambda2),
                    ended or 1.0)
        why = f"{why} at v = {s.v0:.4g}" if why else \
            f"it ended at a lower v (v = {v_end:.4g}) and v = {s.v0:.4g} is beyond"
        raise ValueError(f"f_ref = {s.f_ref} Hz is past the end of the {s.approximant} inspiral: {why}; for these "
                         f"masses and spins f_ref must be below {_ini.frequency_from_v(v_end, s.M_sec):.6g} Hz "
                         f"(v = {v_end:.6g})")


def ended_at(n0, d0, e0, peak0):
    """Why the inspiral has ended at v₀ by N, D, Ê′ and event 6 there, or None (:func:`check_start`)."""
    return ("E'(v) >= 0, the PN energy balance is invalid" if not e0 > 0.0
            else "dv/dt <= 0" if not n0 * d0 > 0.0
            else f"the denominator of dv/dt is {d0:.3g} <= {layout.DEN_EPS:g}, next to its pole" if not d0 > layout.DEN_EPS
            else "the orbital frequency no longer accelerates (d2(omega)/dt2 <= 0)" if not peak0 > 0.0 else None)


# ---------------------------------------------------------------------------------------------------
# stage 3: one half of the integration
# ---------------------------------------------------------------------------------------------------

_FORWARD_EVENTS = np.array([1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0])
_BACKWARD_EVENTS = np.array([-1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0])
"""Directions of the terminal events (:mod:`pnrotor.pn.rhs`): v − v_end rising forward, falling
backward; the denominator of v̇ and event 6 falling; the others on any crossing."""


def half(v0, nu, v_min, p, forward):
    """(parameter vector, t_end, event directions) of the forward half (to f_max, or to the end of the inspiral
    within 4τ_N(v₀) + 10⁴ M) or the backward half (to f_min, within twice the Newtonian time from f_min to f_ref +
    10⁴ M) of the run from v0 with symmetric mass ratio nu and parameter vector ``p`` (a copy with v_end = v_min for
    the backward half).  Floats and one p (``evolve``), or arrays (n,) and P (n, P_SIZE) of n runs
    (``evolve_many``), elementwise the same numbers."""
    tau0 = _newtonian_time(v0, nu)
    if forward:
        return p, 4.0 * tau0 + 1.0e4, _FORWARD_EVENTS
    p = p.copy()
    p[..., layout.P_VEND] = v_min
    return p, -(2.0 * (_newtonian_time(v_min, nu) - tau0) + 1.0e4), _BACKWARD_EVENTS


def _newtonian_time(v, nu):
    """τ_N(v) (:func:`pnrotor.pn.initial.newtonian_time_to_coalescence`) of floats, or elementwise of arrays."""
    if isinstance(v, np.ndarray):
        return _ini.elementwise(_ini.newtonian_time_to_coalescence, v, nu)
    return _ini.newtonian_time_to_coalescence(v, nu)


_NO_T_EVAL = np.empty(0)


def integrate_half(s, system, forward, t_eval, dense):
    """DOP853 from f_ref over the forward or backward :func:`half` → (OdeResult, termination name); ``t_eval``
    is None (every step) or 'final'.  What :func:`pnrotor.ode.dop853` would check is guaranteed by
    :func:`~pnrotor.pn.settings.settings` and :func:`build_system`, so its core is called directly
    (:func:`pnrotor.ode.dop853.run_core`)."""
    p, t_end, directions = half(s.v0, s.nu, s.v_min, system.p, forward)
    res = run_core(system.rhs, default_hook("after_step"), system.events, 0.0, system.y0, t_end, p,
                   *tolerances(system.y0.size, float(s.atol), float(s.rtol)), 0.0, math.inf, s.max_steps,
                   _NO_T_EVAL, OUT_FINAL if t_eval == "final" else OUT_STEPS, dense, layout.N_EVENTS, directions,
                   *CONTROLLER_ARGS)
    return res, termination(res.status, res.event_index, end_name(forward, s.f_max is not None), s.approximant)


def end_name(forward, f_max_given):
    """The name of a half's end-frequency termination: 'f_max' (forward to a given f_max), 'v_max' (forward to the end
    of the inspiral) or 'f_min' (backward)."""
    return ("f_max" if f_max_given else "v_max") if forward else "f_min"


@functools.lru_cache(maxsize=8)
def tolerances(n, atol, rtol):
    """(atol, rtol) per component as the core takes them; cached, as the core only reads them."""
    return np.full(n, atol), np.full(n, rtol)


def termination(status, idx, end, approximant):
    """The termination name (module docstring) of an integration's status and event index ``idx``; ``end``
    names the end-frequency event."""
    if status == STATUS_EVENT:
        if idx == layout.EV_V_END:
            return end
        if idx == layout.EV_POLE:
            return approximants.REGISTRY[approximant].pole
        return {layout.EV_ENERGY: "energy_balance", layout.EV_VDOT: "vdot_nonpositive",
                layout.EV_SPIN1: "spin_magnitude", layout.EV_SPIN2: "spin_magnitude", layout.EV_VDOT_PEAK: "vdot_peak"}[idx]
    return {STATUS_SUCCESS: "time_limit", STATUS_MAX_STEPS: "max_steps",
            STATUS_STEP_UNDERFLOW: "step_underflow", STATUS_NONFINITE: "nonfinite"}[status]


# ---------------------------------------------------------------------------------------------------
# evolve: the stages in order
# ---------------------------------------------------------------------------------------------------

def evolve(m1, m2, chi1, chi2, f_ref, *, f_min=None, f_max=None, ell_hat=(0.0, 0.0, 1.0), n_hat=(1.0, 0.0, 0.0),
           kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0, sampling="steps", options=None, **keywords):
    r"""Evolve a quasi-circular (precessing) compact binary in post-Newtonian theory.

    Parameters
    ----------
    m1, m2 : float or astropy Quantity
        Component masses (floats are solar masses).
    chi1, chi2 : array_like (3,)
        Dimensionless spins at f_ref, inertial frame, |χᵢ| ≤ 1.
    f_ref : float or Quantity
        Gravitational-wave frequency (2 × orbital, Hz) at t = 0, where the inputs are given.
    f_min : float or Quantity, optional
        Integrate backward from f_ref down to this GW frequency (< f_ref).  None: start at f_ref.
    f_max : float or Quantity, optional
        Stop the forward integration at this GW frequency (> f_ref, and v ≤ 1 there).  None: integrate until
        the PN energy balance terminates the inspiral (or v = 1).
    ell_hat, n_hat : array_like (3,)
        ℓ̂ and n̂ at t = 0 (unit, orthogonal to 1e-8; made exactly orthonormal).
    kappa1, kappa2 : float
        Spin-induced quadrupole constants (1 for black holes).
    lambda1, lambda2 : float
        Dimensionless tidal deformabilities Λᵢ = (2/3) k₂,ᵢ (Rᵢ c²/G mᵢ)⁵ of the bodies (LALSuite's ``lambda1``,
        ``lambda2``; 0 for black holes): the adiabatic quadrupolar tides of Vines, Flanagan & Hinderer 2011 in the
        energy and flux (:mod:`pnrotor.pn.energy`, :mod:`pnrotor.pn.flux`).  κᵢ is not derived from Λᵢ: any
        universal relation between them is the caller's choice.
    sampling : 'steps' | 'final' | float | Quantity | ('dt', Δt) | ('per_orbit', n)
        Output at every accepted step, only the final state, uniformly in time with step Δt seconds
        (Δt > 0; at t = k Δt, t = 0 at f_ref, as LALSuite's grid from fStart), or n points per orbit
        (n ≥ 1 an integer; Φ = 2πj/n).  Uniform and per-orbit samples come from the dense output.
    options : Options, optional
        The model and integration options (:class:`pnrotor.Options`: approximant, PN orders, tolerances, precession
        model, rotor, tides' order, horizon absorption, …; None: the defaults).
    **keywords
        Any field of :class:`pnrotor.Options` by name, replacing that of ``options`` (``pn_order=3``,
        ``atol=1e-10``, ``**lalsuite_orders('T4')``).

    Returns
    -------
    Evolution
    """
    wall0 = time.perf_counter()
    s = settings(m1, m2, chi1, chi2, f_ref, f_min=f_min, f_max=f_max, ell_hat=ell_hat, n_hat=n_hat, kappa1=kappa1,
                 kappa2=kappa2, lambda1=lambda1, lambda2=lambda2, sampling=sampling, options=options, **keywords)
    res_f, res_b, term_f, stats = integrate(s)
    inputs = s.inputs()
    t_out, (v, Phi, x1, x2, R, ellh) = sample(s, res_f, res_b)
    stats["wall_time_s"] = time.perf_counter() - wall0
    return Evolution(t=np.asarray(t_out, dtype=np.float64), t_seconds=np.asarray(t_out) * s.M_sec, v=v, Phi=Phi,
                     chi1=x1, chi2=x2, R=R, ell_hat=ellh, termination=term_f, stats=stats, inputs=inputs)


def integrate(s):
    """Stages 2 and 3 of the run with settings ``s`` (the output kernel of its sampling compiled first, see
    :func:`pnrotor.pn.sampling.compile_output_kernel`): (forward result, backward result or None, the forward
    termination, :class:`Evolution` stats but ``wall_time_s``)."""
    system = build_system(s)
    warn_if_unresolved(s.atol, s.rtol, system.y0)
    compile_output_kernel(s)
    dense = s.sampling in ("dt", "per_orbit")
    t_eval = "final" if s.sampling == "final" else None
    t_int = time.perf_counter()
    res_f, term_f = integrate_half(s, system, True, t_eval, dense)
    res_b, term_b = (None, "not_integrated") if s.v_min is None else integrate_half(s, system, False, t_eval, dense)
    t_int = time.perf_counter() - t_int
    stats = _stats(res_f, res_b, term_f, term_b)
    stats["wall_time_integrate_s"] = t_int
    if s.horizon_absorption:   # the masses the horizons' absorption leaves at both ends of the run
        M = s.m1 + s.m2
        for key, res in (("final", res_f), ("initial", res_b)):
            m = (s.X1, 1.0 - s.X1) if res is None else res.y[-1, layout.Y_M1:layout.Y_M2 + 1].tolist()
            stats[f"m1_{key}_Msun"], stats[f"m2_{key}_Msun"] = m[0] * M, m[1] * M
    return res_f, res_b, term_f, stats


def warn_if_unresolved(atol, rtol, y0):
    """A warning naming ``atol`` (and True) if the tolerance of a component of the initial state(s) ``y0``,
    atol + rtol |yᵢ|, is below the float64 resolution of its value, the spacing of float64 numbers there
    (``np.spacing(|yᵢ|)``: 2.2e-16 for a rotor component of 1, 1.4e-17 for v = 0.094): the rounding of yᵢ in a
    step then exceeds what the step may err, so the run can be no more accurate than at that bound, and its steps
    shrink towards the rounding noise, down to max_steps.  A warning, not an error: such a run is well defined and
    often ends as asked, and a tiny atol is how a run is driven to a step underflow on purpose."""
    y = np.abs(y0)
    need = np.spacing(y) - rtol * y
    if not (atol >= need).all():
        bound = float(need.max())
        warnings.warn(f"atol = {float(atol)!r} is below the float64 resolution of the state: with rtol = "
                      f"{float(rtol)!r} the tolerance must be at least {bound:.3g} (the spacing of float64 numbers "
                      f"at the initial state's values) to be met; this run can be no more accurate than at atol = "
                      f"{bound:.3g}, and its steps may shrink until max_steps ends it", stacklevel=3)
        return True
    return False


def check_inputs(m1, m2, chi1, chi2, f_ref, **keywords):
    """:func:`evolve`'s checks of its arguments (its first stage, :func:`~pnrotor.pn.settings.settings`), without
    running anything compiled: the ValueError ``evolve`` would raise first for them, or None.  The CLI calls it
    before it says it is compiling and starts compiling (a cold cache is no reason to wait for an input error).
    Two checks need more and stay in ``evolve``: whether f_ref is past the end of the inspiral (the compiled set-up)
    and whether a uniform or per-orbit sampling fits in memory (the integrated span)."""
    settings(m1, m2, chi1, chi2, f_ref, **{**OPTIONS, **keywords})


OPTIONS = {name: parameter.default for name, parameter in inspect.signature(evolve).parameters.items()
           if parameter.kind is inspect.Parameter.KEYWORD_ONLY}
"""evolve's named keyword arguments and their defaults (those of the binary, its sampling and ``options``; the
fields of :class:`pnrotor.Options` are its other keywords)."""


_STATS_KEYS = [(key, f"{key}_forward", f"{key}_backward") for key in ("nfev", "nsteps", "naccepted", "nrejected")]


def _stats(res_f, res_b, term_f, term_b):
    """`Evolution.stats` but the wall times: the work of both halves, their terminations and the span."""
    stats = {}
    for key, key_f, key_b in _STATS_KEYS:
        f = getattr(res_f, key)
        b = getattr(res_b, key) if res_b is not None else 0
        stats[key] = f + b
        stats[key_f] = f
        stats[key_b] = b
    stats["termination_backward"] = term_b
    stats["termination_message"] = TERMINATION_MESSAGES[term_f]
    stats["termination_backward_message"] = TERMINATION_MESSAGES[term_b]
    stats["integrator_message_forward"] = res_f.message
    stats["integrator_message_backward"] = res_b.message if res_b is not None else ""
    stats["t_final"] = float(res_f.t[-1])
    stats["v_final"] = float(res_f.y[-1, 0])
    stats["t_initial"] = float(res_b.t[-1]) if res_b is not None else 0.0
    return stats


def lalsuite_orders(approximant, phaseO=7, spinO=-1, tideO=-1):
    """Our truncation equivalent to LALSuite's SpinTaylorTn (``SimInspiralSpinTaylorPNEvolveOrbit``).

    With phaseO = 7 (3.5PN), spinO = −1 (all), lscorr = 0, quadparam = κ, lambda1/lambda2 = Λᵢ:

    * SpinTaylorT4 / T5: nonspinning to 3.5PN; spin-orbit in v̇ to 3PN (LALSuite's 3.5PN spin-orbit
      coefficients are set only for its IMRPhenomTP path and not used by SpinTaylor); spin² to 3PN,
      orbit averaged; precession: spin-orbit LO + NLO, spin-spin 2PN + 3PN, |L| with its 1PN term;
      phase shift on.  → pn_order 3.5, spin_orbit_order 3.0, spin_spin_order 3.0.
    * SpinTaylorT1: as T4, but its flux omits the 3PN spin-orbit (tail) term (it is computed in the
      setup but not added in the derivative) → spin_orbit_order 2.5, with the phase shift still on
      (LALSuite applies it for spinO = −1).  Its 3PN QM (ℓ̂·S)² flux coefficient differs from ours
      (see :mod:`pnrotor.pn.flux`).
    * tides: tideO = −1 (LAL's default, ``LAL_SIM_INSPIRAL_TIDAL_ORDER_ALL``) or 12 → tidal_order 6; 10 (5PN
      only) → 5; 0 → 0.

    The orders are the approximant's ``lal_orders`` in :mod:`pnrotor.approximants`.
    """
    a = approximants.get(approximant)
    if a.lal_orders is None:
        raise ValueError(f"approximant {a.name} has no LALSuite counterpart")
    if spinO != -1 or phaseO not in (7, -1):
        raise ValueError("only phaseO = 7 (or -1) with spinO = -1 is mapped")
    if tideO not in LAL_TIDAL_ORDERS:
        raise ValueError(f"tideO must be one of -1 (all), 12, 10 or 0, got {tideO!r}")
    return {**a.lal_orders, "tidal_order": LAL_TIDAL_ORDERS[tideO]}


LAL_TIDAL_ORDERS = {-1: 6.0, 12: 6.0, 10: 5.0, 0: 0.0}
"""LALSuite SpinTaylor's tideO (``LAL_SIM_INSPIRAL_TIDAL_ORDER_ALL`` −1, ``_6PN`` 12, ``_5PN`` 10, ``_0PN`` 0;
LALSimInspiralWaveformFlags.h; its SpinTaylor set-up refuses the others) → ``tidal_order``."""
