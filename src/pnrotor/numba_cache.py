"""Whether numba's cache already holds pnrotor's compiled kernels, found without importing numba.

pnrotor's kernels are compiled with ``cache=True``: the first run on a machine compiles them (the CLI's
main job took 33 s cold against ~1.5 s warm on this project's 2-core machine) and numba stores them beside
the sources in ``__pycache__``, or in ``NUMBA_CACHE_DIR`` when that is set.  :func:`is_cold` looks for the
index file of the DOP853 core, the kernel every run needs, so that a caller can say what the wait is.
"""

import glob
import os
from importlib.util import find_spec

__all__ = ["is_cold"]


def is_cold():
    """True if numba's cache has no compiled DOP853 core for this installation yet."""
    folder = os.environ.get("NUMBA_CACHE_DIR")
    ode = os.path.dirname(find_spec("pnrotor.ode").origin)
    where = os.path.join(folder, "ode_*") if folder else os.path.join(ode, "__pycache__")
    return not glob.glob(os.path.join(where, "dop853._dop853_core-*.nbi"))
