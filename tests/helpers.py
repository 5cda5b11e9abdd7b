"""Helpers shared by the test modules (``tests`` is on pytest's ``pythonpath``)."""

import importlib
import signal
import subprocess
import sys

import pytest

REFERENCES = {
    "lal": "lalsuite",
    "lalsimulation": "lalsuite",
    "matplotlib": "matplotlib",
    "distributed": "dask[distributed]",
    "spherical": "spherical",
    "sxs": "sxs",
    "quaternionic": "sxs",
    "pycbc": "pycbc",
    "gwpy": "gwpy",
    "bilby": "bilby",
    "sphinx": "sphinx",
    "furo": "furo",
    "myst_parser": "myst-parser",
    "sphinx_gallery": "sphinx-gallery",
}
"""The optional references of the test extra (pyproject.toml): module imported → the requirement that installs it.
A test that needs one is skipped where it is missing (`reference`, `needs`, or ``pytest.importorskip``), except
with PNROTOR_REQUIRE_REFERENCES=1 (set by .ci/run), where conftest fails the run unless every one imports.  Add
here each new one the test extra gets."""


def reference(name):
    """The module ``name`` (``import name``), or None where a module of `REFERENCES` it needs is not installed.
    Any other import error, pnrotor's own included, is raised: a broken module must fail, never skip."""
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as error:
        if (error.name or "").partition(".")[0] not in REFERENCES:
            raise
        return None


def needs(*names):
    """A mark: skip the test where one of the modules ``names`` is not installed (`reference`)."""
    missing = [name for name in names if reference(name) is None]
    return pytest.mark.skipif(bool(missing), reason=f"not installed: {', '.join(missing)} (a reference of the "
                                                    "test extra; PNROTOR_REQUIRE_REFERENCES=1 fails instead)")


def default_signals():
    """``preexec_fn`` of a child process that a test signals: SIGINT, SIGTERM and SIGHUP at their defaults, as a
    terminal starts a command, whatever this process has (pnrotor leaves an ignored signal ignored, and a suite
    started in the background has SIGINT ignored, one under nohup SIGHUP)."""
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)


def kill_9_after(script, *args, line):
    """Run ``python -c script *args`` and send it SIGKILL once it has printed ``line`` (asserted: its first line)."""
    process = subprocess.Popen([sys.executable, "-c", script, *map(str, args)], stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout.readline() == line + "\n"
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=30)
    finally:
        process.kill()
        process.stdout.close()
