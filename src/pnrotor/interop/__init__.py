"""Bridges to other codes, each importable only where that code is installed.

``pnrotor.interop.lal`` — LALSuite's SpinTaylor orbit evolution called with pnrotor's matching options, and
pnrotor's modes and polarizations as LAL time series (``Modes.to_lal``; needs ``lalsuite``, extra ``lal``).
``pnrotor.interop.sxs`` — pnrotor's modes as ``sxs.WaveformModes`` (``Modes.to_sxs``; needs ``sxs``, extra
``sxs``).  Both are in the ``test`` extra.
"""
