"""`pnrotor.batch` from Python: a table run in this process or on worker processes equals single
`pnrotor.evolve` calls bitwise, a bad row is reported without losing the others, a bad table is a
ValueError naming what is wrong, and nothing is written before the batch is complete."""

import os

import numpy as np
import pytest
from helpers import kill_9_after
from test_cli_evolve import assert_same_run

import pnrotor
from pnrotor import batch, hdf5

ROWS = [
    dict(m1=30.0, m2=10.0, chi1=(0.6, 0.0, 0.2), chi2=(0.0, -0.4, 0.1), f_ref=100.0),
    dict(m1=20.0, m2=15.0, chi1=(0.0, 0.0, 0.3), chi2=(0.0, 0.0, -0.2), f_ref=90.0, sampling=1 / 4096),
    dict(m1=12.0, m2=9.0, chi1=(0.0, 0.0, 0.0), chi2=(0.0, 0.0, 0.0), f_ref=120.0, approximant="T5"),
]
CSV = ("m1,m2,chi1,chi2,f_ref,sampling,approximant,name\n"
       '30,10,"0.6,0,0.2","0,-0.4,0.1",100,,,a\n'
       '20,15,"0,0,0.3","0,0,-0.2",90,1/4096,,b\n'
       "-5,10,\"0,0,0\",\"0,0,0\",100,,,bad\n"
       '12,9,"0,0,0","0,0,0",120,,T5,c\n')


@pytest.fixture
def table(tmp_path):
    path = tmp_path / "binaries.csv"
    path.write_text(CSV)
    return path


@pytest.mark.parametrize("jobs", [1, 2])
def test_run_equals_single_evolve_calls_bitwise(table, tmp_path, jobs):
    out = tmp_path / f"jobs{jobs}.h5"
    outcome = batch.run(table, out, jobs=jobs)
    assert outcome.written == 3 and outcome.path == out and sorted(outcome.briefs) == [0, 1, 3]
    assert [row.name for row in outcome.failed] == ["bad"]
    assert outcome.failed[0].error == "m1 must be a finite positive mass, got -5.0"
    assert sorted(hdf5.list_runs(out)) == ["a", "b", "c"]
    for name, kw in zip("abc", ROWS):
        assert_same_run(hdf5.read(out, name), pnrotor.evolve(**kw))
    assert set(os.listdir(tmp_path)) == {"binaries.csv", out.name}      # no part files left


def test_plan_shows_rows_and_backend_before_running(table, tmp_path):
    plan = batch.plan(table, tmp_path / "out.h5", jobs=2)
    assert [row.name for row in plan.rows] == ["a", "b", "bad", "c"]
    assert [index for index, _ in plan.tasks] == [0, 1, 2, 3] and plan.where == "2 worker processes"
    assert not (tmp_path / "out.h5").exists()
    assert batch.plan(table, tmp_path / "out.h5", jobs=1).where == "this process"


@pytest.mark.parametrize("text, message", [
    ("m1,m2,chi1,chi2\n", "missing column f_ref"),
    ("m1,m2,chi1,chi2,f_ref,spin\n", "unknown column 'spin'"),
    ('m1,m2,chi1,chi2,f_ref,name\n30,10,"0,0,0","0,0,0",20,x\n30,10,"0,0,0","0,0,0",30,x\n', "the same name 'x'"),
])
def test_bad_table_is_a_value_error_naming_the_problem(tmp_path, text, message):
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        batch.run(path, tmp_path / "out.h5")
    assert os.listdir(tmp_path) == ["t.csv"]


@pytest.mark.parametrize("options, message", [(dict(jobs=0), "jobs must be at least 1"),
                                              (dict(jobs=2, scheduler="tcp://x:1"), "jobs applies to local runs")])
def test_bad_options(table, tmp_path, options, message):
    with pytest.raises(ValueError, match=message):
        batch.plan(table, tmp_path / "out.h5", **options)


def test_existing_output_refused_before_running_unless_overwrite(table, tmp_path, monkeypatch):
    out = tmp_path / "out.h5"
    out.write_bytes(b"keep")
    monkeypatch.setattr(batch.backends, "evolve_row", lambda params: pytest.fail("ran"))
    with pytest.raises(FileExistsError, match="exists"):
        batch.run(table, out)
    assert out.read_bytes() == b"keep"


def interrupt_third_run(monkeypatch):
    """Make the batch backends' third evolve_row call raise KeyboardInterrupt (Ctrl-C); → the list of calls."""
    real, calls = batch.backends.evolve_row, []

    def interrupt_third(params):
        calls.append(params)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(params)

    monkeypatch.setattr(batch.backends, "evolve_row", interrupt_third)
    return calls


@pytest.mark.parametrize("jobs", [1, 2])
def test_interrupted_batch_keeps_its_finished_runs_and_resumes(table, tmp_path, monkeypatch, jobs):
    """Ctrl-C at the third run: no batch file, the finished runs in OUT.parts; resume=True computes only
    the others and the file equals an uninterrupted batch's bitwise (issue 15: every finished run was lost)."""
    real, calls = batch.backends.evolve_row, interrupt_third_run(monkeypatch)
    with pytest.raises(KeyboardInterrupt, match="finished runs? kept in .*out.h5.parts; complete the batch"):
        batch.run(table, tmp_path / "out.h5", jobs=1)
    assert sorted(os.listdir(tmp_path)) == ["binaries.csv", "out.h5.parts"]
    with pytest.raises(FileExistsError, match="pass --resume"):
        batch.plan(table, tmp_path / "out.h5")
    monkeypatch.setattr(batch.backends, "evolve_row", lambda params: calls.append(params) or real(params))
    outcome = batch.run(table, tmp_path / "out.h5", jobs=jobs, resume=True)
    if jobs == 1:                # (workers' calls are not seen here)
        assert len(calls) == 3 + 2   # the two finished before the interrupt are not computed again
    assert outcome.written == 3 and sorted(outcome.briefs) == [0, 1, 3]
    assert sorted(os.listdir(tmp_path)) == ["binaries.csv", "out.h5"]
    for name, kw in zip("abc", ROWS):
        assert_same_run(hdf5.read(tmp_path / "out.h5", name), pnrotor.evolve(**kw))


def test_resume_refuses_the_runs_of_another_table(table, tmp_path, monkeypatch):
    interrupt_third_run(monkeypatch)     # two runs kept (an interrupt before any leaves no folder)
    with pytest.raises(KeyboardInterrupt):
        batch.run(table, tmp_path / "out.h5", jobs=1)
    table.write_text(CSV.replace("120,,T5,c", "125,,T5,c"))
    with pytest.raises(ValueError, match="holds runs of another table"):
        batch.run(table, tmp_path / "out.h5", jobs=1, resume=True)


@pytest.mark.parametrize("change", ["without the bad row", "with other storage options"])
def test_resume_refuses_shifted_rows_and_other_options(table, tmp_path, monkeypatch, change):
    """The part files are named by row position: removing a row that failed its checks shifts the others,
    and would have put a row's run under the next row's name; other storage options would give a mixed file."""
    unreadable = 'abc,10,"0,0,0","0,0,0",100,,,unreadable\n'    # fails when the table is read
    table.write_text(CSV.replace("-5,", "5,") + unreadable + '25,10,"0,0,0","0,0,0",100,,,d\n')
    interrupt_third_run(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        batch.run(table, tmp_path / "out.h5", jobs=1)
    options = {}
    if change == "without the bad row":
        table.write_text(table.read_text().replace(unreadable, ""))
    else:
        options = dict(compression="gzip")
    with pytest.raises(ValueError, match="holds runs of another table, or of other options"):
        batch.run(table, tmp_path / "out.h5", jobs=1, resume=True, **options)


def test_modes_with_an_unnamed_row_that_failed_its_checks(tmp_path):
    """plan(modes=…) read every row's name (None for this one): an AttributeError traceback."""
    path = tmp_path / "t.csv"
    path.write_text('m1,m2,chi1,chi2,f_ref\n30,10,"0,0,0","0,0,0",100\nabc,10,"0,0,0","0,0,0",100\n')
    plan = batch.plan(path, tmp_path / "out.h5", jobs=1, modes=(4, 1.5, None))
    assert [row.error is None for row in plan.rows] == [True, False] and len(plan.tasks) == 1


def test_an_interrupt_before_any_run_keeps_nothing_and_says_so(table, tmp_path, monkeypatch):
    def interrupt(params):
        raise KeyboardInterrupt

    monkeypatch.setattr(batch.backends, "evolve_row", interrupt)
    with pytest.raises(KeyboardInterrupt, match="^no run had finished; nothing kept$"):
        batch.run(table, tmp_path / "out.h5", jobs=1)
    assert os.listdir(tmp_path) == ["binaries.csv"]


def test_resume_without_an_earlier_attempt_runs_the_whole_batch(table, tmp_path):
    """The parts folder is made (and locked) before the runs kept in it are looked for: finding it without a
    fingerprint, --resume called a first attempt "runs of another table"."""
    outcome = batch.run(table, tmp_path / "out.h5", jobs=1, resume=True)
    assert outcome.written == 3 and sorted(os.listdir(tmp_path)) == ["binaries.csv", "out.h5"]


def test_resume_computes_a_damaged_part_again(table, tmp_path, monkeypatch):
    real = batch.backends.evolve_row
    interrupt_third_run(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        batch.run(table, tmp_path / "out.h5", jobs=1)
    part = tmp_path / "out.h5.parts" / "runs.h5"   # the batch file being built: runs a and c
    data = bytearray(part.read_bytes())
    run = hdf5.read(part, "a")
    at = data.find(run.v.tobytes()[:16])   # a byte of the run's v: Fletcher-32 catches it
    data[at + 3] ^= 0x10
    part.write_bytes(bytes(data))
    calls = []
    monkeypatch.setattr(batch.backends, "evolve_row", lambda params: calls.append(params) or real(params))
    outcome = batch.run(table, tmp_path / "out.h5", jobs=1, resume=True)
    assert outcome.written == 3
    assert [params["m1"] for params in calls] == [30.0, -5.0, 12.0]   # the damaged run and the two not computed
    for name, kw in zip("abc", ROWS):
        assert_same_run(hdf5.read(tmp_path / "out.h5", name), pnrotor.evolve(**kw))


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_run_that_cannot_be_written_fails_its_row_only(table, tmp_path, monkeypatch, jobs):
    """A run pnrotor.hdf5 refuses to write (here one with a NaN sample) fails its row; it stopped the whole
    batch, and every --resume of it."""
    real = batch.backends.evolve_row

    def nan_for_b(params):
        run = real(params)
        if params["m1"] == 20.0:
            run.v[3] = np.nan
        return run

    monkeypatch.setattr(batch.backends, "evolve_row", nan_for_b)
    monkeypatch.setattr(batch.backends, "start_method", lambda: "fork")   # the workers see the patch
    outcome = batch.run(table, tmp_path / "out.h5", jobs=jobs)
    assert [row.name for row in outcome.failed] == ["b", "bad"]
    assert outcome.failed[0].error.startswith("its run cannot be written: cannot write this Evolution: dataset 'v' "
                                              "has 1 non-finite value")
    assert sorted(hdf5.list_runs(tmp_path / "out.h5")) == ["a", "c"]


def test_a_second_batch_on_the_same_output_fails_at_once(table, tmp_path, monkeypatch):
    """Two batches writing one output shared its part files (run-INDEX.h5): one table's runs came out under the
    other's names.  The running batch holds a lock in OUTPUT.parts; a second one fails before computing."""
    import fcntl

    first = batch.plan(table, tmp_path / "out.h5", jobs=1)        # planned while the output is free
    second = batch.plan(table, tmp_path / "out.h5", jobs=1)
    real = batch.backends.evolve_row

    def run_second_meanwhile(params):
        if params["m1"] == 30.0:
            with pytest.raises(FileExistsError, match="another batch is writing .*out.h5"):
                second.run()
        return real(params)

    def plan_meanwhile(params):
        with pytest.raises(FileExistsError, match="another batch is writing"):   # not "remove the folder"
            batch.plan(table, tmp_path / "out.h5", jobs=1)
        return run_second_meanwhile(params)

    monkeypatch.setattr(batch.backends, "evolve_row", plan_meanwhile)
    outcome = first.run()
    assert outcome.written == 3 and sorted(os.listdir(tmp_path)) == ["binaries.csv", "out.h5"]
    (tmp_path / "p.parts").mkdir()   # and the lock is an flock: held by another open file, it refuses too
    with open(tmp_path / "p.parts" / "lock", "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        with pytest.raises(FileExistsError, match="another batch is writing"):
            batch.run(table, tmp_path / "p", jobs=1, resume=True)
    assert os.listdir(tmp_path / "p.parts") == ["lock"]


def test_a_worker_killed_once_loses_no_run(table, tmp_path, monkeypatch):
    """A worker killed (as the out-of-memory killer would) broke the pool and every row not finished failed, the
    finished ones too (their part files were removed): the lost rows now go to a new pool once."""
    import signal

    real, marker = batch.backends.evolve_row, tmp_path / "killed"

    def die_once(params):
        if params["m1"] == 20.0 and not marker.exists():
            marker.touch()
            os.kill(os.getpid(), signal.SIGKILL)
        return real(params)

    monkeypatch.setattr(batch.backends, "evolve_row", die_once)
    monkeypatch.setattr(batch.backends, "start_method", lambda: "fork")   # the workers see the patch
    outcome = batch.run(table, tmp_path / "out.h5", jobs=2)
    assert marker.exists() and [row.name for row in outcome.failed] == ["bad"]
    for name, kw in zip("abc", ROWS):
        assert_same_run(hdf5.read(tmp_path / "out.h5", name), pnrotor.evolve(**kw))


def test_a_row_that_kills_its_worker_every_time_fails_alone(table, tmp_path, monkeypatch):
    """Every row unfinished when a pool broke a second time failed with it (bystanders too)."""
    import signal

    real = batch.backends.evolve_row

    def poison_b(params):
        if params["m1"] == 20.0:
            os.kill(os.getpid(), signal.SIGKILL)
        return real(params)

    monkeypatch.setattr(batch.backends, "evolve_row", poison_b)
    monkeypatch.setattr(batch.backends, "start_method", lambda: "fork")   # the workers see the patch
    outcome = batch.run(table, tmp_path / "out.h5", jobs=2)
    assert sorted(row.name for row in outcome.failed) == ["b", "bad"]
    assert "its worker process died running it" in next(row for row in outcome.failed if row.name == "b").error
    assert sorted(hdf5.list_runs(tmp_path / "out.h5")) == ["a", "c"]


def test_run_restores_the_callers_ctrl_c_handler(table, tmp_path):
    import signal

    def mine(signum, frame):
        pass

    previous = signal.signal(signal.SIGINT, mine)
    try:
        batch.run(table, tmp_path / "out.h5", jobs=1)
        assert signal.getsignal(signal.SIGINT) is mine
    finally:
        signal.signal(signal.SIGINT, previous)


KILLED_SERIAL = """
import sys, time
from pnrotor import batch
real, count = batch.backends.evolve_row, [0]
def slow_after_two(params):
    count[0] += 1
    if count[0] == 3:
        print("two done", flush=True)
        time.sleep(120)
    return real(params)
batch.backends.evolve_row = slow_after_two
batch.run(sys.argv[1], sys.argv[2], jobs=1)
"""


def test_batch_killed_with_sigkill_resumes(table, tmp_path):
    """kill -9 while the third row runs: the two finished runs survive in OUT.parts and resume completes the
    batch, equal to single evolve calls."""
    out = tmp_path / "out.h5"
    kill_9_after(KILLED_SERIAL, table, out, line="two done")
    assert not out.exists() and hdf5.list_runs(tmp_path / "out.h5.parts" / "runs.h5") == ["a", "b"]
    outcome = batch.run(table, out, jobs=1, resume=True)
    assert outcome.written == 3
    for name, kw in zip("abc", ROWS):
        assert_same_run(hdf5.read(out, name), pnrotor.evolve(**kw))


def test_rows_already_read_and_defaults_for_empty_cells(table, tmp_path):
    rows = batch.read_batch(table, {"sampling": "final"})
    outcome = batch.plan(rows, tmp_path / "out.h5", jobs=1).run()
    assert outcome.written == 3
    assert len(hdf5.read(tmp_path / "out.h5", "a")) == 1                   # the default filled the empty cell
    assert len(hdf5.read(tmp_path / "out.h5", "b")) > 1                    # its own 1/4096 s kept


KILLED_BATCH = """
import os, sys, time
from pnrotor.batch import backends
backends.evolve_row = lambda params: time.sleep(120)
results = backends.results_pool([(i, {}) for i in range(4)], 2, context=sys.argv[1], chunksize=1)
print(" ".join(str(p.pid) for p in results.gi_frame.f_locals["pool"]._processes.values()), flush=True)
next(results)
"""


@pytest.mark.parametrize("context", ["fork", "forkserver"])
def test_workers_die_with_a_killed_batch(context):
    """kill -9 of the batch process: its pool workers go too, within seconds (issue 15: two orphan workers
    blocked forever, 8 of 8 times)."""
    import signal
    import subprocess
    import sys
    import time

    parent = subprocess.Popen([sys.executable, "-c", KILLED_BATCH, context], stdout=subprocess.PIPE, text=True)
    try:
        workers = [int(pid) for pid in parent.stdout.readline().split()]
        assert len(workers) == 2
        parent.send_signal(signal.SIGKILL)
        parent.wait(timeout=30)
        deadline = time.monotonic() + 20
        alive = workers
        while alive and time.monotonic() < deadline:
            time.sleep(0.1)
            alive = [pid for pid in workers if _alive(pid)]
        assert alive == []
    finally:
        parent.kill()
        parent.stdout.close()


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"   # a zombie has exited
    except FileNotFoundError:
        return False


def test_dask_cluster_without_workers_fails_after_the_stated_timeout(table, tmp_path, monkeypatch):
    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr(batch.backends, "SCHEDULER_TIMEOUT", "1s")
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        with pytest.raises(ValueError, match=r"has no workers \(waited 1s\)"):
            batch.run(table, tmp_path / "out.h5", scheduler=cluster.scheduler_address)
    assert os.listdir(tmp_path) == ["binaries.csv"]


@pytest.mark.parametrize("jobs", [1, 2])
def test_modes_beside_each_run_and_kept_by_resume(table, tmp_path, monkeypatch, jobs):
    """modes=(ℓ_max, amplitude order, distance): each row's Modes as NAME.modes, equal to pnrotor.modes of
    the single evolve call; a resumed batch keeps those already computed, and its fingerprint includes the
    modes asked for."""
    out = tmp_path / "out.h5"
    outcome = batch.run(table, out, jobs=jobs, modes=(4, 1.5, 100.0))
    assert outcome.written == 3
    assert sorted(hdf5.list_runs(out)) == ["a", "a.modes", "b", "b.modes", "c", "c.modes"]
    for name, kw in zip("abc", ROWS):
        expected = pnrotor.modes(pnrotor.evolve(**kw), 4, 1.5, 100.0)
        got = hdf5.read(out, f"{name}.modes")
        np.testing.assert_array_equal(got.data, expected.data)
        assert got.distance_Mpc == 100.0
    real = batch.backends.evolve_row
    interrupt_third_run(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        batch.run(table, tmp_path / "again.h5", jobs=1, modes=(4, 1.5, 100.0))
    with pytest.raises(ValueError, match="holds runs of another table"):
        batch.run(table, tmp_path / "again.h5", jobs=1, resume=True, modes=(3, 1.5, 100.0))
    resumed = []
    monkeypatch.setattr(batch.backends, "evolve_row", lambda params: resumed.append(params) or real(params))
    batch.run(table, tmp_path / "again.h5", jobs=1, resume=True, modes=(4, 1.5, 100.0))
    assert sorted(p["m1"] for p in resumed) == [-5.0, 12.0]   # only rows bad (failed, not kept) and c again
    for name in ("a", "a.modes", "c.modes"):
        assert_same_file_run(hdf5.read(tmp_path / "again.h5", name), hdf5.read(out, name))


def assert_same_file_run(a, b):
    for field in ("t", "data", "v", "R"):
        if hasattr(a, field):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


CLOSED_BATCH = """
import pathlib, sys, time
from pnrotor.batch import backends
folder = pathlib.Path(sys.argv[1])


def row(params):
    time.sleep(0.2)
    (folder / f"row-{params['i']}").touch()


backends.evolve_row = row
results = backends.results_pool([(i, {"i": i}) for i in range(40)], 2, context="fork", chunksize=1)
next(results)
results.close()   # what Plan._run does on a Ctrl-C or SIGTERM
done = len(list(folder.iterdir()))
time.sleep(1.0)
print(done, len(list(folder.iterdir())))
"""


def test_closing_a_pool_batch_stops_its_workers_at_once(tmp_path):
    """Closing the pool's results early (a Ctrl-C or SIGTERM of a --jobs batch) cancels its queued rows and ends its
    workers: no row runs after it (a review of 2026-11-28: shutdown forgot the workers before they were terminated,
    and the queued rows ran on; a batch of 400 rows computed them all in 36 s more)."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", CLOSED_BATCH, str(tmp_path)], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    done, later = map(int, out.stdout.split())
    assert 1 <= done < 40 and later == done
