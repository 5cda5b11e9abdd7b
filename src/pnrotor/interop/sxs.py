"""pnrotor's modes as the ``sxs`` package's ``WaveformModes`` (``pip install sxs``).

:func:`waveform_modes` hands :class:`pnrotor.waveform.modes.Modes` to the SXS tools in their units and layout:
time in units of the total mass M, data r h / M, one row per time and one column per mode (ℓ = 2 … ℓ_max,
m = −ℓ … ℓ), spin weight −2, inertial frame.  The mode values are unchanged: pnrotor's h_ℓm (LALSuite's
convention, h₊ − i h× = Σ h_ℓm ₋₂Y_ℓm) evaluated by ``WaveformModes.evaluate`` in the direction (ι, φ)
give pnrotor's h₊ − i h× for (ι, φ_ref = π/2 − φ), to 7e-16 (tests/test_waveform_modes.py), so the two
packages share ₋₂Y_ℓm and the sign of h_ℓm.

Importing this module needs ``sxs``.
"""

import sxs

from pnrotor.waveform.distance import scale

__all__ = ["waveform_modes"]


def waveform_modes(modes):
    """``sxs.WaveformModes`` of ``modes`` (module docstring)."""
    inertial = modes.in_frame("inertial")
    data = inertial.data.T
    if modes.distance_Mpc is not None:   # strain at a distance → r h / M
        data = data / scale(None, modes.distance_Mpc, modes.inputs["M_seconds"])
    return sxs.WaveformModes(data, time=modes.t, time_axis=0, modes_axis=1, ell_min=2, ell_max=modes.ell_max,
                             spin_weight=-2)
