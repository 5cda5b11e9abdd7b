"""pnrotor.io.journal and the batch file grown with it (pnrotor.hdf5.Journaled): a death at any point of adding a
run leaves the file as of its last commit, byte for byte, with every committed run readable; the runs' bytes are
written once."""

import os
import signal
import subprocess
import sys
import time

import pytest

from pnrotor import hdf5
from pnrotor.io import journal
from test_hdf5 import assert_identical, frame_history


def _grown(tmp_path, count):
    """A batch file of `count` runs added one commit each → (its Journaled, the runs by name)."""
    store = hdf5.Journaled(tmp_path / "runs.h5", tmp_path / "runs.journal")
    runs = {f"r{i}": frame_history(n=3000 + 500 * i, message=f"run {i}") for i in range(count)}
    for name, run in runs.items():
        store.add({name: run})
    return store, runs


def test_runs_added_one_commit_each_read_back_bitwise(tmp_path):
    store, runs = _grown(tmp_path, 4)
    assert store.names() == sorted(runs) == hdf5.list_runs(store.path)
    for name, run in runs.items():
        assert_identical(hdf5.read(store.path, name), run)
    store.publish(tmp_path / "out.h5", overwrite=False)
    assert sorted(os.listdir(tmp_path)) == ["out.h5"]
    assert_identical(hdf5.read(tmp_path / "out.h5", "r3"), runs["r3"])


def test_a_death_while_a_run_is_written_leaves_the_last_commit_byte_for_byte(tmp_path):
    """A run written and its file closed, but no commit (the process died): HDF5 rewrote its headers and B-trees
    (pages over the committed bytes, held in memory) and appended the run; recovery gives back the committed bytes
    exactly, and the next run goes on from there."""
    import h5py

    store, runs = _grown(tmp_path, 2)
    committed = store.path.read_bytes()
    with journal.JournaledFile(store.path, store.journal, len(committed)) as file:
        with h5py.File(file, "r+", libver=("v110", "v110")) as f:
            hdf5._put_run(f.create_group("lost"), frame_history(n=5000), None, True)
        assert os.path.getsize(store.path) > len(committed)   # the new run reached the file, its headers did not
        assert store.path.read_bytes()[:len(committed)] == committed
    again = hdf5.Journaled(store.path, store.journal)
    assert store.path.read_bytes() == committed and again.names() == ["r0", "r1"]
    again.add({"r2": frame_history(n=700)})
    assert again.names() == ["r0", "r1", "r2"]
    assert_identical(hdf5.read(store.path, "r1"), runs["r1"])


def test_a_death_in_a_commit_after_its_journal_is_completed_on_recovery(tmp_path, monkeypatch):
    store, _ = _grown(tmp_path, 1)

    def die(*args):
        raise SystemExit("killed")

    monkeypatch.setattr(journal, "_apply", die)   # the journal is written, the file not yet changed
    with pytest.raises(SystemExit):
        store.add({"r1": frame_history(n=900)})
    monkeypatch.undo()
    assert hdf5.Journaled(store.path, store.journal).names() == ["r0", "r1"]
    assert_identical(hdf5.read(store.path, "r1"), frame_history(n=900))


def test_a_failed_add_keeps_nothing_of_it_and_a_damaged_journal_is_an_error(tmp_path):
    store, _ = _grown(tmp_path, 1)
    before = store.path.read_bytes()
    bad = frame_history(n=800)
    bad.t[5] = float("nan")
    with pytest.raises(ValueError, match="cannot write this FrameHistory"):
        store.add({"r1": frame_history(), "r2": bad})
    assert store.path.read_bytes() == before and store.names() == ["r0"]
    store.journal.write_bytes(store.journal.read_bytes()[:-1] + b"x")
    with pytest.raises(ValueError, match="runs.journal is damaged"):
        hdf5.Journaled(store.path, store.journal)


KILLED = """
import sys
from pnrotor import hdf5
from test_hdf5 import frame_history
store = hdf5.Journaled(sys.argv[1], sys.argv[2])
for i in range(10 ** 6):
    store.add({f"r{i}": frame_history(n=20000)})
    print(i, flush=True)
"""


def test_kill_9_at_random_moments_keeps_every_committed_run(tmp_path):
    """SIGKILL at five moments of a process adding runs of 20,000 samples in a loop: after recovery the file
    holds every run it had reported committed (and at most the one it was writing), each read back exactly."""
    import random

    rng, path, log = random.Random(32), tmp_path / "runs.h5", tmp_path / "runs.journal"
    for _ in range(5):
        process = subprocess.Popen([sys.executable, "-c", KILLED, str(path), str(log)], stdout=subprocess.PIPE,
                                   text=True, cwd=os.path.dirname(__file__))
        reported = [process.stdout.readline() for _ in range(2)]
        time.sleep(rng.uniform(0.0, 0.05))
        process.send_signal(signal.SIGKILL)
        reported += process.stdout.read().splitlines()
        process.wait()
        names = hdf5.Journaled(path, log).names()
        assert len(reported) <= len(names) <= len(reported) + 1
        for name in names:
            assert_identical(hdf5.read(path, name), frame_history(n=20000))
        path.unlink()
        log.unlink()
