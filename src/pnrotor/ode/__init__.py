r"""ODE integrators in numba: DOP853 (Dormand–Prince 8(5,3)) and Gragg–Bulirsch–Stoer extrapolation.

This package owns the general-purpose integrators used by pnrotor to integrate the rotor equation
dR/dt = ½ ω R (Boyle 2016, arXiv:1604.08139) and the coupled post-Newtonian system.

* :func:`dop853` — Hairer's DOP853 (Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed., Sec. II.10
  and the DOP853 code): adaptive steps, 7th-order dense output, terminal events, ``after_step`` hook.
* :func:`bulirsch_stoer` — Gragg's modified midpoint rule with polynomial extrapolation and
  Deuflhard/Hairer order and step-size control (Sec. II.9, as in Hairer's ODEX).
* :class:`OdeResult`, :class:`DenseOutput` and the status codes.

Right-hand sides and hooks are numba functions compiled with the exported signatures, e.g.::

    from numba import njit
    from pnrotor.ode import RHS_SIG, dop853

    @njit(RHS_SIG, cache=True)
    def rhs(t, y, p, dydt):
        dydt[0] = y[1]
        dydt[1] = -p[0] * y[0]

    res = dop853(rhs, 0.0, [1.0, 0.0], 10.0, atol=1e-10, args=[4.0])

The driver loops take these functions by the addresses of their compiled code (signatures checked
before), so they are compiled once per machine (numba cache) and reused for every right-hand side.

Modules: :mod:`~pnrotor.ode.common` (what the solvers share, and the protocol a solver module follows),
:mod:`~pnrotor.ode.events` (the event root finder), :mod:`~pnrotor.ode.result`, :mod:`~pnrotor.ode.tableau`, and
one per solver, :mod:`~pnrotor.ode.dop853` and :mod:`~pnrotor.ode.bulirsch_stoer`, neither importing the other.
"""

from .common import AFTER_STEP_SIG, EVENTS_SIG, RHS_SIG, by_address, no_after_step, no_events, select_initial_step
from .dop853 import dop853
from .result import (STATUS_EVENT, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW,
                     STATUS_SUCCESS, DenseOutput, OdeResult)

__all__ = [
    "RHS_SIG", "AFTER_STEP_SIG", "EVENTS_SIG",
    "dop853", "bulirsch_stoer", "by_address", "OdeResult", "DenseOutput",
    "no_after_step", "no_events", "select_initial_step",
    "STATUS_SUCCESS", "STATUS_EVENT", "STATUS_MAX_STEPS", "STATUS_STEP_UNDERFLOW", "STATUS_NONFINITE",
]


def __getattr__(name):
    # Bulirsch–Stoer on first use: importing its module compiles its core,
    # which a PN run does not need
    if name == "bulirsch_stoer":
        from .bulirsch_stoer import bulirsch_stoer
        globals()["bulirsch_stoer"] = bulirsch_stoer   # the function, not the submodule the import just set
        return bulirsch_stoer
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
