"""Batch backends: where the runs of a batch are computed, each yielding (index, ok, result) as runs finish.

* :func:`results_serial` — in this process, in order;
* :func:`results_pool` — local worker processes (``fork`` where safe, :func:`start_method`), a few rows per
  task (:func:`chunk_size`); with ``parts`` the workers write each run into its own HDF5 part file
  (:func:`write_chunk`, :func:`store`) and send back only a :class:`Stored` and the run's :func:`brief`;
* :func:`results_dask` — a Dask cluster (the ``pnrotor[dask]`` extra), one task per row.

``result`` is the `Evolution`, a :class:`Stored`, or the message of the row's failure: one failing row
(a bad value, evolve's ``ValueError``, a dead worker) never stops the others (:func:`attempt`).
"""

import sys
from pathlib import Path

from pnrotor.processes import die_with_parent

SCHEDULER_TIMEOUT = "10s"
"""How long to wait for a Dask scheduler to answer."""


def evolve_row(params):
    """`pnrotor.evolve` on one row's keywords (the numba code is imported on the first call); with the key
    ``modes`` = (ell_max, 2 × amplitude_order, distance in Mpc or None), the pair (Evolution, its `Modes`)."""
    from pnrotor.pn.evolve import evolve

    params = dict(params)
    wave = params.pop("modes", None)
    run = evolve(**params)
    if wave is None:
        return run
    import warnings

    from pnrotor.waveform.modes import CoarseSamplingWarning, modes

    ell_max, order2, distance = wave
    with warnings.catch_warnings():   # a row's sampling is the table's choice (--modes' help says steps are coarse)
        warnings.simplefilter("ignore", CoarseSamplingWarning)
        return run, modes(run, ell_max, order2 / 2, distance)


def attempt(params):
    """evolve_row(params) → (True, Evolution or (Evolution, Modes)) or (False, message): one row's failure must
    not stop the batch."""
    try:
        return True, evolve_row(params)
    except Exception as error:  # noqa: BLE001 - reported per row
        return False, str(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"


def attempt_chunk(chunk):
    """`attempt` on each (index, params) of a chunk → [(index, ok, Evolution or message)]."""
    return [(index, *attempt(params)) for index, params in chunk]


def attempt_chunk_in_dask(chunk):
    """`attempt_chunk` as a task on a Dask worker, whose other threads run tasks of their own: each run's modes on
    this task's thread alone (`pnrotor.threads.limited`; the worker process, and the caller's with an in-process
    cluster, keep their threads)."""
    from pnrotor import threads

    with threads.limited(1):
        return attempt_chunk(chunk)


class Stored:
    """A run that a worker wrote into the part file `path` as group `group`, with the `brief` of it."""

    def __init__(self, path, group, brief):
        self.path, self.group, self.brief = path, group, brief


MODES_SUFFIX = ".modes"
"""A row's modes are stored beside its run as the group ``NAME.modes``."""


def brief(run):
    """What the batch summary needs of a run: small enough to send back from a worker instead of the run."""
    return {"span": run.span(), "M_seconds": run.inputs["M_seconds"], "termination": run.termination,
            "samples": len(run), "nfev": run.stats["nfev"], "wall_time_s": run.stats["wall_time_s"]}


def store(result, folder, index, storage):
    """Write one finished row (an Evolution, or (Evolution, Modes)) into its own part file ``run-INDEX.h5``
    (groups INDEX and INDEX.modes) in `folder` → `Stored`; atomic but not fsynced: it survives the process
    (kill -9 included), not a power loss (fsyncs made 200 runs at 1/4096 s with --jobs 2 take ~20% longer)."""
    from pnrotor import hdf5

    run, *waves = result if isinstance(result, tuple) else (result,)
    path = Path(folder) / f"run-{index}.h5"
    with hdf5.batch(path, overwrite=True, durable=False, **storage) as part:
        part.add(str(index), run)
        for wave in waves:
            part.add(str(index) + MODES_SUFFIX, wave)
    return Stored(path, str(index), brief(run))


def store_row(result, folder, index, storage):
    """:func:`store` → (True, Stored), or (False, message) for a run that `pnrotor.hdf5` refuses to write (e.g.
    a non-finite sample): that row fails, not the batch."""
    try:
        return True, store(result, folder, index, storage)
    except ValueError as error:
        return False, f"its run cannot be written: {error}"


def write_chunk(chunk, folder, storage):
    """`attempt` on each (index, params) of a chunk, each finished run written at once into its own part file
    in `folder` (:func:`store`, so a killed worker loses only the run it was computing) → [(index, ok, Stored
    or message)]. Encoding HDF5 costs several times a typical run, so the workers do it and the parent only
    copies the groups into the batch file (`Batch.copy_from`, HDF5's object copy, which keeps their layout
    and filters)."""
    results = []
    for index, params in chunk:
        ok, result = attempt(params)
        results.append((index, *(store_row(result, folder, index, storage) if ok else (ok, result))))
    return results


def _preload():
    from pnrotor import signals

    signals.leave_to_parent()   # Ctrl-C and SIGHUP are the parent's to handle: it stops the workers
    die_with_parent()
    import pnrotor.pn.evolve  # noqa: F401 - numba's kernels, loaded once per worker
    from pnrotor import threads

    threads.limit(1)   # the workers fill the cores: a run's modes are not split over threads in a worker


def results_serial(tasks):
    """Yield (index, ok, result) for each (index, params), computed in this process."""
    for index, params in tasks:
        yield (index, *attempt(params))


def chunk_size(n_tasks, jobs):
    """Rows per task sent to a worker: about 4 tasks per worker for load balance, at most 8 rows each."""
    return max(1, min(8, n_tasks // (4 * jobs)))


def start_method():
    """How worker processes start: 'fork' on Linux when this process runs no other thread (idle workers of
    :mod:`pnrotor.threads` are stopped first; a worker then starts in ~0.02 s with the PN code already loaded, against
    ~0.6 s for 'forkserver' and ~0.8 s for 'spawn', benchmarks/bench_batch.py); otherwise 'forkserver' (forking a
    process with threads can deadlock the child), or 'spawn' where there is no forkserver (Windows)."""
    import multiprocessing
    import threading

    from pnrotor import threads

    methods = multiprocessing.get_all_start_methods()
    if sys.platform.startswith("linux") and "fork" in methods and threads.stop_idle_workers() and \
            threading.active_count() == 1:
        return "fork"
    return "forkserver" if "forkserver" in methods else "spawn"


def results_pool(tasks, jobs, context=None, chunksize=None, parts=None, storage=None):
    """Start `jobs` worker processes on `tasks` [(index, params)] and return a generator of (index, ok, result),
    in the order the chunks finish.

    The workers (started by `multiprocessing` method `context`, default `start_method`) load the PN code once
    and take `chunksize` rows per task. They send back each run, or with `parts` (a folder) write the runs
    to part files there (with the `pnrotor.hdf5.batch` options `storage`, a dict) and send back a `Stored`
    each, the part files staying for the caller. Closing the generator early (Ctrl-C) cancels the
    queued tasks and stops the workers.
    The workers are started here, before the caller starts any thread (a progress bar's)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    from pnrotor import signals

    size = chunksize or chunk_size(len(tasks), jobs)
    chunks = [tasks[i : i + size] for i in range(0, len(tasks), size)]
    mp_context = multiprocessing.get_context(context or start_method())
    if mp_context.get_start_method() == "forkserver":
        # the server dies with this process (and its workers with it), then loads the PN code once
        mp_context.set_forkserver_preload(["pnrotor.batch.forkserver", "pnrotor.pn.evolve"])

    def start(chunks, workers):
        """A pool of `workers` processes on `chunks` → (pool, {future: chunk} in submission order, chunks not
        submitted because a worker died at once).  The workers start with SIGINT, SIGTERM and SIGHUP blocked
        until `_preload` has set theirs (one that came before printed a worker's traceback)."""
        pool = ProcessPoolExecutor(max_workers=min(workers, len(chunks)), mp_context=mp_context, initializer=_preload)
        futures = {}
        try:
            with signals.blocked():   # the workers start (fork) in submit
                for chunk in chunks:
                    if parts is None:
                        futures[pool.submit(attempt_chunk, chunk)] = chunk
                    else:
                        futures[pool.submit(write_chunk, chunk, parts, storage or {})] = chunk
        except BrokenProcessPool:
            pass  # a worker died at start-up: the chunks not submitted are lost with the others
        except BaseException:
            _stop(pool)
            raise
        return pool, futures, chunks[len(futures):]

    return _pool_results(start, start(chunks, jobs), jobs)


def _stop(pool):
    """Cancel the pool's queued tasks and terminate its workers, then wait for them.  The workers are listed first:
    ``shutdown`` forgets them (CPython 3.11 sets ``_processes`` to None), and a second ``shutdown(wait=True)`` would
    let the queued tasks run again (a review found a Ctrl-C'd batch computing all 400 rows for 36 s more)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    for process in processes:
        process.join()


def _pool_results(start, first, jobs):
    """(index, ok, result) of every row of the pool `first` (:func:`results_pool`'s ``start(chunks, jobs)``,
    already called).  A worker that dies (killed, out of memory) breaks its whole pool, and with it every chunk
    not finished: those rows go to a new pool, one per task, as long as each pool finishes some row; a pool
    that finishes none is followed by one of a single worker, and when that one too finishes none, its first
    row (the one it was running) fails and the others go on.  So a row that kills its worker every time fails
    alone."""
    from concurrent.futures import as_completed
    from concurrent.futures.process import BrokenProcessPool

    state, workers = first, jobs
    while True:
        pool, futures, unsubmitted = state
        broken, finished, completed = set(), False, False
        try:
            for future in as_completed(futures):
                try:
                    results = future.result()
                except BrokenProcessPool:
                    broken.add(future)
                    continue
                finished = True
                yield from results
            completed = True
        finally:
            if completed:
                pool.shutdown(wait=True)
            else:
                _stop(pool)
        lost = [task for future, chunk in futures.items() if future in broken for task in chunk]
        lost += [task for chunk in unsubmitted for task in chunk]
        if not lost:
            return
        if workers == 1 and not finished:
            index, _ = lost.pop(0)
            yield index, False, "its worker process died running it (killed, or out of memory?)"
            if not lost:
                return
        workers = jobs if finished else 1
        state = start([[task] for task in lost], workers)


def results_dask(tasks, address):
    """Connect to the Dask scheduler at `address`, submit one task per (index, params) and return a generator
    of (index, ok, result) as they finish (the runs themselves come back; this process writes them)."""
    try:
        from distributed import Client
    except ImportError:
        raise ValueError("--scheduler needs Dask's distributed scheduler: pip install 'pnrotor[dask]'") from None
    try:
        client = Client(address, timeout=SCHEDULER_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError) as error:
        raise ValueError(f"cannot connect to the Dask scheduler at {address}: {error}") from None
    try:  # tasks given to a cluster without workers would wait forever
        client.wait_for_workers(1, timeout=SCHEDULER_TIMEOUT)
    except (OSError, TimeoutError):
        client.close()
        raise ValueError(f"the Dask scheduler at {address} has no workers (waited {SCHEDULER_TIMEOUT})") from None
    return _dask_results(client, tasks)


def _dask_results(client, tasks):
    from distributed import as_completed

    with client:
        futures = client.map(attempt_chunk_in_dask, [[task] for task in tasks], pure=False)
        chunk_of = {future.key: [task] for future, task in zip(futures, tasks)}
        for future in as_completed(futures, loop=client.loop):
            try:
                results = future.result()
            except Exception as error:  # noqa: BLE001 - a lost worker, reported per row
                results = [(index, False, f"Dask task failed: {type(error).__name__}: {error}")
                           for index, _ in chunk_of[future.key]]
            yield from results
