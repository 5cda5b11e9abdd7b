"""pnrotor: orientation of precessing compact binaries by integrating the rotor (Boyle 2016)."""

__version__ = "0.1.0"

_EXPORTS = {
    "integrate_angular_velocity": "pnrotor.integrate",
    "FrameHistory": "pnrotor.results",
    "evolve": "pnrotor.pn.evolve",
    "Evolution": "pnrotor.results",
    "evolve_many": "pnrotor.pn.many",
    "Population": "pnrotor.results",
    "modes": "pnrotor.waveform.stream",
    "Modes": "pnrotor.results",
    "polarizations": "pnrotor.waveform.stream",
    "stream": "pnrotor.waveform.stream",
    "Options": "pnrotor.options",
}


_SUBMODULES = {"analytic", "batch", "formulations", "hdf5", "ode", "pn", "quaternion", "results", "waveform"}
"""The subpackages the README uses as ``pnrotor.NAME`` without importing them first."""


def __getattr__(name):
    # imported on first use, so that `import pnrotor` (and the CLI's startup) does not load numba
    import importlib

    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    if name in _SUBMODULES:
        return importlib.import_module(f"pnrotor.{name}")
    raise AttributeError(f"module 'pnrotor' has no attribute {name!r}")
