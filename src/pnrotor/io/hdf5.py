"""pnrotor's HDF5 files: run results (`FrameHistory`, `Evolution`, `Modes`, `Polarizations`, `PopulationTable`) to and
from disk, atomic and versioned.

This module and its reading half (:mod:`pnrotor.io.hdf5_read`) own the file format (documented for readers without
pnrotor in docs/hdf5-schema.md) and every write and read of it:

* `write(path, run)` stores a run dataclass: each field that is an array becomes a dataset (float64 stays
  float64; chunked with a Fletcher-32 checksum per chunk and optional gzip/lzf compression, or with
  ``checksum=False`` and no compression contiguous, see `write`; an object array of `str` a fixed-length
  UTF-8 dataset, stored the same way, as is a numpy string array, read back as one of `str`), each number,
  string (numpy's ``np.str_`` too, read back as `str`; a fixed-length UTF-8 attribute, `_string`, since schema 2:
  no file holds a variable-length string, which HDF5 would keep in its unchecksummed global heap), bool or
  ``None`` an attribute, each dict a subgroup holding its items by the same rules, each list or tuple of numbers
  a dataset marked with a ``sequence`` attribute. The ``dense`` field (the integrator's dense output, a
  function rather than data) and other callables are not written. Metadata attributes name the
  dataclass (``kind``), the schema version (``pnrotor_schema``), ``pnrotor_version`` and ``created``.
* `read(path)` rebuilds the same dataclass, bitwise: arrays with their dtype and bytes, numbers as
  Python ``int``/``float``/``bool``, strings exactly, after checking the run's layout (`layout_problems`: every
  field present with its type, the arrays of `ARRAYS` with their dtype, shape and finite values, the inputs
  and statistics of `REQUIRED_KEYS`); `write` checks the same before writing, so what it writes reads back.
* A streamed result (``pnrotor.stream(...).modes()`` and the like, `_streamed`) is written as its whole run would
  be, a block of samples at a time (`_put_streamed`): files larger than memory.
* Writes are atomic. The file is built under a temporary name beside the target,
  ``NAME.HOST.PID.XXXXXXXX.pnrotor-tmp``, fsynced (the writeback of each large dataset starts in a background thread
  while the next is written), then published as the target: linked to its name (`os.link`) if it is new, renamed
  over it (`os.replace`) with overwrite. Any exception,
  Ctrl-C included, removes the temporary file; only a hard kill (SIGKILL, power loss) can leave one,
  and the target is then absent or still the old complete file; the next write of the same target on
  that host removes the temporary files of writers no longer alive.
* Batch files hold one run per top-level group (`list_runs`). `batch(path)` is the way to write many runs:
  a context manager whose `Batch` adds each run (`Batch.add`, or `Batch.copy_from` another file, which reads the
  run first and copies only one `read` accepts, unless told the source is checked) to the
  temporary file, at the cost of that run alone, and renames the file into place on leaving the block
  without an exception. ``batch(path, append=True)`` adds runs to an existing batch file, which it copies
  to the temporary name once; ``write(..., group=NAME)`` adds one run that way, so each such call costs a
  copy of the file. One writer per file at a time.

Files are written in HDF5's 1.10 format (``libver=("v110", "v110")``: readable by HDF5 1.10 and later),
whose object headers carry checksums, so damaged metadata or attributes are an error on reading; damaged
data are one too with the default ``checksum=True`` (Fletcher-32 per chunk).  Reading checks that the file
exists, is HDF5, is not truncated, is a pnrotor file and has a schema version this pnrotor knows, then the
layout of the run, and says which of these failed (`FileNotFoundError`, `IsADirectoryError` or one
`ValueError` naming the file and every problem found); whatever else damage makes HDF5 raise while reading
becomes a `ValueError` naming the file, never a traceback.
"""

import dataclasses
import os
from contextlib import ExitStack, contextmanager
from datetime import datetime, timezone
from pathlib import Path
from typing import NamedTuple

import h5py
import numpy as np

from pnrotor import __version__
from pnrotor.io import atomic
from pnrotor.io import journal as journal_file
from pnrotor.io.hdf5_read import (BATCH, NOT_FIELDS, SCHEMA_VERSION, SEQUENCES, STRINGS_CRC, attributes_of,
                                  attr_of, check_metadata, check_schema, defaulted, get_fields, list_runs, metadata,
                                  open_file, opened, read, run_group, run_names, strings_crc, valid_name)
from pnrotor.results import ARRAYS, KINDS, NOT_WRITTEN, REQUIRED_KEYS, UNITS, Array, check, layout_problems
from pnrotor.results.schema import ARRAY_KINDS, is_strings

__all__ = ["write", "read", "batch", "Batch", "Journaled", "image", "concatenate", "metadata", "list_runs", "check",
           "layout_problems", "valid_name", "KINDS", "ARRAYS", "UNITS", "REQUIRED_KEYS", "NOT_WRITTEN", "Array",
           "SCHEMA_VERSION", "BATCH", "COMPRESSIONS"]

COMPRESSIONS = (None, "gzip", "lzf")

_CHUNK_BYTES = 1 << 20  # chunks of at most about 1 MiB along the first (time) axis
_WRITEBACK_BYTES = 1 << 20  # a dataset this large starts the writeback of the file to disk in the background
_GZIP_LEVEL = 1  # on 10⁶-sample PN-like data level 4 saved 1.5% of the size for 1.7× the write time
_STREAM_SAMPLES = 1 << 17  # samples per block of a streamed run: a multiple of each of its chunks (of <= 1 MiB)


# --------------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------------


def write(path, run, *, overwrite=False, compression=None, checksum=True, group=None):
    """Write the run dataclass `run` to `path` atomically and return the path.

    ``group=None`` makes a one-run file; ``group=NAME`` adds the run as group NAME of a batch file (created
    if absent) with ``batch(path, append=True)``, which copies an existing file: to write many runs, use
    `batch`. An existing file, or an existing run NAME in a batch file, is replaced only with
    ``overwrite=True``. ``compression`` is None, ``"gzip"`` (portable) or ``"lzf"`` (fast; readers need
    h5py or the lzf filter plugin).

    ``checksum=True`` (the default) stores each array in chunks with a Fletcher-32 checksum (HDF5's filter,
    checked by every HDF5 reader): a damaged byte is then an error on reading (`ValueError` from `read`)
    instead of a wrong number. ``checksum=False``, for scratch files, stores the arrays contiguous when
    uncompressed, HDF5 writing their own bytes, and writes faster (measurements in docs/hdf5-schema.md).
    Files written either way read the same.

    The run is checked first as `read` checks it (`layout_problems`: a `ValueError` naming the run's type
    and every problem, e.g. a NaN in ``v``), so that every file written reads back.

    A streamed result (``pnrotor.stream(...).evolution()``, ``.modes(...)``, ``.polarizations(...)``) is computed and
    written a block of samples at a time into chunked datasets (or contiguous ones, with ``checksum=False`` and no
    compression), each block checked as a run is: the file is the one its ``compute()`` would give, and needs
    memory for one block, not for the run (docs/hdf5-schema.md).
    """
    path = Path(path)
    if _streamed(run):
        first = _first_block(run)
    else:
        first = None
        _check_run(run)
    _check_compression(compression)
    _check_checksum(checksum)
    if group is not None:
        _check_name(group, "group")
        with batch(path, overwrite=overwrite, compression=compression, checksum=checksum, append=True) as runs:
            runs.add(group, run)  # checks the run
        return path
    atomic.check_target(path, overwrite)
    atomic.check_space(path, _run_bytes(run) if first is None else _streamed_bytes(run, first), compression)
    with _replacing(path, overwrite) as f:
        if first is None:
            _put_run(f, run, compression, checksum)
        else:
            _put_streamed(f, run, first, compression, checksum)
    return path


def _streamed(run):
    """Whether `run` is a streamed result (`pnrotor.stream(...).modes()` and the like): not a run dataclass, but
    ``len(run)`` samples and ``run.block(lo, hi)``, the run dataclass of samples lo ... hi-1, which `write` and
    `Batch.add` write block by block."""
    return not dataclasses.is_dataclass(run) and callable(getattr(run, "block", None))


def image(run):
    """The bytes of the file `write` would write for the run dataclass `run` (checked as it checks it; no compression,
    checksums on), built in memory: for a process that computes a run and hands it to another to store (a population's
    chunks)."""
    import io

    _check_run(run)
    buffer = io.BytesIO()
    with h5py.File(buffer, "w", libver=("v110", "v110")) as f:
        _put_run(f, run, None, True)
    return buffer.getvalue()


@contextmanager
def batch(path, *, overwrite=False, compression=None, checksum=True, append=False, durable=True):
    """Write many runs into the batch file `path`, atomically: a context manager that yields a `Batch`.

    ::

        with pnrotor.hdf5.batch("runs.h5") as runs:
            for name, run in results:
                runs.add(name, run)

    The runs go into a file under a temporary name beside `path` (``NAME.HOST.PID.XXXXXXXX.pnrotor-tmp``), each at
    the cost of writing that run, whatever the size of the file. Leaving the block without an exception
    fsyncs it and renames it to `path`; an exception (Ctrl-C included) removes it, and `path` stays as it
    was. A batch to which no run was added writes nothing.

    An existing `path` is refused (`FileExistsError`, before the block runs) unless ``overwrite=True``,
    which replaces it with the new batch. With ``append=True`` the runs are added to the existing batch
    file `path` instead (which is copied to the temporary name at the first run added: the only cost that
    grows with the file); an existing run is then replaced only with ``overwrite=True``. ``compression``
    and ``checksum`` apply to the runs `Batch.add` writes, as in `write`. ``durable=False`` skips the fsyncs
    of the file and its folder, for scratch files that need not survive a crash (after power loss such a
    file can be missing or incomplete).
    """
    path = Path(path)
    _check_compression(compression)
    _check_checksum(checksum)
    existing = None
    if append and path.is_file():
        with opened(path) as f:
            if attr_of(f, "kind") != BATCH:
                raise ValueError(f"{path} holds a single run, not a batch; add runs to another file")
            existing = set(run_names(f))
    else:
        atomic.check_target(path, overwrite)
    try:
        with ExitStack() as stack:
            runs = Batch(path, compression, overwrite, existing, durable, stack, checksum)
            yield runs
            if not runs.names:
                raise _NoRuns  # removes the temporary file if a failed first run opened it
    except _NoRuns:
        pass


class _NoRuns(Exception):
    """Leaves a `batch` to which no run was added without writing it."""


class Batch:
    """A batch file being written, as yielded by `batch`: each run added becomes a top-level group.

    ``names`` lists the runs added, in order; ``len(batch)`` is their number. A name can be added once. If
    `add` or `copy_from` raises, the batch holds no run of that name (nor the one of the file it was to
    replace) and can go on."""

    def __init__(self, path, compression, overwrite, existing, durable, stack, checksum=True):
        self.path, self.compression, self.checksum, self.names = path, compression, checksum, []
        self._overwrite, self._existing, self._durable, self._stack = overwrite, existing, durable, stack
        self._file, self._added = None, set()

    def __len__(self):
        return len(self.names)

    def add(self, name, run):
        """Write the run dataclass `run` (or a streamed result, block by block) as the run `name`, by the rules of
        `write` (checked as it checks)."""
        if _streamed(run):
            first = _first_block(run)
            atomic.check_space(self.path, _streamed_bytes(run, first), self.compression)
            with self._adding(name) as f:
                _put_streamed(f.create_group(name), run, first, self.compression, self.checksum)
            return
        _check_run(run)
        atomic.check_space(self.path, _run_bytes(run), self.compression)
        with self._adding(name) as f:
            _put_run(f.create_group(name), run, self.compression, self.checksum)

    def copy_from(self, source, group, name=None, *, verify=True):
        """Copy the run `group` of the pnrotor file `source` (``"/"`` for a one-run file) as the run `name`
        (default: `group`), as stored: HDF5 copies its datasets' bytes, their compression included, after
        checking the free space as `add` does.  With `verify` the run is first read as `read` reads it (layout,
        checksums, the CRC of its strings), so a run `read` refuses is not copied (a ValueError naming `source`);
        ``verify=False`` is for a source already read or just written by pnrotor (a run of 10⁴ samples took
        ~13 ms to read, several times its copy)."""
        name = group if name is None else name
        if verify:
            read(source, group)
        with open_file(source) as f:
            check_schema(f, source)
            run = run_group(f, source, group)
            stored = []
            run.visititems(lambda _, item: stored.append(item.id.get_storage_size())
                           if isinstance(item, h5py.Dataset) else None)
            atomic.check_space(self.path, sum(stored))
            with self._adding(name) as target:   # errors here are the target's, not "source is corrupt"
                f.copy(run, target, name)

    @contextmanager
    def _adding(self, name):
        """Yield the open temporary file, without a run `name`, for the caller to write it (removed again if
        that raises)."""
        _check_name(name, "run name")
        if name in self._added:
            raise ValueError(f"run {name!r} was already added to this batch of {self.path}")
        if self._existing is not None and name in self._existing and not self._overwrite:
            raise FileExistsError(
                f"{self.path} already has run {name!r}; pass overwrite=True (--overwrite) to replace it"
            )
        if self._file is None:
            copy = self._existing is not None
            self._file = self._stack.enter_context(_replacing(self.path, self._overwrite or copy, copy, self._durable))
            if not copy:
                _put_metadata(self._file, BATCH)
        if name in self._file:
            del self._file[name]
        try:
            yield self._file
        except BaseException:
            if name in self._file:
                del self._file[name]
            raise
        self.names.append(name)
        self._added.add(name)


class Journaled:
    """A batch file grown in place, run by run, that a process death leaves as of its last `add` (`pnrotor.io.journal`;
    ``pnrotor evolve --batch`` builds its file so, in ``OUTPUT.parts``): each run's bytes are written once, and
    `publish` gives the finished file its name.  Opening it completes or undoes what a death interrupted.  A
    `ValueError` (a run `write` refuses) or any other exception in `add` or `remove` leaves the file as it was."""

    def __init__(self, path, journal, *, compression=None, checksum=True):
        _check_compression(compression)
        _check_checksum(checksum)
        self.path, self.journal, self.compression, self.checksum = Path(path), Path(journal), compression, checksum
        self._committed = journal_file.recover(self.path, self.journal)

    def names(self):
        """The runs in the file (its top-level groups), sorted."""
        return list_runs(self.path) if self._committed else []

    def add(self, runs):
        """Write the runs {name: run dataclass} (checked first as `write` checks them), in one commit."""
        for name, run in runs.items():
            _check_name(name, "run name")
            _check_run(run)
        atomic.check_space(self.path, sum(_run_bytes(run) for run in runs.values()), self.compression)
        self._commit(lambda f: [_put_run(f.create_group(name), run, self.compression, self.checksum)
                                for name, run in runs.items()])

    def remove(self, names):
        """Remove the runs `names` from the file, in one commit (their bytes stay, unreferenced)."""
        self._commit(lambda f: [f.__delitem__(name) for name in names if name in f])

    def _commit(self, change):
        try:
            with journal_file.JournaledFile(self.path, self.journal, self._committed) as file:
                with h5py.File(file, "r+" if self._committed else "w", libver=("v110", "v110")) as f:
                    if not self._committed:
                        _put_metadata(f, BATCH)
                    change(f)
                file.commit()
        finally:   # after a failure, the file as of the last commit (or of this one, if its journal was written)
            self._committed = journal_file.recover(self.path, self.journal)

    def publish(self, path, overwrite):
        """fsync the file and give it the name `path` (`pnrotor.io.atomic.publish`), then fsync its folder."""
        path = Path(path)
        atomic.fsync(self.path)
        atomic.publish(self.path, path, overwrite)
        atomic.fsync(path.parent)
        self.journal.unlink(missing_ok=True)


def concatenate(path, sources, *, overwrite=False, compression=None, checksum=True):
    """Write the one-run files `sources` (pnrotor files of one kind, e.g. the chunks of a population) as one run at
    `path`, atomically as `write` does, and return the path: each array of `ARRAYS` with N samples along its first
    axis is the concatenation of the sources' in their order; every other field is the first source's.

    The first source is read as `read` reads it (checked); each other one must hold the same kind and fields, with
    the same values but for its arrays of samples, and those of the first's dtype and shape but for their length (a
    ValueError naming it otherwise).  Their bytes are copied as stored, one source at a time, so the memory taken is
    that of the largest, whatever the total (their checksums are checked as HDF5 reads them, but the layout of the
    others is not checked again: a population's chunks were checked as they were written).  ``compression`` and
    ``checksum`` as in `write`."""
    path, sources = Path(path), [Path(source) for source in sources]
    if not sources:
        raise ValueError("concatenate needs at least one source file")
    _check_compression(compression)
    _check_checksum(checksum)
    atomic.check_target(path, overwrite)
    first = read(sources[0])
    kind = _kind_of(first)
    stacked = {name: spec for name, spec in ARRAYS.get(kind, {}).items() if spec.shape[:1] == ("N",)}
    if not stacked:
        raise ValueError(f"runs of kind {kind} have no arrays of samples to concatenate")
    lengths, widths = [], {}
    for source in sources:   # the length of each and the widest string of each column, from the files' metadata
        with opened(source) as f:
            lengths.append(f[next(iter(stacked))].shape[0])
            for name, spec in stacked.items():
                if spec.dtype == "str":
                    widths[name] = max(widths.get(name, 1), f[name].dtype.itemsize)
    values = _fields(first)
    for name, spec in stacked.items():
        array = _item(values, name)
        dtype = h5py.string_dtype("utf-8", widths[name]) if spec.dtype == "str" else array.dtype
        _set(values, name, _Unwritten((sum(lengths),) + array.shape[1:], np.dtype(dtype)))
    template = type(first)(**values)
    others = {name: value for name, value in _fields(first).items() if name not in NOT_WRITTEN and not callable(value)}
    for name in stacked:
        _set(others, name, None)
    atomic.check_space(path, _run_bytes(template), compression)
    with _replacing(path, overwrite) as out:
        _put_run(out, template, compression, checksum)
        start = 0
        for source, length in zip(sources, lengths):
            with opened(source) as f:
                attributes = attributes_of(f)
                check_metadata(attributes, source)
                found = get_fields(f, attributes, skip=NOT_FIELDS, leave=stacked)
                for name in stacked:
                    _set(found, name, None)
                if attributes["kind"] != kind or not _same(found, others):
                    raise ValueError(f"{source} differs from {sources[0]} in more than its arrays of samples: not "
                                     "concatenated")
                for name, spec in stacked.items():
                    data = f[name][...]
                    if spec.dtype == "str" and h5py.check_string_dtype(f[name].dtype) is None or \
                            spec.dtype != "str" and data.dtype != out[name].dtype or \
                            data.shape != (length,) + out[name].shape[1:]:
                        raise ValueError(f"{source}: dataset {name!r} is {data.dtype} {data.shape}, not "
                                         f"{out[name].dtype} of {length} samples as its length and {sources[0]} say")
                    out[name][start:start + length] = data
            start += length
    return path


class _Unwritten(NamedTuple):
    """An array that `_dataset` creates empty, of this shape and dtype, to be written in slices (`concatenate`)."""

    shape: tuple
    dtype: np.dtype

    ndim = property(lambda self: len(self.shape))
    size = property(lambda self: int(np.prod(self.shape)))
    itemsize = property(lambda self: self.dtype.itemsize)
    nbytes = property(lambda self: self.size * self.itemsize)


def _fields(run):
    """The fields of the run dataclass `run`, name → value, its dicts copied."""
    values = {field.name: getattr(run, field.name) for field in dataclasses.fields(run)}
    return {name: dict(value) if isinstance(value, dict) else value for name, value in values.items()}


def _item(values, name):
    """The value ``values[name]``, or ``values[GROUP][KEY]`` for a name ``GROUP/KEY``."""
    group, _, key = name.rpartition("/")
    return (values[group] if group else values)[key]


def _set(values, name, value):
    group, _, key = name.rpartition("/")
    (values[group] if group else values)[key] = value


def _same(a, b):
    """Whether two fields' values are equal: dicts item by item, arrays in shape and bytes, NaN equal to NaN."""
    if isinstance(a, dict) or isinstance(b, dict):
        return isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and np.asarray(a).tobytes() == np.asarray(b).tobytes()
    return a == b or a != a and b != b


def _check_run(run):
    """Raise unless the run dataclass `run` is of a kind `write` writes (`TypeError`) and one `read` would accept
    back (`check`'s `ValueError`)."""
    kind = _kind_of(run)
    check(run)
    return kind


# --------------------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------------------


def _kind_of(run):
    cls = type(run)
    if not dataclasses.is_dataclass(cls) or KINDS.get(cls.__name__) != f"{cls.__module__}:{cls.__qualname__}":
        raise TypeError(f"pnrotor.hdf5 writes the run types {sorted(KINDS)}, not {cls.__qualname__}")
    return cls.__name__


def _check_name(name, what):
    if not isinstance(name, str):
        raise TypeError(f"{what} must be a string, not {type(name).__name__}")
    if not valid_name(name):
        raise ValueError(f"{what} {name!r} is not a valid HDF5 name (non-empty, no '/', not '.')")


def _check_compression(compression):
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be one of {COMPRESSIONS}, not {compression!r}")


def _check_checksum(checksum):
    if not isinstance(checksum, bool):
        raise TypeError(f"checksum must be True or False, not {checksum!r}")


def _run_bytes(run):
    """Bytes of the arrays of the run dataclass `run`."""
    return _array_bytes({field.name: getattr(run, field.name) for field in dataclasses.fields(run)})


def _array_bytes(value):
    """Bytes of the numpy arrays in `value` and in the dicts it holds."""
    if isinstance(value, (np.ndarray, _Unwritten)):
        return value.nbytes
    if isinstance(value, dict):
        return sum(_array_bytes(item) for item in value.values())
    return 0


@contextmanager
def _replacing(path, overwrite, copy=False, durable=True):
    """Yield an `h5py.File` open for writing on :func:`pnrotor.io.atomic.replaced`'s temporary file beside `path`:
    new, or with `copy` a copy of `path`, published as `path` on leaving without an exception (fsynced if `durable`),
    removed on an exception.

    If `durable`, each large dataset written (`_dataset`) starts the writeback of the file in a background
    thread (`atomic.Writeback`) while the next one is encoded, so that the final fsync waits for the last ones only
    (10⁶-sample `Evolution`, 136 MB contiguous, best of 5: 0.100 s in h5py with one fsync at the end, 0.084 s
    so)."""
    with atomic.replaced(path, overwrite, copy, durable) as (temporary, writeback):
        with h5py.File(temporary, "r+" if copy else "w", libver=("v110", "v110")) as f:
            if writeback:
                _WRITEBACKS[f.filename] = writeback
            try:
                yield f
            except BaseException:
                # the space the failed write took is freed before HDF5 closes the file: on a full disk
                # its closing flush failed again and again and crashed the process (SIGSEGV, 66 lines
                # of ignored exceptions, the temporary file left; benchmarks/faults.py --sections disk)
                os.truncate(temporary, 0)
                raise
            finally:
                _WRITEBACKS.pop(f.filename, None)


_WRITEBACKS = {}
"""File name of an open temporary file written durably → its `atomic.Writeback`."""


def _put_run(g, run, compression, checksum, written=()):
    """Store the run dataclass `run` in group `g`: its metadata attributes, its fields (but those `written`
    already), then the CRC of its strings."""
    kind = _kind_of(run)
    stamp = _put_metadata(g, kind)
    _put_fields(g, run, UNITS.get(kind, {}), (compression, checksum), written)
    fields = {field.name: getattr(run, field.name) for field in dataclasses.fields(run)}
    g.attrs[STRINGS_CRC] = np.uint32(strings_crc({**stamp, **fields}))


def _first_block(streamed):
    """The first block of a streamed result, checked as `write` checks a run."""
    first = streamed.block(0, min(len(streamed), _STREAM_SAMPLES))
    _check_run(first)
    return first


def _streamed_bytes(streamed, first):
    """Bytes of the arrays of a streamed result of which `first` is the first block (all of them per sample)."""
    return _run_bytes(first) * len(streamed) // len(first.t_seconds)


def _put_streamed(g, streamed, first, compression, checksum):
    """Store the streamed result `streamed` in group `g` as `_put_run` stores its whole run: datasets of its arrays
    (those of `ARRAYS`, each with a time axis "N") created at full length, then filled a block of `_STREAM_SAMPLES`
    at a time (`first` the first, each block checked before it is written), then the other fields and the CRC from
    the first block.  Chunks run along the time axis, `_streamed_chunks`."""
    n, kind = len(streamed), _kind_of(first)
    axes = {name: spec.shape.index("N") for name, spec in ARRAYS[kind].items()}
    datasets = {}
    for name, axis in axes.items():
        array = getattr(first, name)
        shape = array.shape[:axis] + (n,) + array.shape[axis + 1:]
        options = _streamed_chunks(shape, axis, array.itemsize, compression, checksum)
        datasets[name] = g.create_dataset(name, shape=shape, dtype=array.dtype, **options)
    block, lo = first, 0
    while True:
        hi = lo + len(block.t_seconds)
        for name, axis in axes.items():
            datasets[name][(slice(None),) * axis + (slice(lo, hi),)] = getattr(block, name)
        if g.file.filename in _WRITEBACKS:
            _WRITEBACKS[g.file.filename].start()
        if hi == n:
            break
        block, lo = streamed.block(hi, min(n, hi + _STREAM_SAMPLES)), hi
        try:
            _check_run(block)
        except ValueError as error:
            raise ValueError(f"{error} (of samples {lo} ... {lo + len(block.t_seconds) - 1})") from None
    for dataset in datasets.values():
        dataset.flush()   # as `_dataset`: a full disk raises here, not in the dataset's deallocation
    _put_run(g, first, compression, checksum, written=set(datasets))


def _streamed_chunks(shape, axis, itemsize, compression, checksum):
    """`create_dataset` options of a streamed array: with `compression` or `checksum` (as `_dataset`) chunks of 2^k
    steps along the time axis `axis`, at most about 1 MiB and 2^17 steps (a block divides into them), of the whole
    extent of the later axes and one step of the earlier ones (a mode of `Modes.data` is read without the others)."""
    if not (compression or checksum):
        return {}
    step = itemsize * int(np.prod(shape[axis + 1:]))
    length = min(shape[axis], 1 << max(0, (_CHUNK_BYTES // step).bit_length() - 1), _STREAM_SAMPLES)
    return {"chunks": (1,) * axis + (max(length, 1),) + tuple(shape[axis + 1:]), **_filters(compression, checksum)}


def _put_metadata(g, kind):
    """Write the metadata attributes of a run group; return them."""
    stamp = {"kind": kind, "pnrotor_schema": SCHEMA_VERSION, "pnrotor_version": __version__,
             "created": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    for name, value in stamp.items():
        g.attrs[name] = _string(value) if isinstance(value, str) else value
    return stamp


def _put_fields(g, run, units, storage, written=()):
    cls = type(run)
    for field in dataclasses.fields(run):
        if field.name in written:
            continue
        value = getattr(run, field.name)
        if field.name in NOT_WRITTEN or callable(value):
            if field.name not in defaulted(cls):
                raise TypeError(f"{cls.__name__}.{field.name} cannot be written and has no default to read back")
            continue
        if field.name in NOT_FIELDS:
            raise ValueError(f"{cls.__name__}.{field.name}: the name is reserved for pnrotor's metadata")
        _put(g, field.name, value, storage, f"{cls.__name__}.{field.name}")
    for name, text in units.items():
        if isinstance(g.get(name), h5py.Dataset):
            g[name].attrs["units"] = _string(text)


def _put(g, name, value, storage, where):
    """Store `value` under `name` in group `g` by the rules in the module docstring; `storage` is
    (compression, checksum) of the datasets."""
    if isinstance(value, np.str_) or isinstance(value, np.ndarray) and value.dtype.kind == "U":
        value = str(value) if isinstance(value, np.str_) else value.astype(object)   # numpy's strings as str's
    if isinstance(value, dict):
        sub = g.create_group(name)
        for key, item in value.items():
            _check_name(key, f"key of {where}")
            _put(sub, key, item, storage, f"{where}[{key!r}]")
    elif is_strings(value) or isinstance(value, _Unwritten):
        _dataset(g, name, _utf8(value, where) if is_strings(value) else value, *storage)
    elif isinstance(value, np.ndarray) or type(value) in SEQUENCES.values():
        try:
            array = np.asarray(value)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
        if array.dtype.kind not in ARRAY_KINDS or (not isinstance(value, np.ndarray) and array.ndim != 1):
            raise TypeError(f"{where}: only numeric arrays and flat lists/tuples of numbers can be written")
        dataset = _dataset(g, name, array, *storage)
        if not isinstance(value, np.ndarray):
            dataset.attrs["sequence"] = _string(type(value).__name__)
    elif isinstance(value, (bytes, np.bytes_)):
        raise TypeError(f"{where}: cannot write bytes; give text as a str")
    elif value is None or isinstance(value, (str, bool, int, float, complex, np.generic)):
        try:
            g.attrs[name] = h5py.Empty("f8") if value is None else _string(value) if isinstance(value, str) \
                else value
        except (TypeError, ValueError) as error:
            raise ValueError(f"cannot write {where} = {value!r}: {error}") from None
    else:
        raise TypeError(f"{where}: cannot write a {type(value).__name__}")


def _string(text):
    """The string `text` as an attribute's value: fixed-length UTF-8, NUL-padded (so a string may not hold a NUL;
    the empty string is one NUL).  It lives in its object's header, which the 1.10 format checksums: a
    variable-length string would live in HDF5's global heap, which has no checksum, and damage there made HDF5's
    reader loop forever (schema 1; docs/hdf5-schema.md)."""
    encoded = text.encode("utf-8", "surrogatepass")
    if b"\0" in encoded:
        raise ValueError("a string attribute may not contain NUL characters")
    return np.array(encoded, dtype=h5py.string_dtype("utf-8", max(1, len(encoded))))


def _utf8(strings, where):
    """An object array of `str` as the fixed-length UTF-8 array h5py stores (HDF5 pads with NULs, so a string may
    not hold one): fixed-length data are chunked and checksummed like numbers, variable-length strings would
    live in HDF5's global heap, which has no checksum."""
    encoded = [x.encode("utf-8", "surrogatepass") for x in strings.flat]
    if any(b"\0" in x for x in encoded):
        raise ValueError(f"cannot write {where}: its strings may not contain NUL characters")
    dtype = h5py.string_dtype("utf-8", max(1, max(map(len, encoded), default=1)))
    return np.array(encoded, dtype=dtype).reshape(strings.shape)


def _dataset(g, name, array, compression, checksum):
    """Create dataset `name` of `array`: contiguous (HDF5 writes the array's own bytes), or, with
    `compression` or `checksum`, in equal chunks along the first axis."""
    options = {}
    if array.ndim and array.size and (compression or checksum):  # HDF5 chunks need every dimension > 0
        rows = array.shape[0]
        nchunks = -(-rows * array.itemsize * (array.size // rows) // _CHUNK_BYTES)  # ceiling division
        options["chunks"] = (-(-rows // nchunks),) + array.shape[1:]  # equal chunks: no padding in the last
        options.update(_filters(compression, checksum))
    if isinstance(array, _Unwritten):
        dataset = g.create_dataset(name, shape=array.shape, dtype=array.dtype, **options)
    else:
        dataset = g.create_dataset(name, data=array, **options)
    if "chunks" in options:   # HDF5 keeps the last chunks in its cache: written now, a full disk raises here
        dataset.flush()       # rather than in the dataset's deallocation, where h5py can only print it
    if array.nbytes >= _WRITEBACK_BYTES and g.file.filename in _WRITEBACKS:
        _WRITEBACKS[g.file.filename].start()
    return dataset


def _filters(compression, checksum):
    """The filters of a chunked dataset: a Fletcher-32 checksum per chunk with `checksum` (damaged bytes give an
    error, not wrong numbers), shuffle and `compression`."""
    options = {"fletcher32": True} if checksum else {}
    if compression:
        options.update(compression=compression, shuffle=True)
        if compression == "gzip":
            options["compression_opts"] = _GZIP_LEVEL
    return options


# --------------------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------------------


