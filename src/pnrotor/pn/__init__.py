r"""Post-Newtonian evolution of precessing quasi-circular compact binaries with the rotor equation.

Modules: :mod:`~pnrotor.pn.series` (truncated PN series with spin invariants),
:mod:`~pnrotor.pn.energy`, :mod:`~pnrotor.pn.flux`, :mod:`~pnrotor.pn.precession` (the PN
quantities, each coefficient beside its source), :mod:`~pnrotor.pn.vdot` (the series of v̇ of each
approximant of :mod:`pnrotor.approximants`), :mod:`~pnrotor.pn.layout` (state, events and parameter vector layout), :mod:`~pnrotor.pn.rhs` (numba
right-hand sides and events), :mod:`~pnrotor.pn.ends` (where an inspiral ends), :mod:`~pnrotor.pn.system` (the
parameter vector), :mod:`~pnrotor.pn.initial` (units, frequencies, frames),
and one run's stages: :mod:`~pnrotor.pn.settings` (inputs checked → ``Settings``),
:mod:`~pnrotor.pn.evolve` (the specialized system, the two integrations, and ``evolve`` →
:class:`Evolution`) and :mod:`~pnrotor.pn.sampling` (the output history from the dense output); :mod:`~pnrotor.pn.many`
(``evolve_many``: a population of binaries to one end state each, in a compiled ``nogil`` loop on pnrotor's
threads).
"""

from .evolve import Evolution, evolve, lalsuite_orders
from .many import Population, evolve_many

__all__ = ["Evolution", "evolve", "lalsuite_orders", "Population", "evolve_many"]
