"""
PN work–precision: pnrotor against LALSuite and scipy
=====================================================

The error of the whole PN system — the orbital frame, including the phase — against a converged reference, and the
time each run takes, for a 30 + 10 M☉ precessing binary from 20 Hz to the end of its inspiral sampled at 1/4096 s:
pnrotor's DOP853 at three tolerances, LALSuite's SpinTaylorT4 and scipy's DOP853 on pnrotor's right-hand side, all
with LALSuite's T4 truncation (`pnrotor.pn_study`, which ``pnrotor bench --pn`` runs on four binaries at nine
tolerances). Times are one call each on whatever else the machine is doing: the median over interleaved rounds is in
``pnrotor bench --pn`` and docs/performance.md.
"""

import matplotlib.pyplot as plt

from pnrotor import pn_study

case = pn_study.CASES["BBH-precessing"]
info, rows = pn_study.measure_errors("BBH-precessing", case, [1e-6, 1e-9, 1e-12], [("DOP853", 1e-10)], use_lal=True)
rows = [row for row in rows if row["tol"] not in (pn_study.ATOL_REF, pn_study.ATOL_CHECK)]
fig, axes = plt.subplots(figsize=(8, 5), layout="constrained")
for row in rows:
    seconds = min(pn_study.timed(pn_study.callable_of(row, case, info["n"]))[0] for _ in range(3))
    label = row["method"] + ("" if row["tol"] is None else f", tol {row['tol']:g}")
    print(f"{label:24s} frame error {row['frame']:.1e} rad, {seconds * 1e3:.2f} ms")
    marker = {"pnrotor": "o", "LAL T4": "s"}.get(row["method"], "^")
    axes.loglog(seconds, row["frame"], marker, ms=8, label=label)
axes.set(xlabel="wall time of one call [s] (best of 3)", ylabel="max frame error [rad]",
         title=f"{info['n']:,} samples, {info['t_final_s']:.2f} s of signal")
axes.legend()
plt.show()
