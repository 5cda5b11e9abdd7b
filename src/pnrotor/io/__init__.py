"""Results to files: one module per format, chosen by the file's suffix, each writing through the one crash-safe
writer (:mod:`pnrotor.io.atomic`).

* :func:`write` ``(path, result, **options)`` — the result (a dataclass of :mod:`pnrotor.results`, or a streamed
  result, ``pnrotor.stream(...).modes(...)``) written in the format `FORMATS` names for the suffix of `path`, with
  that format's options (for HDF5: ``overwrite``, ``compression``, ``checksum``, ``group``, as
  :func:`pnrotor.io.hdf5.write`);
* :mod:`~pnrotor.io.atomic` — a file built under a temporary name and published whole or not at all;
* :mod:`~pnrotor.io.hdf5` — pnrotor's HDF5 files (also ``pnrotor.hdf5``; docs/hdf5-schema.md).

A new format is one module with ``write(path, result, **options)`` (writing through :func:`atomic.replaced`) and
one entry in `FORMATS` (docs/architecture.md, "Adding an output format").  Importing this package loads no format:
each is imported when a file of its suffix is first written.
"""

import importlib
from pathlib import Path

__all__ = ["write", "format_of", "FORMATS"]

FORMATS = {".h5": "pnrotor.io.hdf5", ".hdf5": "pnrotor.io.hdf5"}
"""Suffix of a file (lower case) → the module that writes results in that format."""


def format_of(path):
    """The name of the module that writes files named `path` (`FORMATS`, by its suffix), without importing it; a
    ValueError naming `path` and the suffixes pnrotor writes otherwise (callers check before computing)."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{path}: pnrotor writes files ending in {', '.join(sorted(FORMATS))}, not "
                         f"{repr(suffix) if suffix else 'a name without a suffix'}")
    return FORMATS[suffix]


def write(path, result, **options):
    """Write `result` to `path` in the format of its suffix (:func:`format_of`) → the path written."""
    return importlib.import_module(format_of(path)).write(path, result, **options)
