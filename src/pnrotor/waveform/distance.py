"""Modes as strain at a distance: the factor between r h / M and h at D Mpc, which :mod:`pnrotor.waveform.modes`
applies and :mod:`pnrotor.interop.sxs` undoes; imports nothing of pnrotor."""

import functools
import math
import sys

__all__ = ["scale"]


def scale(from_Mpc, to_Mpc, M_seconds):
    """Factor taking modes at distance ``from_Mpc`` (None: r h / M) to strain at ``to_Mpc``; a ValueError naming
    ``distance`` where it is not a normal float64 (inf, or 0 or subnormal: the modes would be lost)."""
    metres_per_Mpc, c = _constants()
    source = M_seconds * c if from_Mpc is None else from_Mpc * metres_per_Mpc
    scale = source / (to_Mpc * metres_per_Mpc)
    if not sys.float_info.min <= scale < math.inf:
        raise ValueError(f"distance = {to_Mpc!r} Mpc is out of range: it scales these modes by {scale:.3g}, "
                         f"beyond float64's normal numbers")
    return scale


@functools.cache
def _constants():
    """(metres in a megaparsec, c in m/s) from astropy, once (a unit conversion costs ~10 µs)."""
    from astropy import constants as const
    from astropy import units as u

    return u.Mpc.to(u.m), const.c.value
