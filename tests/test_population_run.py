"""`pnrotor.batch.population.run` in chunks (issue 35): the same file from this process, two worker processes and a
Dask cluster; a run killed with SIGKILL and resumed equals an uninterrupted one without computing its finished
chunks again; a worker killed in the middle of a chunk loses no row; Parquet and HDF5 tables; memory that does not
grow with the table (the table read as chunks finish)."""

import os
import signal

import h5py
import numpy as np
import pytest
from helpers import kill_9_after

from pnrotor import hdf5
from pnrotor.batch import backends, population
from pnrotor.cli import main

CHUNK = 6


def _table(n, seed=1):
    """n rows: precessing binaries to f_max, to the end of the inspiral and backward to f_min, with a bad mass (its
    row fails alone) and a pn_order of 3 (a second group of shared options) here and there."""
    rng = np.random.default_rng(seed)
    lines = ["name,m1,m2,chi1,chi2,f_ref,f_max,f_min,pn_order"]
    for i in range(n):
        m1 = rng.uniform(8.0, 40.0)
        m2 = m1 / rng.uniform(1.0, 4.0)
        c1, c2 = (",".join(map(repr, rng.uniform(-0.5, 0.5, 3).tolist())) for _ in range(2))
        target = ",,15" if i % 7 == 0 else ",," if i % 5 == 0 else ",60,"
        lines.append(f'b{i},{-1.0 if i % 11 == 4 else m1!r},{m2!r},"{c1}","{c2}",20{target},{3 if i % 3 == 0 else ""}')
    return "\n".join(lines) + "\n"


def contents(path):
    """Every dataset's dtype, shape and bytes and every attribute of a file, but the time it was written (and the
    CRC of its strings, which holds that time)."""
    found = {}

    def visit(name, item):
        if isinstance(item, h5py.Dataset):
            found[name] = (item.dtype.str, item.shape, item[()].tobytes())
        found.update({f"{name}@{key}": repr(value) for key, value in item.attrs.items()
                      if key not in ("created", "pnrotor_strings_crc32")})

    with h5py.File(path, "r") as f:
        visit("/", f)
        f.visititems(visit)
    return found


@pytest.fixture
def table(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text(_table(40))
    return path


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The table of 40 rows run in this process, in chunks of CHUNK rows: (its outcome, its file)."""
    folder = tmp_path_factory.mktemp("serial")
    (folder / "t.csv").write_text(_table(40))
    return population.run(folder / "t.csv", folder / "serial.h5", chunk=CHUNK), folder / "serial.h5"


def _failures(outcome):
    return [(row.number, row.name, row.error) for row in outcome.failed]


def test_serial_chunks_equal_one_chunk_and_single_evolve_rows(serial, table, tmp_path):
    """Chunks change nothing: the file of 7 chunks is the file of one; failures in order, each alone."""
    outcome, path = serial
    whole = population.run(table, tmp_path / "whole.h5")
    assert contents(path) == contents(tmp_path / "whole.h5")
    assert _failures(outcome) == _failures(whole) and [n for n, _, _ in _failures(outcome)] == [5, 16, 27, 38]
    assert outcome.written == whole.written == 36
    stored = hdf5.read(path)
    assert list(stored.inputs["row"]) == [i for i in range(1, 41) if i not in (5, 16, 27, 38)]
    assert stored.reached.all() and set(stored.termination) == {"f_max", "f_min", "energy_balance"}


def test_jobs_2_and_a_dask_cluster_write_the_same_file(serial, table, tmp_path, capsys):
    """Two local worker processes (through the CLI) and a Dask LocalCluster of two worker processes: the same bytes
    in every dataset and attribute as this process, the same failures."""
    distributed = pytest.importorskip("distributed")
    outcome, path = serial
    code = main(["evolve", "--batch", str(table), "--population", "--jobs", "2", "-o", str(tmp_path / "jobs.h5"),
                 "-q"])
    out = capsys.readouterr().out
    assert code == 1 and out.count("FAILED") == 4
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        dask = population.run(table, tmp_path / "dask.h5", scheduler=cluster.scheduler_address, chunk=CHUNK)
    assert contents(tmp_path / "jobs.h5") == contents(path) == contents(tmp_path / "dask.h5")
    assert _failures(dask) == _failures(outcome)


KILLED = """
import sys, time
from pnrotor.batch import population
real, done = population._evolve, []
def evolve(shared, params):   # the fourth chunk hangs (its group of pn_order 3 comes after the first group)
    if len(done) == 6:
        print("three chunks done", flush=True)
        time.sleep(120)
    done.append(1)
    return real(shared, params)
population._evolve = evolve
population.run(sys.argv[1], sys.argv[2], chunk=int(sys.argv[3]))
"""


def test_killed_with_sigkill_then_resumed_equals_uninterrupted(serial, table, tmp_path, monkeypatch):
    """kill -9 in the fourth chunk: the three finished chunks stay in OUT.parts, and resume computes the four others
    only (counted), giving the uninterrupted run's file and failures."""
    out = tmp_path / "out.h5"
    kill_9_after(KILLED, table, out, CHUNK, line="three chunks done")
    parts = tmp_path / "out.h5.parts"
    assert not out.exists() and sorted(p.name for p in parts.glob("chunk-*.json")) == [f"chunk-{k}.json"
                                                                                        for k in range(3)]
    real, computed = population.compute_chunk, []
    monkeypatch.setattr(population, "compute_chunk", lambda chunk, defaults: computed.append(chunk[0][0]) or
                        real(chunk, defaults))
    resumed = population.run(table, out, chunk=CHUNK, resume=True)
    assert computed == [3, 4, 5, 6] and not parts.exists()
    assert contents(out) == contents(serial[1]) and _failures(resumed) == _failures(serial[0])


@pytest.mark.parametrize("change, options", [("table", {}), ("chunk", {"chunk": 5}), ("defaults", {"defaults":
                                                                                                  {"atol": 1e-10}})])
def test_resume_refuses_another_table_or_options(table, tmp_path, monkeypatch, change, options):
    def interrupt_second(shared, params, seen=[]):
        seen.append(1)
        if len(seen) == 3:
            raise KeyboardInterrupt
        return real(shared, params)

    real = population._evolve
    monkeypatch.setattr(population, "_evolve", interrupt_second)
    with pytest.raises(KeyboardInterrupt, match=r"^1 finished chunk kept in .*out.h5.parts; complete the population "
                                                r"with --resume \(resume=True\)$"):
        population.run(table, tmp_path / "out.h5", chunk=CHUNK)
    monkeypatch.setattr(population, "_evolve", real)
    if change == "table":
        table.write_text(table.read_text().replace("b39,", "b39x,"))
    with pytest.raises(ValueError, match="holds chunks of another table, or of other options"):
        population.run(table, tmp_path / "out.h5", resume=True, **{"chunk": CHUNK, **options})
    with pytest.raises(FileExistsError, match="holds the finished chunks of an interrupted batch: pass --resume"):
        population.run(table, tmp_path / "out.h5", chunk=CHUNK)


def _die(marker, chunk):
    """An _evolve that kills its worker process in the rows of table row ``chunk`` * CHUNK + 1 (the first time only
    if ``marker`` is a path)."""
    real = population._evolve

    def evolve(shared, params):
        if any(p["m2"] == _M2[chunk] for p in params) and not (marker and marker.exists()):
            if marker:
                marker.touch()
            os.kill(os.getpid(), signal.SIGKILL)
        return real(shared, params)

    return evolve


_M2 = {}


def test_a_worker_killed_in_a_chunk_loses_no_row(serial, table, tmp_path, monkeypatch):
    """A worker killed (as the out-of-memory killer would) in the middle of chunk 2: the chunks lost with its pool
    go to a new pool, and the file is the uninterrupted one."""
    _M2[2] = float(table.read_text().splitlines()[1 + 2 * CHUNK].split(",")[2])
    monkeypatch.setattr(population, "_evolve", _die(tmp_path / "killed", 2))
    monkeypatch.setattr(backends, "start_method", lambda: "fork")   # the workers see the patch
    outcome = population.run(table, tmp_path / "out.h5", jobs=2, chunk=CHUNK)
    assert (tmp_path / "killed").exists()
    assert contents(tmp_path / "out.h5") == contents(serial[1]) and _failures(outcome) == _failures(serial[0])


def test_a_chunk_that_kills_its_worker_every_time_fails_its_rows_with_the_reason(serial, table, tmp_path,
                                                                                  monkeypatch):
    _M2[1] = float(table.read_text().splitlines()[1 + CHUNK].split(",")[2])
    monkeypatch.setattr(population, "_evolve", _die(None, 1))
    monkeypatch.setattr(backends, "start_method", lambda: "fork")
    outcome = population.run(table, tmp_path / "out.h5", jobs=2, chunk=CHUNK)
    lost = [row for row in outcome.failed if "worker process died" in row.error]
    assert [(row.number, row.name) for row in lost] == [(i, f"b{i - 1}") for i in range(CHUNK + 1, 2 * CHUNK + 1)]
    assert lost[0].error == "its worker process died running it (killed, or out of memory?)"
    assert [row.number for row in outcome.failed if row not in lost] == [5, 16, 27, 38]
    kept = hdf5.read(tmp_path / "out.h5")
    assert not set(kept.inputs["row"]) & set(range(CHUNK + 1, 2 * CHUNK + 1)) and outcome.written == 36 - CHUNK


def test_parquet_and_hdf5_tables_give_the_csv_tables_file(serial, table, tmp_path):
    """The same rows as Parquet (vectors as lists, empty cells null) and as HDF5 (vectors (N, 3), empty cells NaN or
    empty text)."""
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    frame = pd.read_csv(table, dtype={"name": str})
    for name in ("chi1", "chi2"):
        frame[name] = [[float(x) for x in cell.split(",")] for cell in frame[name]]
    frame.to_parquet(tmp_path / "t.parquet")
    with h5py.File(tmp_path / "t.h5", "w") as f:
        for name in frame.columns:
            f[name] = np.array(frame[name].tolist()) if name != "name" else frame[name].to_numpy().astype("S")
    for path in ("t.parquet", "t.h5"):
        outcome = population.run(tmp_path / path, tmp_path / f"{path}.out.h5", chunk=CHUNK)
        assert contents(tmp_path / f"{path}.out.h5") == contents(serial[1]), path
        assert [(n, name) for n, name, _ in _failures(outcome)] == [(n, name) for n, name, _ in _failures(serial[0])]


def test_table_faults_are_value_errors_before_anything_runs(tmp_path):
    (tmp_path / "t.h5").write_bytes(b"not hdf5")
    with pytest.raises(ValueError, match="t.h5 is not an HDF5 file HDF5 can open"):
        population.run(tmp_path / "t.h5", tmp_path / "out.h5")
    with h5py.File(tmp_path / "u.h5", "w") as f:
        f["m1"], f["m2"], f["chi1"], f["chi2"], f["f_ref"] = [1.0], [1.0, 2.0], np.zeros((1, 3)), np.zeros((1, 3)), [9.0]
    with pytest.raises(ValueError, match=r"columns must be datasets of one length N, \(N,\) or \(N, 3\); got chi1"):
        population.run(tmp_path / "u.h5", tmp_path / "out.h5")
    (tmp_path / "t.parquet").write_text("m1\n")
    with pytest.raises(ValueError, match="t.parquet is not a Parquet file"):
        population.run(tmp_path / "t.parquet", tmp_path / "out.h5")
    (tmp_path / "t.csv").write_text('m1,m2,chi1,chi2,f_ref\n30,10,"0,0,0","0,0,0",20\n30,10,"0,0,0"\n')
    with pytest.raises(ValueError, match="line 3: 3 fields for 5 columns"):
        population.run(tmp_path / "t.csv", tmp_path / "out.h5")
    assert sorted(os.listdir(tmp_path)) == ["t.csv", "t.h5", "t.parquet", "u.h5"]


def test_to_pandas_and_derived_columns(serial):
    pytest.importorskip("pandas")
    stored = hdf5.read(serial[1])
    frame = stored.to_pandas()
    assert len(frame) == 36 and frame["name"].tolist() == list(stored.name)
    assert frame["row"].tolist() == stored.inputs["row"].tolist() and frame.attrs["rtol"] == 0.0
    for name in ("theta1", "theta2", "phi12", "chi_eff", "chi_p"):
        np.testing.assert_array_equal(frame[name], getattr(stored, name))
    np.testing.assert_array_equal(frame["chi1_ref_x"], stored.inputs["chi1"][:, 0])
    np.testing.assert_array_equal(frame["stopped_ell_hat_z"], stored.stopped_at["ell_hat"][:, 2])


def test_progress_bar_of_rows(table, tmp_path, capsys):
    population.run(table, tmp_path / "a.h5", chunk=CHUNK, progress=True)
    err = capsys.readouterr().err
    assert "40/40" in err and "row/s" in err
    population.run(table, tmp_path / "b.h5", chunk=CHUNK)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("jobs", [1, 2])
def test_the_table_is_read_as_chunks_finish(table, tmp_path, monkeypatch, jobs):
    """The table is never read whole: when a chunk is stored, the rows read from the table and not yet stored are at
    most those of the chunks in flight (one in this process; two per worker with --jobs) and of the next one.  (The
    memory of a 10⁶-row population is measured in benchmarks/bench_population.py.)"""
    read, stored, ahead = [0], [0], []
    records, store = population.TableFile.records, population.Plan._store

    def counted(self):
        for record in records(self):
            read[0] += 1
            yield record

    def measured(self, index, chunk):
        ahead.append(read[0] - stored[0])
        stored[0] += chunk.rows
        return store(self, index, chunk)

    monkeypatch.setattr(population.TableFile, "records", counted)
    monkeypatch.setattr(population.Plan, "_store", measured)
    outcome = population.run(table, tmp_path / "out.h5", chunk=2, jobs=jobs)
    assert outcome.written == 36 and len(ahead) == 20 and read[0] == 40
    assert max(ahead) <= (2 * jobs if jobs > 1 else 1) * 2 + 2, ahead


def test_concatenate_refuses_a_source_that_differs_in_more_than_its_rows(serial, tmp_path):
    """hdf5.concatenate takes the first source's other fields: a source whose shared options differ, or whose
    columns have another dtype, is refused, not mixed in."""
    table = hdf5.read(serial[1])
    hdf5.concatenate(tmp_path / "twice.h5", [serial[1], serial[1]])
    twice = hdf5.read(tmp_path / "twice.h5")
    assert len(twice) == 72 and list(twice.name) == list(table.name) * 2
    np.testing.assert_array_equal(twice.stopped_at["R"][36:], table.stopped_at["R"])
    other = tmp_path / "other.h5"
    hdf5.write(other, population.PopulationTable(**{**table.__dict__, "inputs": {**table.inputs, "rtol": 1e-9}}))
    with pytest.raises(ValueError, match=r"other.h5 differs from .*serial.h5 in more than its arrays of samples"):
        hdf5.concatenate(tmp_path / "mixed.h5", [serial[1], other])
    with h5py.File(other, "r+") as f:
        f["inputs"].attrs["rtol"] = 0.0
        del f["nfev"]
        f["nfev"] = np.zeros(36)
    with pytest.raises(ValueError, match=r"other.h5: dataset 'nfev' is float64 \(36,\), not int64 of 36 samples"):
        hdf5.concatenate(tmp_path / "mixed.h5", [serial[1], other])
    assert not (tmp_path / "mixed.h5").exists()
