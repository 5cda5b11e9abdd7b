"""One large kernel call spread over the machine's cores.

A kernel that computes every sample on its own — the waveform modes of a run
(:func:`pnrotor.waveform.amplitudes.modes_in_frame`) and their rotation to another frame
(:func:`pnrotor.waveform.wigner.rotate_modes`) — has its range of samples cut into parts (:func:`parts`), the first
computed on the calling thread and the others at the same time on the threads of a pool (:func:`run`); the kernels
are numba ``nogil`` functions, so the parts run in parallel.  Every sample is computed by the same code
either way: the output is bitwise the same (tested).  Much of a large output's cost is the first touch of its fresh
pages (benchmarks/bench_modes.py), which the parts share too.  (The uniform samples of a run,
:func:`pnrotor.pn.sampling.sample`, were tried the same way and gained nothing measurable: evolve of the 30+10 M☉
precessing run at 1/4096 s 0.74 ms whole, 0.82 ms in two parts; 238,041 samples of a BNS 20.1 and 22.1 ms.)

Threads: numba's (``NUMBA_NUM_THREADS``, or ``numba.set_num_threads`` once numba's parallel layer runs, e.g.
after :func:`pnrotor.evolve_many`), at most :func:`limit`'s (the worker processes of a batch take one each: they
already fill the cores); 1 computes everything on the calling thread.  A part has about the ``min_part`` samples
its caller gives at least (:func:`parts`): handing parts to the pool and back costs ~100 µs here (modes of 1,024
samples, ℓ ≤ 4: 212 µs in one part, 219 in two; 2,048: 351 and 286; 4,096: 699 and 462).  The pool is made on the
first call that splits and kept (one per process: a forked child makes its own).
"""

import numbers
import os
from functools import lru_cache

import numba
from numba.np.ufunc import parallel as _numba_parallel

__all__ = ["parts", "run", "thread_count", "limit"]

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
    """kernel(lo, hi) for every range of :func:`parts`, the first on this thread and the others on the pool's
    threads at the same time; returns when all are done (also when one raises: the first exception is raised)."""
    if len(ranges) == 1:
        kernel(*ranges[0])
        return
    pool = _pool(os.getpid(), len(ranges) - 1)
    futures = [pool.submit(kernel, lo, hi) for lo, hi in ranges[1:]]
    try:
        kernel(*ranges[0])
    finally:
        for future in futures:   # every part finished before the caller sees (or frees) the output
            future.exception()
    for future in futures:
        future.result()


@lru_cache(maxsize=None)
def _pool(pid, workers):
    """The pool of this process (``pid``: a forked child does not inherit the parent's threads)."""
    from concurrent.futures import ThreadPoolExecutor   # 13 ms to import: only for a call that splits

    return ThreadPoolExecutor(workers, thread_name_prefix="pnrotor")
