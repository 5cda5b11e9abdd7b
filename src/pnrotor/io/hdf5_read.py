"""Reading pnrotor's HDF5 files (the reading half of :mod:`pnrotor.io.hdf5`, whose docstring describes the format;
``pnrotor.hdf5.read``, ``.metadata``, ``.list_runs`` are these): a run rebuilt as the dataclass it was written from,
bitwise, after checking that the file exists, is HDF5, is not truncated, is a pnrotor file of a schema this pnrotor
knows (1 or 2), and the run's layout (`pnrotor.results.layout_problems`).  The helpers that open a file, find a run's
group and read its attributes and fields are public for the writing half (a batch appended to, a run copied, chunks
concatenated).
"""

import dataclasses
import importlib
import zlib
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from pnrotor import __version__
from pnrotor.results import KINDS, layout_problems

SCHEMA_VERSION = 2
"""Integer version of the layout below; `read` refuses files with a newer one.  Version 2 stores every string
attribute as fixed-length UTF-8 (`_string`), version 1 as variable-length strings in HDF5's global heap; both are
read."""

BATCH = "batch"
"""``kind`` of the root of a batch file, whose top-level groups are runs."""

METADATA = ("kind", "pnrotor_schema", "pnrotor_version", "created")

STRINGS_CRC = "pnrotor_strings_crc32"
"""Attribute of a run group: `strings_crc` of the run, written after everything else; files before it lack it."""

NOT_FIELDS = METADATA + (STRINGS_CRC,)
"""The attributes of a run group that are not fields of its dataclass."""

SEQUENCES = {"list": list, "tuple": tuple}


def read(path, group=None):
    """The run stored in `path` (in its batch group `group`), as the dataclass it was written from.

    Before the dataclass is built the run's layout is checked: its metadata attributes (`metadata`), its
    ``kind`` (a registered dataclass, `KINDS`) and then `layout_problems`: every stored field of that
    dataclass present, no other, each of the type its annotation names (a dataset for an array, a group for
    a dict, an attribute of that type otherwise); the arrays of `ARRAYS` of the dtype and shape given there,
    all of the same number of samples N, with finite values; the keys of `REQUIRED_KEYS` in its inputs and
    statistics; the CRC-32 of its string attributes (`strings_crc`, in files that have it). Any problem
    raises one `ValueError` naming the file (and run) and every problem found, e.g.
    ``run.h5: dataset 'R' has shape (10, 3), expected (10, 4)``."""
    with opened(path) as f:
        g = run_group(f, path, group)
        where = path if group is None else f"{path} run {group!r}"
        attributes = attributes_of(g)   # each read once: HDF5 attribute reads are most of the time of a small file
        check_metadata(attributes, where)
        cls = class_of(attributes["kind"], where)
        values = get_fields(g, attributes, skip=NOT_FIELDS)
        metadata = {name: _value(attributes[name]) for name in METADATA}
        crc = attributes.get(STRINGS_CRC)
        damaged = crc is not None and crc != strings_crc({**metadata, **values})
        if hasattr(cls, "upgraded"):   # fields added since the file was written, derived
            values = cls.upgraded(values, metadata["pnrotor_schema"])
        problems = layout_problems(cls, values)
        if not problems and damaged:
            problems.append("its string attributes are damaged (their CRC-32 is not the one written with them)")
        if problems:
            raise ValueError(f"{where}: {'; '.join(problems)}")
        return cls(**values)


def metadata(path, group=None):
    """The metadata attributes of a run: ``kind``, ``pnrotor_schema``, ``pnrotor_version``, ``created``
    (checked: all four present, the schema version one this pnrotor reads, the others strings)."""
    with opened(path) as f:
        attributes = attributes_of(run_group(f, path, group))
        check_metadata(attributes, path if group is None else f"{path} run {group!r}")
        return {name: _value(attributes[name]) for name in METADATA}


def list_runs(path):
    """Names of the runs in a batch file, sorted; ``["/"]`` for a one-run file. Each works as `read`'s group."""
    with opened(path) as f:
        return run_names(f)


def check_metadata(attributes, where):
    """Raise `ValueError` unless the attributes of a run group (`attributes_of`) hold the four metadata attributes,
    ``kind``, ``pnrotor_version`` and ``created`` strings (the schema version is checked on opening)."""
    missing = [name for name in METADATA if name not in attributes]
    wrong = [name for name in ("kind", "pnrotor_version", "created") if name in attributes
             and not isinstance(attributes[name], str)]
    if STRINGS_CRC in attributes and not isinstance(attributes[STRINGS_CRC], np.integer):
        wrong.append(STRINGS_CRC)
    if missing or wrong:
        raise ValueError(f"{where}: " + "; ".join([f"attribute {name!r} is missing" for name in missing]
                                                 + [f"attribute {name!r} is not a "
                                                    + ("number" if name == STRINGS_CRC else "string")
                                                    for name in wrong]))


def strings_crc(values):
    """CRC-32 of the strings of a run, `values` (name → value, a dict for a group: its metadata and fields, as
    written or as `get_fields` reads them back), each as ``PATH=VALUE`` with PATH its names from the run group
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


def valid_name(name):
    """Whether `name` names a member of a group (rather than a path): non-empty, no '/', not '.'."""
    return isinstance(name, str) and name not in ("", ".") and "/" not in name and "\x00" not in name


def open_file(path):
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
def opened(path):
    """Open a pnrotor file for reading, or raise the error that says what it is instead; what HDF5 raises while
    it is read becomes a ValueError naming the file."""
    with open_file(path) as f:
        try:
            check_schema(f, path)
            yield f
        except OSError as error:
            if type(error) is not OSError:  # FileExistsError and kin come from the caller, not from HDF5
                raise
            raise ValueError(f"{path} is corrupt: HDF5 cannot read it ({error})") from None
        except (RuntimeError, TypeError, KeyError, IndexError, AttributeError, UnicodeDecodeError) as error:
            # what damaged metadata makes h5py or the rebuilding of the dataclass raise: one clear error
            raise ValueError(f"{path} is corrupt: {type(error).__name__} while reading it ({error})") from None


def check_schema(g, path):
    if not isinstance(attr_of(g, "kind", ""), str):   # compared with strings before the run is read
        raise ValueError(f"{path}: attribute 'kind' is not a string")
    schema = attr_of(g, "pnrotor_schema")
    if schema is None:
        raise ValueError(f"{path} is an HDF5 file but not a pnrotor file (no 'pnrotor_schema' attribute)")
    if not isinstance(schema, np.integer) or not 1 <= schema <= SCHEMA_VERSION:
        writer = _value(attr_of(g, "pnrotor_version", "an unknown version"))
        newer = isinstance(schema, np.integer) and schema > SCHEMA_VERSION
        raise ValueError(
            f"{path} has pnrotor schema version {_value(schema)!r} (written by pnrotor {writer}); "
            f"pnrotor {__version__} reads schema versions 1 to {SCHEMA_VERSION}"
            + ("; upgrade pnrotor to read it" if newer else "")
        )


def run_names(f):
    if attr_of(f, "kind") != BATCH:
        return ["/"]
    return sorted(name for name, g in f.items() if isinstance(g, h5py.Group) and "kind" in g.attrs)


def run_group(f, path, group):
    """The group of the run `group` (None: of a one-run file) of the open file `f`: a `h5py.Group`, the root for
    a one-run file (whose attributes are read without opening the root again for each, as the file's are)."""
    if group is None:
        if attr_of(f, "kind") == BATCH:
            raise ValueError(f"{path} is a batch file; choose a run with group=NAME (--group NAME) from {run_names(f)}")
        return f["/"]
    if attr_of(f, "kind") != BATCH:
        g = f["/"] if group == "/" else None
    else:  # the one group, not `run_names`, which opens every group
        g = f.get(group) if valid_name(group) else None
        g = g if isinstance(g, h5py.Group) and "kind" in g.attrs else None
    if g is None:
        raise ValueError(f"{path} has no run {group!r}; its runs are {run_names(f)}")
    check_schema(g, f"{path} run {group!r}")
    return g


def class_of(kind, path):
    if kind not in KINDS:
        raise ValueError(f"{path}: unknown run kind {kind!r}; this pnrotor reads {sorted(KINDS)}")
    module, _, name = KINDS[kind].partition(":")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as error:
        raise ValueError(f"{path}: runs of kind {kind!r} need {KINDS[kind]}, which is not importable ({error})") from None


def defaulted(cls):
    return {
        f.name
        for f in dataclasses.fields(cls)
        if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
    }


def attr_of(obj, name, default=None):
    """Attribute `name` of the group or dataset `obj` as h5py reads it, but a fixed-length string (UTF-8, how
    `write` stores strings since schema 2, `_string`; or ASCII, as h5py writes ``bytes``) as `str`, as h5py gives
    a variable-length one (schema 1); `default` if there is none."""
    attributes = obj.attrs
    return _decoded(attributes, name) if name in attributes else default


def attributes_of(obj):
    """All attributes of `obj` as `attr_of` gives them, name → value, each read once."""
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


def get_fields(g, attributes=None, skip=(), leave=(), prefix=""):
    """The attributes (group `g`'s `attributes_of`, or `attributes` if given; but those in `skip`), datasets (but those
    whose path from the run is in `leave`) and subgroups of group `g` (whose path from the run is `prefix`) as the
    values written: name → value."""
    attributes = attributes_of(g) if attributes is None else attributes
    values = {name: _value(value) for name, value in attributes.items() if name not in skip}
    for name, item in g.items():
        if isinstance(item, h5py.Group):
            values[name] = get_fields(item, leave=leave, prefix=f"{prefix}{name}/")
        elif prefix + name in leave:
            continue
        elif h5py.check_string_dtype(item.dtype) is not None:   # an array of strings (`_utf8`)
            values[name] = item.asstr()[...]
        else:
            array = item[...]
            sequence = attr_of(item, "sequence")
            values[name] = array if sequence is None else SEQUENCES[sequence](array.tolist())
    return values
