"""
A population's spin tilts: 20 Hz against the end of the inspiral
=================================================================

2,000 binaries with isotropic spins at 20 Hz, evolved together by `pnrotor.evolve_many` to the end of each
inspiral (one compiled loop, only the final states kept). Spin–orbit coupling moves the tilts θᵢ between χᵢ and ℓ̂
as the binaries precess; the masses set how long each has to do so.
"""

import matplotlib.pyplot as plt
import numpy as np

import pnrotor
from pnrotor.pn.initial import MTSUN_SI

rng = np.random.default_rng(2026)
n = 2000
m1 = rng.uniform(10, 50, n)
m2 = rng.uniform(5, 10, n)


def isotropic(n, largest):
    direction = rng.normal(size=(n, 3))
    return direction / np.linalg.norm(direction, axis=1)[:, None] * rng.uniform(0, largest, n)[:, None]


chi1, chi2 = isotropic(n, 0.9), isotropic(n, 0.9)
end = pnrotor.evolve_many(m1, m2, chi1, chi2, f_ref=20.0)
start = np.degrees(np.arccos(chi1[:, 2] / np.linalg.norm(chi1, axis=1)))   # ℓ̂ = ẑ at f_ref
print(dict(zip(*np.unique(end.termination, return_counts=True))))

fig, (tilts, frequencies) = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
points = tilts.scatter(start, np.degrees(end.theta1), c=m1 / m2, s=4, cmap="viridis")
tilts.plot([0, 180], [0, 180], color="0.5", lw=0.8)
tilts.set(xlabel="θ₁ at 20 Hz [deg]", ylabel="θ₁ at the end of the inspiral [deg]", title="tilt of χ₁ from ℓ̂")
fig.colorbar(points, ax=tilts, label="m₁ / m₂")
M = (m1 + m2) * MTSUN_SI                 # G M / c³ in seconds
frequencies.hist(end.v ** 3 / (np.pi * M), bins=np.geomspace(50, 5000, 41))   # f_GW = v³ / (π M)
frequencies.set(xlabel="GW frequency at the end [Hz]", ylabel="binaries", xscale="log",
                title="where the inspirals end (`termination` says why)")
plt.show()
