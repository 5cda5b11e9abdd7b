"""Helpers shared by the test modules (``tests`` is on pytest's ``pythonpath``)."""

import signal


def default_signals():
    """``preexec_fn`` of a child process that a test signals: SIGINT, SIGTERM and SIGHUP at their defaults, as a
    terminal starts a command, whatever this process has (pnrotor leaves an ignored signal ignored, and a suite
    started in the background has SIGINT ignored, one under nohup SIGHUP)."""
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)
