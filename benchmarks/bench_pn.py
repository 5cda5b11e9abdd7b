"""Benchmark of pnrotor.pn.evolve against LALSuite's SpinTaylor orbit evolution, same cases, same output.

For every case (equal mass, q = 3, q = 10, near-extremal spins, BNS; nonspinning, aligned, precessing; and
with neutron-star tides, :data:`TIDAL`: a 1.4 + 1.3 M☉ BNS from 40 Hz with Λ = 350, 820, nonspinning and
precessing, and an 8 + 1.4 M☉ NSBH with Λ₂ = 600) both codes produce the orbit uniformly sampled at
Δt = 1/4096 s from f_start to the end of the inspiral:

* LAL: ``pnrotor.interop.lal.spintaylor_series``, i.e.
  ``lalsimulation.SimInspiralSpinTaylorPNEvolveOrbit(Δt, …, fStart, fEnd=0, …, lambda1, lambda2, …, spinO=-1,
  tideO=-1 with tides or 0, phaseO=7, lscorr=0, SpinTaylorTn)`` (Python call included);
* pnrotor: ``evolve(…, f_start, approximant=Tn, sampling=Δt, lambda1=…, lambda2=…, **lalsuite_orders(Tn))``
  (Python call included: unit conversion, setup, both integrations, sampling, rotor reconstruction).

Then the cost of each of pnrotor's physics options against the same run without it, interleaved (``--options``
only, or skipped with ``--no-options``; orbits with sampling='final', so that the cost of ~10⁵ output samples,
whose allocation varies by ms from call to call on a shared machine, is not measured): the tides of that BNS, horizon
absorption on a q = 10 binary with χ₁ = 0.9 along ℓ̂ (the run without it on the aligned state, with it on the
precessing one, as evolve chooses) and tilted 60° from it (precessing either way), and the orbital phase it adds to
v = 0.3, 0.4 and the end of the inspiral with the spin's and mass's change there, the modes of the BNS at amplitude
order 4 against 3.5 and with the memory against without.

Timings are medians over interleaved rounds (LAL and pnrotor alternate case by case), which is robust on
a shared machine.  Each timing includes freeing that call's own output and nothing else (freeing a
previous 30 MB BNS result can cost ~7 ms of system time on this machine, which would otherwise land on
whichever call happens to drop it).  pnrotor's cache of a binary's spin-independent set-up
(``pn.system.cached_spin_independent_parts``, ~50–100 µs of Python) is emptied before each pnrotor call, so every
call pays it as for a new binary, as LAL does.  Also reported: pnrotor with sampling='steps' (every accepted step, no dense output)
and its integration-only wall time, its accepted steps, and the samples.  Numba compile time is
measured separately, in fresh processes with an empty NUMBA_CACHE_DIR (cold) and again with that
cache filled (warm).

    python benchmarks/bench_pn.py [--rounds 15] [--approximants T4 T1 T5] [--no-compile] [--no-options]
                                  [--options] [--json out.json]
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

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from pn_cases import CASES  # noqa: E402  (the cases of tests/test_pn_lal.py)

DT = 1.0 / 4096
TIDAL = {   # m1, m2, χ₁, χ₂, f_start, (Λ₁, Λ₂): cases of tests/test_pn_tides.py
    "BNS-tidal": (1.4, 1.3, [0, 0, 0], [0, 0, 0], 40.0, (350.0, 820.0)),
    "BNS-tidal-precessing": (1.4, 1.3, [0.03, 0.02, 0.03], [0.0, -0.04, 0.01], 40.0, (350.0, 820.0)),
    "NSBH-tidal": (8.0, 1.4, [0, 0, 0.5], [0, 0, 0], 30.0, (0.0, 600.0)),
}
ALL = {**{name: (*case, (0.0, 0.0)) for name, case in CASES.items()}, **TIDAL}


def _median_ms(samples):
    return 1e3 * statistics.median(samples)


def option_costs(rounds):
    """Each physics option's cost: the run (or its modes) with the option against the same without it, interleaved
    round by round (a call of < 20 ms as the mean of a loop of ~20 ms, the same count with and without) → {option:
    (median ms without, its range, median ms with, its range, the median of the rounds' ratios with/without, their
    range)} (ranges (min, max) over the rounds)."""
    from pnrotor.pn import evolve, lalsuite_orders
    from pnrotor.pn.system import cached_spin_independent_parts
    from pnrotor.waveform.modes import modes

    m1, m2, c1, c2, f, lambdas = TIDAL["BNS-tidal"]
    orders = lalsuite_orders("T4")
    base = dict(approximant="T4", sampling="final", **orders)   # the model's cost: set-up and integration
    run = evolve(m1, m2, c1, c2, f, **{**base, "sampling": DT})
    bh, tilted = ((50.0, 5.0, HORIZON_SPINS[name], [0, 0, 0], 20.0) for name in ("aligned", "tilted 60 deg"))
    pairs = {
        "tides (BNS from 40 Hz, Λ = 350, 820; evolve)": (
            lambda: evolve(m1, m2, c1, c2, f, **base),
            lambda: evolve(m1, m2, c1, c2, f, lambda1=lambdas[0], lambda2=lambdas[1], **base)),
        "horizon absorption (50 + 5 Msun, chi1 = 0.9 along l, 20 Hz)": (
            lambda: evolve(*bh, **base), lambda: evolve(*bh, horizon_absorption=True, **base)),
        "horizon absorption (50 + 5 Msun, chi1 = 0.9 tilted 60 deg, 20 Hz)": (
            lambda: evolve(*tilted, **base), lambda: evolve(*tilted, horizon_absorption=True, **base)),
        "amplitude order 4 against 3.5 (modes, l <= 8, the BNS)": (
            lambda: modes(run, 8, 3.5), lambda: modes(run, 8, 4.0)),
        "memory (modes, l <= 8, the BNS)": (
            lambda: modes(run, 8, 3.5), lambda: modes(run, 8, 3.5, memory=True)),
    }
    times = {name: ([], []) for name in pairs}
    repeats = {}
    for name, (off, on) in pairs.items():   # warm up; calls of < 20 ms are timed in a loop of ~20 ms
        on()
        t = time.perf_counter()
        off()
        repeats[name] = max(1, round(0.02 / (time.perf_counter() - t)))
    for _ in range(rounds):
        for name, (off, on) in pairs.items():
            for fn, out in zip((off, on), times[name]):
                t = time.perf_counter()
                for _ in range(repeats[name]):
                    cached_spin_independent_parts.cache_clear()
                    fn()
                out.append((time.perf_counter() - t) / repeats[name])
    span = lambda x: (min(x), max(x))  # noqa: E731
    return {name: (_median_ms(a), span([1e3 * x for x in a]), _median_ms(b), span([1e3 * x for x in b]),
                   statistics.median([y / x for x, y in zip(a, b)]), span([y / x for x, y in zip(a, b)]))
            for name, (a, b) in times.items()}


HORIZON_SPINS = {"aligned": [0.0, 0.0, 0.9], "tilted 60 deg": [0.9 * 3 ** 0.5 / 2, 0.0, 0.45]}
"""χ₁ of the q = 10 binaries of horizon absorption's cost and dephasing: 0.9 along ℓ̂ = ẑ and tilted 60° from it."""


def horizon_dephasing():
    """What horizon absorption does to the q = 10 binaries of :func:`option_costs` (χ₁ = 0.9 along ℓ̂ and tilted 60°,
    T4 at LAL's orders) from 20 Hz to the GW frequencies of v = 0.3 and 0.4 and to the end of the inspiral (each run
    to its own end) → {spin: {target: (ΔΦ in rad, Δ|χ₁|, Δm₁ in M☉, v at the end with the option)}}: the orbital
    phase it adds, the change of the hole's spin magnitude and mass."""
    from pnrotor.pn import evolve, lalsuite_orders
    from pnrotor.pn.initial import frequency_from_v, total_mass_seconds

    out = {}
    for name, chi1 in HORIZON_SPINS.items():
        out[name] = {}
        for v in (0.3, 0.4, "end"):
            f_max = None if v == "end" else frequency_from_v(v, total_mass_seconds(50.0, 5.0))
            off, on = (evolve(50.0, 5.0, chi1, [0, 0, 0], 20.0, f_max=f_max, sampling="final", horizon_absorption=h,
                              **lalsuite_orders("T4")) for h in (False, True))
            out[name][v] = (on.Phi[-1] - off.Phi[-1], float(np.linalg.norm(on.chi1[-1]) - 0.9),
                            on.stats["m1_final_Msun"] - 50.0, float(on.v[-1]))
    return out


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
    ap.add_argument("--cases", nargs="+", default=list(ALL))
    ap.add_argument("--no-compile", action="store_true")
    ap.add_argument("--no-options", action="store_true", help="skip the cost of the physics options")
    ap.add_argument("--options", action="store_true", help="only the cost of the physics options")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()

    from pnrotor.interop.lal import spintaylor_series
    from pnrotor.pn import evolve, lalsuite_orders
    from pnrotor.pn.system import cached_spin_independent_parts

    def lal_call(case, approx):
        *binary, lambdas = case
        return spintaylor_series(*binary, approx, DT, lambdas=lambdas, tideO=-1 if any(lambdas) else 0)[0].data.length

    results = {}
    if args.options:
        args.approximants, args.no_compile = [], True
    for approx in args.approximants:
        orders = lalsuite_orders(approx)
        runs = {}
        for name in args.cases:
            case = ALL[name]
            m1, m2, c1, c2, f, (l1, l2) = case
            # warm up both (numba cache load, LAL lazy init)
            n_lal = lal_call(case, approx)
            e = evolve(m1, m2, c1, c2, f, approximant=approx, sampling=DT, lambda1=l1, lambda2=l2, **orders)
            es = evolve(m1, m2, c1, c2, f, approximant=approx, sampling="steps", lambda1=l1, lambda2=l2, **orders)
            runs[name] = dict(lal=[], ours=[], ours_steps=[], integrate=[], n_lal=n_lal, n_ours=len(e),
                              steps=e.stats["naccepted"], rejected=e.stats["nrejected"], nfev=e.stats["nfev"],
                              state=e.inputs["state"], termination=e.termination, steps_rows=len(es))
        for _ in range(args.rounds):
            for name in args.cases:
                m1, m2, c1, c2, f, (l1, l2) = ALL[name]
                r = runs[name]
                # each timing includes freeing the output (LAL's SWIG series are destroyed when
                # lal_call returns), so no run pays for the deallocation of another one
                t = time.perf_counter()
                lal_call(ALL[name], approx)
                r["lal"].append(time.perf_counter() - t)
                cached_spin_independent_parts.cache_clear()   # each call pays its set-up, as for a new binary
                t = time.perf_counter()
                e = evolve(m1, m2, c1, c2, f, approximant=approx, sampling=DT, lambda1=l1, lambda2=l2, **orders)
                integ = e.stats["wall_time_integrate_s"]
                del e
                r["ours"].append(time.perf_counter() - t)
                r["integrate"].append(integ)
                cached_spin_independent_parts.cache_clear()
                t = time.perf_counter()
                e = evolve(m1, m2, c1, c2, f, approximant=approx, sampling="steps", lambda1=l1, lambda2=l2, **orders)
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

    if not args.no_options:
        costs = option_costs(args.rounds)
        print(f"\nCost of the physics options: median of {args.rounds} interleaved rounds (ms, range over the rounds; "
              "ratio: median of the rounds' with/without, range)")
        for name, (off, (a, b), on, (c, d), ratio, (lo, hi)) in costs.items():
            print(f"  {name:66s} without {off:8.2f} ({a:.2f}-{b:.2f})  with {on:8.2f} ({c:.2f}-{d:.2f})  "
                  f"ratio {ratio:5.2f} ({lo:.2f}-{hi:.2f})")
        dephasing = horizon_dephasing()
        for name, by_v in dephasing.items():
            print(f"  horizon absorption, 50 + 5 Msun, chi1 = 0.9 {name}, from 20 Hz: orbital phase "
                  + ", ".join(f"{phase:+.4f} rad to v = {v}" for v, (phase, *_) in by_v.items() if v != "end")
                  + ", {:+.4f} rad to the end (v = {:.4f}); there |chi1| {:+.3e}, m1 {:+.3e} Msun".format(
                      by_v["end"][0], by_v["end"][3], *by_v["end"][1:3]))
        results["options"] = costs
        results["horizon_dephasing"] = dephasing
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
