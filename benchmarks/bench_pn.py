"""Benchmark of pnrotor.pn.evolve against LALSuite's SpinTaylor orbit evolution, same cases, same output.

For every case (equal mass, q = 3, q = 10, near-extremal spins, BNS; nonspinning, aligned, precessing)
both codes produce the orbit uniformly sampled at Δt = 1/4096 s from f_start to the end of the
inspiral:

* LAL: ``pnrotor.interop.lal.spintaylor_series``, i.e.
  ``lalsimulation.SimInspiralSpinTaylorPNEvolveOrbit(Δt, …, fStart, fEnd=0, …, spinO=-1, tideO=0, phaseO=7,
  lscorr=0, SpinTaylorTn)`` (Python call included);
* pnrotor: ``evolve(…, f_start, approximant=Tn, sampling=Δt, **lalsuite_orders(Tn))`` (Python call
  included: unit conversion, setup, both integrations, sampling, rotor reconstruction).

Timings are medians over interleaved rounds (LAL and pnrotor alternate case by case), which is robust on
a shared machine.  Each timing includes freeing that call's own output and nothing else (freeing a
previous 30 MB BNS result can cost ~7 ms of system time on this machine, which would otherwise land on
whichever call happens to drop it).  pnrotor's cache of a binary's spin-independent set-up
(``pn.system._spin_independent_parts``, ~50–100 µs of Python) is emptied before each pnrotor call, so every
call pays it as for a new binary, as LAL does.  Also reported: pnrotor with sampling='steps' (every accepted step, no dense output)
and its integration-only wall time, its accepted steps, and the samples.  Numba compile time is
measured separately, in fresh processes with an empty NUMBA_CACHE_DIR (cold) and again with that
cache filled (warm).

    python benchmarks/bench_pn.py [--rounds 15] [--approximants T4 T1 T5] [--no-compile] [--json out.json]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from pn_cases import CASES  # noqa: E402  (the cases of tests/test_pn_lal.py)

DT = 1.0 / 4096


def compile_times():
    """Cold and warm numba start-up, each in a fresh process."""
    code = textwrap.dedent("""
        import json, time
        t0 = time.perf_counter()
        import pnrotor.quaternion, pnrotor.ode
        t1 = time.perf_counter()
        import pnrotor.pn
        t2 = time.perf_counter()
        pnrotor.pn.evolve(10, 10, [0, 0, 0], [0, 0, 0], 20.0, sampling=1 / 4096)
        t3 = time.perf_counter()
        pnrotor.pn.evolve(30, 10, [0.5, 0.1, 0.3], [0, 0.4, -0.2], 20.0, f_min=15.0, sampling=1 / 4096)
        t4 = time.perf_counter()
        pnrotor.pn.evolve(30, 10, [0.5, 0.1, 0.3], [0, 0.4, -0.2], 20.0, sampling=("per_orbit", 8),
                          approximant="T1")
        t5 = time.perf_counter()
        print(json.dumps(dict(import_quaternion_ode=t1 - t0, import_pn=t2 - t1, first_aligned=t3 - t2,
                              first_precessing=t4 - t3, first_other_modes=t5 - t4)))
    """)
    out = {}
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for label in ("cold", "warm"):
            r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            out[label] = json.loads(r.stdout.strip().splitlines()[-1])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--approximants", nargs="+", default=["T4"])
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    ap.add_argument("--no-compile", action="store_true")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()

    from pnrotor.interop.lal import spintaylor_series
    from pnrotor.pn import evolve, lalsuite_orders
    from pnrotor.pn.system import _spin_independent_parts

    def lal_call(case, approx):
        return spintaylor_series(*case, approx, DT)[0].data.length

    results = {}
    for approx in args.approximants:
        orders = lalsuite_orders(approx)
        runs = {}
        for name in args.cases:
            case = CASES[name]
            m1, m2, c1, c2, f = case
            # warm up both (numba cache load, LAL lazy init)
            n_lal = lal_call(case, approx)
            e = evolve(m1, m2, c1, c2, f, approximant=approx, sampling=DT, **orders)
            es = evolve(m1, m2, c1, c2, f, approximant=approx, sampling="steps", **orders)
            runs[name] = dict(lal=[], ours=[], ours_steps=[], integrate=[], n_lal=n_lal, n_ours=len(e),
                              steps=e.stats["naccepted"], rejected=e.stats["nrejected"], nfev=e.stats["nfev"],
                              state=e.inputs["state"], termination=e.termination, steps_rows=len(es))
        for _ in range(args.rounds):
            for name in args.cases:
                m1, m2, c1, c2, f = CASES[name]
                r = runs[name]
                # each timing includes freeing the output (LAL's SWIG series are destroyed when
                # lal_call returns), so no run pays for the deallocation of another one
                t = time.perf_counter()
                lal_call(CASES[name], approx)
                r["lal"].append(time.perf_counter() - t)
                _spin_independent_parts.cache_clear()   # each call pays its set-up, as for a new binary
                t = time.perf_counter()
                e = evolve(m1, m2, c1, c2, f, approximant=approx, sampling=DT, **orders)
                integ = e.stats["wall_time_integrate_s"]
                del e
                r["ours"].append(time.perf_counter() - t)
                r["integrate"].append(integ)
                _spin_independent_parts.cache_clear()
                t = time.perf_counter()
                e = evolve(m1, m2, c1, c2, f, approximant=approx, sampling="steps", **orders)
                del e
                r["ours_steps"].append(time.perf_counter() - t)
        print(f"\nSpinTaylor{approx} vs pnrotor {approx}: Δt = 1/4096 s, median of {args.rounds} interleaved rounds (ms)")
        print(f"{'case':26s} {'samples':>8s} {'LAL':>8s} {'pnrotor':>8s} {'ratio':>6s} {'steps-mode':>10s} "
              f"{'integr.':>8s} {'steps':>6s} {'rej':>4s} {'state':>10s}  end")
        for name, r in runs.items():
            med = {k: 1e3 * statistics.median(r[k]) for k in ("lal", "ours", "ours_steps", "integrate")}
            r["median_ms"] = med
            print(f"{name:26s} {r['n_ours']:8d} {med['lal']:8.2f} {med['ours']:8.2f} {med['lal'] / med['ours']:6.2f} "
                  f"{med['ours_steps']:10.2f} {med['integrate']:8.2f} {r['steps']:6d} {r['rejected']:4d} "
                  f"{r['state']:>10s}  {r['termination']}" + ("" if abs(r["n_ours"] - r["n_lal"]) <= 1
                                                             else f"  (LAL {r['n_lal']} samples)"))
        slower = [n for n, r in runs.items() if r["median_ms"]["ours"] >= r["median_ms"]["lal"]]
        print("pnrotor faster than LAL on every case" if not slower else f"pnrotor NOT faster on: {slower}")
        results[approx] = {n: {k: v for k, v in r.items() if k not in ("lal", "ours", "ours_steps", "integrate")}
                           for n, r in runs.items()}

    if not args.no_compile:
        ct = compile_times()
        print("\nNumba start-up (fresh processes; seconds):")
        for label, d in ct.items():
            print(f"  {label:5s} cache: " + ", ".join(f"{k} {v:.2f}" for k, v in d.items()))
        results["compile"] = ct
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
