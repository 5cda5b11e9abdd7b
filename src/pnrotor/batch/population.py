"""Population mode of a batch: the state of every row of a table at its target, from `pnrotor.evolve_many`, in one
file, for tables of any length, on this machine or a Dask cluster.

``pnrotor evolve --batch F --population [--jobs N | --scheduler ADDRESS] [--resume]``
(``pnrotor.batch.population.run(F, OUT.h5, jobs=…, scheduler=…, chunk=…, resume=…)`` from Python).  This module owns
that mode and :class:`PopulationTable`, the dataclass of its file (``kind`` = ``"PopulationTable"`` in
`pnrotor.hdf5`; layout in docs/hdf5-schema.md):

* the table (CSV, TOML, Parquet or HDF5: `pnrotor.batch.table.TableFile`) is read in chunks of :data:`CHUNK` rows,
  never whole; its structure is checked and its rows counted first.  Each chunk is one task (:func:`compute_chunk`):
  its rows checked as a batch checks them (a bad value marks its row only; an empty sampling cell means final), and
  marked where this mode cannot compute them (:func:`unsupported`: a sampling other than final, f_min and f_max
  together, or masses and frequencies that `pnrotor.evolve` refuses, with its message); then one `evolve_many`
  call per group of rows sharing the options it takes as shared (:data:`SHARED`), each row to its own target: f_max
  forward, else f_min backward, else the end of the inspiral.  A row evolve_many marks ``'invalid'`` fails with its
  message; a group whose shared options it refuses (a pn_order of 5, say) fails whole, each row with that message;
* the chunks run in this process (on pnrotor's threads), on ``jobs`` local worker processes (each with its share of
  the cores' threads) or as tasks of a Dask cluster (one thread each), at most two per worker in flight, through
  `pnrotor.batch.backends`.  A worker lost in the middle of a chunk (killed, out of memory) has its chunk computed
  again (a new pool; Dask's rescheduling), and where that fails too, the chunk's rows fail with the reason;
* each finished chunk is on disk at once, in the folder ``OUTPUT.parts`` as for batches (`pnrotor.batch`): its
  states as a :class:`PopulationTable` file ``chunk-K.h5`` (encoded by the worker, `pnrotor.hdf5.image`) and then
  ``chunk-K.json`` (its failed rows; the mark of a finished chunk), both written atomically and fsynced.  A kill loses the chunks in flight only; ``resume=True``
  (``--resume``) computes the chunks missing, after checking that the table's bytes and the options are those that
  made the others;
* at the end the chunks are copied, one at a time, into one :class:`PopulationTable` file, the rows that succeeded
  in the table's order (`pnrotor.hdf5.concatenate`: atomic, checksummed), and the folder is removed.

Each state is bitwise what `pnrotor.evolve` gives for that row (``sampling='final'``; with f_min, its first sample),
whatever the backend, chunk size and number of threads; where the row's target was not reached, the state is NaN
and the state where it stopped is in ``stopped_at`` (`pnrotor.Population`).  The outcome is a
`pnrotor.batch.Outcome` whose ``rows`` are the rows that failed (the table may not fit in memory).
"""

import functools
import json
import math
import os
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from pnrotor.batch import TABLE, InterruptFlag, Outcome, backends, check_output, progress_bar
from pnrotor.batch import Plan as _BatchPlan
from pnrotor.batch.table import Row, TableFile, parse_row
from pnrotor.options import TABLE_OPTIONS
from pnrotor.results.populations import FIELDS, STATE, PopulationTable

__all__ = ["PopulationTable", "Plan", "plan", "run", "unsupported", "compute_chunk", "SHARED", "CHUNK"]

CHUNK = 10_000
"""Rows per chunk: one task, one `evolve_many` call per group of options, one part file."""

SHARED = TABLE_OPTIONS
"""The table's columns that `evolve_many` takes as shared by all its binaries: one call per combination."""

def unsupported(params):
    """Why this mode cannot compute a row of `pnrotor.evolve` keywords (a message naming the column), or None."""
    sampling = params["sampling"]
    if sampling != "final":
        text = (f"per_orbit:{sampling[1]}" if isinstance(sampling, tuple) else
                f"a time step of {sampling!r} s" if isinstance(sampling, float) else sampling)
        return f"sampling must be final (or empty) in the population mode, which gives final states only; got {text}"
    if params["f_min"] is not None and params["f_max"] is not None:
        return ("f_min and f_max are both given: the population mode gives one state per row, at f_max (forward), "
                "at f_min (backward) or at the end of the inspiral; give at most one of them")
    # evolve_many checks the rest as evolve does, with its messages, but takes its target on either side of f_ref
    # (and NaN as the end of the inspiral), while a row's f_max must lie above f_ref and its f_min below, both
    # finite: such a row gets evolve's checks of the masses, spins and frequencies here, in its order (so a row with
    # two faults gets evolve's message)
    f_min, f_max, f_ref = params["f_min"], params["f_max"], params["f_ref"]
    if (f_min is None or math.isfinite(f_min) and f_min < f_ref) and (f_max is None or math.isfinite(f_max) and
                                                                       f_max > f_ref):
        return None
    from pnrotor.pn import initial, settings

    try:
        given = settings.masses_and_frequencies(*(params[key] for key in ("m1", "m2", "f_ref", "f_min", "f_max")))
        for name in ("chi1", "chi2"):
            initial.spin_vector(params[name], name)
        settings.frequencies(*given)
    except ValueError as error:
        return str(error)
    return None


class Chunk(NamedTuple):
    """What a chunk's task returns: its rows that succeeded as the bytes of a :class:`PopulationTable` file
    (`pnrotor.hdf5.image`, encoded by the worker; None: no row) and their number, its rows that failed
    (`pnrotor.batch.table.Row` with ``error``), the seconds of its `evolve_many` calls, its rows."""

    image: bytes
    written: int
    failed: list
    seconds: float
    rows: int


def compute_chunk(chunk, defaults):
    """The work of one chunk task (`pnrotor.batch.backends`): ``chunk`` = [(K, records)], records the (number, label,
    record) of its rows (`pnrotor.batch.table.TableFile.records`), ``defaults`` the values of empty cells →
    [(K, True, :class:`Chunk`)]."""
    [(index, records)] = chunk
    rows = [parse_row(number, label, record, defaults) for number, label, record in records]
    groups = {}
    for i, row in enumerate(rows):
        if row.error is None:
            row.error = unsupported(row.params)
        if row.error is None:
            groups.setdefault(_shared(row.params), []).append(i)
    parts, seconds = [], 0.0
    for shared, indices in groups.items():
        began = time.perf_counter()
        result = _evolve(shared, [rows[i].params for i in indices])
        seconds += time.perf_counter() - began
        if isinstance(result, str):   # the group's shared options were refused
            for i in indices:
                rows[i].error = result
            continue
        for i, termination, message in zip(indices, result.termination, result.message):
            if termination == "invalid":
                rows[i].error = message
        parts.append((np.array(indices), result))
    from pnrotor import hdf5

    table = _table(rows, parts)
    image = None if table is None else hdf5.image(table)
    return [(index, True, Chunk(image, 0 if table is None else len(table), [row for row in rows if row.error is not None],
                                seconds, len(rows)))]


def _evolve(shared, params):
    """`evolve_many` on one group's rows → its `Population`, or the message of its ValueError."""
    from pnrotor.pn.many import evolve_many

    column = lambda key: np.array([p[key] for p in params], dtype=np.float64)  # noqa: E731
    f_end = [p["f_max"] if p["f_max"] is not None else p["f_min"] for p in params]
    try:
        return evolve_many(column("m1"), column("m2"), column("chi1"), column("chi2"), column("f_ref"),
                           f_end=np.array([math.nan if f is None else f for f in f_end]), lambda1=column("lambda1"),
                           lambda2=column("lambda2"), **dict(zip(SHARED, shared)))
    except ValueError as error:
        return str(error)


def _table(rows, parts):
    """The :class:`PopulationTable` of the rows that succeeded, in the table's order, or None."""
    from pnrotor.pn.many import PER_BINARY

    if not parts:
        return None
    indices = np.concatenate([indices for indices, _ in parts])
    ok = np.concatenate([population.termination != "invalid" for _, population in parts])
    order = np.argsort(indices[ok])
    if not order.size:
        return None
    rows = [rows[i] for i in indices[ok][order]]
    pick = lambda arrays: np.concatenate(arrays)[ok][order]  # noqa: E731
    columns = {name: pick([getattr(population, name) for _, population in parts]) for name in FIELDS}
    stopped_at = {name: pick([population.stopped_at[name] for _, population in parts]) for name in STATE}
    nan = lambda x: math.nan if x is None else x  # noqa: E731
    per_row = {
        "row": np.array([row.number for row in rows], dtype=np.int64),
        "m1_Msun": _floats(rows, "m1"), "m2_Msun": _floats(rows, "m2"),
        "chi1": _floats(rows, "chi1"), "chi2": _floats(rows, "chi2"), "f_ref_Hz": _floats(rows, "f_ref"),
        "f_min_Hz": _floats(rows, "f_min", nan), "f_max_Hz": _floats(rows, "f_max", nan),
        "approximant": _strings(_shared(row.params)[0] for row in rows),
        "pn_order": _floats(rows, "pn_order"),
        "spin_orbit_order": _floats(rows, "spin_orbit_order", nan),
        "spin_spin_order": _floats(rows, "spin_spin_order", nan),
        "precession": _strings(row.params["precession"] for row in rows), "atol": _floats(rows, "atol"),
        "lambda1": _floats(rows, "lambda1"), "lambda2": _floats(rows, "lambda2"),
        "tidal_order": _floats(rows, "tidal_order", nan),
        "horizon_absorption": np.array([row.params["horizon_absorption"] for row in rows], dtype=bool),
    }
    common = {key: value for key, value in parts[0][1].inputs.items() if key not in SHARED + PER_BINARY}
    return PopulationTable(name=_strings(row.name for row in rows), **columns, stopped_at=stopped_at,
                           inputs={**per_row, **common, "sampling": "final"})


def _shared(params):
    """A row's values of :data:`SHARED`, the approximant by its canonical name (so T4 and TaylorT4 share a call)."""
    from pnrotor.approximants import normalize_approximant

    return (normalize_approximant(params["approximant"]),) + tuple(params[key] for key in SHARED[1:])


def _floats(rows, key, convert=lambda x: x):
    return np.array([convert(row.params[key]) for row in rows], dtype=np.float64)


def _strings(values):
    values = list(values)
    strings = np.empty(len(values), dtype=object)
    strings[:] = values
    return strings


@dataclass(eq=False)
class Plan(_BatchPlan):
    """A checked population, not yet computed: its table, the output file, the backend (``where``) and its storage.
    Its ``rows`` collect the rows that failed, as the run finds them (module docstring)."""

    table: TableFile = None
    chunk: int = CHUNK
    defaults: dict = field(default_factory=dict)

    _PARTS = "chunk-*.json"
    _KEPT = "chunks", "chunk size, defaults of empty cells, compression, checksum"

    @property
    def tasks(self):
        """The chunks' numbers, from 0."""
        return range(-(-self.table.rows // self.chunk))

    def _run(self, start, progress):
        from pnrotor import hdf5

        done = self._stored() if self.resume else {}
        remaining = self.table.rows - sum(done.values())
        pending = {}   # the records of the chunks in flight, to name their rows if the task fails
        work = functools.partial(compute_chunk, defaults=self.defaults)

        def tasks():
            for index, records in self._chunks(done):
                pending[index] = records
                yield index, records

        jobs = min(self.jobs, len(self.tasks) - len(done))
        if self.scheduler is not None:
            results = backends.results_dask(tasks(), self.scheduler, work, window=lambda threads: 2 * threads)
        (self.parts / TABLE).write_text(self._fingerprint())
        if self.scheduler is None and jobs <= 1:
            results = (result for task in tasks() for result in work([task]))
        elif self.scheduler is None:
            results = backends.pool_results(work, ([task] for task in tasks()), jobs, window=2 * jobs,
                                            thread_count=max(1, (os.cpu_count() or 1) // jobs))
        evolve_seconds = 0.0
        interrupted = InterruptFlag()
        try:
            with interrupted.deferred(), progress_bar(remaining, enabled=progress, unit="row") as bar:
                for index, ok, result in interrupted.interruptible(results):
                    records = pending.pop(index)
                    if not ok:   # a worker lost (twice for a pool): every row of the chunk fails with the reason
                        failed = [parse_row(*record, self.defaults) for record in records]
                        for row in failed:
                            row.error = result
                        result = Chunk(None, 0, failed, 0.0, len(records))
                    self._store(index, result)
                    done[index] = result.rows
                    evolve_seconds += result.seconds
                    bar.update(result.rows)
        except KeyboardInterrupt:
            raise self._interrupted() from None
        finally:
            results.close()  # stops the workers early after an error or Ctrl-C
            interrupted.restore()
        written, tables = 0, []
        for index in sorted(done):
            marker = json.loads(self._part(index, ".json").read_text())
            self.rows.extend(_failed(*failure) for failure in marker["failed"])
            if marker["written"]:
                tables.append(self._part(index, ".h5"))
                written += marker["written"]
        try:
            if tables:
                hdf5.concatenate(self.path, tables, overwrite=self.overwrite, **self.storage)
        except KeyboardInterrupt:
            raise self._interrupted() from None
        return Outcome(self.rows, {}, self.path if written else None, written, time.perf_counter() - start,
                       evolve_seconds)

    def _interrupted(self):
        """The KeyboardInterrupt that says what an interrupted population keeps."""
        kept = len(list(self.parts.glob(self._PARTS)))   # what is on disk, not only what was reported yet
        if not kept:   # (and the folder goes)
            return KeyboardInterrupt("no chunk had finished; nothing kept")
        return KeyboardInterrupt(f"{kept} finished chunk{'s' * (kept != 1)} kept in {self.parts}; complete the "
                                 "population with --resume (resume=True)")

    def _chunks(self, done):
        """(K, records) of each chunk K of the table not in ``done``, read as they are taken."""
        index, records = 0, []
        for record in self.table.records():
            records.append(record)
            if len(records) == self.chunk:
                if index not in done:
                    yield index, records
                index, records = index + 1, []
        if records and index not in done:
            yield index, records

    def _part(self, index, suffix):
        return self.parts / f"chunk-{index}{suffix}"

    def _store(self, index, chunk):
        """Chunk ``index`` on disk: its table (if a row succeeded), then its mark (failures and count), each written
        under a temporary name, fsynced and renamed."""
        marker = {"rows": chunk.rows, "written": chunk.written,
                  "failed": [[row.number, row.label, row.name, row.error] for row in chunk.failed]}
        for suffix, data in ((".h5", chunk.image), (".json", json.dumps(marker).encode())):
            if data is not None:
                temporary = self._part(index, suffix + ".tmp")
                with open(temporary, "wb") as f:
                    f.write(data)
                    f.flush()
                    os.fsync(f.fileno())
                os.replace(temporary, self._part(index, suffix))

    def _fingerprint(self):
        """What identifies the chunks a population stores: the table's bytes, the chunk size, the defaults of empty
        cells, the storage options."""
        import hashlib

        text = (f"table {self.table.digest}\nchunk {self.chunk}\ndefaults {sorted(self.defaults.items())!r}\n"
                f"storage {sorted(self.storage.items())!r}")
        return hashlib.sha256(text.encode()).hexdigest() + "\n"

    def _stored(self):
        """{chunk: its rows} of the chunks already in :attr:`parts`, after checking they are this table's; a chunk
        whose files are damaged (or cut short by a crash) is computed again."""
        from pnrotor import hdf5

        if not self._kept():
            return {}
        done = {}
        for marker in self.parts.glob(self._PARTS):
            index = marker.name[len("chunk-"):-len(".json")]
            try:
                stored = json.loads(marker.read_text())
                if stored["written"] and len(hdf5.read(self._part(int(index), ".h5"))) != stored["written"]:
                    continue
            except (OSError, ValueError, KeyError, TypeError):
                continue
            done[int(index)] = stored["rows"]
        return done


def _failed(number, label, name, error):
    """A row that failed, from what a chunk's mark keeps of it."""
    row = Row(number, label)
    row.name, row.error = name, error
    return row


def plan(table, output, *, jobs=None, scheduler=None, chunk=CHUNK, resume=False, overwrite=False, compression=None,
         checksum=True, defaults=None, create_folder=False):
    """Check a population before it is computed → :class:`Plan`.

    ``table``: a CSV, TOML, Parquet or HDF5 batch table (`pnrotor.batch.table.TableFile`: its columns checked and its
    rows counted now; ``defaults`` fill its empty cells, then ``sampling='final'``, then the table's defaults).
    ``jobs`` local worker processes (default 1: this process, on all of pnrotor's threads) or a Dask ``scheduler``
    (an address, or a `distributed.Client`); ``chunk`` rows per task; ``resume`` completes an interrupted population
    from the chunks kept in ``OUTPUT.parts`` (module docstring), which without it is an error.  ``output``: the file
    to write, refused if it exists unless ``overwrite``; its folder must exist, or is created (not its parents) with
    ``create_folder``.  ``compression`` and ``checksum`` as in `pnrotor.hdf5.write`."""
    if jobs is not None and scheduler is not None:
        raise ValueError("jobs applies to local runs; a Dask cluster (scheduler) sets its own parallelism")
    jobs = 1 if jobs is None else jobs
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be an integer of at least 1, got {jobs!r}")
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise ValueError(f"chunk must be an integer of at least 1 (rows per task), got {chunk!r}")
    given = {key: value for key, value in (defaults or {}).items() if value is not None}
    source = TableFile(table)
    path = check_output(output, overwrite)
    return Plan([], path, jobs, scheduler, overwrite, dict(compression=compression, checksum=checksum), create_folder,
                bool(resume), table=source, chunk=chunk, defaults={"sampling": "final", **given}).check_parts()


def run(table, output, *, progress=False, **options):
    """:func:`plan` then :meth:`Plan.run`: the whole population → `pnrotor.batch.Outcome` (``progress``: a tqdm bar of
    the rows on stderr)."""
    return plan(table, output, **options).run(progress=progress)
