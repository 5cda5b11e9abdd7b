"""The invariants of pnrotor's result types, which are also the layout of their files: one check for a result in
memory and for one read from a file.  Imports nothing of pnrotor, and neither h5py nor numba.

Each result type (a dataclass of `pnrotor.results`) is registered where it is defined (:func:`register`), with its
array fields beside its fields: ``ARRAYS[kind]`` (each an :class:`Array`: shape, units, dtype, finite values, rotors),
``REQUIRED_KEYS[kind]`` (keys its dict fields must hold), ``DIMENSIONS[kind]`` (its named axes) and, for a kind that
files store, ``KINDS[kind]``, the ``module:class`` a file's ``kind`` attribute names.  :func:`layout_problems` checks
a result's values against these (what `pnrotor.hdf5.read` does before it builds the dataclass), and :func:`check`
raises on them (what `pnrotor.hdf5.write` does before writing, and the result types when built or before their
kernels read them).
"""

import dataclasses
import numbers
from collections import Counter
from typing import NamedTuple

import numpy as np

KINDS = {}
"""The ``kind`` attribute of a file's run → ``module:class`` of the dataclass it names, imported when a file is read
(`pnrotor.hdf5.read`)."""
ARRAYS = {}
"""The array fields of each result kind (:class:`Array`): what :func:`layout_problems` checks, and their ``units``.  A
name ``GROUP/NAME`` is the array NAME of the result's dict field GROUP (a dataset of that subgroup of its file)."""
UNITS = {}
"""``units`` attribute written on a run's datasets of `ARRAYS`, by kind and field (``GROUP/NAME`` in a subgroup)."""
REQUIRED_KEYS = {}
"""Keys a result's dict fields must hold, by kind: those pnrotor itself reads from a stored run (`Evolution.span`,
`Evolution.f_gw`, `pnrotor.modes`, `Modes.polarizations`, a resumed batch)."""
DIMENSIONS = {}
"""Named axes of a kind's `ARRAYS` other than N, each a function of the result's values (checked first) → its size,
or None: the result has no such axis."""

NOT_WRITTEN = frozenset({"dense"})
"""Fields that are functions of the integrator rather than data: not checked, not stored; `read` leaves them at their
default."""
ARRAY_KINDS = "biufc"
"""numpy dtype kinds of the arrays a result holds (bool, signed, unsigned, float, complex), beside arrays of `str`."""


class Array(NamedTuple):
    """How an array field of a result is stored: its ``shape``, each entry an int, ``"N"`` (the number of samples,
    the same in every array of the result) or a name in `DIMENSIONS`; its ``units`` attribute; its ``dtype``
    (either byte order; ``"str"``: a numpy object array of `str`, stored as fixed-length UTF-8).  Its values
    must be finite unless ``finite`` is False (float and complex arrays; NaN then marks an absent value); with
    ``rotors`` each row along the last axis is a rotor, its squared norm a normal float64 (not zero, nor so small
    or large that the kernels dividing by it would fail; a row of NaN where NaN is allowed)."""

    shape: tuple
    units: str
    dtype: str = "float64"
    finite: bool = True
    rotors: bool = False


ROTOR = Array(("N", 4), (
    "1; scalar-first unit quaternion (w, x, y, z), sign-continuous in time; "
    "frame vectors are R x R^-1, R y R^-1, R z R^-1 (Boyle 2016, eq:rotor-rotation)"
), rotors=True)
"""An array of rotors, one per sample."""
M_UNIT = "M (G M / c^3, total mass M)"
"""The unit of times in units of the total mass."""

def register(arrays=None, required_keys=None, dimensions=None, stored=True):
    """A class decorator that registers a result dataclass under its name: its `arrays` (name → :class:`Array`),
    the keys its dict fields must hold (`required_keys`, field → names), its named axes (`dimensions`) and, if
    `stored`, its kind of file (`KINDS`)."""
    def decorate(cls):
        kind = cls.__name__
        if stored:
            KINDS[kind] = f"{cls.__module__}:{cls.__qualname__}"
        if arrays is not None:
            ARRAYS[kind] = arrays
            UNITS[kind] = {name: array.units for name, array in arrays.items()}
        if required_keys is not None:
            REQUIRED_KEYS[kind] = required_keys
        if dimensions is not None:
            DIMENSIONS[kind] = dimensions
        return cls
    return decorate


def short_repr(run):
    """The one-line ``repr`` of a result dataclass (a run's arrays can hold millions of samples): each array
    field as its range ``[first … last]`` (1-D floats) or its dtype and shape, each dict as its number of keys,
    any other field as its repr (cut at 40 characters; an object that is not data, such as a dense output, as its
    type)."""
    parts = []
    for f in dataclasses.fields(run):
        value = getattr(run, f.name)
        if isinstance(value, np.ndarray):
            if value.ndim == 1 and value.dtype.kind == "f" and value.size:
                text = f"[{value[0]:.6g}" + (f" … {value[-1]:.6g}]" if value.size > 1 else "]")
            else:
                text = f"{value.dtype.name} {value.shape}"
        elif isinstance(value, dict):
            text = f"{{{len(value)} keys}}"
        elif value is None or isinstance(value, (str, int, float, np.generic)):
            text = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
        else:
            text = f"<{type(value).__name__}>"
        parts.append(f"{f.name}={text}")
    return f"{type(run).__name__}({', '.join(parts)})"


def check(run, doing="cannot write", scan=True):
    """Raise ``ValueError(f"{doing} this KIND: PROBLEMS")`` unless the result dataclass `run` passes
    :func:`layout_problems`: the one check of a result's invariants (its fields' types, its arrays' shapes, dtypes and
    finite values, nonzero rotors, the keys of its dicts), which `pnrotor.hdf5.write` makes before writing (so every
    file written reads back), `pnrotor.modes` and `Modes`' methods before their compiled kernels read the arrays, and
    `FrameHistory` and `Population` when they are built.  ``scan`` as for :func:`layout_problems`."""
    values = {field.name: getattr(run, field.name) for field in dataclasses.fields(run)}
    values = {name: value for name, value in values.items() if name not in NOT_WRITTEN and not callable(value)}
    problems = layout_problems(type(run), values, scan)
    if problems:
        raise ValueError(f"{doing} this {type(run).__name__}: {'; '.join(problems)}")


def layout_problems(cls, values, scan=True):
    """What is wrong with the result `values` (field name → value, as `pnrotor.hdf5.read` gets them from a file or
    :func:`check` from a dataclass) of the result dataclass `cls`, as a list of sentences (empty: nothing). Checked:

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
    sizes = {dim: size(values) for dim, size in DIMENSIONS.get(kind, {}).items()
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
            if not is_strings(array):
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


def is_strings(value):
    """Whether `value` is a numpy object array of `str` (how a result holds a column of strings)."""
    return (isinstance(value, np.ndarray) and value.dtype.kind == "O"
            and all(isinstance(x, str) for x in value.flat))


_TYPES = {
    "ndarray": (lambda v: isinstance(v, np.ndarray) and (v.dtype.kind in ARRAY_KINDS or is_strings(v)), "dataset",
                "a numeric array or an array of strings"),
    "dict": (lambda v: isinstance(v, dict), "group", "a group"),
    "str": (lambda v: isinstance(v, str), "attribute", "a string"),
    "int": (lambda v: isinstance(v, numbers.Integral) and not isinstance(v, bool), "attribute", "an integer"),
    "float": (lambda v: isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)), "attribute", "a number"),
}
"""Annotation of a result field → (check of a value, what stores it, what it must be) for `layout_problems`."""


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
