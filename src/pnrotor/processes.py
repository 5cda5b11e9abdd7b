"""Helpers for the processes pnrotor starts: batch workers (:mod:`pnrotor.batch.backends`), their fork server
(:mod:`pnrotor.batch.forkserver`) and the compilations the CLI runs aside (:mod:`pnrotor.numba_cache`).  Imports
nothing of pnrotor, so that any module may use it."""

import os

__all__ = ["die_with_parent"]


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
