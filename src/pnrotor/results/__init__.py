"""pnrotor's result types, apart from storage: what a run, its waveform or a population is, with the invariants that
are also the layout of their files (`schema`: the arrays of each type, beside its fields).  Imports neither h5py nor
numba: `pnrotor.hdf5` (and any other format, `pnrotor.io`) stores these; the modules that compute them build them.

* :mod:`~pnrotor.results.schema` — `Array`, `register`, `layout_problems`, `check` and the registries `KINDS`,
  `ARRAYS`, `UNITS`, `REQUIRED_KEYS`;
* :mod:`~pnrotor.results.runs` — `FrameHistory` (`pnrotor.integrate_angular_velocity`), `Evolution` (`pnrotor.evolve`);
* :mod:`~pnrotor.results.waves` — `Modes` (`pnrotor.modes`), `Polarizations` (`pnrotor.polarizations`);
* :mod:`~pnrotor.results.populations` — `Population` (`pnrotor.evolve_many`), `PopulationTable`
  (`pnrotor.batch.population`), and the spin angles derived from their states.
"""

from pnrotor.results.schema import (ARRAYS, KINDS, NOT_WRITTEN, REQUIRED_KEYS, UNITS, Array, check, layout_problems,
                                    register, short_repr)
# in this order, the kinds' order in the registries
from pnrotor.results.runs import Evolution, FrameHistory  # isort: skip
from pnrotor.results.waves import FRAMES, CoarseSamplingWarning, Modes, Polarizations  # isort: skip
from pnrotor.results.populations import (INSPIRAL_ENDS, STATE, Population, PopulationTable,  # isort: skip
                                         SpinAngles, spin_angles)

__all__ = ["FrameHistory", "Evolution", "Modes", "Polarizations", "Population", "PopulationTable", "SpinAngles",
           "spin_angles", "STATE", "INSPIRAL_ENDS", "FRAMES", "CoarseSamplingWarning", "Array", "register", "check",
           "layout_problems", "short_repr", "KINDS", "ARRAYS", "UNITS", "REQUIRED_KEYS", "NOT_WRITTEN"]
