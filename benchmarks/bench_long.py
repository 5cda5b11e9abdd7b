"""Benchmark of long signals: ``pnrotor.polarizations`` (h₊, h× straight from the dense output) against LALSuite's
``ChooseTDWaveform(SpinTaylorT4)``, from 10⁴ to 3·10⁷ samples, and the full default modes from 5 Hz streamed to HDF5.

The binary is the 1.4 + 1.3 M☉ precessing BNS of tests/pn_cases.py at Δt = 1/4096 s, from f_start (also f_ref) to
the end of the inspiral, seen at inclination 0.5 rad, φ_ref = 0, 100 Mpc:

* LAL: ``SimInspiralChooseTDWaveform(m1, m2, χ₁, χ₂, r, ι, 0, 0, 0, 0, Δt, f_start, f_start, LALparams,
  SpinTaylorT4)`` with PN amplitude order 3 (1.5PN) in LALparams;
* pnrotor: ``pnrotor.polarizations(m1, m2, χ₁, χ₂, f_start, inclination=ι, distance=r, delta_t=Δt, ell_max=4,
  amplitude_order=1.5, **lalsuite_orders("T4"))`` (ℓ ≤ 4: the modes LAL's 1.5PN polarizations hold but ℓ = 5's
  1.5PN terms), on pnrotor's threads (two here; LAL uses one).

Every call runs in a fresh process of its own (this script with ``--child``): the process imports its code and makes
one small call first (numba's cache loaded, pnrotor's worker thread started, LAL's set-ups), then times the call and reads its peak resident memory
(``ru_maxrss``) before and after: the call's peak is the difference, set against the 16 bytes per sample of the two
output arrays h₊, h× (pnrotor also returns t: 24 bytes per sample in all).  A fresh process pays the first touch of
its output's pages, as a new call of a long-running program does after the memory went back to the system (about
4.5 µs a page on this virtual machine, README).  Rounds alternate LAL and pnrotor case by case; the table gives
medians and (min–max) ranges.  LAL from 5 Hz needs ~6.6 GB and ~16 s: it runs ``--lal-5hz-rounds`` times (1 by
default), and calls expected to need more than 4 GB wait until that much memory is available (on a shared machine:
never two big ones at once).

Last, ``--stream``: the full default, ℓ ≤ 8 at 3.5PN (``pnrotor.stream(…).modes()``: 77 modes, 34 GB from 5 Hz), written
with ``pnrotor.hdf5.write`` to ``--stream-dir`` in a fresh process, its peak memory and time; the file is removed
afterwards.  It needs that much free disk (checked first).

    python benchmarks/bench_long.py [--rounds 3] [--frequencies 100 60 40 25 15 10 7 5] [--lal-5hz-rounds 1]
                                    [--stream] [--stream-dir /tmp]
"""

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from pn_cases import CASES  # noqa: E402

M1, M2, CHI1, CHI2, _ = CASES["BNS-precessing"]
DT, INCLINATION, DISTANCE_MPC = 1.0 / 4096, 0.5, 100.0
LAL_BYTES_PER_SAMPLE = 240
"""LAL's peak per sample (6.6 GB for 2.8·10⁷ samples, the issue's measurement): the memory a LAL call waits for."""


def child(which, f_start):
    """One call in this process after a small one: its wall time and peak memory, as JSON on stdout."""
    if which == "lal":
        import lal
        import lalsimulation as ls

        params = lal.CreateDict()
        ls.SimInspiralWaveformParamsInsertPNAmplitudeOrder(params, 3)

        def call(f):
            hp, hc = ls.SimInspiralChooseTDWaveform(M1 * lal.MSUN_SI, M2 * lal.MSUN_SI, *CHI1, *CHI2,
                                                    DISTANCE_MPC * 1e6 * lal.PC_SI, INCLINATION, 0.0, 0.0, 0.0, 0.0, DT,
                                                    f, f, params, ls.SpinTaylorT4)
            return hp.data.length
    elif which == "ours":
        import pnrotor
        from pnrotor.pn import lalsuite_orders

        orders = lalsuite_orders("T4")

        def call(f):
            t, hp, hc = pnrotor.polarizations(M1, M2, CHI1, CHI2, f, inclination=INCLINATION, distance=DISTANCE_MPC,
                                              delta_t=DT, ell_max=4, amplitude_order=1.5, **orders)
            return t.size
    else:   # the full default modes streamed to a file: f_start is the file's folder's run
        import pnrotor
        from pnrotor.pn import lalsuite_orders

        folder = which.partition(":")[2]

        def call(f):
            path = os.path.join(folder, "bench_long_stream.h5")
            modes = pnrotor.stream(M1, M2, CHI1, CHI2, f, delta_t=DT, **lalsuite_orders("T4")).modes(
                distance=DISTANCE_MPC)
            try:
                pnrotor.hdf5.write(path, modes, overwrite=True)
                print(json.dumps({"file_GB": os.path.getsize(path) / 1e9}), file=sys.stderr)
            finally:
                if os.path.exists(path):
                    os.unlink(path)
            return len(modes)
    call(150.0)   # 3,500 samples: numba's cache loaded, pnrotor's worker thread started, LAL's set-ups made
    before = resource.getrusage(resource.RUSAGE_SELF)
    t = time.perf_counter()
    n = call(f_start)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_SELF)
    print(json.dumps(dict(samples=n, seconds=wall, before_MB=before.ru_maxrss / 1024, peak_MB=after.ru_maxrss / 1024,
                          user=after.ru_utime - before.ru_utime, sys=after.ru_stime - before.ru_stime,
                          faults=after.ru_minflt - before.ru_minflt)))


def available_GB():
    with open("/proc/meminfo") as f:
        info = dict(line.split(":", 1) for line in f)
    return int(info["MemAvailable"].split()[0]) / 2 ** 20


def run_child(which, f_start, need_GB=0.0):
    """The result of :func:`child` in a fresh process; first waits (up to 10 min) until ``need_GB`` are available."""
    waited = 0
    while need_GB > 4 and available_GB() < need_GB + 2:
        if waited >= 600:
            raise SystemExit(f"{which} from {f_start} Hz needs ~{need_GB:.1f} GB; only {available_GB():.1f} GB "
                             f"available for 10 minutes")
        time.sleep(10)
        waited += 10
    out = subprocess.run([sys.executable, __file__, "--child", which, str(f_start)], capture_output=True, text=True,
                         check=True)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    for line in out.stderr.strip().splitlines():
        if line.startswith("{"):
            result.update(json.loads(line))
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--frequencies", type=float, nargs="+", default=[100, 60, 40, 25, 15, 10, 7, 5])
    ap.add_argument("--lal-5hz-rounds", type=int, default=1)
    ap.add_argument("--stream", action="store_true", help="also stream the full default modes from 5 Hz to a file")
    ap.add_argument("--stream-dir", default=tempfile.gettempdir())
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args.child[0], float(args.child[1]))

    results = {f: {"lal": [], "ours": []} for f in args.frequencies}
    for r in range(args.rounds):
        for f in args.frequencies:
            for which in ("lal", "ours"):
                if which == "lal" and f <= 5 and r >= args.lal_5hz_rounds:
                    continue
                samples = results[f]["ours"][0]["samples"] if results[f]["ours"] else 2.8e7 * (5 / f) ** (8 / 3)
                need = samples * LAL_BYTES_PER_SAMPLE / 1e9 if which == "lal" else samples * 24 / 1e9
                results[f][which].append(run_child(which, f, need))
    print(f"1.4 + 1.3 Msun precessing BNS, dt = 1/4096 s, h+ and hx (pnrotor: l <= 4, 1.5PN amplitude, 2 threads; "
          f"LAL ChooseTDWaveform SpinTaylorT4, ampO 3); each call in a fresh process; medians (min-max) of "
          f"{args.rounds} rounds (LAL from 5 Hz: {args.lal_5hz_rounds})")
    print(f"{'f_start':>7s} {'samples':>10s} {'LAL s':>20s} {'pnrotor s':>20s} {'LAL/pnrotor':>11s} "
          f"{'ns/sample':>9s} {'LAL MB':>8s} {'pnrotor MB':>10s} {'pnrotor/(h+,hx)':>15s}")
    per_sample = {}
    for f, r in results.items():
        n = r["ours"][0]["samples"]
        lal_s = [x["seconds"] for x in r["lal"]]
        ours_s = [x["seconds"] for x in r["ours"]]
        peak = lambda xs: max(x["peak_MB"] - x["before_MB"] for x in xs)  # noqa: E731
        per_sample[f] = 1e9 * statistics.median(ours_s) / n
        span = lambda xs: f"{statistics.median(xs):7.3f} ({min(xs):.3f}-{max(xs):.3f})"  # noqa: E731
        ratio = statistics.median(lal_s) / statistics.median(ours_s) if lal_s else float("nan")
        lal_n = {x["samples"] for x in r["lal"]}
        print(f"{f:7g} {n:10d} {span(lal_s) if lal_s else '-':>20s} {span(ours_s):>20s} {ratio:11.2f} "
              f"{per_sample[f]:9.1f} {peak(r['lal']) if r['lal'] else float('nan'):8.0f} {peak(r['ours']):10.0f} "
              f"{peak(r['ours']) * 2 ** 20 / (16 * n):15.2f}" + ("" if lal_n <= {n, n + 1, n - 1} else f"  (LAL {lal_n})"))
    cpu = lambda xs: "/".join(f"{statistics.median(x[k] for x in xs):.2f}" for k in ("user", "sys"))  # noqa: E731
    print("CPU seconds of the calls, user/sys (medians), and page faults: "
          + "; ".join(f"{f:g} Hz LAL {cpu(r['lal']) if r['lal'] else '-'} ({r['lal'][0]['faults'] if r['lal'] else '-'}), "
                      f"pnrotor {cpu(r['ours'])} ({r['ours'][0]['faults']})" for f, r in results.items()))
    best = min(per_sample.values())
    print(f"pnrotor's ns/sample from {min(per_sample)} to {max(per_sample)} Hz: {best:.1f} to {max(per_sample.values()):.1f} "
          f"(largest / smallest {max(per_sample.values()) / best:.2f})")

    if args.stream:
        f = min(args.frequencies)
        need = 16 * 77 * results[f]["ours"][0]["samples"] * 1.05 / 1e9
        free = shutil.disk_usage(args.stream_dir).free / 1e9
        if free < need + 20:
            raise SystemExit(f"--stream needs ~{need:.0f} GB of disk in {args.stream_dir} (and 20 GB to spare); "
                             f"{free:.0f} GB free")
        r = run_child(f"stream:{args.stream_dir}", f)
        print(f"full default modes (l <= 8, 3.5PN; 77 modes) from {f:g} Hz streamed to HDF5 (hdf5.write of "
              f"pnrotor.stream(...).modes(), checksummed): {r['samples']} samples, {r['file_GB']:.1f} GB file in "
              f"{r['seconds']:.0f} s; peak memory of the call {r['peak_MB'] - r['before_MB']:.0f} MB "
              f"(process {r['peak_MB']:.0f} MB)")


if __name__ == "__main__":
    main()
