"""Waveforms from the frame: the modes h_ℓm of a PN evolution and their polarizations.

* :mod:`~pnrotor.waveform.modes` — ``modes(evolution, ell_max, amplitude_order, distance)`` → :class:`Modes`
  (inertial, co-precessing or co-orbital frame; h₊, h×), also ``pnrotor.modes``;
* :mod:`~pnrotor.waveform.nonspinning`, :mod:`~pnrotor.waveform.spin` — the co-orbital amplitudes, one
  file per source, each term cited; :mod:`~pnrotor.waveform.amplitudes` — their table and the numba kernel
  that sums them and rotates them to the inertial frame in the same pass;
* :mod:`~pnrotor.waveform.wigner` — 𝔇^ℓ_{m m'}(R) straight from rotors (no Euler angles),
  :func:`~pnrotor.waveform.wigner.rotate_modes` and the block rotation the amplitude kernel uses, numba;
* :mod:`~pnrotor.waveform.polarizations` — ₛY_ℓm and h₊, h× from modes, in LALSuite's convention;
* :mod:`~pnrotor.waveform.layout` — the order of the (ℓ, m) rows.
"""
