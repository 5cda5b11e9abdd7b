"""Waveforms from the frame: mode layout, Wigner matrices from rotors, spin-weighted harmonics and
polarizations.

* :mod:`~pnrotor.waveform.layout` — the order of the (ℓ, m) rows;
* :mod:`~pnrotor.waveform.wigner` — 𝔇^ℓ_{m m'}(R) straight from rotors (no Euler angles) and
  :func:`~pnrotor.waveform.wigner.rotate_modes`, numba;
* :mod:`~pnrotor.waveform.polarizations` — ₛY_ℓm and h₊, h× from modes, in LALSuite's convention.
"""
