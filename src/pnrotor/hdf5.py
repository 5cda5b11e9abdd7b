"""pnrotor's HDF5 files: run results (`FrameHistory`, `Evolution`) to and from disk, atomic and versioned.

This module owns the file format (documented for readers without pnrotor in docs/hdf5-schema.md) and
every write and read of it:

* `write(path, run)` stores a run dataclass: each field that is an array becomes a dataset (chunked,
  checksummed, float64 stays float64, optional gzip/lzf compression), each number, string, bool or ``None`` an
  attribute, each dict a subgroup holding its items by the same rules, each list or tuple of numbers
  a dataset marked with a ``sequence`` attribute. The ``dense`` field (the integrator's dense output, a
  function rather than data) and other callables are not written. Metadata attributes name the
  dataclass (``kind``), the schema version (``pnrotor_schema``), ``pnrotor_version`` and ``created``.
* `read(path)` rebuilds the same dataclass, bitwise: arrays with their dtype and bytes, numbers as
  Python ``int``/``float``/``bool``, strings exactly.
* Writes are atomic. The file is built under a temporary name beside the target,
  ``NAME.XXXXXXXX.pnrotor-tmp``, fsynced, then renamed over the target with `os.replace`. Any exception,
  Ctrl-C included, removes the temporary file; only a hard kill (SIGKILL, power loss) can leave one,
  and the target is then absent or still the old complete file.
* Batch files hold one run per top-level group (``write(..., group=NAME)``, `list_runs`); adding a run
  copies the file to the temporary name first, so it too is atomic. One writer per file at a time.

Reading checks that the file exists, is HDF5, is not truncated, is a pnrotor file and has a schema
version this pnrotor knows, and says which of these failed (`FileNotFoundError`, `IsADirectoryError`
or `ValueError`).
"""

import dataclasses
import importlib
import os
import secrets
import shutil
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

from pnrotor import __version__

SCHEMA_VERSION = 1
"""Integer version of the layout below; `read` refuses files with a newer one."""

KINDS = {
    "FrameHistory": "pnrotor.history:FrameHistory",
    "Evolution": "pnrotor.pn.evolve:Evolution",
}
"""The ``kind`` attribute → ``module:class`` of the dataclass it names, imported when a file is read."""

BATCH = "batch"
"""``kind`` of the root of a batch file, whose top-level groups are runs."""

COMPRESSIONS = (None, "gzip", "lzf")

NOT_WRITTEN = frozenset({"dense"})
"""Fields that are functions of the integrator rather than data; `read` leaves them at their default."""

_METADATA = ("kind", "pnrotor_schema", "pnrotor_version", "created")
_SEQUENCES = {"list": list, "tuple": tuple}
_ARRAY_KINDS = "biufc"  # numpy dtype kinds stored as datasets: bool, signed, unsigned, float, complex
_CHUNK_BYTES = 1 << 20  # chunks of at most about 1 MiB along the first (time) axis
_GZIP_LEVEL = 1  # on 10⁶-sample PN-like data level 4 saved 1.5% of the size for 1.7× the write time
_TEMPORARY_SUFFIX = ".pnrotor-tmp"

_ROTOR = (
    "1; scalar-first unit quaternion (w, x, y, z), sign-continuous in time; "
    "frame vectors are R x R^-1, R y R^-1, R z R^-1 (Boyle 2016, eq:rotor-rotation)"
)
UNITS = {
    "FrameHistory": {"t": "time unit of the angular velocity (omega in rad per unit)", "R": _ROTOR},
    "Evolution": {
        "t": "M (G M / c^3, total mass M)",
        "t_seconds": "s",
        "v": "c; PN parameter v = (M Omega_orb)^(1/3)",
        "Phi": "rad; orbital phase",
        "chi1": "1; dimensionless spin S1 / m1^2, inertial-frame components",
        "chi2": "1; dimensionless spin S2 / m2^2, inertial-frame components",
        "ell_hat": "1; unit normal to the orbital plane, inertial-frame components",
        "R": _ROTOR,
    },
}
"""``units`` attribute written on a run's top-level datasets, by kind and field."""


# --------------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------------


def write(path, run, *, overwrite=False, compression=None, group=None):
    """Write the run dataclass `run` to `path` atomically and return the path.

    ``group=None`` makes a one-run file; ``group=NAME`` adds the run as group NAME of a batch file
    (created if absent). An existing file, or an existing run NAME in a batch file, is replaced only with
    ``overwrite=True``. ``compression`` is None, ``"gzip"`` (portable) or ``"lzf"`` (fast; readers need
    h5py or the lzf filter plugin).
    """
    path = Path(path)
    kind = _kind_of(run)
    if compression not in COMPRESSIONS:
        raise ValueError(f"compression must be one of {COMPRESSIONS}, not {compression!r}")
    if group is not None:
        _check_name(group, "group")
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder; give a file name such as {path / 'run.h5'}")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"folder {path.parent} does not exist (writing {path}); create it first")
    append = group is not None and path.exists()
    if append:
        with _open(path) as f:
            if f.attrs.get("kind") != BATCH:
                raise ValueError(f"{path} holds a single run, not a batch; write run {group!r} to another file")
            if group in f and not overwrite:
                raise FileExistsError(f"{path} already has run {group!r}; pass overwrite=True (--overwrite) to replace it")
    elif path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True (--overwrite) to replace it")

    temporary = _temporary_beside(path)
    try:
        if append:
            shutil.copyfile(path, temporary)
        with h5py.File(temporary, "r+" if append else "w") as f:
            if group is None:
                target = f
            else:
                if not append:
                    _put_metadata(f, BATCH)
                if group in f:
                    del f[group]
                target = f.create_group(group)
            _put_metadata(target, kind)
            _put_fields(target, run, UNITS.get(kind, {}), compression)
        _fsync(temporary)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    _fsync(path.parent)
    return path


def read(path, group=None):
    """The run stored in `path` (in its batch group `group`), as the dataclass it was written from."""
    with _open(path) as f:
        g = _run_group(f, path, group)
        cls = _class_of(g.attrs.get("kind"), path)
        values = _get(g, skip=_METADATA)
        fields = {f.name for f in dataclasses.fields(cls)}
        stored = fields - NOT_WRITTEN
        if values.keys() - fields or stored - values.keys() - _defaulted(cls):
            raise ValueError(
                f"{path}: stored fields {sorted(values)} do not match {cls.__name__} "
                f"{sorted(stored)}; the file is damaged or from an incompatible pnrotor"
            )
        return cls(**values)


def metadata(path, group=None):
    """The metadata attributes of a run: ``kind``, ``pnrotor_schema``, ``pnrotor_version``, ``created``."""
    with _open(path) as f:
        g = _run_group(f, path, group)
        return {name: _value(g.attrs[name]) for name in _METADATA}


def list_runs(path):
    """Names of the runs in a batch file, sorted; ``["/"]`` for a one-run file. Each works as `read`'s group."""
    with _open(path) as f:
        return _runs(f)


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
    if name in ("", ".") or "/" in name or "\x00" in name:
        raise ValueError(f"{what} {name!r} is not a valid HDF5 name (non-empty, no '/', not '.')")


def _put_metadata(g, kind):
    g.attrs["kind"] = kind
    g.attrs["pnrotor_schema"] = SCHEMA_VERSION
    g.attrs["pnrotor_version"] = __version__
    g.attrs["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")


def _put_fields(g, run, units, compression):
    cls = type(run)
    for field in dataclasses.fields(run):
        value = getattr(run, field.name)
        if field.name in NOT_WRITTEN or callable(value):
            if field.name not in _defaulted(cls):
                raise TypeError(f"{cls.__name__}.{field.name} cannot be written and has no default to read back")
            continue
        if field.name in _METADATA:
            raise ValueError(f"{cls.__name__}.{field.name}: the name is reserved for pnrotor's metadata")
        _put(g, field.name, value, compression, f"{cls.__name__}.{field.name}")
        if field.name in units and isinstance(g.get(field.name), h5py.Dataset):
            g[field.name].attrs["units"] = units[field.name]


def _put(g, name, value, compression, where):
    """Store `value` under `name` in group `g` by the rules in the module docstring."""
    if isinstance(value, dict):
        sub = g.create_group(name)
        for key, item in value.items():
            _check_name(key, f"key of {where}")
            _put(sub, key, item, compression, f"{where}[{key!r}]")
    elif isinstance(value, np.ndarray) or type(value) in _SEQUENCES.values():
        try:
            array = np.asarray(value)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
        if array.dtype.kind not in _ARRAY_KINDS or (not isinstance(value, np.ndarray) and array.ndim != 1):
            raise TypeError(f"{where}: only numeric arrays and flat lists/tuples of numbers can be written")
        dataset = _dataset(g, name, array, compression)
        if not isinstance(value, np.ndarray):
            dataset.attrs["sequence"] = type(value).__name__
    elif value is None or isinstance(value, (str, bool, int, float, complex, np.generic)):
        try:
            g.attrs[name] = h5py.Empty("f8") if value is None else value
        except (TypeError, ValueError) as error:
            raise ValueError(f"cannot write {where} = {value!r}: {error}") from None
    else:
        raise TypeError(f"{where}: cannot write a {type(value).__name__}")


def _dataset(g, name, array, compression):
    options = {}
    if array.ndim and array.size:  # HDF5 chunks need every dimension > 0
        rows = array.shape[0]
        nchunks = -(-rows * array.itemsize * (array.size // rows) // _CHUNK_BYTES)  # ceiling division
        options["chunks"] = (-(-rows // nchunks),) + array.shape[1:]  # equal chunks: no padding in the last
        options["fletcher32"] = True  # a checksum per chunk: damaged bytes give an error, not wrong numbers
        if compression:
            options.update(compression=compression, shuffle=True)
            if compression == "gzip":
                options["compression_opts"] = _GZIP_LEVEL
    return g.create_dataset(name, data=array, **options)


def _temporary_beside(path):
    """Create and return an empty, new file ``NAME.XXXXXXXX.pnrotor-tmp`` in the folder of `path`."""
    while True:
        temporary = path.with_name(f"{path.name}.{secrets.token_hex(4)}{_TEMPORARY_SUFFIX}")
        try:
            os.close(os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except FileExistsError:
            continue
        return temporary


def _fsync(path):
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


# --------------------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------------------


@contextmanager
def _open(path):
    """Open a pnrotor file for reading, or raise the error that says what it is instead."""
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder, not a pnrotor HDF5 file")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if not h5py.is_hdf5(path):
        empty = " (it is empty)" if path.stat().st_size == 0 else ""
        raise ValueError(f"{path} is not an HDF5 file{empty}")
    try:
        f = h5py.File(path, "r")
    except OSError as error:
        raise ValueError(f"{path} is truncated or corrupt: HDF5 cannot open it ({error})") from None
    with f:
        _check_schema(f, path)
        try:
            yield f
        except OSError as error:
            if type(error) is not OSError:  # FileExistsError and kin come from the caller, not from HDF5
                raise
            raise ValueError(f"{path} is corrupt: HDF5 cannot read it ({error})") from None


def _check_schema(g, path):
    schema = g.attrs.get("pnrotor_schema")
    if schema is None:
        raise ValueError(f"{path} is an HDF5 file but not a pnrotor file (no 'pnrotor_schema' attribute)")
    if not isinstance(schema, np.integer) or not 1 <= schema <= SCHEMA_VERSION:
        writer = _value(g.attrs.get("pnrotor_version", "an unknown version"))
        newer = isinstance(schema, np.integer) and schema > SCHEMA_VERSION
        raise ValueError(
            f"{path} has pnrotor schema version {_value(schema)!r} (written by pnrotor {writer}); "
            f"pnrotor {__version__} reads schema versions 1 to {SCHEMA_VERSION}"
            + ("; upgrade pnrotor to read it" if newer else "")
        )


def _runs(f):
    if f.attrs.get("kind") != BATCH:
        return ["/"]
    return sorted(name for name, g in f.items() if isinstance(g, h5py.Group) and "kind" in g.attrs)


def _run_group(f, path, group):
    if group is None:
        if f.attrs.get("kind") == BATCH:
            raise ValueError(f"{path} is a batch file; choose a run with group=NAME (--group NAME) from {_runs(f)}")
        return f
    if group not in _runs(f):
        raise ValueError(f"{path} has no run {group!r}; its runs are {_runs(f)}")
    g = f[group]
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


def _value(attribute):
    """An attribute as the Python value written: None for empty, int/float/bool for numpy scalars."""
    if isinstance(attribute, h5py.Empty):
        return None
    return attribute.item() if isinstance(attribute, np.generic) else attribute


def _get(g, skip=()):
    values = {name: _value(attribute) for name, attribute in g.attrs.items() if name not in skip}
    for name, item in g.items():
        if isinstance(item, h5py.Group):
            values[name] = _get(item)
        else:
            array = item[...]
            sequence = item.attrs.get("sequence")
            values[name] = array if sequence is None else _SEQUENCES[sequence](array.tolist())
    return values
