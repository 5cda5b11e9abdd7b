"""Helpers for this process and those pnrotor starts: the memory it can still allocate (checked before a large
result is allocated), and for batch workers (:mod:`pnrotor.batch.backends`), their fork server
(:mod:`pnrotor.batch.forkserver`) and the compilations the CLI runs aside (:mod:`pnrotor.numba_cache`).  Imports
nothing of pnrotor, so that any module may use it."""

import math
import os

try:
    import resource
except ImportError:  # pragma: no cover - not Unix
    resource = None

__all__ = ["die_with_parent", "available_memory"]


def die_with_parent():
    """Make this worker die when its parent does (Linux: the kernel's parent-death signal; the parent is the
    batch process, or with 'forkserver' the server, which exits with it), so a batch killed with kill -9
    leaves no orphan workers blocked on their queue (issue 15: two of ~130 MB each, every time)."""
    import ctypes
    import signal

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        return
    if os.getppid() == 1:  # orphaned before the request: nobody would send the signal
        os._exit(1)


def available_memory():
    """Bytes that can still be allocated now: the physical memory free, or less where the process's address space is
    limited (``ulimit -v``, RLIMIT_AS) to less than its size plus that (inf where the OS says neither)."""
    try:
        free = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, OSError, ValueError):  # pragma: no cover - not Linux
        free = math.inf
    limit = None if resource is None else resource.getrlimit(resource.RLIMIT_AS)[0]
    if limit is not None and limit != resource.RLIM_INFINITY:
        try:
            with open("/proc/self/statm") as f:   # the address space's size, in pages
                size = int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        except OSError:  # pragma: no cover - not Linux
            return free
        free = min(free, max(limit - size, 0))
    return free
