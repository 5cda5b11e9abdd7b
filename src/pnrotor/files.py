"""Files other than HDF5 (CSV tables, JSON summaries, figures) written whole or not at all.

:func:`replaced_on_success` gives a temporary name beside the target; the target gets the finished file by one
``os.replace`` (atomic on POSIX), and an exception (or Ctrl-C) on the way removes the temporary and leaves the
target as it was: never a half-written table or figure under the expected name.  HDF5 files have their own,
durable, machinery (:mod:`pnrotor.hdf5`).
"""

import os
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path

__all__ = ["replaced_on_success"]


@contextmanager
def replaced_on_success(path):
    """A temporary path beside ``path`` (same suffix, so that matplotlib infers the format) to write; on leaving
    without an exception it replaces ``path``, else it is removed (module docstring)."""
    path = Path(path)
    fd, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        yield Path(temporary)
        os.replace(temporary, path)
    except BaseException:
        with suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
