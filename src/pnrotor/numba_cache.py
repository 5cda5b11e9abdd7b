"""Whether numba's cache already holds pnrotor's compiled kernels, found without importing numba, and
compiling the biggest of them beside the rest.

pnrotor's kernels are compiled with ``cache=True``: the first run on a machine compiles them and numba
stores them beside the sources in ``__pycache__``, or in ``NUMBA_CACHE_DIR`` when that is set.
:func:`is_cold` looks for the index file of a kernel (by default the DOP853 core, which every run needs) in the
folder numba would use (:func:`cache_folder`), so that a caller can say what the wait is.  numba compiles one
function at a time in a process, and the biggest units take ~12 s each here: on a cold cache
:func:`compile_aside` compiles the DOP853 core (``'core'``), and for a run whose modes will be written the
modes kernels (``'modes'``; ``'waves'`` for a uniformly sampled run, whose modes and polarizations are computed as
they are written), each in a process of its own while this one compiles the rest of its run
(parameters, right-hand side, events); their first use waits for that process (:func:`wait_for_aside`) and loads
what it cached (``pnrotor.ode.common.entry_point``, ``pnrotor.waveform.amplitudes.modes_in_frame``).
"""

import glob
import hashlib
import os
import subprocess
import sys
from importlib.util import find_spec

__all__ = ["is_cold", "cache_folder", "compile_aside", "wait_for_aside"]

_ASIDE_CODE = {"core": "from pnrotor.ode.dop853 import compile_core; compile_core()",
               "modes": "from pnrotor.waveform.amplitudes import compile_kernels; compile_kernels()",
               "waves": "from pnrotor.waveform.stream import compile_kernels; compile_kernels()"}
"""What :func:`compile_aside` can compile, and the code its process runs."""

_asides = {}
"""The processes compiling aside, by what they compile, while they may still be running."""


def is_cold(kernel="dop853.core", package="ode"):
    """True if numba's cache has no compiled ``kernel`` (``module.function`` of the subpackage ``pnrotor.package``)
    for this installation yet; by default the DOP853 core, which every run needs (``evolve_many`` compiles
    its own loop around it, ``many._integrate_all`` of ``pn``)."""
    return not glob.glob(os.path.join(cache_folder(package), f"{kernel}-*.nbi"))


def cache_folder(package="ode"):
    """Where numba caches the kernels of the subpackage ``pnrotor.package`` (numba 0.5x–0.6x's locators, in their
    order): NUMBA_CACHE_DIR/<package>_<sha1 of its folder> if set; else the folder's ``__pycache__`` if it can
    be written; else the user-wide ``$XDG_CACHE_HOME/numba/<package>_<sha1>`` (~/.cache by default), where a
    read-only install (a system site-packages) gets its cache."""
    folder = os.path.dirname(os.path.abspath(find_spec(f"pnrotor.{package}").origin))
    sub = f"{package}_" + hashlib.sha1(folder.encode()).hexdigest()
    if os.environ.get("NUMBA_CACHE_DIR"):
        return os.path.join(os.environ["NUMBA_CACHE_DIR"], sub)
    tree = os.path.join(folder, "__pycache__")
    if os.access(tree if os.path.isdir(tree) else folder, os.W_OK):
        return tree
    return os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "numba", sub)


def compile_aside(what):
    """Start compiling ``what`` ('core', 'modes' or 'waves', module docstring) into numba's cache in another process; it
    dies with this one.  Nothing is lost if it fails: the first use then compiles it here."""
    from pnrotor.processes import die_with_parent

    _asides[what] = subprocess.Popen([sys.executable, "-c", _ASIDE_CODE[what]], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, preexec_fn=die_with_parent)


def wait_for_aside(what):
    """Wait for the process of :func:`compile_aside` compiling ``what``, if one was started (at most once)."""
    process = _asides.pop(what, None)
    if process is not None:
        process.wait()
