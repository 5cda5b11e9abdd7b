"""Signals (issue 36, items 3 and 4): pnrotor takes only the signals at their default disposition, in the command
line and in the library (a signal the parent set to be ignored stays ignored: ``nohup``'s SIGHUP, a background
job's SIGINT); a batch's workers leave every signal to the batch process; a Ctrl-C of a ``--jobs`` batch prints
one line, with the ``--resume`` hint when runs were kept."""

import os
import signal
import subprocess
import sys
import time

import h5py
import pytest
from helpers import default_signals

from pnrotor import batch, hdf5, signals
from pnrotor.cli import main

ROW = "30,10,\"0.6,0,0.2\",\"0,-0.4,0.1\",100,r{}\n"
FAST = ["--m1", "30", "--m2", "10", "--chi1", "0.6,0,0.2", "--chi2", "0,-0.4,0.1", "--f-ref", "100"]
"""A cheap precessing binary: from 100 Hz, ~4 orbits to the end of the inspiral (a batch's row, the options)."""


def _table(path, rows):
    path.write_text("m1,m2,chi1,chi2,f_ref,name\n" + "".join(ROW.format(i) for i in range(rows)))
    return path


def _handlers_while_writing(monkeypatch):
    """The handlers of SIGINT, SIGTERM and SIGHUP each time HDF5 writes a dataset."""
    seen, create = [], h5py.Group.create_dataset

    def create_dataset(self, name, *args, **kwargs):
        seen.append({s: signal.getsignal(s) for s in signals.STOPPING})
        return create(self, name, *args, **kwargs)

    monkeypatch.setattr(h5py.Group, "create_dataset", create_dataset)
    return seen


def dispositions(**handlers):
    """Set these signals' handlers (name=handler) for the test (conftest's `_process_state` puts them back)."""
    for name, handler in handlers.items():
        signal.signal(getattr(signal, name), handler)


def test_only_signals_at_their_default_disposition_are_taken():
    """Ignored, or the program's own: left alone; SIG_DFL and Python's own SIGINT handler: taken, and put back."""
    def mine(signum, frame):
        pass

    dispositions(SIGINT=signal.SIG_IGN, SIGTERM=mine, SIGHUP=signal.SIG_DFL)
    previous = signals.take(mine)
    try:
        assert set(previous) == {signal.SIGHUP} and signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is mine and signals.free(signal.SIGHUP)   # an outer pnrotor handler
    finally:
        signals.restore(previous)
    assert signal.getsignal(signal.SIGHUP) is signal.SIG_DFL
    dispositions(SIGINT=signal.default_int_handler, SIGTERM=signal.default_int_handler)
    assert signals.free(signal.SIGINT) and not signals.free(signal.SIGTERM)   # Python's default is SIGINT's only


def test_hdf5_write_leaves_an_ignored_signal_ignored(tmp_path, monkeypatch):
    """A nohup'ed script calling hdf5.write died of SIGHUP (a KeyboardInterrupt traceback): pnrotor's handler
    replaced the ignored disposition while the file was written."""
    from test_hdf5 import frame_history

    seen = _handlers_while_writing(monkeypatch)
    dispositions(SIGINT=signal.SIG_IGN, SIGTERM=signal.SIG_DFL, SIGHUP=signal.SIG_IGN)
    hdf5.write(tmp_path / "run.h5", frame_history())
    assert seen and all(h[signal.SIGHUP] is signal.SIG_IGN and h[signal.SIGINT] is signal.SIG_IGN for h in seen)
    assert all(getattr(h[signal.SIGTERM], "pnrotor_handler", False) for h in seen)   # its default: taken
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


def test_a_batch_leaves_an_ignored_ctrl_c_ignored(tmp_path, monkeypatch):
    """A background batch (``cmd &``: SIGINT ignored) had its SIGINT turned back on while it ran and wrote (its
    workers: `test_a_nohup_or_background_batch_survives_the_signal_it_ignores`)."""
    seen, evolve_row = _handlers_while_writing(monkeypatch), batch.backends.evolve_row

    def row(params):
        seen.append({s: signal.getsignal(s) for s in signals.STOPPING})
        return evolve_row(params)

    monkeypatch.setattr(batch.backends, "evolve_row", row)
    dispositions(SIGINT=signal.SIG_IGN, SIGTERM=signal.SIG_DFL, SIGHUP=signal.SIG_DFL)
    outcome = batch.run(_table(tmp_path / "b.csv", 4), tmp_path / "out.h5", jobs=1)
    assert outcome.written == 4 and not outcome.failed
    assert len(seen) >= 8 and all(h[signal.SIGINT] is signal.SIG_IGN for h in seen)
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN


def _ignore(*names):
    """A preexec_fn: the child starts with these signals ignored (as nohup or a shell's ``cmd &`` start it), the
    others at their defaults, whatever this process's are."""
    def preexec():
        default_signals()
        for name in names:
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    return preexec


PAUSED_BATCH = """
import os, sys, time
from pnrotor.batch import backends
from pnrotor.cli import main
evolve_row = backends.evolve_row
def paused(params):   # in the workers too (fork): every row but the first one computed pauses
    try:
        os.close(os.open("first", os.O_CREAT | os.O_EXCL))
    except FileExistsError:
        print("computing", flush=True)
        time.sleep(float(os.environ["PAUSE"]))
    return evolve_row(params)
backends.evolve_row = paused
sys.exit(main(sys.argv[1:]))
"""


def _paused_batch(tmp_path, pause, rows, *ignored):
    """`pnrotor evolve --batch` (2 jobs) in its own process group, every row but the first pausing ``pause`` s in
    its worker; returned once the first run is kept (in the batch file being built) and the workers compute others."""
    _table(tmp_path / "b.csv", rows)
    process = subprocess.Popen([sys.executable, "-c", PAUSED_BATCH, "evolve", "--batch", "b.csv", "--jobs", "2", "-q",
                                "-o", "out.h5"], cwd=tmp_path, env=dict(os.environ, PAUSE=str(pause)),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                               preexec_fn=_ignore(*ignored))
    assert process.stdout.readline().startswith("computing"), process.communicate(timeout=60)
    deadline = time.monotonic() + 60
    while not (tmp_path / "out.h5.parts" / "runs.journal").exists():
        assert process.poll() is None and time.monotonic() < deadline, process.communicate(timeout=60)
        time.sleep(0.01)
    return process


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the pause reaches the workers by fork")
@pytest.mark.parametrize("name", ["SIGHUP", "SIGINT"])
def test_a_nohup_or_background_batch_survives_the_signal_it_ignores(tmp_path, name):
    """``nohup pnrotor evolve --batch …`` died of the SIGHUP of a closed terminal (exit 130 "interrupted"), and a
    background batch of a SIGINT: here sent to the whole process group, while the workers compute."""
    process = _paused_batch(tmp_path, 0.5, 6, name)
    try:
        os.killpg(process.pid, getattr(signal, name))
        out, err = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 0 and err == "", err
    assert "wrote 6 runs to out.h5; 0 failed" in out
    assert len(hdf5.list_runs(tmp_path / "out.h5")) == 6


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the pause reaches the workers by fork")
def test_ctrl_c_of_a_jobs_batch_prints_one_line_with_the_resume_hint(tmp_path):
    """Ctrl-C (SIGINT to the process group) while the workers compute: one line, with the hint. The
    workers (which wrote part files then) took SIGINT while they wrote, and SIGTERM (how the batch stops them) with
    the command's handler, and printed "Process ForkProcess-2" tracebacks or "Exception ignored in sys.unraisablehook"."""
    process = _paused_batch(tmp_path, 60, 4)
    try:
        os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130
    assert err == ("pnrotor evolve: interrupted; 1 finished run kept in out.h5.parts; complete the batch with "
                   "--resume (resume=True)\n")


def test_the_command_line_leaves_an_ignored_sighup_ignored(tmp_path, monkeypatch):
    """SIGTERM and SIGHUP stop a command like Ctrl-C, unless set to be ignored (nohup) or the program's own."""
    def mine(signum, frame):
        pass

    seen = _handlers_while_writing(monkeypatch)
    dispositions(SIGTERM=mine, SIGHUP=signal.SIG_IGN)
    assert main(["evolve", *FAST, "-o", str(tmp_path / "w.h5"), "-q"]) == 0
    assert seen and all(h[signal.SIGHUP] is signal.SIG_IGN and h[signal.SIGTERM] is mine for h in seen)
    dispositions(SIGTERM=signal.SIG_DFL, SIGHUP=signal.SIG_DFL)
    assert main(["evolve", *FAST, "-o", str(tmp_path / "v.h5"), "-q"]) == 0
    assert all(getattr(h[s], "pnrotor_handler", False) for h in seen[-1:] for s in (signal.SIGHUP, signal.SIGTERM))
    assert signal.getsignal(signal.SIGHUP) is signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
