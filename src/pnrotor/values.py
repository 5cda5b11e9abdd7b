"""What a number given by a user must be: real, finite, an integer, positive in a unit (an astropy Quantity is
accepted where a unit is named, and recognized only when the caller has imported astropy; pnrotor never imports it).
Imports nothing of pnrotor: for the PN inputs (`pnrotor.pn.initial`, `pnrotor.pn.settings`), the waveform options and
the result types (`pnrotor.results`)."""

import math
import numbers
import sys

import numpy as np

BOOLS = (bool, np.bool_)
"""Refused where a number is expected (float(True) would be 1.0)."""
TEXT = (str, bytes, bytearray)
"""Refused where a number is expected too (float("30") would be 30.0): numbers only, as ``evolve_many`` takes them."""


def float_or_nan(x):
    """float(x), or NaN for what is not a real number: a bool, text, None, an int beyond any float (10**400)."""
    if isinstance(x, BOOLS + TEXT):
        return math.nan
    try:
        return float(x)
    except (TypeError, ValueError, OverflowError):
        return math.nan


def real(x):
    """Whether x is a real number (Python's or numpy's), not a bool."""
    return isinstance(x, numbers.Real) and not isinstance(x, BOOLS)


def finite(x):
    """Whether the real number x is finite as a float (an int beyond any float, 10**400, is not)."""
    try:
        return math.isfinite(x)
    except OverflowError:
        return False


def integer(x):
    """Whether x is an integer (Python's or numpy's), not a bool."""
    return isinstance(x, (int, np.integer)) and not isinstance(x, BOOLS)


def in_unit(x, unit, name, what):
    """x itself, or an astropy Quantity's value in ``unit`` (an astropy unit name; None: no Quantity taken), else a
    ValueError "`name` must be `what`" naming the Quantity's unit."""
    u = sys.modules.get("astropy.units")   # a Quantity exists only if its module was imported
    if u is None or not isinstance(x, u.Quantity):
        return x
    try:
        if unit is None:
            raise u.UnitsError
        return x.to_value(getattr(u, unit))
    except u.UnitsError:
        given = x.unit.to_string() or "dimensionless"
        raise ValueError(f"{name} must be {what}, got an astropy Quantity in {given}"
                         + (f" (not convertible to {unit})" if unit else "")) from None


def positive(x, unit, name, what):
    """A float from a float (already in `unit`) or an astropy Quantity converted to `unit` (an astropy unit
    name); must be finite and > 0, else a ValueError "`name` must be a finite positive `what`"."""
    x = in_unit(x, unit, name, f"a finite positive {what}")
    try:
        if isinstance(x, BOOLS + TEXT):
            raise TypeError
        x = float(x)
    except (TypeError, ValueError, OverflowError):   # OverflowError: an int beyond any float (10**400)
        raise ValueError(f"{name} must be a finite positive {what}, got {x!r}") from None
    if not math.isfinite(x) or x <= 0.0:
        raise ValueError(f"{name} must be a finite positive {what}, got {x!r}")
    return x
