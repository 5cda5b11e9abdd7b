"""The results of one run: `FrameHistory` (an angular velocity integrated, the verification mode) and `Evolution` (a
PN evolution, `pnrotor.evolve`), each registered with the arrays its file holds (`pnrotor.results.schema`).

`FrameHistory` is the result of integrating an angular velocity (`pnrotor.integrate_angular_velocity`):
times and unit, sign-continuous rotors R(t), with the integrator's statistics and every input that defines the run.
Rotors are scalar first (w, x, y, z); the frame vectors are R x̂ R⁻¹, R ŷ R⁻¹, R ẑ R⁻¹ (Boyle 2016,
eq:rotor-rotation).  `Evolution` is the history of a PN evolution (its stages: `pnrotor.pn.evolve`).
"""

import math
from dataclasses import dataclass, field

import numpy as np

from pnrotor.results.schema import M_UNIT, ROTOR, Array, check, register, short_repr


@register(arrays={
    "t": Array(("N",), "time unit of the angular velocity (omega in rad per unit)"),
    "R": ROTOR,
})
@dataclass(eq=False)
class FrameHistory:
    """Rotor history R(t) from integrating an angular velocity.

    Arrays: ``t`` (N,), ``R`` (N, 4) unit and sign-continuous. Scalars: the formulation and integration
    method, tolerances, integrator statistics (``nfev`` right-hand-side evaluations, ``nsteps`` attempted,
    ``naccepted``, ``nrejected``, ``n_resets`` generator resets), ``status`` (0 success, see
    `pnrotor.ode`), ``message`` and ``wall_time`` in seconds. ``inputs`` holds any further parameters
    of the run (plain numbers, strings, or float arrays). ``dense``, when requested, is the integrator's
    dense output of the evolved state (not written to files).  Checked when built (`pnrotor.results.check`: a
    ValueError naming every problem, as `pnrotor.hdf5.write` would).
    """

    t: np.ndarray
    R: np.ndarray
    formulation: str
    method: str
    atol: float
    rtol: float
    nfev: int
    nsteps: int
    naccepted: int
    nrejected: int
    n_resets: int
    status: int
    message: str
    wall_time: float
    inputs: dict = field(default_factory=dict)
    dense: object = None

    __repr__ = short_repr

    def __post_init__(self):
        check(self, "cannot build")


@register(arrays={
    "t": Array(("N",), M_UNIT),
    "t_seconds": Array(("N",), "s"),
    "v": Array(("N",), "c; PN parameter v = (M Omega_orb)^(1/3)"),
    "Phi": Array(("N",), "rad; orbital phase"),
    "chi1": Array(("N", 3), "1; dimensionless spin S1 / m1^2, inertial-frame components"),
    "chi2": Array(("N", 3), "1; dimensionless spin S2 / m2^2, inertial-frame components"),
    "ell_hat": Array(("N", 3), "1; unit normal to the orbital plane, inertial-frame components"),
    "R": ROTOR,
}, required_keys={
    "inputs": ("m1_Msun", "m2_Msun", "kappa1", "kappa2", "ell_hat", "n_hat", "state", "spin_content", "M_seconds",
               "v_ref", "f_min_Hz"),
    "stats": ("nfev", "wall_time_s", "t_initial", "t_final", "v_final", "termination_backward"),
})
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

    In a nonspinning or aligned run (``inputs['state'] == 'aligned'``) chi1, chi2 and ell_hat are constant: they
    are read-only (N, 3) views of their one row (zero stride along N, as ``np.broadcast_to`` gives);
    ``run.chi1.copy()`` gives a writable C-ordered array.
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

    __repr__ = short_repr

    @property
    def n_hat(self):
        """Separation direction n̂ = R x̂ R⁻¹, (N, 3)."""
        w, x, y, z = self.R.T
        return np.column_stack((1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)))

    @property
    def f_gw(self):
        """Gravitational-wave frequency 2 f_orb = v³/(π M) in Hz (as `pnrotor.pn.initial.frequency_from_v`)."""
        return np.asarray(self.v) ** 3 / (math.pi * self.inputs["M_seconds"])

    def __len__(self):
        return self.t.size

    def span(self):
        """(t_start, t_end in M, v_start, v_end, orbits, whether the orbits span the whole integration).

        Times and v are those of the whole integration whatever the sampling (without f_min the start is f_ref,
        where Φ = 0). The orbits (Φ_end − Φ_start)/2π are exact when the samples include both ends (sampling
        'steps', or 'final' without f_min); otherwise they are counted between the first and last samples (a
        Δt or per-orbit grid), or None (one sample that is not the start)."""
        stats, inputs = self.stats, self.inputs
        backward = stats["termination_backward"] != "not_integrated"
        t0, t1 = stats["t_initial"], stats["t_final"]
        n = len(self)
        if not backward:
            v0, phi0 = inputs["v_ref"], 0.0
        elif n and self.t[0] == t0:
            v0, phi0 = self.v[0].item(), self.Phi[0].item()
        elif stats["termination_backward"] == "f_min":
            v0, phi0 = (math.pi * inputs["M_seconds"] * inputs["f_min_Hz"]) ** (1 / 3), None
        else:
            v0, phi0 = (self.v[0].item() if n else math.nan), None
        v1 = stats["v_final"]
        phi1 = self.Phi[-1].item() if n and self.t[-1] == t1 else None
        if phi0 is not None and phi1 is not None:
            return t0, t1, v0, v1, (phi1 - phi0) / (2 * math.pi), True
        if n >= 2:
            return t0, t1, v0, v1, (self.Phi[-1] - self.Phi[0]).item() / (2 * math.pi), False
        return t0, t1, v0, v1, None, False
