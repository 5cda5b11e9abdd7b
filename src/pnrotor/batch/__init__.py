"""Many binaries: read a table, run it on a backend, write one HDF5 batch file.

``pnrotor.batch.run(table, output, jobs=…, scheduler=…)`` (or, to see the rows and the backend before the
runs start, ``plan(…)`` then ``Plan.run()``) is what ``pnrotor evolve --batch`` calls:

* :mod:`~pnrotor.batch.table` — the CSV/TOML file → rows of `pnrotor.evolve` keywords, checked first;
* :mod:`~pnrotor.batch.backends` — serial, local worker processes or a Dask cluster;
* :mod:`~pnrotor.batch.population` — the population mode (``--population``): final states only, by
  `pnrotor.evolve_many`, into one file of columns instead of a group per run;
* here — the writer.  Every finished run is on disk at once, in the batch file being built in the folder
  ``OUTPUT.parts`` beside the output (``runs.h5``): this process adds each run as it arrives from the backend
  (`pnrotor.hdf5.Journaled`), its bytes written once, each addition a commit of `pnrotor.io.journal`, so that
  whatever stops a batch (Ctrl-C, SIGTERM, kill -9, a crash) leaves the file as of its last finished run.  When
  every row is done the file is fsynced and renamed to the output, and the folder removed.  Interrupted, the
  finished runs stay in ``OUTPUT.parts`` and ``resume=True`` (``pnrotor evolve --batch F --resume``) computes only
  the others, after checking that the table is the one that made them (a run that no longer reads back is
  computed again).  Ctrl-C is deferred while HDF5 writes (:class:`InterruptFlag`) and stops the workers.

A row that fails keeps its message in :attr:`~pnrotor.batch.table.Row.error`; the others are written.
"""

import contextlib
import hashlib
import os
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from pnrotor.batch import backends
from pnrotor.batch.table import COLUMNS, DEFAULTS, REQUIRED, Row, default_name, read_batch

__all__ = ["plan", "run", "Plan", "Outcome", "Row", "read_batch", "default_name", "check_output", "COLUMNS", "DEFAULTS",
           "REQUIRED"]


@dataclass(eq=False)
class Outcome:
    """What a batch did: its rows (failures in ``row.error``), the brief of each written run by row index
    (none for a population, `pnrotor.batch.population`), the file (None if no run succeeded), and times."""

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
    resume: bool = False
    modes: tuple = None

    _PARTS = "runs.journal"
    """The files in :attr:`parts` whose presence means finished results are kept there (the journal of the batch
    file being built, which exists once a run has been added)."""
    _KEPT = "runs", "modes, compression, checksum"
    """What the part files hold, and the options besides the table that they depend on (the resume's message)."""

    @property
    def tasks(self):
        extra = {} if self.modes is None else {"modes": self.modes}
        return [(i, {**row.params, **extra}) for i, row in enumerate(self.rows) if row.error is None]

    @property
    def where(self):
        if self.scheduler is not None:
            return f"Dask scheduler {self.scheduler}"
        if self.jobs == 1 or len(self.tasks) <= 1:
            return "this process"
        return f"{min(self.jobs, len(self.tasks))} worker processes"

    @property
    def parts(self):
        """The folder of finished runs, ``OUTPUT.parts``."""
        return self.path.with_name(self.path.name + ".parts")

    def run(self, progress=False):
        """Compute the rows (those not already in :attr:`parts` with ``resume``), then write the batch file
        (module docstring) → :class:`Outcome`; ``progress`` shows a tqdm bar on stderr."""
        start = time.perf_counter()
        with self._claimed():
            outcome = self._run(start, progress)
        if self.parts.exists():   # once its lock file is closed (Windows cannot remove an open file)
            shutil.rmtree(self.parts)
        return outcome

    def _run(self, start, progress):
        store = self._store() if self.tasks else None
        done = self._stored(store) if self.resume else {}
        tasks = [(i, params) for i, params in self.tasks if i not in done]
        evolve_seconds, results = 0.0, None
        interrupted = InterruptFlag()
        try:
            if self.scheduler is not None:
                results = backends.results_dask(tasks, self.scheduler)
            if self.tasks:
                (self.parts / TABLE).write_text(self._fingerprint())
            if self.scheduler is None:
                results = (backends.results_serial(tasks) if self.jobs == 1 or len(tasks) <= 1 else
                           backends.results_pool(tasks, self.jobs))
            with interrupted.deferred(), progress_bar(len(tasks), enabled=progress) as bar:
                for index, ok, result in interrupted.interruptible(results):
                    if ok:
                        ok, result = self._add(store, index, result)
                    if ok:
                        done[index] = result
                        evolve_seconds += result["wall_time_s"]
                    else:
                        self.rows[index].error = result
                    bar.update()
        except KeyboardInterrupt:
            if results is not None:
                results.close()   # the workers stopped
            if not done:   # (and the folder goes)
                raise KeyboardInterrupt("no run had finished; nothing kept") from None
            raise KeyboardInterrupt(f"{len(done)} finished run{'s' * (len(done) != 1)} kept in {self.parts}; "
                                    "complete the batch with --resume (resume=True)") from None
        finally:
            if results is not None:
                results.close()  # stops the workers early after an error
            interrupted.restore()
        if done:
            interrupted = InterruptFlag()
            try:
                with interrupted.deferred():
                    store.publish(self.path, self.overwrite)
            finally:
                interrupted.restore()
        return Outcome(self.rows, done, self.path if done else None, len(done), time.perf_counter() - start,
                       evolve_seconds)

    def _store(self):
        """The batch file being built in :attr:`parts`, each finished run added at once (`pnrotor.hdf5.Journaled`)."""
        from pnrotor import hdf5

        return hdf5.Journaled(self.parts / _RUNS, self.parts / _JOURNAL, **self.storage)

    def _add(self, store, index, result):
        """Row `index`'s finished `result` (an Evolution, or (Evolution, Modes)) added to `store` under the row's
        name → (True, its `backends.brief`), or (False, message) for a run `pnrotor.hdf5` refuses to write (e.g. a
        non-finite sample): that row fails, not the batch."""
        run, *waves = result if isinstance(result, tuple) else (result,)
        name = self.rows[index].name
        try:
            store.add({name: run, **{name + backends.MODES_SUFFIX: wave for wave in waves}})
        except ValueError as error:
            return False, f"its run cannot be written: {error}"
        return True, backends.brief(run)

    def _fingerprint(self):
        """What identifies the runs a batch stores: every row at its position (the part files are named by it;
        a row that failed its checks by its message), the modes asked for and the storage options."""
        text = "\n".join(f"{i}\t{row.name}\t{sorted(row.params.items())!r}" if row.error is None else
                         f"{i}\terror\t{row.error}" for i, row in enumerate(self.rows))
        text += f"\nmodes {self.modes!r}" if self.modes is not None else ""
        text += f"\nstorage {sorted(self.storage.items())!r}"
        return hashlib.sha256(text.encode()).hexdigest() + "\n"

    def check_parts(self):
        """Self, unless :attr:`parts` is held by a running batch, or holds the results of an interrupted one that
        this plan does not resume (an error naming it)."""
        if self.parts.exists() and _locked(self.parts):
            raise _another_batch(self)
        if self.parts.exists() and not self.resume:
            raise FileExistsError(f"{self.parts} holds the finished {self._KEPT[0]} of an interrupted batch: pass "
                                  "--resume (resume=True) to complete it, or remove the folder")
        return self

    def _kept(self):
        """Whether :attr:`parts` holds results of an earlier attempt, after checking that they are this table's (its
        fingerprint, a ValueError otherwise)."""
        table = self.parts / TABLE
        if not table.exists() and not any(self.parts.glob(self._PARTS)):   # nothing kept: a first attempt
            return False
        if not table.exists() or table.read_text() != self._fingerprint():
            raise ValueError(f"{self.parts} holds {self._KEPT[0]} of another table, or of other options "
                             f"({self._KEPT[1]}), or of an older version of them; remove the folder to start the batch "
                             "afresh")
        return True

    def _stored(self, store):
        """{row index: brief} of the runs already in `store`, after checking they are this table's; a run that does
        not read back (damaged), or whose modes do not, is removed from it, to be computed again."""
        from pnrotor import hdf5

        if not self._kept():
            return {}
        rows = {row.name: i for i, row in enumerate(self.rows) if row.error is None}
        done, damaged = {}, []
        for name in store.names():
            if name not in rows:
                continue   # a row's modes
            try:
                run = hdf5.read(store.path, name)
                if self.modes is not None:
                    hdf5.read(store.path, name + backends.MODES_SUFFIX)
            except (OSError, ValueError):
                damaged += [name, name + backends.MODES_SUFFIX]
                continue
            done[rows[name]] = backends.brief(run)
        if damaged:
            store.remove(damaged)
        return done

    @contextlib.contextmanager
    def _claimed(self):
        """:attr:`parts` (made if need be, and the output's folder with ``create_folder``) held under an
        exclusive lock while the batch runs: a second batch writing the same output fails at once (their runs
        would share its part files), and the folders this batch made are removed if it stops before keeping a
        run (a Dask scheduler it cannot use, say)."""
        if not self.tasks:
            yield
            return
        made_folder = self.create_folder and not self.path.parent.exists()
        if made_folder:
            self.path.parent.mkdir()
        made = not self.parts.exists()
        self.parts.mkdir(exist_ok=True)
        try:
            with open(self.parts / _LOCK, "a") as lock:
                if not _flock(lock):
                    made = False
                    raise _another_batch(self)
                yield
        except BaseException:
            if made and self.parts.is_dir() and not any(self.parts.glob(self._PARTS)):
                shutil.rmtree(self.parts)
                if made_folder and not any(self.path.parent.iterdir()):
                    self.path.parent.rmdir()
            raise


TABLE = "table.sha256"
"""In the parts folder: the fingerprint of the table whose runs it holds."""
_RUNS, _JOURNAL = "runs.h5", "runs.journal"
"""In the parts folder: the batch file being built, a run added as each finishes, and its journal
(`pnrotor.io.journal`)."""
_LOCK = "lock"
"""In the parts folder: the file a running batch holds its exclusive lock on (``flock``)."""


def _flock(file):
    """Take the exclusive lock of the open ``file`` without waiting → False if another process holds it (True
    where there is no flock: no lock there)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return True
    try:
        fcntl.flock(file, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


def _another_batch(plan):
    """The error for a batch whose output another running batch writes (it holds the lock of its parts folder)."""
    return FileExistsError(f"another batch is writing {plan.path} (its runs are in {plan.parts}); wait for it to "
                           "finish")


def _locked(parts):
    """Whether a running batch holds the lock of the parts folder ``parts``."""
    if not (parts / _LOCK).exists():
        return False
    with open(parts / _LOCK, "a") as held:
        return not _flock(held)


def plan(table, output, *, jobs=None, scheduler=None, overwrite=False, compression=None, checksum=True,
         defaults=None, create_folder=False, resume=False, modes=None):
    """Check a batch before it runs → :class:`Plan`.

    ``table``: a CSV or TOML batch file (read with :func:`~pnrotor.batch.table.read_batch`; ``defaults``
    fill its empty cells before :data:`DEFAULTS`) or rows already read.  ``output``: the batch file to write,
    refused if it exists unless ``overwrite``; its folder must exist when the batch runs, or is created then
    (not its parents) with ``create_folder`` if there is a run to write.  ``jobs`` local worker processes
    (default: every core; 1 runs in this process) or a Dask ``scheduler`` address; ``compression`` and
    ``checksum`` as in `pnrotor.hdf5.batch`; ``resume`` completes an interrupted batch from the runs kept in
    ``OUTPUT.parts`` (module docstring), which without it is an error.  ``modes`` = (ell_max, amplitude_order,
    distance) (`pnrotor.modes`' arguments, distance None for r h / M) also computes each row's modes and stores
    them beside its run as the group ``NAME.modes``."""
    if jobs is not None and scheduler is not None:
        raise ValueError("jobs applies to local runs; a Dask cluster (scheduler) sets its own parallelism")
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    if jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    rows = table if isinstance(table, list) else read_batch(table, defaults or {})
    path = check_output(output, overwrite)
    wave = None
    if modes is not None:
        from pnrotor.waveform.modes import check_arguments

        wave = check_arguments(*modes)
        clash = [row.name for row in rows if row.name is not None and row.name.endswith(backends.MODES_SUFFIX)]
        if clash:
            raise ValueError(f"with modes, run names may not end in {backends.MODES_SUFFIX!r} (the modes' groups "
                             f"do): {', '.join(clash)}")
    result = Plan(rows, path, jobs, scheduler, overwrite, dict(compression=compression, checksum=checksum),
                  create_folder, bool(resume), wave)
    return result.check_parts()


def check_output(output, overwrite):
    """The batch file `output` as a Path, checked before anything runs: not a folder, new unless `overwrite`."""
    path = Path(output)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder; give a file name for the batch")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    return path


def run(table, output, *, progress=False, **options):
    """:func:`plan` then :meth:`Plan.run`: the whole batch → :class:`Outcome`."""
    return plan(table, output, **options).run(progress=progress)


class InterruptFlag:
    """Ctrl-C is remembered and raised as KeyboardInterrupt at once, or by `check` after a `deferred` block
    (inside one, also when `interruptible` waits for its next item).

    Python drops (prints as "Exception ignored") a KeyboardInterrupt raised inside a weakref callback or
    ``__del__``, which h5py runs while the batch is written; raised there, Ctrl-C would be lost and the
    interrupted batch would run on to the end. So while writing the handler only records it."""

    def __init__(self):
        import signal

        from pnrotor import signals

        self.seen, self.defer = False, False
        self.previous = signals.take(self._handle, [signal.SIGINT])   # none where SIGINT is ignored (`cmd &`)

    def _handle(self, signum, frame):
        first, self.seen = not self.seen, True
        if first and not self.defer:   # a second Ctrl-C while the batch stops its workers: nothing more
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
        from pnrotor import signals

        signals.restore(self.previous)
        self.previous = {}


def progress_bar(total, enabled, unit="run"):
    """A tqdm bar on stderr (`unit`s done, their rate, the time left), without tqdm's monitor thread (a thread would
    make later worker pools avoid 'fork'), or a stand-in that does nothing."""
    if not enabled:
        return contextlib.nullcontext(type("NoBar", (), {"update": lambda self, n=1: None})())
    from tqdm import tqdm

    class Bar(tqdm):
        monitor_interval = 0

    return Bar(total=total, unit=unit, file=sys.stderr, desc="evolve")
