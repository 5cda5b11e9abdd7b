"""Batch backends: where the runs of a batch are computed, each yielding (index, ok, result) as runs finish.

* :func:`results_serial` — in this process, in order;
* :func:`results_pool` — local worker processes (``fork`` where safe, :func:`start_method`), a few rows per
  task (:func:`chunk_size`), each sending back its runs;
* :func:`results_dask` — a Dask cluster (the ``pnrotor[dask]`` extra), one task per row.

``result`` is the `Evolution` (or (Evolution, Modes)), or the message of the row's failure: one failing row
(a bad value, evolve's ``ValueError``, a dead worker) never stops the others (:func:`attempt`).

The pool (:func:`pool_results`) and Dask take any ``work`` too: a function of a chunk of (index, payload) tasks that
returns [(index, ok, result)], with the chunks as an iterable read as they are sent (at most a ``window`` of them in
flight): the population mode (`pnrotor.batch.population`) sends the chunks of a table's rows so.
"""

import functools
import sys

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


def in_dask_task(work, chunk):
    """``work(chunk)`` as a task on a Dask worker, whose other threads run tasks of their own: a run's modes, a
    population's integrations, on this task's thread alone (`pnrotor.threads.limited`; the worker process, and the
    caller's with an in-process cluster, keep their threads)."""
    from pnrotor import threads

    with threads.limited(1):
        return work(chunk)


MODES_SUFFIX = ".modes"
"""A row's modes are stored beside its run as the group ``NAME.modes``."""


def brief(run):
    """What the batch summary needs of a run: small enough to send back from a worker instead of the run."""
    return {"span": run.span(), "M_seconds": run.inputs["M_seconds"], "termination": run.termination,
            "samples": len(run), "nfev": run.stats["nfev"], "wall_time_s": run.stats["wall_time_s"]}


def _preload(thread_count=1):
    from pnrotor import signals

    signals.leave_to_parent()   # Ctrl-C and SIGHUP are the parent's to handle: it stops the workers
    die_with_parent()
    import pnrotor.pn.evolve  # noqa: F401 - numba's kernels, loaded once per worker
    from pnrotor import threads

    threads.limit(thread_count)   # the workers fill the cores: a batch's run is not split over threads in a worker


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


def results_pool(tasks, jobs, context=None, chunksize=None):
    """Start `jobs` worker processes on `tasks` [(index, params)] and return a generator of (index, ok, result),
    in the order the chunks finish (:func:`pool_results`).

    The workers take `chunksize` rows per task and send back each run (the batch writer adds it to the batch file
    at once)."""
    size = chunksize or chunk_size(len(tasks), jobs)
    chunks = [tasks[i : i + size] for i in range(0, len(tasks), size)]
    return pool_results(attempt_chunk, chunks, min(jobs, len(chunks)), context)


def pool_results(work, chunks, jobs, context=None, window=None, thread_count=1):
    """Start `jobs` worker processes and return a generator of the items (index, ok, result) of ``work(chunk)`` for
    each chunk of `chunks` (lists of (index, payload) tasks), in the order the chunks finish.

    The workers (started by `multiprocessing` method `context`, default `start_method`) load the PN code once and
    use `thread_count` threads each (`pnrotor.threads.limit`).  `chunks` is an iterable, read as chunks are
    submitted, at most `window` in flight (None: all at once).  A dying worker is :func:`_pool_results`' to handle.
    Closing the generator early (Ctrl-C) cancels the queued tasks and stops the workers.  The workers are started
    here, and the first chunks submitted, before the caller starts any thread (a progress bar's)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    mp_context = multiprocessing.get_context(context or start_method())
    if mp_context.get_start_method() == "forkserver":
        # the server dies with this process (and its workers with it), then loads the PN code once
        mp_context.set_forkserver_preload(["pnrotor.batch.forkserver", "pnrotor.pn.evolve"])

    def start(workers):
        return ProcessPoolExecutor(max_workers=workers, mp_context=mp_context, initializer=_preload,
                                   initargs=(thread_count,))

    feed = _Feed(chunks, work, window)
    pool = start(jobs)
    return _pool_results(start, pool, feed.submit(pool), feed, jobs)


class _Feed:
    """The chunks a pool has yet to compute: those of a broken pool (``retry``) first, then the rest of the caller's
    iterable (``rest``), at most ``window`` in flight (None: all)."""

    def __init__(self, chunks, work, window):
        self.retry, self.rest, self.work, self.window = [], iter(chunks), work, window

    def submit(self, pool, futures=None):
        """Submit chunks to `pool` until `futures` ({future: chunk}, returned) holds a window of them or none is left;
        a chunk the pool refuses because a worker died goes back to ``retry``."""
        from concurrent.futures.process import BrokenProcessPool

        from pnrotor import signals

        futures = {} if futures is None else futures
        while self.window is None or len(futures) < self.window:
            chunk = self.retry.pop(0) if self.retry else next(self.rest, None)
            if chunk is None:
                break
            try:
                with signals.blocked():   # a worker starts (forks) in submit, with SIGINT, SIGTERM and SIGHUP
                    futures[pool.submit(self.work, chunk)] = chunk   # blocked until _preload has set its own
            except BrokenProcessPool:   # a worker died at start-up: this chunk goes to the next pool
                self.retry.insert(0, chunk)
                break
            except BaseException:
                _stop(pool)
                raise
        return futures


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


def _pool_results(start, pool, futures, feed, jobs):
    """(index, ok, result) of every chunk of the `_Feed` `feed`, from `pool` (made by ``start(workers)``; `futures`,
    its chunks in flight) and the pools after it.  A worker that dies (killed, out of memory) breaks its whole pool,
    and with it every chunk not finished: those rows go to a new pool, one per task, as long as each pool finishes
    some row; a pool that finishes none is followed by one of a single worker, and when that one too finishes none,
    its first row (the one it was running) fails and the others go on.  So a row that kills its worker every time
    fails alone."""
    from concurrent.futures import FIRST_COMPLETED, wait
    from concurrent.futures.process import BrokenProcessPool

    workers = jobs
    while True:
        broken, finished, completed = [], False, False
        try:
            while futures:
                done, _ = wait(futures, return_when=FIRST_COMPLETED)
                for future in [future for future in futures if future in done]:   # in submission order
                    chunk = futures.pop(future)
                    try:
                        results = future.result()
                    except BrokenProcessPool:
                        broken.append(chunk)
                        continue
                    finished = True
                    yield from results
                if not broken:
                    feed.submit(pool, futures)
            completed = True
        finally:
            if completed:
                pool.shutdown(wait=True)
            else:
                _stop(pool)
        lost = [task for chunk in broken + feed.retry for task in chunk]
        if lost and workers == 1 and not finished:
            index, _ = lost.pop(0)
            yield index, False, "its worker process died running it (killed, or out of memory?)"
        feed.retry = [[task] for task in lost]
        if not feed.retry:
            chunk = next(feed.rest, None)
            if chunk is None:
                return
            feed.retry = [chunk]
        workers = jobs if finished else 1
        pool = start(workers)
        futures = feed.submit(pool)


def results_dask(tasks, scheduler, work=None, window=None):
    """One Dask task per (index, payload) of `tasks` (an iterable, read as tasks are submitted, at most `window` in
    flight, or ``window(threads)`` for a function of the cluster's worker threads; None: all at once) on the Dask
    scheduler `scheduler` (an address, connected to here, or a
    `distributed.Client`, used as it is), computing ``work([task])`` (default :func:`attempt_chunk`: the runs
    themselves come back, this process writes them) on one thread of its worker (:func:`in_dask_task`) → a generator
    of (index, ok, result) as they finish.  A task whose worker was lost is rescheduled by Dask (up to its
    ``distributed.scheduler.allowed-failures``); one that fails anyway fails its rows with Dask's reason."""
    try:
        from distributed import Client
    except ImportError:
        raise ValueError("--scheduler needs Dask's distributed scheduler: pip install 'pnrotor[dask]'") from None
    if isinstance(scheduler, Client):
        return _dask_results(scheduler, tasks, work, window, close=False)
    try:
        client = Client(scheduler, timeout=SCHEDULER_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError) as error:
        raise ValueError(f"cannot connect to the Dask scheduler at {scheduler}: {error}") from None
    try:  # tasks given to a cluster without workers would wait forever
        client.wait_for_workers(1, timeout=SCHEDULER_TIMEOUT)
    except (OSError, TimeoutError):
        client.close()
        raise ValueError(f"the Dask scheduler at {scheduler} has no workers (waited {SCHEDULER_TIMEOUT})") from None
    return _dask_results(client, tasks, work, window)


def _dask_results(client, tasks, work=None, window=None, close=True):
    import contextlib

    from distributed import as_completed

    task = functools.partial(in_dask_task, attempt_chunk if work is None else work)
    tasks, chunk_of, queue = iter(tasks), {}, as_completed(loop=client.loop)

    def submit(n):
        """Submit the next `n` tasks (None: all) to the cluster, in one call."""
        chunks = [[item] for item in (tasks if n is None else (x for _, x in zip(range(n), tasks)))]
        for future, chunk in zip(client.map(task, chunks, pure=False), chunks):
            chunk_of[future.key] = chunk
            queue.add(future)

    with client if close else contextlib.nullcontext():
        if callable(window):
            window = window(sum(client.nthreads().values()))
        submit(window)
        for future in queue:
            chunk = chunk_of.pop(future.key)
            try:
                results = future.result()
            except Exception as error:  # noqa: BLE001 - a lost worker, reported per row
                results = [(index, False, f"Dask task failed: {type(error).__name__}: {error}") for index, _ in chunk]
            if window is not None:
                submit(1)
            yield from results
