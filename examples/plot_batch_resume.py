"""
A batch, interrupted and resumed
================================

`pnrotor.batch.run` runs a table of binaries into one HDF5 file (``pnrotor evolve --batch`` from the shell). Each
finished run is on disk at once in ``OUTPUT.parts``; the batch file is assembled only at the end. Here a Ctrl-C
(simulated: the third run raises `KeyboardInterrupt`) stops the batch after two runs; ``resume=True`` computes
only the other three and the file is the one an uninterrupted batch writes.
"""

import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import pnrotor
from pnrotor import batch, hdf5

folder = Path(tempfile.mkdtemp())
table = folder / "binaries.csv"
table.write_text("name,m1,m2,chi1,chi2,f_ref,sampling\n"
                 'q1,10,10,"0,0,0.5","0.3,0,0",20,per_orbit:8\n'
                 'q2,20,10,"0.5,0,0.2","0,0.3,0",20,per_orbit:8\n'
                 'q3,30,10,"0.6,0,0.2","0,-0.4,0.1",20,per_orbit:8\n'
                 'q5,50,10,"0.7,0,0","0,0,0",20,per_orbit:8\n'
                 'q8,40,5,"0.4,0.4,0","0,0,0.5",20,per_orbit:8\n')
output = folder / "batch.h5"

computed, evolve_row = [], batch.backends.evolve_row


def interrupted_at_the_third(params):
    computed.append(params)
    if len(computed) == 3:
        raise KeyboardInterrupt        # what Ctrl-C raises in the batch's process
    return evolve_row(params)


batch.backends.evolve_row = interrupted_at_the_third
try:
    batch.run(table, output, jobs=1)
except KeyboardInterrupt as stop:
    print(f"interrupted: {stop}")
print("kept:", sorted(os.listdir(folder / "batch.h5.parts")))

computed.clear()
batch.backends.evolve_row = lambda params: computed.append(params) or evolve_row(params)
outcome = batch.run(table, output, jobs=1, resume=True)
batch.backends.evolve_row = evolve_row
print(f"resumed: {len(computed)} runs computed, {outcome.written} in {output.name}: {hdf5.list_runs(output)}")

fig, axes = plt.subplots(figsize=(9, 4.5), layout="constrained")
for name in hdf5.list_runs(output):
    run = hdf5.read(output, name)
    axes.plot(run.t_seconds - run.t_seconds[-1], run.ell_hat[:, 2], lw=0.8, label=f"{name}: {run.inputs['m1_Msun']:g} + "
              f"{run.inputs['m2_Msun']:g} M☉")
axes.set(xlabel="t [s] (0 at each run's end)", ylabel="ℓ̂_z", title="the orbital plane's tilt from ẑ, every run of the batch")
axes.legend()
plt.show()
