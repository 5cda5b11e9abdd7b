"""
ℓ̂'s precession cone and the spins
==================================

A 30 + 10 M☉ binary with in-plane spins, from 20 Hz to the end of its inspiral: the orbital plane's normal ℓ̂ and
the spins χ₁, χ₂ precess about the total angular momentum, faster as the binary shrinks. ``sampling=("per_orbit",
16)`` gives 16 samples per orbit from the integrator's dense output.
"""

import matplotlib.pyplot as plt
import numpy as np

import pnrotor

run = pnrotor.evolve(30, 10, (0.6, 0, 0.2), (0, -0.4, 0.1), f_ref=20, sampling=("per_orbit", 16))
M = run.inputs["M_seconds"]     # G M / c³ in seconds
print(f"{len(run.t)} samples, {run.t_seconds[-1]:.3f} s = {run.t[-1]:.0f} M, ends at {run.f_gw[-1]:.0f} Hz "
      f"({run.termination})")

fig = plt.figure(figsize=(11, 4.5), layout="constrained")
cone = fig.add_subplot(1, 2, 1, projection="3d")
for vector, label in ((run.ell_hat, "ℓ̂"), (run.chi1 / np.linalg.norm(run.chi1[0]), "χ₁/|χ₁|"),
                      (run.chi2 / np.linalg.norm(run.chi2[0]), "χ₂/|χ₂|")):
    cone.plot(*vector.T, lw=0.8, label=label)
cone.set(xlabel="x", ylabel="y", zlabel="z", title="directions in the inertial frame")
cone.legend()

components = fig.add_subplot(1, 2, 2)
for k, axis in enumerate("xyz"):
    components.plot(run.t_seconds, run.ell_hat[:, k], label=f"ℓ̂_{axis}")
components.set(xlabel="t [s]", title="ℓ̂ against time (t = 0 at f_ref = 20 Hz)")
components.secondary_xaxis("top", functions=(lambda s: s / M, lambda t: t * M)).set_xlabel("t [M]")
frequency = components.twinx()
frequency.semilogy(run.t_seconds, run.f_gw, color="0.5", ls="--", label="f_GW")
frequency.set_ylabel("GW frequency [Hz]")
components.legend(loc="lower left")
plt.show()
