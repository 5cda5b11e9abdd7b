"""Bridges to other codes, each importable only where that code is installed.

``pnrotor.interop.lal`` — LALSuite's SpinTaylor orbit evolution called with pnrotor's matching options
(needs ``lalsuite``, in the ``test`` extra).
"""
