"""Hypothesis profiles: ``default`` draws the same examples on every run (derandomized), so the suite
and CI pass or fail reproducibly; ``explore`` draws new random examples each run, to hunt for new
failures: ``python3 -m pytest --hypothesis-profile=explore``.  (A random run found the degenerate binary
of tests/test_integrate.py::test_generator_on_the_half_pi_sphere_converges.)

The suite runs in a random order (pytest-randomly, in the test extra: ``--randomly-seed=N`` repeats an order,
``-p no:randomly`` runs the files in order), so every test leaves the process as it found it (`_process_state`);
and it passes where it is started with SIGINT ignored (a background job, a supervisor): a test that needs
Python's Ctrl-C installs it (`default_sigint`), in a child process too.

A test that needs an optional reference of the test extra (LALSuite, …: helpers.REFERENCES) is skipped where it
is missing, except with PNROTOR_REQUIRE_REFERENCES=1 (.ci/run sets it): then the run stops at once unless every
reference imports and pytest-randomly is active, and a test skipped for a module it could not import fails."""

import importlib
import os
import signal
import subprocess
import sys

import pytest
from helpers import REFERENCES
from hypothesis import settings

settings.register_profile("default", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("default")

REQUIRE = os.environ.get("PNROTOR_REQUIRE_REFERENCES") == "1"


def pytest_configure(config):
    if not REQUIRE:
        return
    missing = []
    for name, requirement in REFERENCES.items():
        try:
            importlib.import_module(name)
        except Exception as error:   # noqa: BLE001 - a broken install too
            missing.append(f"{requirement} (import {name}: {type(error).__name__}: {error})")
    if not config.pluginmanager.hasplugin("randomly"):
        missing.append("pytest-randomly (the random order of the suite)")
    if missing:
        raise pytest.UsageError("PNROTOR_REQUIRE_REFERENCES=1, but the test extra is not fully installed: "
                                + "; ".join(missing))


def _required(report):
    """With PNROTOR_REQUIRE_REFERENCES=1, a test or module skipped by ``pytest.importorskip`` fails."""
    if REQUIRE and report.skipped and "could not import" in str(report.longrepr):
        reason = report.longrepr[-1] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome, report.longrepr = "failed", f"PNROTOR_REQUIRE_REFERENCES=1: {reason}"
    return report


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    return _required((yield))


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector):
    return _required((yield))


_COMPILED = """from numba.core import event
compiled = []   # what numba compiles in this process, in order
class _Compiled(event.Listener):
    def on_start(self, ev): pass
    def on_end(self, ev): compiled.append(str(ev.data["dispatcher"]))
event.register("numba:compile", _Compiled())
"""


@pytest.fixture
def cold_python(tmp_path):
    """run(code, timeout) → the output of ``code`` run in a fresh Python with an empty numba cache (NUMBA_CACHE_DIR
    in tmp_path), where the list ``compiled`` names what numba has compiled so far; a failing process fails the
    test with its stderr."""
    def run(code, timeout=600):
        done = subprocess.run([sys.executable, "-c", _COMPILED + code], capture_output=True, text=True,
                              timeout=timeout, env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache")))
        assert done.returncode == 0, done.stderr[-3000:]
        return done.stdout
    return run


@pytest.fixture(autouse=True, scope="session")
def _warm_numba_cache():
    """The kernels whose absence makes the CLI say one line before compiling (`pnrotor.cli.evolve._warn_if_cold`)
    compiled into numba's cache before the first test, if missing: otherwise whether a test asserting a CLI's stderr
    sees that line depends on the tests that ran before it (the random order; a clean clone's cold cache).  The line
    itself is tested with an empty NUMBA_CACHE_DIR (test_cli_evolve.py)."""
    from pnrotor import numba_cache
    if numba_cache.is_cold():
        from pnrotor.ode.dop853 import compile_core
        compile_core()
    for kernel, package, module in (("amplitudes._sum", "waveform", "pnrotor.waveform.amplitudes"),
                                    ("stream._waves", "waveform", "pnrotor.waveform.stream")):
        if numba_cache.is_cold(kernel, package):
            importlib.import_module(module).compile_kernels()
    if numba_cache.is_cold("many._integrate_all", "pn"):
        from pnrotor import evolve_many
        evolve_many([10.0], [10.0], [(0.0, 0.0, 0.1)], [(0.0, 0.0, 0.0)], 20.0)


@pytest.fixture(autouse=True)
def _process_state():
    """After each test: the signal handlers and this thread's signal mask as before it, and no idle worker thread
    of `pnrotor.threads` (the next test starts those it needs, with its own thread count)."""
    handlers = {signum: signal.getsignal(signum) for signum in signal.valid_signals()}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    yield
    for signum, handler in handlers.items():
        if handler is not None and signal.getsignal(signum) is not handler:
            signal.signal(signum, handler)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    threads = sys.modules.get("pnrotor.threads")
    if threads is not None:
        threads.stop_idle_workers()


@pytest.fixture
def default_sigint():
    """Python's own SIGINT handler (Ctrl-C raises KeyboardInterrupt) during the test, whatever this process started
    with; `_process_state` puts the one before back."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
