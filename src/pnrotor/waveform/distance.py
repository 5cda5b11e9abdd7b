"""Modes as strain at a distance: the factor between r h / M and h at D Mpc, which :mod:`pnrotor.waveform.modes`
applies and :mod:`pnrotor.interop.sxs` undoes; imports nothing of pnrotor."""

import functools

__all__ = ["scale"]


SCALES = (2.0 ** -511, 2.0 ** 511)
"""The factors a distance may scale modes by: those whose squares (as in |h|², a power or a matched filter) are
normal float64 numbers, as far from underflow as from overflow."""


def scale(from_Mpc, to_Mpc, M_seconds):
    """Factor taking modes at distance ``from_Mpc`` (None: r h / M) to strain at ``to_Mpc``; a ValueError naming
    ``distance`` where it is outside :data:`SCALES` (one range, symmetric in the exponent: a distance so small
    that |h| ~ 1e305 is refused as one so large that h underflows)."""
    metres_per_Mpc, c = _constants()
    source = M_seconds * c if from_Mpc is None else from_Mpc * metres_per_Mpc
    scale = source / (to_Mpc * metres_per_Mpc)
    if not SCALES[0] <= scale <= SCALES[1]:
        raise ValueError(f"distance = {to_Mpc!r} Mpc is out of range: it scales these modes by {scale:.3g}, outside "
                         f"the {SCALES[0]:.3g} to {SCALES[1]:.3g} whose squares are normal float64 numbers")
    return scale


@functools.cache
def _constants():
    """(metres in a megaparsec, c in m/s) from astropy, once (a unit conversion costs ~10 µs)."""
    from astropy import constants as const
    from astropy import units as u

    return u.Mpc.to(u.m), const.c.value
