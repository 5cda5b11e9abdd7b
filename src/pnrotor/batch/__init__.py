"""Many binaries: read a table, run it on a backend, write one HDF5 batch file.

``pnrotor.batch.run(table, output, jobs=…, scheduler=…)`` (or, to see the rows and the backend before the
runs start, ``plan(…)`` then ``Plan.run()``) is what ``pnrotor evolve --batch`` calls:

* :mod:`~pnrotor.batch.table` — the CSV/TOML file → rows of `pnrotor.evolve` keywords, checked first;
* :mod:`~pnrotor.batch.backends` — serial, local worker processes or a Dask cluster;
* here — the writer: this process alone writes the batch file with `pnrotor.hdf5.batch`, each result as it
  arrives (local workers write part files whose groups it copies), under a temporary name renamed to
  ``output`` only when the batch is complete, so an interrupt never leaves a partial file.  Ctrl-C is
  deferred while HDF5 writes (see :class:`_InterruptFlag`) and stops the workers.

A row that fails keeps its message in :attr:`~pnrotor.batch.table.Row.error`; the others are written.
"""

import contextlib
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from pnrotor.batch import backends
from pnrotor.batch.table import COLUMNS, DEFAULTS, REQUIRED, Row, default_name, read_batch

__all__ = ["plan", "run", "Plan", "Outcome", "Row", "read_batch", "default_name", "COLUMNS", "DEFAULTS", "REQUIRED"]


@dataclass(eq=False)
class Outcome:
    """What a batch did: its rows (failures in ``row.error``), the brief of each written run by row index,
    the file (None if no run succeeded), and times."""

    rows: list
    briefs: dict
    path: Path
    written: int
    wall_time_s: float
    evolve_seconds: float

    @property
    def failed(self):
        return [row for row in self.rows if row.error is not None]


@dataclass(eq=False)
class Plan:
    """A checked batch, not yet run: its rows, their tasks, the output file and the backend (``where``)."""

    rows: list
    path: Path
    jobs: int
    scheduler: str = None
    overwrite: bool = False
    storage: dict = field(default_factory=dict)
    create_folder: bool = False

    @property
    def tasks(self):
        return [(i, row.params) for i, row in enumerate(self.rows) if row.error is None]

    @property
    def where(self):
        if self.scheduler is not None:
            return f"Dask scheduler {self.scheduler}"
        if self.jobs == 1 or len(self.tasks) <= 1:
            return "this process"
        return f"{min(self.jobs, len(self.tasks))} worker processes"

    def run(self, progress=False):
        """Compute the rows and write the batch file (module docstring) → :class:`Outcome`; ``progress``
        shows a tqdm bar on stderr."""
        start = time.perf_counter()
        tasks, parts = self.tasks, None
        if self.scheduler is not None:
            results = backends.results_dask(tasks, self.scheduler)
        elif self.jobs == 1 or len(tasks) <= 1:
            results = backends.results_serial(tasks)
        else:
            self._make_folder()
            parts = tempfile.mkdtemp(prefix=f"{self.path.name}.", suffix=".pnrotor-tmp", dir=self.path.parent)
            results = backends.results_pool(tasks, self.jobs, parts=parts, storage=self.storage)
        briefs, evolve_seconds = {}, 0.0
        interrupted = _InterruptFlag()
        try:
            # without a run to write no file is needed: an empty list stands in for the batch
            batch = contextlib.nullcontext([])
            if tasks:
                from pnrotor import hdf5

                self._make_folder()
                batch = hdf5.batch(self.path, overwrite=self.overwrite, **self.storage)
            with interrupted.deferred(), batch as writer, _progress_bar(len(tasks), enabled=progress) as bar:
                for index, ok, result in interrupted.interruptible(results):
                    row = self.rows[index]
                    if ok:
                        if isinstance(result, backends.Stored):
                            writer.copy_from(result.path, result.group, row.name)
                            result = result.brief
                        else:
                            writer.add(row.name, result)
                            result = backends.brief(result)
                        evolve_seconds += result["wall_time_s"]
                        briefs[index] = result
                    else:
                        row.error = result
                    bar.update()
        finally:
            results.close()  # stops the workers early after an error or Ctrl-C
            if parts is not None:
                shutil.rmtree(parts, ignore_errors=True)
            interrupted.restore()
        written = len(writer)
        return Outcome(self.rows, briefs, self.path if written else None, written, time.perf_counter() - start,
                       evolve_seconds)

    def _make_folder(self):
        if self.create_folder and self.tasks:
            self.path.parent.mkdir(exist_ok=True)


def plan(table, output, *, jobs=None, scheduler=None, overwrite=False, compression=None, checksum=False,
         defaults=None, create_folder=False):
    """Check a batch before it runs → :class:`Plan`.

    ``table``: a CSV or TOML batch file (read with :func:`~pnrotor.batch.table.read_batch`; ``defaults``
    fill its empty cells before :data:`DEFAULTS`) or rows already read.  ``output``: the batch file to write,
    refused if it exists unless ``overwrite``; its folder must exist when the batch runs, or is created then
    (not its parents) with ``create_folder`` if there is a run to write.  ``jobs`` local worker processes
    (default: every core; 1 runs in this process) or a Dask ``scheduler`` address; ``compression`` and
    ``checksum`` as in `pnrotor.hdf5.batch`."""
    if jobs is not None and scheduler is not None:
        raise ValueError("jobs applies to local runs; a Dask cluster (scheduler) sets its own parallelism")
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    rows = table if isinstance(table, list) else read_batch(table, defaults or {})
    path = Path(output)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder; give a file name for the batch")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    return Plan(rows, path, jobs, scheduler, overwrite, dict(compression=compression, checksum=checksum),
                create_folder)


def run(table, output, *, progress=False, **options):
    """:func:`plan` then :meth:`Plan.run`: the whole batch → :class:`Outcome`."""
    return plan(table, output, **options).run(progress=progress)


class _InterruptFlag:
    """Ctrl-C is remembered and raised as KeyboardInterrupt at once, or by `check` after a `deferred` block
    (inside one, also when `interruptible` waits for its next item).

    Python drops (prints as "Exception ignored") a KeyboardInterrupt raised inside a weakref callback or
    ``__del__``, which h5py runs while the batch is written; raised there, Ctrl-C would be lost and the
    interrupted batch would run on to the end. So while writing the handler only records it."""

    def __init__(self):
        import signal

        self.seen, self.defer, self.previous = False, False, None
        try:
            self.previous = signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread: no handler of ours
            pass

    def _handle(self, signum, frame):
        self.seen = True
        if not self.defer:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def deferred(self):
        self.defer = True
        try:
            yield
        finally:
            self.defer = False
        self.check()

    def interruptible(self, iterator):
        """Yield the items of `iterator`; Ctrl-C is raised at once while the next one is computed or awaited."""
        while True:
            defer, self.defer = self.defer, False
            try:
                self.check()
                item = next(iterator)
            except StopIteration:
                return
            finally:
                self.defer = defer
            yield item

    def check(self):
        if self.seen:
            raise KeyboardInterrupt

    def restore(self):
        if self.previous is not None:
            import signal

            signal.signal(signal.SIGINT, self.previous)
            self.previous = None


def _progress_bar(total, enabled):
    """A tqdm bar on stderr, without tqdm's monitor thread (a thread would make later worker pools avoid
    'fork'), or a stand-in that does nothing."""
    if not enabled:
        return contextlib.nullcontext(type("NoBar", (), {"update": lambda self, n=1: None})())
    from tqdm import tqdm

    class Bar(tqdm):
        monitor_interval = 0

    return Bar(total=total, unit="run", file=sys.stderr, desc="evolve")
