"""pnrotor's HDF5 files: run results (`FrameHistory`, `Evolution`, `Modes`, `Polarizations`, `PopulationTable`) to and
from disk, atomic and versioned.

This module owns the file format (documented for readers without pnrotor in docs/hdf5-schema.md) and
every write and read of it:

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
import errno
import importlib
import numbers
import os
import re
import signal
import socket
import secrets
import shutil
import threading
import zlib
from collections import Counter
from contextlib import ExitStack, contextmanager
from datetime import datetime, timezone
from pathlib import Path
from typing import NamedTuple

import h5py
import numpy as np

from pnrotor import __version__, approximants, signals

SCHEMA_VERSION = 2
"""Integer version of the layout below; `read` refuses files with a newer one.  Version 2 stores every string
attribute as fixed-length UTF-8 (`_string`), version 1 as variable-length strings in HDF5's global heap; both are
read."""

KINDS = {
    "FrameHistory": "pnrotor.history:FrameHistory",
    "Evolution": "pnrotor.pn.evolve:Evolution",
    "Modes": "pnrotor.waveform.modes:Modes",
    "Polarizations": "pnrotor.waveform.polarizations:Polarizations",
    "PopulationTable": "pnrotor.batch.population:PopulationTable",
}
"""The ``kind`` attribute → ``module:class`` of the dataclass it names, imported when a file is read."""

BATCH = "batch"
"""``kind`` of the root of a batch file, whose top-level groups are runs."""

COMPRESSIONS = (None, "gzip", "lzf")

NOT_WRITTEN = frozenset({"dense"})
"""Fields that are functions of the integrator rather than data; `read` leaves them at their default."""

_METADATA = ("kind", "pnrotor_schema", "pnrotor_version", "created")
_STRINGS_CRC = "pnrotor_strings_crc32"
"""Attribute of a run group: `_strings_crc` of the run, written after everything else; files before it lack it."""
_NOT_FIELDS = _METADATA + (_STRINGS_CRC,)
"""The attributes of a run group that are not fields of its dataclass."""
_SEQUENCES = {"list": list, "tuple": tuple}
_ARRAY_KINDS = "biufc"  # numpy dtype kinds stored as datasets: bool, signed, unsigned, float, complex
_CHUNK_BYTES = 1 << 20  # chunks of at most about 1 MiB along the first (time) axis
_WRITEBACK_BYTES = 1 << 20  # a dataset this large starts the writeback of the file to disk in the background
_GZIP_LEVEL = 1  # on 10⁶-sample PN-like data level 4 saved 1.5% of the size for 1.7× the write time
_TEMPORARY_SUFFIX = ".pnrotor-tmp"
_STREAM_SAMPLES = 1 << 17  # samples per block of a streamed run: a multiple of each of its chunks (of <= 1 MiB)



class Array(NamedTuple):
    """How an array field of a run is stored: its ``shape``, each entry an int, ``"N"`` (the number of samples,
    the same in every array of the run) or a name in `_DIMENSIONS`; its ``units`` attribute; its ``dtype``
    (either byte order; ``"str"``: a numpy object array of `str`, stored as fixed-length UTF-8).  Its values
    must be finite unless ``finite`` is False (float and complex arrays; NaN then marks an absent value); with
    ``rotors`` each row along the last axis is a rotor, its squared norm a normal float64 (not zero, nor so small
    or large that the kernels dividing by it would fail; a row of NaN where NaN is allowed)."""

    shape: tuple
    units: str
    dtype: str = "float64"
    finite: bool = True
    rotors: bool = False


_M = "M (G M / c^3, total mass M)"
_ROTOR = Array(("N", 4), (
    "1; scalar-first unit quaternion (w, x, y, z), sign-continuous in time; "
    "frame vectors are R x R^-1, R y R^-1, R z R^-1 (Boyle 2016, eq:rotor-rotation)"
), rotors=True)
_STATE = {
    "t": Array(("N",), _M + "; t = 0 at f_ref"),
    "t_seconds": Array(("N",), "s; t = 0 at f_ref"),
    "v": Array(("N",), "c; PN parameter v = (M Omega_orb)^(1/3)"),
    "Phi": Array(("N",), "rad; orbital phase, 0 at f_ref"),
    "chi1": Array(("N", 3), "1; dimensionless spin S1 / m1^2, inertial-frame components"),
    "chi2": Array(("N", 3), "1; dimensionless spin S2 / m2^2, inertial-frame components"),
    "R": _ROTOR,
    "ell_hat": Array(("N", 3), "1; unit normal to the orbital plane, inertial-frame components"),
}
"""The state of a binary in a `PopulationTable`, one per row: at its target, and where its integration stopped."""
ARRAYS = {
    "FrameHistory": {
        "t": Array(("N",), "time unit of the angular velocity (omega in rad per unit)"),
        "R": _ROTOR,
    },
    "Evolution": {
        "t": Array(("N",), _M),
        "t_seconds": Array(("N",), "s"),
        "v": Array(("N",), "c; PN parameter v = (M Omega_orb)^(1/3)"),
        "Phi": Array(("N",), "rad; orbital phase"),
        "chi1": Array(("N", 3), "1; dimensionless spin S1 / m1^2, inertial-frame components"),
        "chi2": Array(("N", 3), "1; dimensionless spin S2 / m2^2, inertial-frame components"),
        "ell_hat": Array(("N", 3), "1; unit normal to the orbital plane, inertial-frame components"),
        "R": _ROTOR,
    },
    "Modes": {
        "t": Array(("N",), _M),
        "t_seconds": Array(("N",), "s"),
        "data": Array(("modes", "N"), "strain at distance_Mpc, or r h / M if distance_Mpc is absent; row k is mode "
                      "(l, m) with k = l (l + 1) + m - 4, l = 2 ... ell_max (LALSuite's convention)", "complex128"),
        "R": _ROTOR,
        "Phi": Array(("N",), "rad; orbital phase"),
    },
    "Polarizations": {
        "t_seconds": Array(("N",), "s; t = 0 at f_ref"),
        "h_plus": Array(("N",), "strain at distance_Mpc; h+ - i hx = sum of h_lm -2Y_lm(inclination, pi/2 - phi_ref) "
                        "(LALSuite's convention)"),
        "h_cross": Array(("N",), "strain at distance_Mpc"),
    },
    "PopulationTable": {
        "name": Array(("N",), "the row's name (the batch table's name column, or its default name)", "str"),
        **{name: array._replace(units=array.units + "; at the row's target, NaN where reached is false", finite=False)
           for name, array in _STATE.items()},
        "termination": Array(("N",), "why the integration to this state stopped (f_max, f_min or the end of the "
                             "inspiral, as pnrotor.evolve names it)", "str"),
        "reached": Array(("N",), "whether the integration reached the row's target (f_max, f_min or the end of the "
                         "inspiral)", "bool"),
        **{"stopped_at/" + name: array._replace(finite=False) for name, array in _STATE.items()},
        "message": Array(("N",), "the termination's explanation", "str"),
        "nsteps": Array(("N",), "step attempts of the integration that gave the state", "int64"),
        "nfev": Array(("N",), "right-hand-side evaluations of that integration", "int64"),
        "inputs/row": Array(("N",), "number of the row in the batch table (1 = the first binary)", "int64"),
        "inputs/m1_Msun": Array(("N",), "Msun"),
        "inputs/m2_Msun": Array(("N",), "Msun"),
        "inputs/chi1": Array(("N", 3), "1; dimensionless spin of body 1 at f_ref, inertial frame"),
        "inputs/chi2": Array(("N", 3), "1; dimensionless spin of body 2 at f_ref, inertial frame"),
        "inputs/f_ref_Hz": Array(("N",), "Hz; GW frequency where the spins are given, t = 0"),
        "inputs/f_min_Hz": Array(("N",), "Hz; the state is the one at this GW frequency, integrated backward "
                                 "(NaN: no f_min)", finite=False),
        "inputs/f_max_Hz": Array(("N",), "Hz; the state is the one at this GW frequency (NaN: no f_max; with "
                                 "neither, the end of the inspiral)", finite=False),
        "inputs/approximant": Array(("N",), approximants.names(), "str"),
        "inputs/pn_order": Array(("N",), "PN order of the nonspinning terms"),
        "inputs/spin_orbit_order": Array(("N",), "PN order of the spin-orbit terms (-1: none; NaN: pnrotor.evolve's "
                                         "default)", finite=False),
        "inputs/spin_spin_order": Array(("N",), "PN order of the spin-spin terms (-1: none; NaN: pnrotor.evolve's "
                                        "default)", finite=False),
        "inputs/precession": Array(("N",), "spin precession model", "str"),
        "inputs/atol": Array(("N",), "absolute tolerance of the integrator"),
        "inputs/lambda1": Array(("N",), "1; dimensionless tidal deformability of body 1"),
        "inputs/lambda2": Array(("N",), "1; dimensionless tidal deformability of body 2"),
        "inputs/tidal_order": Array(("N",), "PN order of the tidal terms (0, 5 or 6; NaN: pnrotor.evolve's default)",
                                    finite=False),
    },
}
_POPULATION = tuple(name for name in ARRAYS["PopulationTable"] if name != "name" and not name.startswith("inputs/"))
ARRAYS["Population"] = {name: ARRAYS["PopulationTable"][name]._replace(
    shape=("N", "K", *ARRAYS["PopulationTable"][name].shape[1:]), finite=False) for name in _POPULATION}
"""The array fields of each run kind (`Array`): what `write` and `read` check, and their ``units``.  A name
``GROUP/NAME`` is the array NAME of the run's dict field GROUP (a dataset of that subgroup).  `pnrotor.Population`,
not a kind of file (its file is a ``PopulationTable``), is checked by the same rules when it is built: the
fields it shares with a ``PopulationTable``, with a second axis K over a list of target frequencies where it has
one, NaN allowed (an invalid binary)."""

_DIMENSIONS = {"modes": lambda values: (values["ell_max"] + 1) ** 2 - 4,
               "K": lambda values: values["t"].shape[1] if values["t"].ndim == 2 else None}
"""Named dimensions of `ARRAYS` other than N, from the run's other values (checked first); None: the run has no
such axis."""

UNITS = {kind: {name: array.units for name, array in arrays.items()} for kind, arrays in ARRAYS.items()}
"""``units`` attribute written on a run's datasets of `ARRAYS`, by kind and field (``GROUP/NAME`` in a subgroup)."""

_EVOLUTION_INPUTS = ("m1_Msun", "m2_Msun", "kappa1", "kappa2", "ell_hat", "n_hat", "state", "spin_content",
                     "M_seconds", "v_ref", "f_min_Hz")
REQUIRED_KEYS = {
    "Evolution": {
        "inputs": _EVOLUTION_INPUTS,
        "stats": ("nfev", "wall_time_s", "t_initial", "t_final", "v_final", "termination_backward"),
    },
    "Modes": {"inputs": ("M_seconds", "ell_max")},
}
"""Keys a run's dict fields must hold, by kind: those pnrotor itself reads from a stored run
(`Evolution.span`, `Evolution.f_gw`, `pnrotor.modes`, `Modes.polarizations`, a resumed batch)."""


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
    _check_target(path, overwrite)
    _check_space(path, _run_bytes(run) if first is None else _streamed_bytes(run, first), compression)
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


def image(run, *, compression=None, checksum=True):
    """The bytes of the file `write` would write for the run dataclass `run` (checked as it checks it), built in
    memory: for a process that computes a run and hands it to another to store (a population's chunks)."""
    import io

    _check_run(run)
    _check_compression(compression)
    _check_checksum(checksum)
    buffer = io.BytesIO()
    with h5py.File(buffer, "w", libver=("v110", "v110")) as f:
        _put_run(f, run, compression, checksum)
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
        with _open(path) as f:
            if _attr(f, "kind") != BATCH:
                raise ValueError(f"{path} holds a single run, not a batch; add runs to another file")
            existing = set(_runs(f))
    else:
        _check_target(path, overwrite)
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
            _check_space(self.path, _streamed_bytes(run, first), self.compression)
            with self._adding(name) as f:
                _put_streamed(f.create_group(name), run, first, self.compression, self.checksum)
            return
        _check_run(run)
        _check_space(self.path, _run_bytes(run), self.compression)
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
        with _open_file(source) as f:
            _check_schema(f, source)
            run = _run_group(f, source, group)
            stored = []
            run.visititems(lambda _, item: stored.append(item.id.get_storage_size())
                           if isinstance(item, h5py.Dataset) else None)
            _check_space(self.path, sum(stored))
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
    _check_target(path, overwrite)
    first = read(sources[0])
    kind = _kind_of(first)
    stacked = {name: spec for name, spec in ARRAYS.get(kind, {}).items() if spec.shape[:1] == ("N",)}
    if not stacked:
        raise ValueError(f"runs of kind {kind} have no arrays of samples to concatenate")
    lengths, widths = [], {}
    for source in sources:   # the length of each and the widest string of each column, from the files' metadata
        with _open(source) as f:
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
    _check_space(path, _run_bytes(template), compression)
    with _replacing(path, overwrite) as out:
        _put_run(out, template, compression, checksum)
        start = 0
        for source, length in zip(sources, lengths):
            with _open(source) as f:
                attributes = _attributes(f)
                _check_metadata(attributes, source)
                found = _get(f, attributes, skip=_NOT_FIELDS, leave=stacked)
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


def read(path, group=None):
    """The run stored in `path` (in its batch group `group`), as the dataclass it was written from.

    Before the dataclass is built the run's layout is checked: its metadata attributes (`metadata`), its
    ``kind`` (a registered dataclass, `KINDS`) and then `layout_problems`: every stored field of that
    dataclass present, no other, each of the type its annotation names (a dataset for an array, a group for
    a dict, an attribute of that type otherwise); the arrays of `ARRAYS` of the dtype and shape given there,
    all of the same number of samples N, with finite values; the keys of `REQUIRED_KEYS` in its inputs and
    statistics; the CRC-32 of its string attributes (`_strings_crc`, in files that have it). Any problem
    raises one `ValueError` naming the file (and run) and every problem found, e.g.
    ``run.h5: dataset 'R' has shape (10, 3), expected (10, 4)``."""
    with _open(path) as f:
        g = _run_group(f, path, group)
        where = path if group is None else f"{path} run {group!r}"
        attributes = _attributes(g)   # each read once: HDF5 attribute reads are most of the time of a small file
        _check_metadata(attributes, where)
        cls = _class_of(attributes["kind"], where)
        values = _get(g, attributes, skip=_NOT_FIELDS)
        metadata = {name: _value(attributes[name]) for name in _METADATA}
        crc = attributes.get(_STRINGS_CRC)
        damaged = crc is not None and crc != _strings_crc({**metadata, **values})
        if metadata["pnrotor_schema"] == 1 and hasattr(cls, "from_schema_1"):   # fields added since, derived
            values = cls.from_schema_1(values)
        problems = layout_problems(cls, values)
        if not problems and damaged:
            problems.append("its string attributes are damaged (their CRC-32 is not the one written with them)")
        if problems:
            raise ValueError(f"{where}: {'; '.join(problems)}")
        return cls(**values)


def metadata(path, group=None):
    """The metadata attributes of a run: ``kind``, ``pnrotor_schema``, ``pnrotor_version``, ``created``
    (checked: all four present, the schema version one this pnrotor reads, the others strings)."""
    with _open(path) as f:
        attributes = _attributes(_run_group(f, path, group))
        _check_metadata(attributes, path if group is None else f"{path} run {group!r}")
        return {name: _value(attributes[name]) for name in _METADATA}


def list_runs(path):
    """Names of the runs in a batch file, sorted; ``["/"]`` for a one-run file. Each works as `read`'s group."""
    with _open(path) as f:
        return _runs(f)


def layout_problems(cls, values, scan=True):
    """What is wrong with the run `values` (field name → value, as `read` gets them from a file or `write`
    from a dataclass) of the run dataclass `cls`, as a list of sentences (empty: nothing). Checked:

    * names: every field of `cls` present but those not written (`NOT_WRITTEN`, callable defaults), no other;
    * types, by each field's annotation (`_TYPES`): ``np.ndarray`` a numeric array or an object array of
      `str` (a dataset), ``dict`` a dict (a group), ``str``, ``int``, ``float`` such a scalar (an attribute; an
      int counts as a float, a bool as neither), or ``None`` where that is the default; other annotations are
      not checked;
    * for the kinds in `ARRAYS`, each array's presence (``GROUP/NAME``: in the dict field GROUP), dtype (either
      byte order) and shape, every ``"N"`` the same number of samples (that of most arrays, a tie going to the
      first), and its values finite (where `Array.finite`; with ``scan=False`` only the rotors', each a pass
      over the array, which a kernel that NaN does not harm need not pay for);
    * for the kinds in `REQUIRED_KEYS`, the keys their dict fields must hold.
    """
    problems, kind = [], cls.__name__
    fields = {field.name: field for field in dataclasses.fields(cls)}
    for name in sorted(values.keys() - fields.keys()):
        problems.append(f"{_what(values[name])} {name!r} is not a field of {kind}")
    for name, field in fields.items():
        if name in NOT_WRITTEN or callable(field.default):
            continue
        check, stored_as, expected = _TYPES.get(getattr(field.type, "__name__", field.type), (None, "field", ""))
        if name not in values:
            problems.append(f"{stored_as} {name!r} is missing")
        elif check and not check(values[name]) and not (values[name] is None and field.default is None):
            problems.append(f"{_what(values[name])} {name!r} is {_describe(values[name])}, expected {expected}")
    if problems:
        return problems  # shapes and keys need the right fields
    arrays = {}
    for name, spec in ARRAYS.get(kind, {}).items():
        group, _, key = name.rpartition("/")
        array = values[group].get(key) if group else values[name]
        if _TYPES["ndarray"][0](array):
            arrays[name] = spec, array
        else:
            problems.append(f"dataset {name!r} is missing" if array is None else
                            f"{_what(array)} {name!r} is {_describe(array)}, expected an array")
    sizes = {dim: size(values) for dim, size in _DIMENSIONS.items()
             if any(dim in spec.shape for spec, _ in arrays.values())}
    axes = {name: tuple(d for d in spec.shape if d not in sizes or sizes[d] is not None)
            for name, (spec, array) in arrays.items()}
    lengths = {name: array.shape[axes[name].index("N")] for name, (spec, array) in arrays.items()
               if "N" in axes[name] and array.ndim == len(axes[name])}
    n, count = Counter(lengths.values()).most_common(1)[0] if lengths else (None, 0)
    like = [name for name, length in lengths.items() if length == n]
    sizes["N"] = n
    for name, (spec, array) in arrays.items():
        shape = tuple(d if sizes.get(d, d) is None else sizes.get(d, d) for d in axes[name])
        if spec.dtype == "str":
            if not _is_strings(array):
                problems.append(f"dataset {name!r} is {_describe(array)}, expected strings")
            elif array.shape != shape:
                problems.append(f"dataset {name!r} has shape {_shape(array.shape)}, expected {_shape(shape)}")
        elif array.dtype.newbyteorder("=") != np.dtype(spec.dtype):
            problems.append(f"dataset {name!r} is {array.dtype.name}, expected {np.dtype(spec.dtype).name}")
        elif array.shape != shape:
            others = f" and {count - 1} other array{'s' * (count > 2)}" if count > 1 else ""
            samples = f" (N = {n} samples, as in {like[0]!r}{others})" if lengths.get(name, n) != n else ""
            problems.append(f"dataset {name!r} has shape {_shape(array.shape)}, expected {_shape(shape)}{samples}")
        elif spec.finite and (scan or spec.rotors) and array.dtype.kind in "fc" and not np.isfinite(array).all():
            bad = np.argwhere(~np.isfinite(array))
            at = tuple(bad[0].tolist()) if array.ndim > 1 else int(bad[0, 0])
            problems.append(f"dataset {name!r} has {len(bad)} non-finite value{'s' * (len(bad) > 1)} "
                            f"(NaN or inf), the first at index {at}")
        elif spec.rotors and array.size:
            with np.errstate(over="ignore", under="ignore"):
                norm2 = np.einsum("...i,...i->...", array, array)
            bad = np.argwhere(~((norm2 >= _TINY) & (norm2 <= _HUGE) | np.isnan(norm2)))
            if len(bad):
                at = tuple(bad[0].tolist()) if array.ndim > 2 else int(bad[0, 0])
                problems.append(f"dataset {name!r} has {len(bad)} row{'s' * (len(bad) > 1)} of zero or extreme norm "
                                f"(not a rotor: |R|^2 must be a normal float64), the first at index {at}")
    for name, keys in REQUIRED_KEYS.get(kind, {}).items():
        missing = [key for key in keys if key not in values[name]]
        if missing:
            problems.append(f"group {name!r} lacks {', '.join(map(repr, missing))}")
    return problems


_TINY, _HUGE = np.finfo(np.float64).tiny, np.finfo(np.float64).max
"""The range of a rotor's squared norm: the kernels that read rotors divide by it."""


def _is_strings(value):
    """Whether `value` is a numpy object array of `str` (how a run holds a column of strings)."""
    return (isinstance(value, np.ndarray) and value.dtype.kind == "O"
            and all(isinstance(x, str) for x in value.flat))


_TYPES = {
    "ndarray": (lambda v: isinstance(v, np.ndarray) and (v.dtype.kind in _ARRAY_KINDS or _is_strings(v)), "dataset",
                "a numeric array or an array of strings"),
    "dict": (lambda v: isinstance(v, dict), "group", "a group"),
    "str": (lambda v: isinstance(v, str), "attribute", "a string"),
    "int": (lambda v: isinstance(v, numbers.Integral) and not isinstance(v, bool), "attribute", "an integer"),
    "float": (lambda v: isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)), "attribute", "a number"),
}
"""Annotation of a run field → (check of a value, what stores it, what it must be) for `layout_problems`."""


def _what(value):
    """What a value read from a file was stored as."""
    return "group" if isinstance(value, dict) else "dataset" if isinstance(value, (np.ndarray, list, tuple)) \
        else "attribute"


def _describe(value):
    if isinstance(value, np.ndarray):
        return f"{'an' if value.dtype.name[0] in 'aeiou' else 'a'} {value.dtype.name} array"
    if isinstance(value, dict):
        return "a group"
    if value is None:
        return "empty"
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 40 else text[:37] + '...'}"


def _shape(shape):
    return f"({', '.join(map(str, shape))}{',' * (len(shape) == 1)})"


def check(run, doing="cannot write", scan=True):
    """Raise ``ValueError(f"{doing} this KIND: PROBLEMS")`` unless the result dataclass `run` (a run kind of
    `KINDS`, or a `pnrotor.Population`) passes `layout_problems`: the one check of a result's invariants (its
    fields' types, its arrays' shapes, dtypes and finite values, nonzero rotors, the keys of its dicts), which
    `write` makes before writing (so every file written reads back), `pnrotor.modes` and `Modes`' methods before
    their compiled kernels read the arrays, and `FrameHistory` and `Population` when they are built.  ``scan``
    as for `layout_problems`."""
    values = {field.name: getattr(run, field.name) for field in dataclasses.fields(run)}
    values = {name: value for name, value in values.items() if name not in NOT_WRITTEN and not callable(value)}
    problems = layout_problems(type(run), values, scan)
    if problems:
        raise ValueError(f"{doing} this {type(run).__name__}: {'; '.join(problems)}")


def _check_run(run):
    """Raise unless the run dataclass `run` is of a kind `write` writes (`TypeError`) and one `read` would accept
    back (`check`'s `ValueError`)."""
    kind = _kind_of(run)
    check(run)
    return kind


def _check_metadata(attributes, where):
    """Raise `ValueError` unless the attributes of a run group (`_attributes`) hold the four metadata attributes,
    ``kind``, ``pnrotor_version`` and ``created`` strings (the schema version is checked on opening)."""
    missing = [name for name in _METADATA if name not in attributes]
    wrong = [name for name in ("kind", "pnrotor_version", "created") if name in attributes
             and not isinstance(attributes[name], str)]
    if _STRINGS_CRC in attributes and not isinstance(attributes[_STRINGS_CRC], np.integer):
        wrong.append(_STRINGS_CRC)
    if missing or wrong:
        raise ValueError(f"{where}: " + "; ".join([f"attribute {name!r} is missing" for name in missing]
                                                 + [f"attribute {name!r} is not a "
                                                    + ("number" if name == _STRINGS_CRC else "string")
                                                    for name in wrong]))


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
    if not _valid_name(name):
        raise ValueError(f"{what} {name!r} is not a valid HDF5 name (non-empty, no '/', not '.')")


def _valid_name(name):
    """Whether `name` names a member of a group (rather than a path): non-empty, no '/', not '.'."""
    return isinstance(name, str) and name not in ("", ".") and "/" not in name and "\x00" not in name


def _check_compression(compression):
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be one of {COMPRESSIONS}, not {compression!r}")


def _check_checksum(checksum):
    if not isinstance(checksum, bool):
        raise TypeError(f"checksum must be True or False, not {checksum!r}")


def _check_target(path, overwrite):
    """Raise unless `path` can be written: not a folder, in a folder that exists, new unless `overwrite`."""
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder; give a file name such as {path / 'run.h5'}")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"folder {path.parent} does not exist (writing {path}); create it first")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True (--overwrite) to replace it")


_METADATA_MARGIN = 2 ** 20
"""Bytes of free space `_check_space` keeps beyond a run's arrays, for HDF5's metadata (a run's groups and
attributes take tens of kB)."""


def _check_space(path, need, compression=None):
    """An `OSError` (ENOSPC) naming the folder of `path` and the sizes if `need` bytes of arrays (`_run_bytes`, the
    uncompressed size: what the file holds, and an upper bound of a compressed file's) and `_METADATA_MARGIN` do
    not fit in its free space: a full disk found before a byte is written, not in the middle of a write, where
    HDF5 fails badly (a compressed write to a full tmpfs crashed the process with SIGSEGV after its error;
    `Batch.copy_from` with a few kB free, a double free in HDF5's object copy)."""
    free = shutil.disk_usage(Path(path).parent).free
    if need + _METADATA_MARGIN > free:
        raise OSError(errno.ENOSPC, f"no space for {Path(path).name} in {Path(path).parent}: its arrays need "
                                    f"{_size(need)}{' before compression' * bool(compression)} and its metadata up "
                                    f"to {_size(_METADATA_MARGIN)}, {_size(free)} are free")


def _size(n):
    return f"{n / 2 ** 20:.1f} MiB" if n >= 2 ** 20 else f"{n / 2 ** 10:.1f} KiB"


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
    """Yield an `h5py.File` open for writing under a temporary name beside `path`: new, or with `copy` a copy
    of `path`. Leaving without an exception fsyncs it (if `durable`) and renames it to `path` (refused if
    `path` appeared meanwhile and not `overwrite`); an exception removes it.

    If `durable`, each large dataset written (`_dataset`) starts the writeback of the file in a background
    thread (`_Writeback`) while the next one is encoded, so that the final fsync waits for the last ones only
    (10⁶-sample `Evolution`, 136 MB contiguous, best of 5: 0.100 s in h5py with one fsync at the end, 0.084 s
    so)."""
    temporary = _temporary_beside(path, sweep=durable)
    writeback = _Writeback(temporary) if durable else None
    try:
        with _Interrupts() as interrupts:
            if copy:
                shutil.copyfile(path, temporary)
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
            if writeback:
                writeback.join()
                _fsync(temporary)
            interrupts.check()
            _publish(temporary, path, overwrite)
    except BaseException as error:
        if writeback:
            writeback.join()
        temporary.unlink(missing_ok=True)
        code = _write_failure(error, temporary)
        if code is not None:
            raise OSError(code, f"no space left on the device of {path.parent} while writing {path.name}"
                          if code == errno.ENOSPC else f"{os.strerror(code)} while writing {path}") from None
        raise
    if durable:
        _fsync(path.parent)


def _write_failure(error, temporary):
    """The errno of HDF5's report of a failed system call on the file being written, a RuntimeError or OSError of
    many lines holding ``errno = N`` (a full disk, a file-size limit, a quota), or None: not for a report that
    names another file (``name = '...'``: one the caller opened in the block, a missing source, say)."""
    if not isinstance(error, (OSError, RuntimeError)):
        return None
    text = str(error)
    code = re.search(r"errno = (\d+)", text)
    others = [name for name in re.findall(r"name = '([^']*)'", text) if Path(name).name != temporary.name]
    return int(code.group(1)) if code and not others else None


class _Interrupts:
    """While a file is written (in the main thread): SIGINT, SIGTERM and SIGHUP raise KeyboardInterrupt at
    once, so the temporary file is removed (SIGTERM's and SIGHUP's default would kill the process and leave
    it), and are remembered: one that Python swallowed because it arrived inside h5py's cleanup callbacks
    ("Exception ignored ... KeyboardInterrupt") is raised again by `check` before the file is published.  A
    signal set to be ignored, or that the program handles, is left as it is (`pnrotor.signals`)."""

    def __init__(self):
        self.seen, self.previous = None, {}

    def __enter__(self):
        self.previous = signals.take(self._handle)
        return self

    def _handle(self, signum, frame):
        self.seen = signum
        raise KeyboardInterrupt

    def check(self):
        if self.seen is not None:
            raise KeyboardInterrupt

    def __exit__(self, *exc):
        signals.restore(self.previous)
        return False


def _publish(temporary, path, overwrite):
    """Give the finished `temporary` file the name `path`: os.replace with `overwrite`, else os.link, which
    fails if `path` exists at that instant, so of two writers of a new path exactly one succeeds (a check
    then a rename let both report success); then the temporary name is removed."""
    if overwrite:
        os.replace(temporary, path)
        return
    message = f"{path} appeared while it was written; pass overwrite=True (--overwrite) to replace"
    try:
        os.link(temporary, path)
    except FileExistsError:
        raise FileExistsError(message) from None
    except OSError:  # a filesystem without hard links: check, then rename (not atomic)
        if path.exists():
            raise FileExistsError(message) from None
        os.replace(temporary, path)
        return
    os.unlink(temporary)


_WRITEBACKS = {}
"""File name of an open temporary file written durably → its `_Writeback`."""


class _Writeback:
    """Background fsyncs of a file being written: `start` begins one in a thread unless one is running. The
    final fsync stays the caller's (it waits for the pages these started too); each thread opens the file
    itself, so none touches a descriptor of the writer, and ignores errors (the file may be gone)."""

    def __init__(self, path):
        self.path, self._thread = path, None

    def start(self):
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._fsync, name="pnrotor-writeback", daemon=True)
            self._thread.start()

    def join(self):
        if self._thread is not None:
            self._thread.join()

    def _fsync(self):
        # a signal the kernel hands to this thread would wait for the main thread to return to Python: a
        # Ctrl-C or SIGTERM during a long sleep or write there went unseen (a writer killed with SIGINT
        # under load still ran 60 s later); blocked here, every signal goes to the main thread
        signal.pthread_sigmask(signal.SIG_BLOCK, signal.valid_signals())
        try:
            _fsync(self.path, os.fdatasync)
        except OSError:
            pass


def _put_run(g, run, compression, checksum, written=()):
    """Store the run dataclass `run` in group `g`: its metadata attributes, its fields (but those `written`
    already), then the CRC of its strings."""
    kind = _kind_of(run)
    metadata = _put_metadata(g, kind)
    _put_fields(g, run, UNITS.get(kind, {}), (compression, checksum), written)
    fields = {field.name: getattr(run, field.name) for field in dataclasses.fields(run)}
    g.attrs[_STRINGS_CRC] = np.uint32(_strings_crc({**metadata, **fields}))


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


def _strings_crc(values):
    """CRC-32 of the strings of a run, `values` (name → value, a dict for a group: its metadata and fields, as
    written or as `_get` reads them back), each as ``PATH=VALUE`` with PATH its names from the run group
    (``/inputs/spin_content``), in sorted order, joined by NUL.  HDF5 keeps a variable-length string in its
    global heap, which has no checksum (the object headers of the 1.10 format and the Fletcher-32 of the
    data cover the rest): without this, 4 of 500 bit flips in a small file read back as a wrong
    ``termination`` or input (benchmarks/faults.py).  From the values, not the file: reading the attributes
    again took 3.9 ms per write of a typical run (measured)."""
    items = []

    def walk(group, prefix):
        for name, value in group.items():
            if isinstance(value, dict):
                walk(value, f"{prefix}/{name}")
            elif isinstance(value, str):
                items.append(f"{prefix}/{name}={value}")

    walk(values, "")
    return zlib.crc32("\0".join(sorted(items)).encode("utf-8", "surrogatepass"))


def _put_metadata(g, kind):
    """Write the metadata attributes of a run group; return them."""
    metadata = {"kind": kind, "pnrotor_schema": SCHEMA_VERSION, "pnrotor_version": __version__,
                "created": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    for name, value in metadata.items():
        g.attrs[name] = _string(value) if isinstance(value, str) else value
    return metadata


def _put_fields(g, run, units, storage, written=()):
    cls = type(run)
    for field in dataclasses.fields(run):
        if field.name in written:
            continue
        value = getattr(run, field.name)
        if field.name in NOT_WRITTEN or callable(value):
            if field.name not in _defaulted(cls):
                raise TypeError(f"{cls.__name__}.{field.name} cannot be written and has no default to read back")
            continue
        if field.name in _NOT_FIELDS:
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
    elif _is_strings(value) or isinstance(value, _Unwritten):
        _dataset(g, name, _utf8(value, where) if _is_strings(value) else value, *storage)
    elif isinstance(value, np.ndarray) or type(value) in _SEQUENCES.values():
        try:
            array = np.asarray(value)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
        if array.dtype.kind not in _ARRAY_KINDS or (not isinstance(value, np.ndarray) and array.ndim != 1):
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


_HOST = socket.gethostname().replace(".", "-").replace("/", "-") or "host"


def _temporary_beside(path, sweep=True):
    """Create and return an empty, new file ``NAME.HOST.PID.XXXXXXXX.pnrotor-tmp`` in the folder of `path`,
    after removing those of `path` that writers on this host left when they died (`_sweep`; not for scratch
    files, written by the thousand into one folder, where listing it each time would cost N²)."""
    if sweep:
        _sweep(path)
    while True:
        temporary = path.with_name(f"{path.name}.{_HOST}.{os.getpid()}.{secrets.token_hex(4)}{_TEMPORARY_SUFFIX}")
        try:
            os.close(os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except FileExistsError:
            continue
        return temporary


def _sweep(path):
    """Remove the temporary files of `path` whose writer ran on this host and is no longer alive (a kill -9
    or a power loss leaves them); those of live writers, of other hosts and anything else are kept."""
    prefix = f"{path.name}.{_HOST}."
    try:
        names = os.listdir(path.parent)
    except OSError:
        return
    for name in names:
        if not (name.startswith(prefix) and name.endswith(_TEMPORARY_SUFFIX)):
            continue
        pid = name[len(prefix):].split(".", 1)[0]
        if pid.isdigit() and not _alive(int(pid)):
            try:
                (path.parent / name).unlink()
            except (IsADirectoryError, PermissionError, FileNotFoundError):
                pass


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    return True


def _fsync(path, sync=os.fsync):
    """``sync`` the file at ``path``: os.fsync, or os.fdatasync for `_Writeback`'s background flush of the data
    (the final fsync writes the rest)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        sync(fd)
    finally:
        os.close(fd)


# --------------------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------------------


def _open_file(path):
    """The HDF5 file `path` open for reading, or the error that says what it is instead."""
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder, not a pnrotor HDF5 file")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if not h5py.is_hdf5(path):
        empty = " (it is empty)" if path.stat().st_size == 0 else ""
        raise ValueError(f"{path} is not an HDF5 file{empty}")
    try:
        return h5py.File(path, "r")
    except OSError as error:
        raise ValueError(f"{path} is truncated or corrupt: HDF5 cannot open it ({error})") from None


@contextmanager
def _open(path):
    """Open a pnrotor file for reading, or raise the error that says what it is instead; what HDF5 raises while
    it is read becomes a ValueError naming the file."""
    with _open_file(path) as f:
        try:
            _check_schema(f, path)
            yield f
        except OSError as error:
            if type(error) is not OSError:  # FileExistsError and kin come from the caller, not from HDF5
                raise
            raise ValueError(f"{path} is corrupt: HDF5 cannot read it ({error})") from None
        except (RuntimeError, TypeError, KeyError, IndexError, AttributeError, UnicodeDecodeError) as error:
            # what damaged metadata makes h5py or the rebuilding of the dataclass raise: one clear error
            raise ValueError(f"{path} is corrupt: {type(error).__name__} while reading it ({error})") from None


def _check_schema(g, path):
    if not isinstance(_attr(g, "kind", ""), str):   # compared with strings before the run is read
        raise ValueError(f"{path}: attribute 'kind' is not a string")
    schema = _attr(g, "pnrotor_schema")
    if schema is None:
        raise ValueError(f"{path} is an HDF5 file but not a pnrotor file (no 'pnrotor_schema' attribute)")
    if not isinstance(schema, np.integer) or not 1 <= schema <= SCHEMA_VERSION:
        writer = _value(_attr(g, "pnrotor_version", "an unknown version"))
        newer = isinstance(schema, np.integer) and schema > SCHEMA_VERSION
        raise ValueError(
            f"{path} has pnrotor schema version {_value(schema)!r} (written by pnrotor {writer}); "
            f"pnrotor {__version__} reads schema versions 1 to {SCHEMA_VERSION}"
            + ("; upgrade pnrotor to read it" if newer else "")
        )


def _runs(f):
    if _attr(f, "kind") != BATCH:
        return ["/"]
    return sorted(name for name, g in f.items() if isinstance(g, h5py.Group) and "kind" in g.attrs)


def _run_group(f, path, group):
    """The group of the run `group` (None: of a one-run file) of the open file `f`: a `h5py.Group`, the root for
    a one-run file (whose attributes are read without opening the root again for each, as the file's are)."""
    if group is None:
        if _attr(f, "kind") == BATCH:
            raise ValueError(f"{path} is a batch file; choose a run with group=NAME (--group NAME) from {_runs(f)}")
        return f["/"]
    if _attr(f, "kind") != BATCH:
        g = f["/"] if group == "/" else None
    else:  # the one group, not `_runs`, which opens every group
        g = f.get(group) if _valid_name(group) else None
        g = g if isinstance(g, h5py.Group) and "kind" in g.attrs else None
    if g is None:
        raise ValueError(f"{path} has no run {group!r}; its runs are {_runs(f)}")
    _check_schema(g, f"{path} run {group!r}")
    return g


def _class_of(kind, path):
    if kind not in KINDS:
        raise ValueError(f"{path}: unknown run kind {kind!r}; this pnrotor reads {sorted(KINDS)}")
    module, _, name = KINDS[kind].partition(":")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as error:
        raise ValueError(f"{path}: runs of kind {kind!r} need {KINDS[kind]}, which is not importable ({error})") from None


def _defaulted(cls):
    return {
        f.name
        for f in dataclasses.fields(cls)
        if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
    }


def _attr(obj, name, default=None):
    """Attribute `name` of the group or dataset `obj` as h5py reads it, but a fixed-length string (UTF-8, how
    `write` stores strings since schema 2, `_string`; or ASCII, as h5py writes ``bytes``) as `str`, as h5py gives
    a variable-length one (schema 1); `default` if there is none."""
    attributes = obj.attrs
    return _decoded(attributes, name) if name in attributes else default


def _attributes(obj):
    """All attributes of `obj` as `_attr` gives them, name → value, each read once."""
    attributes = obj.attrs
    return {name: _decoded(attributes, name) for name in attributes}


def _decoded(attributes, name):
    value = attributes[name]
    return value.decode("utf-8", "surrogatepass") if isinstance(value, np.bytes_) else value


def _value(attribute):
    """An attribute as the Python value written: None for empty, int/float/bool for numpy scalars."""
    if isinstance(attribute, h5py.Empty):
        return None
    return attribute.item() if isinstance(attribute, np.generic) else attribute


def _get(g, attributes=None, skip=(), leave=(), prefix=""):
    """The attributes (group `g`'s `_attributes`, or `attributes` if given; but those in `skip`), datasets (but those
    whose path from the run is in `leave`) and subgroups of group `g` (whose path from the run is `prefix`) as the
    values written: name → value."""
    attributes = _attributes(g) if attributes is None else attributes
    values = {name: _value(value) for name, value in attributes.items() if name not in skip}
    for name, item in g.items():
        if isinstance(item, h5py.Group):
            values[name] = _get(item, leave=leave, prefix=f"{prefix}{name}/")
        elif prefix + name in leave:
            continue
        elif h5py.check_string_dtype(item.dtype) is not None:   # an array of strings (`_utf8`)
            values[name] = item.asstr()[...]
        else:
            array = item[...]
            sequence = _attr(item, "sequence")
            values[name] = array if sequence is None else _SEQUENCES[sequence](array.tolist())
    return values
