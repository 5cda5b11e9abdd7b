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

Threads: numba's (``NUMBA_NUM_THREADS``, or what ``numba.set_num_threads`` set for the calling thread once numba's
parallel layer runs, e.g. after :func:`pnrotor.evolve_many`), at most :func:`limit`'s (the worker processes of a
batch take one each: they already fill the cores); 1 computes everything on the calling thread.  A part has about
the ``min_part`` samples its caller gives at least (:func:`parts`): handing a part to a worker and back costs ~40
µs here (median of a call in two parts with nothing to compute; 34–51 µs from the 10th to the 90th percentile), and
the parts slow each other where they share memory bandwidth (modes of 1,024 samples, ℓ ≤ 4: 214 µs in one part, 226
in two; 2,048: 378 and 311; 4,096: 687 and 447).  The workers are daemon threads of this process, started by the first call that needs them and kept, idle,
for the next ones (a forked child starts its own; a batch still forks its workers beside idle ones,
:func:`idle_workers`).
"""

import numbers
import os
import queue
import threading

import numba
from numba.np.ufunc import parallel as _numba_parallel

__all__ = ["parts", "run", "thread_count", "limit", "idle_workers"]

_limit = None
"""At most this many threads per call in this process (None: numba's count)."""


def limit(count):
    """Use at most ``count`` (≥ 1) threads per call in this process from now on; None: numba's count again."""
    global _limit
    if count is not None and (isinstance(count, bool) or not isinstance(count, numbers.Integral) or count < 1):
        raise ValueError(f"count must be None or an integer >= 1; got {count!r}")
    _limit = count


def thread_count():
    """Threads for one call: numba's current count once its parallel layer is running (launching it costs ~50 ms),
    else ``numba.config.NUMBA_NUM_THREADS``; at most :func:`limit`'s."""
    count = numba.get_num_threads() if getattr(_numba_parallel, "_is_initialized", False) else \
        numba.config.NUMBA_NUM_THREADS
    return count if _limit is None else min(count, _limit)


def parts(n, min_part, align=1):
    """Ranges (lo, hi) covering 0 … n−1 in order: as many as :func:`thread_count`, fewer if a part would have less
    than ``min_part`` samples, each starting at a multiple of ``align`` (the kernel's blocks; so a part has at least
    ``align`` and ``min_part − align`` samples)."""
    k = min(thread_count(), n // max(min_part, align, 1))
    if k <= 1:
        return [(0, n)]
    bounds = [0] + [n * j // k // align * align for j in range(1, k)] + [n]
    return list(zip(bounds[:-1], bounds[1:]))


def run(kernel, ranges):
    """kernel(lo, hi) for every range of :func:`parts`, the first on this thread and the others on the workers' at
    the same time; returns when all are done, also when one raises (the first exception, this thread's first, is
    raised) or a KeyboardInterrupt comes meanwhile (raised once they are done): no part writes after the call.  Where
    no thread can be started (at interpreter shutdown), the whole range runs on this thread."""
    handed = [_Part(kernel, lo, hi) for lo, hi in ranges[1:]]
    if handed and not _hand_out(handed):
        handed, ranges = [], [(ranges[0][0], ranges[-1][1])]
    try:
        kernel(*ranges[0])
    finally:
        _wait(handed)
    for part in handed:
        if part.error is not None:
            raise part.error


def idle_workers():
    """How many worker threads this process has if none is computing a part, else 0: threads that a fork may
    ignore (an idle worker holds no lock the child needs, and the child starts its own workers)."""
    with _lock:
        return len(_workers) if _busy == 0 else 0


class _Part:
    """kernel(lo, hi) for a worker, then ``done`` set; ``error`` what it raised."""

    __slots__ = ("kernel", "lo", "hi", "done", "error")

    def __init__(self, kernel, lo, hi):
        self.kernel, self.lo, self.hi = kernel, lo, hi
        self.done = threading.Event()
        self.error = None

    def __call__(self):
        try:
            self.kernel(self.lo, self.hi)
        except BaseException as e:   # the caller raises it
            self.error = e
        finally:
            self.done.set()


_queue = queue.SimpleQueue()
_workers = []
"""The worker threads (daemons, named pnrotor-k), started as calls need them, all taking parts from _queue."""
_busy = 0
"""Parts handed out and not finished yet."""
_lock = threading.Lock()


def _work(parts):
    """A worker: runs the parts it is given, forever."""
    global _busy
    while True:
        parts.get()()
        with _lock:
            _busy -= 1


def _hand_out(handed):
    """Give the parts to the workers, starting as many as there are parts; False if there is no worker and none can
    be started (interpreter shutdown)."""
    global _busy
    with _lock:
        try:
            while len(_workers) < len(handed):
                worker = threading.Thread(target=_work, args=(_queue,), name=f"pnrotor-{len(_workers)}", daemon=True)
                worker.start()
                _workers.append(worker)
        except RuntimeError:   # "can't create new thread at interpreter shutdown"
            if not _workers:
                return False
        _busy += len(handed)
    for part in handed:
        _queue.put(part)
    return True


def _wait(handed):
    """Wait until every part is done, a KeyboardInterrupt meanwhile raised only then."""
    interrupted = None
    for part in handed:
        while not part.done.is_set():
            try:
                part.done.wait()
            except KeyboardInterrupt as e:
                interrupted = e
    if interrupted is not None:
        raise interrupted


def _forget_workers():
    """In a forked child: the parent's workers do not exist here; start afresh (a lock held at the fork too)."""
    global _queue, _workers, _busy, _lock
    _queue, _workers, _busy, _lock = queue.SimpleQueue(), [], 0, threading.Lock()


os.register_at_fork(after_in_child=_forget_workers)
