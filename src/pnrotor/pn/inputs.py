"""``evolve_many``'s inputs checked and converted: arrays per binary (one value for all, or one each), the number of
binaries they agree on, the target frequencies, and a pandas DataFrame with a batch table's columns
(:mod:`pnrotor.options`).  A ValueError names the input (and row) that does not fit."""

import sys

import numpy as np

from .. import values
from ..options import COLUMNS, DEFAULTS, REQUIRED, TABLE_OPTIONS


def per_binary(x, n, name, shape=(), unit=None):
    """x as float64 of shape (n,) + shape, from that shape or ``shape`` or (1,) + shape (one value for every
    binary), or a ValueError naming the parameter (booleans, text and complex numbers refused, as ``evolve``
    refuses them; an astropy Quantity converted to ``unit``, and refused where the parameter has none)."""
    want = "(N,) or a scalar" if not shape else f"(N, {shape[0]}) or ({shape[0]},)"
    a = numbers(x, name, f"{want} with N = {n} binaries", unit)
    if a.shape not in (shape, (1,) + shape, (n,) + shape):
        raise ValueError(f"{name} must have shape {want} with N = {n} binaries, got {a.shape}")
    return np.ascontiguousarray(np.broadcast_to(a, (n,) + shape))


def numbers(x, name, shape, unit=None):
    """x as a float64 array, or a ValueError naming it and the ``shape`` expected: booleans are refused, as
    ``evolve`` refuses them, and so are text, complex numbers and ragged sequences; an astropy Quantity is
    converted to ``unit`` (M_sun, Hz), or refused where there is none; so is a numpy masked array with masked
    entries (numpy would compute its hidden values)."""
    if np.ma.is_masked(x):
        count = np.ma.count_masked(x)
        raise ValueError(f"{name} has {count} masked entr{'ies' if count > 1 else 'y'} (a numpy masked array): "
                         f"evolve_many would compute the values hidden under the mask; drop those binaries or fill "
                         f"them (x.filled(...))")
    x = values.in_unit(x, unit, name, "numbers" if unit is None else f"numbers (in {unit})")
    try:
        if _has_bool_or_text(x) or np.iscomplexobj(x):
            raise TypeError
        return np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be numbers (real: not booleans, text or complex) of shape {shape}") from None


def population_size(scalars, rows, lists):
    """N, the number of binaries: the length of every (N,) per-binary value in ``scalars``, (N, 3) one in ``rows``
    and (N, K) one in ``lists`` (the frequencies), which must agree but where it is 1 (shared, as numpy
    broadcasts); 1 if every value is shared.  A ValueError names the values that disagree."""
    sizes = {}
    for group, ndim in ((scalars, 1), (rows, 2), (lists, 2)):
        for name, x in group.items():
            shape = _shape(x)
            if shape != "ragged" and len(shape) == ndim:
                sizes[name] = shape[0]
    if len(set(sizes.values()) - {1}) > 1:
        raise ValueError("the per-binary inputs must all have the same length N (one per binary) or 1, got "
                         + ", ".join(f"{name} {n}" for name, n in sizes.items()))
    n = max(sizes.values(), default=1)
    if 0 in sizes.values():
        raise ValueError(f"{min(sizes, key=sizes.get)} has no binary: N must be at least 1")
    return n


def _has_bool_or_text(x):
    """Whether x is a boolean or text, an array of them, or a list or tuple holding one at any depth (numpy would
    take True as 1 and "30" as 30)."""
    if isinstance(x, np.ndarray):
        return x.dtype.kind in "bSU"
    if isinstance(x, (list, tuple)):
        return any(_has_bool_or_text(item) for item in x)
    return isinstance(x, values.BOOLS + values.TEXT)


def _shape(x):
    """np.shape(x), or "ragged" for nested sequences of unequal lengths (or of what numpy cannot stack, such as
    astropy Quantities with units)."""
    try:
        return np.shape(x)
    except (ValueError, TypeError):
        return "ragged"


def target_table(f_end, frequencies, n):
    """(N, K) target frequencies (NaN: to the end of the inspiral) and whether the outputs keep the K axis."""
    if frequencies is None:
        return per_binary(np.nan if f_end is None else f_end, n, "f_end", unit="Hz")[:, None], False
    if f_end is not None:
        raise ValueError("give f_end (one state per binary) or frequencies (a list of them), not both")
    f = numbers(frequencies, "frequencies", f"(K,) or (N, K) with N = {n} binaries", "Hz")
    if f.ndim == 1:
        f = np.broadcast_to(f, (n, f.size))
    if f.ndim != 2 or f.shape[0] != n or f.shape[1] == 0:
        raise ValueError(f"frequencies must have shape (K,) or (N, K) with K >= 1 and N = {n} binaries, "
                         f"got {f.shape}")
    return np.ascontiguousarray(f), True


def is_frame(x):
    """Whether x is a pandas DataFrame (pandas is not imported for that)."""
    pandas = sys.modules.get("pandas")
    return pandas is not None and isinstance(x, pandas.DataFrame)


def from_frame(frame, given, f_end, frequencies, shared, lambdas):
    """evolve_many's per-binary inputs from a DataFrame with a batch table's columns (evolve_many's docstring) →
    (m1, m2, chi1, chi2, f_ref, f_end, backward: where the target is an f_min, or None, lambda1, lambda2: the
    columns, or where absent the values ``lambdas`` gives); the options its columns hold go into ``shared`` (the
    fields of the call's :class:`pnrotor.Options`, by name).  A ValueError names the column (and row) that does not
    fit."""
    from pandas.api.types import is_bool_dtype, is_numeric_dtype

    twice = [name for name, x in given.items() if x is not None]
    if twice:
        raise ValueError(f"{', '.join(twice)} must not be given with a DataFrame: its columns hold them")
    unknown = [repr(c) for c in frame.columns if c not in COLUMNS]
    missing = [c for c in REQUIRED if c not in frame.columns]
    if unknown or missing or frame.columns.has_duplicates or not len(frame):
        raise ValueError("the DataFrame of binaries must have the columns " + ", ".join(REQUIRED)
                         + f" and may have {', '.join(c for c in COLUMNS if c not in REQUIRED)}, each once, and a row"
                         + (f"; unknown: {', '.join(unknown)}" if unknown else "")
                         + (f"; missing: {', '.join(missing)}" if missing else ""))

    def numbers(name):
        column = frame[name]
        if not is_numeric_dtype(column) or is_bool_dtype(column):
            raise ValueError(f"column {name} of the DataFrame must be numbers (not booleans or text), got dtype "
                             f"{column.dtype}")
        return column.to_numpy(dtype=np.float64, na_value=np.nan)

    def vectors(name):
        rows = []
        for label, cell in frame[name].items():
            try:
                x = [float(item) for item in cell.split(",")] if isinstance(cell, str) else cell
                x = np.asarray(x, dtype=np.float64)
                if x.shape != (3,):
                    raise ValueError
            except (TypeError, ValueError):
                raise ValueError(f"column {name} of the DataFrame must hold three numbers per row (a sequence or "
                                 f"\"x,y,z\" text); row {label!r} holds {cell!r}") from None
            rows.append(x)
        return np.array(rows)

    f_min, f_max = (numbers(name) if name in frame.columns else np.full(len(frame), np.nan) for name in ("f_min", "f_max"))
    has_min, has_max = ~np.isnan(f_min), ~np.isnan(f_max)
    backward = None
    if has_min.any() or has_max.any():
        if f_end is not None or frequencies is not None:
            raise ValueError("the DataFrame's f_min or f_max column gives each binary its target: f_end and "
                             "frequencies must not be given too")
        both = frame.index[has_min & has_max]
        if len(both):
            raise ValueError(f"rows {', '.join(map(repr, both[:5]))}{' ...' * (len(both) > 5)} of the DataFrame have "
                             "both f_min and f_max: evolve_many gives one state per row, at f_max (forward), at f_min "
                             "(backward) or at the end of the inspiral")
        f_end, backward = np.where(has_max, f_max, f_min), has_min
    for name in TABLE_OPTIONS + ("sampling",):
        values = frame[name].dropna().unique() if name in frame.columns else ()
        if len(values) > 1:
            raise ValueError(f"column {name} of the DataFrame holds several values ({', '.join(map(str, values[:5]))}"
                             f"{' ...' * (len(values) > 5)}); evolve_many shares it among all binaries: call it once "
                             "per value, or run the table with pnrotor.batch.population.run, which groups the rows")
        if len(values) == 1:
            value = values[0].item() if isinstance(values[0], np.generic) else values[0]
            if name == "sampling":
                if value != "final":
                    raise ValueError(f"column sampling of the DataFrame must be final or empty (evolve_many gives "
                                     f"states, not histories), got {value!r}")
            elif shared[name] != DEFAULTS[name] and shared[name] != value:
                raise ValueError(f"{name} is given twice, as {shared[name]!r} and as the DataFrame's column, "
                                 f"{value!r}")
            else:
                shared[name] = value
    for name, value in lambdas.items():
        if name in frame.columns:
            if not (np.ndim(value) == 0 and value == DEFAULTS[name]):
                raise ValueError(f"{name} is given twice, as an argument and as the DataFrame's column")
            lambdas[name] = numbers(name)
    return (numbers("m1"), numbers("m2"), vectors("chi1"), vectors("chi2"), numbers("f_ref"), f_end, backward,
            lambdas["lambda1"], lambdas["lambda2"])
