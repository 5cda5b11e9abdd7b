"""Benchmark of waveform modes: pnrotor's evolve + modes against LALSuite's SpinTaylorT4 modes, same cases,
same grid, same run.

For every case of tests/pn_cases.py (BBH at q = 1, 3, 10, near-extremal spins and BNS; nonspinning,
aligned, precessing), sampled at Δt = 1/4096 s from f_start to the end of the inspiral:

* LAL: ``SimInspiralChooseTDModes(0, Δt, m1, m2, χ₁, χ₂, f_start, f_start, r, LALparams, lmax=4,
  SpinTaylorT4)`` with PN amplitude order 3 (1.5PN) in LALparams (its orbit and its inertial modes);
* pnrotor (ℓ ≤ 4): ``evolve(…, sampling=Δt, **lalsuite_orders("T4"))`` then ``modes(run, ell_max=4,
  amplitude_order=1.5, distance=r)``;
* pnrotor's default: the same evolution, ``modes(run)`` (ℓ ≤ 8, 3.5PN).

modes() computes a run of ≥ 2,048 samples in parts on the machine's threads (:mod:`pnrotor.threads`, two here);
LAL uses one.  The column "1 thread" is pnrotor's ℓ ≤ 4 again with one thread (``numba.set_num_threads(1)``).

Timings include the Python calls and freeing each call's own output, and pnrotor's set-ups of each binary (its
caches of spin-independent parts and of mode terms, `pn.system.cached_spin_independent_parts` and
`waveform.amplitudes._real_terms`, are emptied before each call, as for a new binary: ~0.07–0.12 ms and
~0.07–0.10 ms); medians over interleaved rounds
(LAL, ours, LAL, ours with one thread, LAL, ours-default and the evolution alone, case by case: each of the three
ours after a LAL call, whose freed output decides what our first touch of fresh memory costs; the one-thread
column had read 20% faster than the two-thread one when it came right after it), robust on a shared machine.  The
last two columns are modes()' own cost per sample, (evolve + modes − evolve) / samples, in ns.

The last line measures what the machine charges for fresh memory, for the largest default output of the table:
filling a new array of its size right after freeing one (memory the kernel has at hand), and after 3 s idle
(a virtual machine with Linux free page reporting has by then handed the freed memory back to its host, and
touching it again faults on the host).  Large outputs pay this inside the timed calls, LAL's as well as ours.

    python benchmarks/bench_modes.py [--rounds 7] [--cases NAME ...]
"""

import argparse
import os
import statistics
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from pn_cases import CASES  # noqa: E402

DT = 1.0 / 4096
DISTANCE_MPC = 100.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    args = ap.parse_args()

    import lal
    import lalsimulation as ls

    from pnrotor import evolve, modes
    from pnrotor.pn import lalsuite_orders
    from pnrotor.pn.system import cached_spin_independent_parts
    from pnrotor.waveform.amplitudes import _real_terms
    from pnrotor.waveform.layout import n_modes

    orders = lalsuite_orders("T4")
    params = lal.CreateDict()
    ls.SimInspiralWaveformParamsInsertPNAmplitudeOrder(params, 3)

    def lal_modes(case):
        m1, m2, c1, c2, f = case
        node = ls.SimInspiralChooseTDModes(0.0, DT, m1 * lal.MSUN_SI, m2 * lal.MSUN_SI, *c1, *c2, f, f,
                                           DISTANCE_MPC * 1e6 * lal.PC_SI, params, 4, ls.SpinTaylorT4)
        return node.mode.data.length

    def ours(case, **options):
        m1, m2, c1, c2, f = case
        return len(modes(evolve(m1, m2, c1, c2, f, sampling=DT, **orders), distance=DISTANCE_MPC, **options).t)

    numba.set_num_threads(numba.get_num_threads())   # launch numba's parallel layer (~50 ms) before the timings
    runs = {}
    for name in args.cases:
        case = CASES[name]
        runs[name] = dict(samples=ours(case, ell_max=4, amplitude_order=1.5), lal_samples=lal_modes(case),
                          lal=[], ours=[], single=[], full=[], evolve=[])
        ours(case)
    for _ in range(args.rounds):
        for name in args.cases:
            case, r = CASES[name], runs[name]
            lal_call = ("lal", lambda: lal_modes(case))
            for key, call in (lal_call, ("ours", lambda: ours(case, ell_max=4, amplitude_order=1.5)),
                              lal_call, ("single", lambda: one_thread(ours, case, ell_max=4, amplitude_order=1.5)),
                              lal_call, ("full", lambda: ours(case)),
                              ("evolve", lambda: evolve(*case, sampling=DT, **orders))):
                cached_spin_independent_parts.cache_clear()   # each call pays its set-ups, as for a new binary
                _real_terms.cache_clear()
                t = time.perf_counter()
                call()
                r[key].append(time.perf_counter() - t)
    print(f"LAL SpinTaylorT4 modes (l <= 4, 1.5PN) vs pnrotor evolve + modes; dt = 1/4096 s; "
          f"median of {args.rounds} interleaved rounds (ms)")
    print(f"{'case':26s} {'samples':>8s} {'LAL':>8s} {'l<=4':>8s} {'ratio':>6s} {'1 thread':>9s} {'ratio':>6s} "
          f"{'l<=8,3.5':>9s} {'ratio':>6s} {'modes ns/sample l<=4, l<=8':>27s}")
    worst, worst_single, worst_full = [], [], []
    for name, r in runs.items():
        lal_ms, ours_ms, single_ms, full_ms, evolve_ms = (1e3 * statistics.median(r[k])
                                                          for k in ("lal", "ours", "single", "full", "evolve"))
        worst.append(lal_ms / ours_ms)
        worst_single.append(lal_ms / single_ms)
        worst_full.append(lal_ms / full_ms)
        per_sample = [1e6 * (ms - evolve_ms) / r["samples"] for ms in (ours_ms, full_ms)]
        print(f"{name:26s} {r['samples']:8d} {lal_ms:8.2f} {ours_ms:8.2f} {lal_ms / ours_ms:6.2f} {single_ms:9.2f} "
              f"{lal_ms / single_ms:6.2f} {full_ms:9.2f} {lal_ms / full_ms:6.2f} {per_sample[0]:18.0f} "
              f"{per_sample[1]:8.0f}"
              + ("" if abs(r["samples"] - r["lal_samples"]) <= 1 else f"  (LAL {r['lal_samples']} samples)"))
    print(f"LAL / pnrotor, l <= 4 at 1.5PN: min {min(worst):.2f}, median {statistics.median(worst):.2f} "
          f"(one thread: min {min(worst_single):.2f}, median {statistics.median(worst_single):.2f}); "
          f"pnrotor's default (l <= 8, 3.5PN): min {min(worst_full):.2f}, median {statistics.median(worst_full):.2f}")
    shape = (n_modes(8), max(r["samples"] for r in runs.values()))
    at_hand, idle = fresh_memory(shape)
    print(f"fresh memory, {np.prod(shape) * 16 / 1e6:.0f} MB (the largest default output) filled: "
          f"{at_hand:.0f} ms right after freeing as much, {idle:.0f} ms after 3 s idle (medians of 3)")


def one_thread(call, *args, **options):
    """call(*args, **options) with numba's threads, and so pnrotor's, set to one for it (numba's parallel layer is
    launched before the timings, in main)."""
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        return call(*args, **options)
    finally:
        numba.set_num_threads(before)


def fresh_memory(shape, repeat=3):
    """Milliseconds to allocate and fill a complex array of ``shape`` right after freeing one of that size,
    and after 3 s idle (medians)."""
    times = {True: [], False: []}
    for _ in range(repeat):
        for idle in (False, True):
            np.ones(shape, dtype=complex)
            if idle:
                time.sleep(3.0)
            t = time.perf_counter()
            np.ones(shape, dtype=complex)
            times[idle].append(1e3 * (time.perf_counter() - t))
    return statistics.median(times[False]), statistics.median(times[True])


if __name__ == "__main__":
    main()
