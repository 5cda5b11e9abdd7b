"""Which signals pnrotor handles: only those at their default disposition, and none in a batch's workers.

pnrotor installs handlers for SIGINT, SIGTERM and SIGHUP for a while in a few places: the command line (SIGTERM
and SIGHUP stop a command as Ctrl-C does), `pnrotor.hdf5` while it writes a file (the temporary file is
removed), a batch (Ctrl-C is deferred while HDF5 writes), `pnrotor.threads` (a Ctrl-C is held until the parts
of a split call are done).  Each takes a signal (:func:`take`) only where it may (:func:`free`): on the main
thread, with the signal at its default disposition (SIG_DFL, or Python's `signal.default_int_handler` for
SIGINT) or handled by pnrotor already (an outer call's handler).  A signal the parent set to be ignored stays
ignored (``nohup`` ignores SIGHUP, a shell's background job ``cmd &`` SIGINT), and a program's own handler stays
its own.  A batch's worker processes take none (:func:`leave_to_parent`)."""

import contextlib
import signal
import threading

STOPPING = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
"""The signals that stop pnrotor's work: Ctrl-C, ``kill``'s default, a closed terminal."""

_worker = False
"""True in a batch's worker process (:func:`leave_to_parent`): the batch process handles the signals."""


def free(signum):
    """Whether pnrotor may install its handler for ``signum`` here (module docstring)."""
    if _worker or threading.current_thread() is not threading.main_thread():
        return False
    current = signal.getsignal(signum)
    return (current is signal.SIG_DFL or (signum == signal.SIGINT and current is signal.default_int_handler)
            or getattr(current, "pnrotor_handler", False))


def take(function, signums=STOPPING):
    """Install ``function(signum, frame)`` as the handler of each of ``signums`` that is :func:`free` → {signum:
    the handler it replaced}, for :func:`restore`."""
    def handler(signum, frame):
        return function(signum, frame)

    handler.pnrotor_handler = True
    return {signum: signal.signal(signum, handler) for signum in signums if free(signum)}


def restore(previous):
    """Put back the handlers :func:`take` replaced."""
    for signum, handler in previous.items():
        signal.signal(signum, handler)


@contextlib.contextmanager
def blocked(signums=STOPPING):
    """Block ``signums`` in this thread during the block (where the system can): a process forked meanwhile
    starts with them blocked until it has set its own handlers (:func:`leave_to_parent`), so none reaches it
    with this process's handlers; here a signal that came meanwhile is delivered after the block."""
    if not hasattr(signal, "pthread_sigmask"):   # pragma: no cover - Windows
        yield
        return
    before = signal.pthread_sigmask(signal.SIG_BLOCK, signums)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def leave_to_parent():
    """In a batch's worker process: SIGINT and SIGHUP ignored (a terminal sends them to every process of the
    job; the batch process handles them and stops its workers), SIGTERM at its default (how the batch process
    stops a worker at once), pnrotor takes no signal in this process; then the signals `blocked` at its start
    are unblocked."""
    global _worker
    _worker = True
    for signum in STOPPING:
        signal.signal(signum, signal.SIG_DFL if signum == signal.SIGTERM else signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, STOPPING)
