"""Result types of pnrotor runs: what a run returns and what `pnrotor.hdf5` writes and reads.

`FrameHistory` is the result of integrating an angular velocity (`pnrotor.integrate_angular_velocity`,
the verification mode): times and unit, sign-continuous rotors R(t), with the integrator's statistics
and every input that defines the run. Rotors are scalar first (w, x, y, z); the frame vectors are
R x̂ R⁻¹, R ŷ R⁻¹, R ẑ R⁻¹ (Boyle 2016, eq:rotor-rotation).
"""

import dataclasses
from dataclasses import dataclass, field

import numpy as np


def short_repr(run):
    """The one-line ``repr`` of a result dataclass (a run's arrays can hold millions of samples): each array
    field as its range ``[first … last]`` (1-D floats) or its dtype and shape, each dict as its number of keys,
    any other field as its repr (cut at 40 characters; an object that is not data, such as a dense output, as its
    type)."""
    parts = []
    for f in dataclasses.fields(run):
        value = getattr(run, f.name)
        if isinstance(value, np.ndarray):
            if value.ndim == 1 and value.dtype.kind == "f" and value.size:
                text = f"[{value[0]:.6g}" + (f" … {value[-1]:.6g}]" if value.size > 1 else "]")
            else:
                text = f"{value.dtype.name} {value.shape}"
        elif isinstance(value, dict):
            text = f"{{{len(value)} keys}}"
        elif value is None or isinstance(value, (str, int, float, np.generic)):
            text = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
        else:
            text = f"<{type(value).__name__}>"
        parts.append(f"{f.name}={text}")
    return f"{type(run).__name__}({', '.join(parts)})"


@dataclass(eq=False)
class FrameHistory:
    """Rotor history R(t) from integrating an angular velocity.

    Arrays: ``t`` (N,), ``R`` (N, 4) unit and sign-continuous. Scalars: the formulation and integration
    method, tolerances, integrator statistics (``nfev`` right-hand-side evaluations, ``nsteps`` attempted,
    ``naccepted``, ``nrejected``, ``n_resets`` generator resets), ``status`` (0 success, see
    `pnrotor.ode`), ``message`` and ``wall_time`` in seconds. ``inputs`` holds any further parameters
    of the run (plain numbers, strings, or float arrays). ``dense``, when requested, is the integrator's
    dense output of the evolved state (not written to files).  Checked when built (`pnrotor.hdf5.check`: a
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
        from pnrotor import hdf5

        hdf5.check(self, "cannot build")
