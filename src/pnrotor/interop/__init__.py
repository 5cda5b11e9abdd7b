"""Bridges to other codes, each importable only where that code is installed.

``pnrotor.interop.lal`` — LALSuite's SpinTaylor orbit evolution called with pnrotor's matching options, and
pnrotor's modes and polarizations as LAL time series (``Modes.to_lal``; needs ``lalsuite``, extra ``lal``).
``pnrotor.interop.sxs`` — pnrotor's modes as ``sxs.WaveformModes`` (``Modes.to_sxs``; needs ``sxs``, extra
``sxs``).
``pnrotor.interop.pycbc``, ``.gwsignal``, ``.bilby`` — pnrotor's waveform in PyCBC (approximants PNRotorT1/T4/T5 by
entry points; extra ``pycbc``), LAL's gwsignal (``PNRotorGenerator``; extra ``gwsignal``) and bilby
(``PNRotorWaveformGenerator``; extra ``bilby``), with LAL SpinTaylor's keywords (``pnrotor.interop.pipelines``,
docs/pipelines.md).  All are in the ``test`` extra.
"""
