"""One large kernel call spread over the machine's cores.

A kernel that computes every sample on its own — the waveform modes of a run
(:func:`pnrotor.waveform.amplitudes.modes_in_frame`) and their rotation to another frame
(:func:`pnrotor.waveform.wigner.rotate_modes`) — has its range of samples cut into parts (:func:`parts`), the first
computed on the calling thread and the others at the same time on worker threads (:func:`run`); the kernels are
numba ``nogil`` functions, so the parts run in parallel.  Every sample is computed by the same code either way:
the output is bitwise the same (tested).  Much of a large output's cost is the first touch of its fresh pages
(benchmarks/bench_modes.py), which the parts share too.  (The uniform samples of a run,
:func:`pnrotor.pn.sampling.sample`, were tried the same way and gained nothing measurable: evolve of the 30+10 M☉
precessing run at 1/4096 s 0.74 ms whole, 0.82 ms in two parts; 238,041 samples of a BNS 20.1 and 22.1 ms.)

:func:`pnrotor.evolve_many` runs its integrations on the same threads: one part per thread, each taking the next
eight halves from a shared iterator as it is free, until the iterator is empty or :func:`run` says stop
(:func:`pnrotor.pn.many._integrate_group`; :func:`parts`' ``min_part`` does not apply).

Threads: numba's (``NUMBA_NUM_THREADS``, or what ``numba.set_num_threads`` set for the calling thread once numba's
parallel layer runs, which set_num_threads launches), at most :func:`limit`'s (the worker processes of a
batch take one each: they already fill the cores) and :func:`limited`'s (a batch's Dask tasks: one each); 1 computes
everything on the calling thread. A part has about the ``min_part`` samples its caller gives at least
(:func:`parts`): handing a part to a worker and back costs ~40 µs here (median of a call in two parts with nothing
to compute; 37–63 µs from the 10th to the 90th percentile), and the parts slow each other where they share memory
bandwidth (modes of 1,024 samples, ℓ ≤ 4: 214 µs in one part, 226 in two; 2,048: 378 and 311; 4,096: 687 and 447).
The workers are daemon threads of this process, started by the first call that needs them and kept, idle, for the
next ones (a forked child starts its own; a batch stops idle ones before it forks its worker processes,
:func:`stop_idle_workers`, so that no thread is copied into them).
"""

import numbers
import os
import queue
import signal
import sys
import threading
import time
from contextlib import contextmanager

import numba
from numba.np.ufunc import parallel as _numba_parallel

from pnrotor import signals

__all__ = ["parts", "run", "run_timed", "thread_count", "limit", "limited", "stop_idle_workers"]

_limit = None
"""At most this many threads per call in this process (None: numba's count)."""


_this_thread = threading.local()
"""``limit``: at most this many threads per call made by this thread, inside :func:`limited`."""


def limit(count):
    """Use at most ``count`` (≥ 1) threads per call in this process from now on; None: numba's count again."""
    global _limit
    _limit = _checked(count)


@contextmanager
def limited(count):
    """In the block, calls made by this thread use at most ``count`` (≥ 1) threads (a Dask task: the worker's other
    threads run tasks of their own); other threads, and this one after the block, are not affected."""
    before = getattr(_this_thread, "limit", None)
    _this_thread.limit = _checked(count)
    try:
        yield
    finally:
        _this_thread.limit = before


def _checked(count):
    """``count`` of :func:`limit` and :func:`limited`: None or an integer ≥ 1 (Python's or numpy's, not a bool), else a
    ValueError naming it."""
    if count is not None and (isinstance(count, bool) or not isinstance(count, numbers.Integral) or count < 1):
        raise ValueError(f"count must be None or an integer >= 1; got {count!r}")
    return count


def thread_count():
    """Threads for one call: numba's current count once its parallel layer is running (launching it costs ~50 ms),
    else ``numba.config.NUMBA_NUM_THREADS``; at most :func:`limit`'s and :func:`limited`'s."""
    count = numba.get_num_threads() if getattr(_numba_parallel, "_is_initialized", False) else \
        numba.config.NUMBA_NUM_THREADS
    for cap in (_limit, getattr(_this_thread, "limit", None)):
        if cap is not None:
            count = min(count, cap)
    return count


def parts(n, min_part, align=1):
    """Ranges (lo, hi) covering 0 … n−1 in order: as many as :func:`thread_count`, fewer if a part would have less
    than ``min_part`` samples, each starting at a multiple of ``align`` (the kernel's blocks; so a part has at least
    ``align`` and ``min_part − align`` samples)."""
    k = min(thread_count(), n // max(min_part, align, 1))
    if k <= 1:
        return [(0, n)]
    bounds = [0] + [n * j // k // align * align for j in range(1, k)] + [n]
    return list(zip(bounds[:-1], bounds[1:]))


def run(kernel, ranges, stop=None):
    """kernel(lo, hi) for every range of :func:`parts`: the first on this thread, the others handed to the workers,
    and those no worker has started yet when this thread's own is done run here too (so concurrent or nested calls
    never wait for a free worker).  Returns when every part is done or dropped, also when one raises: this thread's
    exception (then the parts no thread has started are dropped; also one a signal handler raises while this thread
    waits for the others, e.g. the CLI's SIGTERM), else the first part's in range order, is raised.  ``stop``, if
    given, is called as soon as this thread has such an exception, for kernels that take their work in blocks and
    can return early (``evolve_many``'s loop): the call raises anyway.  On the main thread a Ctrl-C during the call
    is held and delivered once every part is done, so no part writes after the call (``stop`` is called at once if
    it will raise KeyboardInterrupt then: Python's own handler).  During interpreter
    finalization the whole range runs on this thread."""
    if len(ranges) == 1 or sys.is_finalizing():
        kernel(ranges[0][0], ranges[-1][1])
        return
    handed = [_Part(kernel, lo, hi) for lo, hi in ranges[1:]]
    error = None

    def failed(e):
        nonlocal error
        if error is None:
            error = e
            if stop is not None:
                stop()

    with _sigint_held(stop):
        _hand_out(handed)
        try:
            kernel(*ranges[0])
        except BaseException as e:
            failed(e)
        for part in handed:   # after an error here, the parts not started are dropped
            part.run_if_unclaimed(compute=error is None)
        for part in handed:
            while True:   # a signal handler's exception while waiting is kept, and the parts still waited for
                try:
                    part.done.wait()
                    break
                except BaseException as e:
                    failed(e)
            if error is None:
                error = part.error
            part.error = None   # no cycle through the traceback: the part's arrays go when the caller's do
    if error is not None:
        try:
            raise error
        finally:
            error = None


PART_SECONDS = 1e-3
"""Work per part at least for :func:`run_timed`: handing a part to a worker costs tens of µs when the calls
follow each other and several times that after its core idled, so a part of 1 ms or more gains about its own time
where the other core is free and loses little where it is not."""

TIMED_SAMPLES = 2048
"""Samples that :func:`run_timed` computes first on the calling thread, timed: a small waveform's kernel call (numba's
dispatch of its ~45 arguments included, ~20 µs) takes ≥ 100 µs for them."""


def run_timed(kernel, n, align):
    """kernel(lo, hi) over 0 … n−1 (a kernel of samples computed each on its own, blocks of ``align``): the first
    :data:`TIMED_SAMPLES` (a multiple of ``align``) on this thread, timed, then the rest by :func:`run` in
    :func:`parts` of at least :data:`PART_SECONDS` at that rate, so that a kernel too short to gain from a second
    thread (a few ms of work) is not handed to one (the hand-off's cost, :data:`PART_SECONDS`, is that of a part of
    ~2,000–16,000 samples of a waveform, depending on its modes; a fixed number of samples cannot say which)."""
    first = min(n, max(align, TIMED_SAMPLES // align * align))
    start = time.perf_counter()
    kernel(0, first)
    if first == n:
        return
    per_sample = max(time.perf_counter() - start, 1e-9) / first
    run(lambda lo, hi: kernel(first + lo, first + hi), parts(n - first, int(PART_SECONDS / per_sample), align))


def stop_idle_workers():
    """Stop this process's worker threads if none has a part to compute: True if none is left then (a fork copies
    no thread of pnrotor's; :mod:`pnrotor.batch` forks its workers only then), False if some are busy.  The next
    call that splits starts them again."""
    with _lock:
        if _busy:
            return False
        stopping = list(_workers)
        _workers.clear()
    for _ in stopping:
        _queue.put(None)
    for worker in stopping:   # idle: each takes a None at once (one started meanwhile may take one instead)
        worker.join(1.0)
    return not any(worker.is_alive() for worker in stopping)


class _Part:
    """kernel(lo, hi) for whichever thread claims it first (a worker, or the caller once its own part is done), then
    ``done`` set; ``error`` what it raised."""

    __slots__ = ("kernel", "lo", "hi", "claimed", "done", "error")

    def __init__(self, kernel, lo, hi):
        self.kernel, self.lo, self.hi = kernel, lo, hi
        self.claimed = False
        self.done = threading.Event()
        self.error = None

    def run_if_unclaimed(self, compute=True):
        """Compute the part here unless another thread has claimed it (or, without ``compute``, just mark it done)."""
        global _busy
        with _lock:
            if self.claimed:
                return
            self.claimed = True
        try:
            if compute:
                self.kernel(self.lo, self.hi)
        except BaseException as e:   # the caller raises it
            self.error = e
        finally:
            self.kernel = None   # a part left in the queue holds no arrays
            with _lock:
                _busy -= 1
            self.done.set()


_queue = queue.SimpleQueue()
_workers = []
"""The worker threads (daemons, named pnrotor-k), started as calls need them, all taking parts from _queue."""
_busy = 0
"""Parts handed out and not finished yet (queued or being computed)."""
_lock = threading.Lock()


def _work(parts):
    """A worker: computes the parts it is given that no other thread has claimed; None stops it."""
    while True:
        part = parts.get()
        if part is None:
            with _lock:
                if threading.current_thread() in _workers:   # started after stop_idle_workers cleared the list
                    _workers.remove(threading.current_thread())
            return
        part.run_if_unclaimed()


def _hand_out(handed):
    """Queue the parts for the workers, first starting workers until as many are free as there are parts (as many
    as can be started: at worst the caller computes its parts itself)."""
    global _busy
    with _lock:
        try:
            while len(_workers) - _busy < len(handed):
                worker = threading.Thread(target=_work, args=(_queue,), name=f"pnrotor-{len(_workers)}", daemon=True)
                worker.start()
                _workers.append(worker)
        except RuntimeError:   # no new thread (interpreter shutdown, resource limits): the caller takes the rest
            pass
        _busy += len(handed)
    for part in handed:
        _queue.put(part)


@contextmanager
def _sigint_held(stop=None):
    """On the main thread: a SIGINT during the block is recorded and raised again after it (a KeyboardInterrupt
    between two statements of :func:`run` could leave its counts wrong or its parts running after it); ``stop`` is
    called at once where the handler it goes to is Python's own, which raises KeyboardInterrupt (another might not
    raise, and a call stopped early would return a partial result).  Elsewhere, or where pnrotor may not handle
    SIGINT (`pnrotor.signals.free`: ignored, or the program's own handler), nothing."""
    if not signals.free(signal.SIGINT):
        yield
        return
    previous = signal.getsignal(signal.SIGINT)
    caught = []

    def held(signum, frame):
        caught.append(signum)
        if stop is not None and previous is signal.default_int_handler:
            stop()

    signal.signal(signal.SIGINT, held)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            signal.raise_signal(signal.SIGINT)


def _forget_workers():
    """In a forked child: the parent's workers do not exist here; start afresh (a lock held at the fork too)."""
    global _queue, _workers, _busy, _lock
    _queue, _workers, _busy, _lock = queue.SimpleQueue(), [], 0, threading.Lock()


os.register_at_fork(after_in_child=_forget_workers)
