"""
Modes, h₊ and h×, and LALSuite
==============================

The modes of a precessing binary in the inertial frame, where precession modulates them, and in the co-precessing
frame, where (2, ±2) dominate and vary slowly; then h₊ seen at an inclination of 0.7 rad from 400 Mpc, against
LALSuite's SpinTaylorT4 through the same PyCBC call (Newtonian amplitude, LAL's spin truncation
``spin_order=6``: the same model, so the difference is the two integrations').
"""

import matplotlib.pyplot as plt
import numpy as np
import pycbc.waveform

import pnrotor

binary = dict(m1=30, m2=10, chi1=(0.6, 0, 0.2), chi2=(0, -0.4, 0.1), f_ref=20)
run = pnrotor.evolve(**binary, sampling=1 / 4096)
h = pnrotor.modes(run, ell_max=4, distance=400)
coprecessing = h.in_frame("coprecessing")
M = run.inputs["M_seconds"]     # G M / c³ in seconds

fig, (inertial_axes, coprecessing_axes, polarization_axes) = plt.subplots(3, 1, figsize=(10, 10),
                                                                            layout="constrained")
for axes, modes, frame in ((inertial_axes, h, "inertial"), (coprecessing_axes, coprecessing, "co-precessing")):
    for ell, m in ((2, 2), (2, 1), (2, 0), (3, 3), (4, 4)):
        axes.semilogy(h.t_seconds, np.abs(modes.mode(ell, m)), lw=0.8, label=f"({ell},{m})")
    axes.set(xlabel="t [s]", ylabel="|h_ℓm| (strain at 400 Mpc)", title=f"{frame} frame", ylim=(1e-25, 1e-20))
    axes.legend(ncol=5, loc="lower right")
    axes.secondary_xaxis("top", functions=(lambda s: s / M, lambda t: t * M)).set_xlabel("t [M]")

keywords = dict(mass1=30, mass2=10, spin1x=0.6, spin1z=0.2, spin2y=-0.4, spin2z=0.1, f_lower=20, delta_t=1 / 4096,
                inclination=0.7, distance=400, amplitude_order=0, spin_order=6)
ours, _ = pycbc.waveform.get_td_waveform(approximant="PNRotorT4", **keywords)
lal, _ = pycbc.waveform.get_td_waveform(approximant="SpinTaylorT4", **keywords)
n = min(len(ours), len(lal))
t = ours.sample_times.numpy()[-n:]                      # both end at t = 0
ours, lal = ours.numpy()[-n:], lal.numpy()[-n:]
difference = np.max(np.abs(ours - lal)) / np.max(np.abs(lal))
print(f"max |h+(pnrotor) - h+(LAL)| = {difference:.1e} of LAL's peak over {n} samples")
polarization_axes.plot(t, lal, lw=1.5, color="0.7", label="LAL SpinTaylorT4")
polarization_axes.plot(t, ours, lw=0.6, label="pnrotor T4")
polarization_axes.set(xlabel="t [s] (0 at the end)", ylabel="h₊ at 400 Mpc",
                      title=f"inclination 0.7 rad; difference {difference:.1e} of the peak", xlim=(-0.5, 0.01))
polarization_axes.legend(loc="upper left")
plt.show()
