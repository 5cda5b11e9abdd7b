r"""``evolve``: integrate the post-Newtonian system backward and forward from f_ref → :class:`Evolution`.

One run:

1. inputs → geometric units (:mod:`pnrotor.pn.initial`), t = 0 at the reference GW frequency f_ref,
   Φ(0) = 0, n̂(0) = ``n_hat``, ℓ̂(0) = ``ell_hat``;
2. choose the right-hand side: :func:`~pnrotor.pn.system.rhs_aligned` (state [v, Φ]) for nonspinning
   and aligned-spin binaries, :func:`~pnrotor.pn.system.rhs_precessing` (state
   [v, χ₁, χ₂, R, Φ]) otherwise or when ``integrate_rotor=True`` (or
   :func:`~pnrotor.pn.system.rhs_precessing_instantaneous` with ``precession='instantaneous'``);
3. integrate with DOP853 backward to f_min (if given) and forward to f_max or to termination, each
   with terminal events; both halves share t = 0 and are stitched into one history;
4. sample from the integrator's steps or its 7th-order dense output (never by shortening steps).

Termination reasons (``Evolution.termination`` for the forward half, ``stats['termination_backward']``):

* ``'f_max'`` / ``'f_min'`` — v reached the requested end frequency;
* ``'v_max'`` — v reached 1 (no f_max given and nothing else stopped the inspiral first);
* ``'energy_balance'`` — E′(v) ≥ 0: the binding energy no longer decreases with v;
* ``'vdot_nonpositive'`` — v̇ ≤ 0; a safety net: where N or D of v̇ = K v⁹N/D falls to zero, event 6
  or the pole guard fires first, so only a change of the spins could end a run here;
* ``'vdot_peak'`` — ∂v̇/∂v ≤ 0 at the current spins: v̇ stopped increasing with v, so the inspiral no
  longer accelerates (LALSuite's d²ω/dt² ≤ 0; the well-defined end where T4's flux ratio approaches
  a root and v would creep towards it forever, :mod:`pnrotor.pn.system` event 6);
* ``'vdot_divergent'`` — the denominator of v̇ (T5: the re-expanded Ê′/F̂) fell to 1e-3, just before
  the pole where v̇ → ∞ (for T1 the denominator is Ê′ itself and this is reported as
  ``'energy_balance'``);
* ``'spin_magnitude'`` — |χᵢ| exceeded 1 (by more than 1e-10 in |χ|²);
* ``'nonfinite'``, ``'max_steps'``, ``'step_underflow'`` — integrator failures;
* ``'time_limit'`` — the generous time bound (4τ_N + 10⁴ M forward) was reached (should not happen);
* ``'not_integrated'`` — backward half only, when no f_min was given.
"""

import math
import numbers
import time
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..ode import EVENTS_SIG, RHS_SIG, by_address, dop853
from ..ode.result import (STATUS_EVENT, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW,
                          STATUS_SUCCESS)
from . import initial as _ini
from . import system as _sys
from .series import MAX_ORDER, basis_values, kmax_from_orders

TERMINATION_MESSAGES = {
    "f_max": "v reached the requested end frequency f_max",
    "f_min": "v reached the requested start frequency f_min",
    "v_max": "v reached v_max = 1",
    "energy_balance": "E'(v) >= 0: the PN binding energy stopped decreasing (energy balance breaks down)",
    "vdot_nonpositive": "dv/dt <= 0: the PN energy balance gives no inspiral",
    "vdot_peak": "d(dv/dt)/dv <= 0: dv/dt stopped increasing with v (the inspiral no longer accelerates)",
    "vdot_divergent": "dv/dt diverges: the denominator of the approximant's dv/dt reached zero",
    "spin_magnitude": "|chi_i| exceeded 1",
    "nonfinite": "the state or its derivative became non-finite",
    "max_steps": "the integrator reached its step limit",
    "step_underflow": "the integrator's step size underflowed",
    "time_limit": "the time bound of the integration was reached before any termination condition",
    "not_integrated": "this half was not integrated (no f_min given)",
}

MAX_SO_ORDER = 4.0
MAX_SS_ORDER = 3.0

CONTROLLER = dict(safety=0.85, max_factor=4.0)
"""DOP853 step-size controller for the inspiral.  With Hairer's defaults (0.9, 6) the accelerating chirp
makes every few steps a rejection (18–57 of 116–216 attempts in the LALSuite comparison cases); with
(0.85, 4) there are none and the runs cost 10–35% fewer evaluations (benchmarks/bench_pn.py)."""


@dataclass
class Evolution:
    """History of a PN evolution: plain arrays and scalars (HDF5-friendly).

    Attributes
    ----------
    t : (N,) times in units of the total mass M (t = 0 at f_ref)
    t_seconds : (N,) the same in seconds
    v : (N,) PN parameter v = (M Ω_orb)^{1/3}
    Phi : (N,) orbital phase Φ (Φ = 0 at t = 0)
    chi1, chi2 : (N, 3) dimensionless spins in the inertial frame
    R : (N, 4) unit orbital-frame rotor (w, x, y, z), sign-continuous: n̂ = R x̂ R⁻¹, ℓ̂ = R ẑ R⁻¹
    ell_hat : (N, 3) orbital angular momentum direction ℓ̂ = R ẑ R⁻¹
    termination : str — why the forward integration stopped (see module docstring)
    stats : dict — nfev, nsteps, naccepted, nrejected (both halves), per-half counts, wall times,
        backward termination, messages
    inputs : dict — every input, with units in the key names; only floats, ints, bools, strings and
        lists of floats (absent f_min/f_max and the value of 'steps'/'final' sampling are NaN)
    """

    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: str
    stats: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)

    @property
    def n_hat(self):
        """Separation direction n̂ = R x̂ R⁻¹, (N, 3)."""
        w, x, y, z = self.R.T
        return np.column_stack((1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)))

    @property
    def f_gw(self):
        """Gravitational-wave frequency 2 f_orb = v³/(π M) in Hz."""
        return _ini.frequency_from_v(self.v, self.inputs["M_seconds"])

    def __len__(self):
        return self.t.size


# ---------------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------------

def normalize_approximant(approximant):
    """'T1', 'T4' or 'T5' from 'Tn' (either case), 'TaylorTn' or 'SpinTaylorTn'; else a ValueError."""
    a = str(approximant).strip()
    for prefix in ("SpinTaylor", "Taylor"):
        if a.startswith(prefix):
            a = a[len(prefix):]
    a = a.upper()
    if a not in _sys.APPROXIMANTS:
        raise ValueError(f"approximant must be one of T1, T4, T5 (or TaylorTn / SpinTaylorTn), got {approximant!r}")
    return a


def _order(x, name, lo, hi, allow_none=False):
    if x is None:
        if allow_none:
            return None
        raise ValueError(f"{name} is required")
    x = float(x)
    if not (lo <= x <= hi) or abs(2 * x - round(2 * x)) > 1e-12:
        raise ValueError(f"{name} must be a multiple of 0.5 in [{lo}, {hi}], got {x!r}")
    return x


def _parse_sampling(sampling):
    """→ ('steps', None) | ('final', None) | ('dt', seconds) | ('per_orbit', n)."""
    if isinstance(sampling, str):
        s = sampling.strip().lower()
        if s in ("steps", "step", "accepted"):
            return "steps", None
        if s == "final":
            return "final", None
        raise ValueError(f"sampling string must be 'steps' or 'final', got {sampling!r}")
    if isinstance(sampling, dict):
        if len(sampling) != 1:
            raise ValueError("sampling dict must have exactly one key: 'dt' or 'per_orbit'")
        (key, val), = sampling.items()
        sampling = (key, val)
    if isinstance(sampling, tuple):
        if len(sampling) != 2:
            raise ValueError("sampling tuple must be ('dt', seconds) or ('per_orbit', n)")
        key, val = sampling
        if key == "dt":
            return "dt", _ini.seconds(val, "sampling dt")
        if key == "per_orbit":
            if (isinstance(val, bool) or not isinstance(val, numbers.Real)
                    or not (math.isfinite(val) and val >= 1 and val == int(val))):
                raise ValueError(f"sampling per_orbit must be a positive integer, got {val!r}")
            return "per_orbit", int(val)
        raise ValueError(f"unknown sampling key {key!r}; use 'dt' or 'per_orbit'")
    # a bare number or Quantity: Δt in seconds
    return "dt", _ini.seconds(sampling, "sampling dt")


def _status_to_termination(res, direction, approximant):
    if res.status == STATUS_EVENT:
        idx = res.event_index
        if idx == _sys.EV_V_END:
            return direction
        if idx == _sys.EV_POLE:
            return "energy_balance" if approximant == "T1" else "vdot_divergent"
        return {_sys.EV_ENERGY: "energy_balance", _sys.EV_VDOT: "vdot_nonpositive",
                _sys.EV_SPIN1: "spin_magnitude", _sys.EV_SPIN2: "spin_magnitude", _sys.EV_VDOT_PEAK: "vdot_peak"}[idx]
    return {STATUS_SUCCESS: "time_limit", STATUS_MAX_STEPS: "max_steps",
            STATUS_STEP_UNDERFLOW: "step_underflow", STATUS_NONFINITE: "nonfinite"}[res.status]


MODE_ALIGNED, MODE_COPRECESSING, MODE_ORBITAL = 0, 1, 2


@njit(cache=True, inline="always")
def _contd8_segment(coef, j, theta, out):
    """DOP853 dense output of segment j at θ into out: the same polynomial as
    :func:`pnrotor.ode.result.contd8` (Hairer's ``contd8``, r₁ + θ(r₂ + θ'(r₃ + θ(r₄ + θ'(r₅ + θ(r₆ +
    θ'(r₇ + θ r₈))))))), θ' = 1 − θ), indexing coef[j] in place: slicing coef[j] for each sample
    costs more than the polynomial for small states (2.4× for [v, Φ]), and calling ``contd8`` on a
    view taken once per segment made a 1.4 + 1.4 M☉ run sampled at 1/4096 s 1.2× slower (2.2·10⁵ samples,
    17 vs 21 ms).  Checked against ``DenseOutput`` in the tests."""
    th1 = 1.0 - theta
    for i in range(out.size):
        out[i] = coef[j, 0, i] + theta * (coef[j, 1, i] + th1 * (coef[j, 2, i] + theta * (coef[j, 3, i] + th1 * (
            coef[j, 4, i] + theta * (coef[j, 5, i] + th1 * (coef[j, 6, i] + theta * coef[j, 7, i]))))))


@njit(cache=True, inline="always")
def _store_row(i, vv, ph, w, x, yy, z, v, Phi, R, ell):
    """Normalize R = (w, x, y, z) and store v, Φ, R and ℓ̂ = R ẑ R⁻¹ in row i."""
    inv = 1.0 / math.sqrt(w * w + x * x + yy * yy + z * z)
    w *= inv
    x *= inv
    yy *= inv
    z *= inv
    v[i] = vv
    Phi[i] = ph
    R[i, 0] = w
    R[i, 1] = x
    R[i, 2] = yy
    R[i, 3] = z
    ell[i, 0] = 2.0 * (x * z + w * yy)
    ell[i, 1] = 2.0 * (yy * z - w * x)
    ell[i, 2] = w * w - x * x - yy * yy + z * z


@njit(cache=True)
def _fill_history(mode, seg_t, seg_h, coef, tq, reverse, Y, R0, ell0, c1, c2, offset, v, Phi, chi1, chi2, R,
                  ell):
    """History rows offset, offset+1, … from states.

    The states are either the rows of Y (``tq`` empty) or the DOP853 interpolant (segments
    ``seg_t``, ``seg_h``, ``coef``) at the times ``tq``, found by walking the segments once: ``tq`` is
    sorted along the direction of integration, or against it with ``reverse`` (then it is visited from
    its end, so no reversed copy is needed; row offset + q still receives time tq[q]).  Per mode:

    * aligned: y = [v, Φ], R = R₀ exp(Φẑ/2), spins constant;
    * coprecessing: y = [v, χ₁, χ₂, R_p, Φ], R = R_p exp(Φẑ/2);
    * orbital: y = [v, χ₁, χ₂, R, Φ].

    exp(Φẑ/2) = (cos Φ/2, 0, 0, sin Φ/2) and q·(c, 0, 0, s) = (wc − zs, xc + ys, yc − xs, zc + ws).
    """
    dense = tq.size > 0
    nrow = tq.size if dense else Y.shape[0]
    nseg = seg_t.size
    n = coef.shape[2] if dense else Y.shape[1]
    y = np.empty(n)
    j = 0
    for qq in range(nrow):
        q = nrow - 1 - qq if reverse else qq
        if dense:
            t = tq[q]
            while j + 1 < nseg and (t - seg_t[j + 1]) * seg_h[j + 1] >= 0.0:
                j += 1
            _contd8_segment(coef, j, (t - seg_t[j]) / seg_h[j], y)
        else:
            for k in range(n):
                y[k] = Y[q, k]
        i = offset + q
        if mode == MODE_ALIGNED:
            # R₀ is a unit rotor and ℓ̂ = R₀ ẑ R₀⁻¹ is constant (rotations about ẑ fix it): ell0 = ℓ̂
            ph = y[1]
            c = math.cos(0.5 * ph)
            s = math.sin(0.5 * ph)
            v[i] = y[0]
            Phi[i] = ph
            R[i, 0] = R0[0] * c - R0[3] * s
            R[i, 1] = R0[1] * c + R0[2] * s
            R[i, 2] = R0[2] * c - R0[1] * s
            R[i, 3] = R0[3] * c + R0[0] * s
            for k in range(3):
                ell[i, k] = ell0[k]
                chi1[i, k] = c1[k]
                chi2[i, k] = c2[k]
        else:
            ph = y[11]
            if mode == MODE_COPRECESSING:
                c = math.cos(0.5 * ph)
                s = math.sin(0.5 * ph)
                _store_row(i, y[0], ph, y[7] * c - y[10] * s, y[8] * c + y[9] * s, y[9] * c - y[8] * s,
                           y[10] * c + y[7] * s, v, Phi, R, ell)
            else:
                _store_row(i, y[0], ph, y[7], y[8], y[9], y[10], v, Phi, R, ell)
            for k in range(3):
                chi1[i, k] = y[1 + k]
                chi2[i, k] = y[4 + k]


_NO_T = np.empty(0)
_NO_Y = np.empty((0, 1))
_NO_SEG = np.empty(1)
_NO_COEF = np.empty((1, 8, 1))


def _allocate_history(n):
    return (np.empty(n), np.empty(n), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 3)))


def _phase_times(dense, phi_index, v_index, targets):
    """Times at which Φ(t) (monotonic along the integration) equals each target: Newton on the dense
    output with Φ̇ ≈ v³, starting from linear interpolation between step boundaries."""
    if targets.size == 0:
        return targets
    ts = dense.ts
    phis = dense(ts)[:, phi_index]
    order = np.argsort(phis)
    ts_o, ph_o = ts[order], phis[order]
    t = np.interp(targets, ph_o, ts_o)
    lo, hi = min(dense.t_min, dense.t_max), max(dense.t_min, dense.t_max)
    for _ in range(8):
        y = dense(t)
        dphi = y[:, phi_index] - targets
        t_new = np.clip(t - dphi / y[:, v_index] ** 3, lo, hi)
        if np.all(np.abs(t_new - t) <= 4e-16 * np.maximum(np.abs(t), 1.0)):
            t = t_new
            break
        t = t_new
    return t


# ---------------------------------------------------------------------------------------------------
# evolve
# ---------------------------------------------------------------------------------------------------

def evolve(m1, m2, chi1, chi2, f_ref, *, f_min=None, f_max=None, approximant="T4", pn_order=3.5,
           spin_orbit_order=None, spin_spin_order=None, ell_hat=(0.0, 0.0, 1.0), n_hat=(1.0, 0.0, 0.0),
           kappa1=1.0, kappa2=1.0, atol=1e-12, rtol=0.0, sampling="steps", rotor="coprecessing",
           precession_phase_shift=None, integrate_rotor=False, precession="averaged", max_steps=2_000_000):
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
        Stop the forward integration at this GW frequency (> f_ref).  None: integrate until the PN
        energy balance terminates the inspiral (or v = 1).
    approximant : {'T1', 'T4', 'T5'}
        TaylorT1 (−F/E′ evaluated as a ratio), TaylorT4 (ratio re-expanded, truncated), TaylorT5 (its
        inverse re-expanded, truncated).  'TaylorT4' and 'SpinTaylorT4' are accepted too.
    pn_order : float
        PN order of the nonspinning terms, 0 … 4.5 in steps of 0.5.
    spin_orbit_order, spin_spin_order : float, optional
        PN orders of the terms linear and quadratic in the spins (default min(pn_order, 4) and
        min(pn_order, 3); −1 removes them).  They also select the precession terms (spin-orbit
        LO/NLO/NNLO at ≥ 1.5/2.5/3.5, spin-spin at ≥ 2/3).  :func:`lalsuite_orders` gives the
        truncation of LALSuite's SpinTaylorTn.
    ell_hat, n_hat : array_like (3,)
        ℓ̂ and n̂ at t = 0 (unit, orthogonal to 1e-8; made exactly orthonormal).
    kappa1, kappa2 : float
        Spin-induced quadrupole constants (1 for black holes).
    atol, rtol : float
        DOP853 tolerances (absolute on every state component; relative).
    sampling : 'steps' | 'final' | float | Quantity | ('dt', Δt) | ('per_orbit', n)
        Output at every accepted step, only the final state, uniformly in time with step Δt seconds
        (Δt > 0; at t = k Δt, t = 0 at f_ref, as LALSuite's grid from fStart), or n points per orbit
        (n ≥ 1 an integer; Φ = 2πj/n).  Uniform and per-orbit samples come from the dense output.
    rotor : {'coprecessing', 'orbital'}
        Which rotor the precessing state holds (see :mod:`pnrotor.pn.system`): the co-precessing R_p
        with R = R_p exp(Φẑ/2) (default, fast) or the full orbital-frame R.
    precession_phase_shift : bool, optional
        Apply Φ̇ = v³ − |Ω_ℓ,LO|²/(4v³) (arXiv:1507.00406).  Default: when spin_orbit_order ≥ 3.
    integrate_rotor : bool
        Use the precessing state even for nonspinning/aligned binaries.
    precession : {'averaged', 'averaged_varpi', 'instantaneous'}
        'averaged' (default; LALSuite's SpinTaylor model with lscorr = 0): orbit-averaged spin
        precession and Ω_ℓ = −ℓ̂ × (Ṡ₁ + Ṡ₂)/|L| (see :mod:`pnrotor.pn.precession`).
        'averaged_varpi': the same, but the spin-orbit part of Ω_ℓ is the orbit average ⟨ϖ n̂⟩ of
        Bohé et al. 2013's ϖ (Eqs. (4.3)–(4.4)); it differs from 'averaged' from NLO on.
        'instantaneous': Ω = v³ℓ̂ + ϖn̂ with Bohé et al.'s ϖ (spin-orbit) and n̂-dependent spin-spin
        precession, on the full orbital rotor (implies rotor='orbital', no phase shift; see
        :mod:`pnrotor.pn.system`).
    max_steps : int
        Step limit per half.

    Returns
    -------
    Evolution
    """
    wall0 = time.perf_counter()
    # ---- inputs → geometric units -------------------------------------------------------------
    m1 = _ini.solar_masses(m1, "m1")
    m2 = _ini.solar_masses(m2, "m2")
    f_ref = _ini.hertz(f_ref, "f_ref")
    f_min = _ini.hertz(f_min, "f_min", allow_none=True)
    f_max = _ini.hertz(f_max, "f_max", allow_none=True)
    c1 = _ini.spin_vector(chi1, "chi1")
    c2 = _ini.spin_vector(chi2, "chi2")
    ell, n = _ini.orthonormal_frame(ell_hat, n_hat)
    approximant = normalize_approximant(approximant)
    pn_order = _order(pn_order, "pn_order", 0.0, MAX_ORDER)
    so_order = (min(pn_order, MAX_SO_ORDER) if spin_orbit_order is None
                else _order(spin_orbit_order, "spin_orbit_order", -1.0, MAX_SO_ORDER))
    ss_order = (min(pn_order, MAX_SS_ORDER) if spin_spin_order is None
                else _order(spin_spin_order, "spin_spin_order", -1.0, MAX_SS_ORDER))
    kappa1 = float(kappa1)
    kappa2 = float(kappa2)
    if rotor not in ("coprecessing", "orbital"):
        raise ValueError(f"rotor must be 'coprecessing' or 'orbital', got {rotor!r}")
    mode, sval = _parse_sampling(sampling)
    if not (atol > 0.0 and math.isfinite(atol)) or not (rtol >= 0.0 and math.isfinite(rtol)):
        raise ValueError(f"atol must be > 0 and rtol >= 0, both finite; got atol = {atol!r}, rtol = {rtol!r}")
    if precession not in ("averaged", "averaged_varpi", "instantaneous"):
        raise ValueError(f"precession must be 'averaged', 'averaged_varpi' or 'instantaneous', got {precession!r}")
    if precession == "instantaneous":
        rotor = "orbital"
        precession_phase_shift = False
    if precession_phase_shift is None:
        precession_phase_shift = so_order >= 3.0

    M_sec = _ini.total_mass_seconds(m1, m2)
    X1 = m1 / (m1 + m2)
    nu = X1 * (1.0 - X1)
    v0 = _ini.v_from_frequency(f_ref, M_sec)
    v_min = None if f_min is None else _ini.v_from_frequency(f_min, M_sec)
    v_max = 1.0 if f_max is None else _ini.v_from_frequency(f_max, M_sec)
    if v0 >= 1.0:
        raise ValueError(f"f_ref = {f_ref} Hz gives v = {v0:.4g} >= 1; f_ref must be below "
                         f"{1.0 / (math.pi * M_sec):.6g} Hz")
    if v_min is not None and not v_min < v0:
        raise ValueError(f"f_min = {f_min} Hz must be below f_ref = {f_ref} Hz")
    if not v_max > v0:
        raise ValueError(f"f_max = {f_max} Hz must be above f_ref = {f_ref} Hz")
    R0 = _ini.frame_rotor(ell, n)

    perp1 = c1 - np.dot(c1, ell) * ell
    perp2 = c2 - np.dot(c2, ell) * ell
    nonspinning = not np.any(c1) and not np.any(c2)
    aligned = np.dot(perp1, perp1) <= 1e-28 and np.dot(perp2, perp2) <= 1e-28
    use_aligned = aligned and not integrate_rotor
    spin_content = "nonspinning" if nonspinning else ("aligned" if aligned else "precessing")
    if aligned:  # remove round-off in-plane parts so the spins are exactly along ℓ̂
        c1 = np.dot(c1, ell) * ell
        c2 = np.dot(c2, ell) * ell

    kmax = kmax_from_orders(pn_order, so_order, ss_order)
    a1, a2 = float(np.dot(ell, c1)), float(np.dot(ell, c2))
    bvals = basis_values(a1, a2, float(np.dot(c1, c2)), float(np.dot(c1, c1)), float(np.dot(c2, c2)))
    p, (n0, d0, e0, peak0) = _sys.make_parameters(
        X1, approximant, kmax, so_order=so_order, ss_order=ss_order, kappa1=kappa1, kappa2=kappa2, v_end=v_max,
        rotor=rotor, phase_shift=precession_phase_shift, aligned_basis=bvals if use_aligned else None,
        omega_l="varpi" if precession == "averaged_varpi" else "torque", basis=bvals, v_check=v0)

    # ---- validity at f_ref: the terminal events only fire on crossing zero, so none may start at or below it
    why = ("E'(v) >= 0, the PN energy balance is invalid" if not e0 > 0.0
           else "dv/dt <= 0" if not n0 * d0 > 0.0
           else f"the denominator of dv/dt is {d0:.3g} <= {_sys.DEN_EPS:g}, next to its pole" if not d0 > _sys.DEN_EPS
           else "dv/dt no longer increases with v" if not peak0 > 0.0 else None)
    if why:
        v_end = _sys.inspiral_end(X1, approximant, kmax, bvals, kappa1, kappa2)
        raise ValueError(f"f_ref = {f_ref} Hz is past the end of the {approximant} inspiral: {why} at v = {v0:.4g}; "
                         f"for these masses and spins f_ref must be below "
                         f"{_ini.frequency_from_v(v_end, M_sec):.6g} Hz (v = {v_end:.6g})")

    inputs = {
        "m1_Msun": m1, "m2_Msun": m2, "chi1": c1.tolist(), "chi2": c2.tolist(), "f_ref_Hz": f_ref,
        "f_min_Hz": math.nan if f_min is None else f_min, "f_max_Hz": math.nan if f_max is None else f_max, "approximant": approximant, "pn_order": pn_order,
        "spin_orbit_order": so_order, "spin_spin_order": ss_order, "ell_hat": ell.tolist(),
        "n_hat": n.tolist(), "kappa1": kappa1, "kappa2": kappa2, "atol": float(atol), "rtol": float(rtol),
        "sampling": mode, "sampling_value": math.nan if sval is None else float(sval), "rotor": rotor,
        "precession_phase_shift": bool(precession_phase_shift), "integrate_rotor": bool(integrate_rotor),
        "precession": precession,
        "max_steps": int(max_steps), "M_seconds": M_sec, "v_ref": v0, "spin_content": spin_content,
        "state": "aligned" if use_aligned else "precessing",
    }

    if use_aligned:
        rhs, events = _sys.rhs_aligned, _sys.events_aligned
        y0 = np.array([v0, 0.0])
    else:
        rhs = _sys.rhs_precessing_instantaneous if precession == "instantaneous" else _sys.rhs_precessing
        events = _sys.events_precessing
        y0 = np.concatenate(([v0], c1, c2, R0, [0.0]))
    # they cannot raise (error_model='numpy'), so they may go to the integrator by address
    rhs, events = by_address(rhs, RHS_SIG), by_address(events, EVENTS_SIG)

    want_dense = mode in ("dt", "per_orbit")
    t_eval = "final" if mode == "final" else None
    tau0 = _ini.newtonian_time_to_coalescence(v0, nu)

    # ---- forward ---------------------------------------------------------------------------------
    t_int = time.perf_counter()
    res_f = dop853(rhs, 0.0, y0, 4.0 * tau0 + 1.0e4, atol, rtol=rtol, args=p, max_steps=max_steps,
                   t_eval=t_eval, dense=want_dense, events=events, n_events=_sys.N_EVENTS, **CONTROLLER,
                   event_direction=np.array([1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0]))
    term_f = _status_to_termination(res_f, "f_max" if f_max is not None else "v_max", approximant)
    # ---- backward --------------------------------------------------------------------------------
    res_b = None
    term_b = "not_integrated"
    if v_min is not None:
        pb = p.copy()
        pb[_sys.P_VEND] = v_min
        t_back = -(2.0 * (_ini.newtonian_time_to_coalescence(v_min, nu) - tau0) + 1.0e4)
        res_b = dop853(rhs, 0.0, y0, t_back, atol, rtol=rtol, args=pb, max_steps=max_steps,
                       t_eval=t_eval, dense=want_dense, events=events, n_events=_sys.N_EVENTS, **CONTROLLER,
                       event_direction=np.array([-1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0]))
        term_b = _status_to_termination(res_b, "f_min", approximant)
    t_int = time.perf_counter() - t_int

    # ---- sampling --------------------------------------------------------------------------------
    phi_i = _sys.YA_PHI if use_aligned else _sys.Y_PHI
    v_i = _sys.YA_V
    out_mode = MODE_ALIGNED if use_aligned else (MODE_ORBITAL if rotor == "orbital" else MODE_COPRECESSING)
    R0c = np.ascontiguousarray(R0, dtype=np.float64)
    if mode in ("final", "steps"):
        if mode == "final":
            parts = [(res_f.t[-1:], res_f.y[-1:])]
        else:
            parts = ([(res_b.t[:0:-1], res_b.y[:0:-1])] if res_b is not None else []) + [(res_f.t, res_f.y)]
        t_out = np.concatenate([tp for tp, _ in parts])
        hist = _allocate_history(t_out.size)
        off = 0
        for tp, Yp in parts:
            _fill_history(out_mode, _NO_SEG, _NO_SEG, _NO_COEF, _NO_T, False, np.ascontiguousarray(Yp), R0c, ell,
                          c1, c2, off, *hist)
            off += tp.size
    else:
        if mode == "dt":
            dt = sval / M_sec
            k_hi = math.floor(res_f.dense.t_max / dt * (1.0 + 1e-15))
            while k_hi * dt > res_f.dense.t_max:
                k_hi -= 1
            k_lo = 0
            if res_b is not None:
                k_lo = math.ceil(res_b.dense.t_max / dt * (1.0 + 1e-15))
                while k_lo * dt < res_b.dense.t_max:
                    k_lo += 1
            t_out = np.arange(k_lo, k_hi + 1, dtype=np.float64)
            t_out *= dt                                   # one allocation: t = k Δt, ascending
            nb = -k_lo
        else:  # per_orbit
            step = 2.0 * math.pi / sval
            phi_end = res_f.y[-1, phi_i]
            tf = _phase_times(res_f.dense, phi_i, v_i, np.arange(0, math.floor(phi_end / step) + 1) * step)
            tf[0] = 0.0
            if res_b is not None:
                phi_start = res_b.y[-1, phi_i]
                tb = _phase_times(res_b.dense, phi_i, v_i, np.arange(math.ceil(phi_start / step), 0) * step)
            else:
                tb = np.empty(0)
            t_out = np.concatenate((tb, tf))
            nb = tb.size
        hist = _allocate_history(t_out.size)
        if nb:
            d = res_b.dense   # backward samples: visited from t = 0 downwards, the direction of integration
            _fill_history(out_mode, d.seg_t, d.seg_h, d.coef, t_out[:nb], True, _NO_Y, R0c, ell, c1, c2, 0, *hist)
        d = res_f.dense
        _fill_history(out_mode, d.seg_t, d.seg_h, d.coef, t_out[nb:], False, _NO_Y, R0c, ell, c1, c2, nb, *hist)
    v, Phi, x1, x2, R, ellh = hist

    halves = {"forward": res_f, "backward": res_b}
    stats = {}
    for key in ("nfev", "nsteps", "naccepted", "nrejected"):
        stats[key] = sum(getattr(r, key) for r in halves.values() if r is not None)
        for name, r in halves.items():
            stats[f"{key}_{name}"] = getattr(r, key) if r is not None else 0
    stats["termination_backward"] = term_b
    stats["termination_message"] = TERMINATION_MESSAGES[term_f]
    stats["termination_backward_message"] = TERMINATION_MESSAGES[term_b]
    stats["integrator_message_forward"] = res_f.message
    stats["integrator_message_backward"] = res_b.message if res_b is not None else ""
    stats["t_final"] = float(res_f.t[-1])
    stats["v_final"] = float(res_f.y[-1, 0])
    stats["t_initial"] = float(res_b.t[-1]) if res_b is not None else 0.0
    stats["wall_time_integrate_s"] = t_int
    stats["wall_time_s"] = time.perf_counter() - wall0

    return Evolution(t=np.asarray(t_out, dtype=np.float64), t_seconds=np.asarray(t_out) * M_sec, v=v, Phi=Phi,
                     chi1=x1, chi2=x2, R=R, ell_hat=ellh, termination=term_f, stats=stats, inputs=inputs)


def lalsuite_orders(approximant, phaseO=7, spinO=-1):
    """Our truncation equivalent to LALSuite's SpinTaylorTn (``SimInspiralSpinTaylorPNEvolveOrbit``).

    With phaseO = 7 (3.5PN), spinO = −1 (all), tideO = 0, lscorr = 0, quadparam = κ:

    * SpinTaylorT4 / T5: nonspinning to 3.5PN; spin-orbit in v̇ to 3PN (LALSuite's 3.5PN spin-orbit
      coefficients are set only for its IMRPhenomTP path and not used by SpinTaylor); spin² to 3PN,
      orbit averaged; precession: spin-orbit LO + NLO, spin-spin 2PN + 3PN, |L| with its 1PN term;
      phase shift on.  → pn_order 3.5, spin_orbit_order 3.0, spin_spin_order 3.0.
    * SpinTaylorT1: as T4, but its flux omits the 3PN spin-orbit (tail) term (it is computed in the
      setup but not added in the derivative) → spin_orbit_order 2.5, with the phase shift still on
      (LALSuite applies it for spinO = −1).  Its 3PN QM (ℓ̂·S)² flux coefficient differs from ours
      (see :mod:`pnrotor.pn.flux`).
    """
    a = normalize_approximant(approximant)
    if spinO != -1 or phaseO not in (7, -1):
        raise ValueError("only phaseO = 7 (or -1) with spinO = -1 is mapped")
    return {"pn_order": 3.5, "spin_orbit_order": 2.5 if a == "T1" else 3.0, "spin_spin_order": 3.0,
            "precession_phase_shift": True}
