"""Binaries per second: pnrotor.evolve_many against LALSuite's SpinTaylorT4 orbit, one end state per binary.

A population of N precessing "30 + 10 M☉-like" binaries (m₁ ∈ [25, 35], m₂ ∈ [8, 12] M☉, isotropic spins
with |χᵢ| ≤ 0.9, f_ref = 20 Hz, ℓ̂ = ẑ), the same truncation on both sides (``lalsuite_orders("T4")``),
each integrated to one state:

* ``end``: to the end of the inspiral.  LAL: ``SimInspiralSpinTaylorPNEvolveOrbitOnlyFinal`` with fEnd = 0
  (timed only: with fEnd = 0, or an fEnd beyond the end, it returns the initial v and zero spins, since it
  stores a state only on reaching fEnd; its integration runs all the same).
* ``100 Hz``: forward to f_GW = 100 Hz, where both return a state (LAL's at its first step past fEnd).
* ``list``: the states at 10 frequencies, 10 … 200 Hz on both sides of f_ref, with ``frequencies=`` (one
  integration per direction) against 10 ``evolve_many`` calls with f_end (one integration per target) and
  LAL's one call per target (backward targets: LAL integrates from fStart = the target up to f_ref).

Rates, medians of interleaved rounds: pnrotor ``evolve_many`` with numba's threads (all cores) and with
one thread; pnrotor single ``evolve(..., sampling='final')`` calls in a Python loop; LAL one call per
binary in a Python loop (on a subset; LAL's per-binary cost does not depend on N).  Per binary, evolve_many's
time in Python (checks and parameter vectors) and in its compiled loops, from its ``stats`` (all threads).

    python benchmarks/bench_many.py [--n 2000] [--rounds 5] [--lal-n 200]
"""

import argparse
import statistics
import time

import lal
import lalsimulation as ls
import numba
import numpy as np

from pnrotor.pn import evolve, evolve_many, lalsuite_orders

ORDERS = lalsuite_orders("T4")
T4 = ls.GetApproximantFromString("SpinTaylorT4")


def population(n, seed=0):
    rng = np.random.default_rng(seed)
    m1, m2 = rng.uniform(25.0, 35.0, n), rng.uniform(8.0, 12.0, n)

    def spins():
        c = rng.normal(size=(n, 3))
        return c / np.linalg.norm(c, axis=1)[:, None] * rng.uniform(0.0, 0.9, (n, 1))

    return m1, m2, spins(), spins()


def lal_final(m1, m2, c1, c2, f_end):
    """LAL's final state (14 one-sample series) of every binary, integrated to f_end (0: the end)."""
    for i in range(m1.size):
        ls.SimInspiralSpinTaylorPNEvolveOrbitOnlyFinal(
            1.0 / 4096, m1[i] * lal.MSUN_SI, m2[i] * lal.MSUN_SI, 20.0, f_end, *c1[i], *c2[i], 0.0, 0.0, 1.0,
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, -1, 0, 7, 0, T4)


def lal_from(m1, m2, c1, c2, f_start):
    """LAL's integration from f_start to f_ref = 20 Hz (its stand-in for a backward target: it integrates only
    forward, so the spins at f_start would have to be searched for; this times one such integration)."""
    for i in range(m1.size):
        ls.SimInspiralSpinTaylorPNEvolveOrbitOnlyFinal(
            1.0 / 4096, m1[i] * lal.MSUN_SI, m2[i] * lal.MSUN_SI, f_start, 20.0, *c1[i], *c2[i], 0.0, 0.0, 1.0,
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, -1, 0, 7, 0, T4)


def singles(m1, m2, c1, c2, f_end):
    for i in range(m1.size):
        evolve(m1[i], m2[i], c1[i], c2[i], 20.0, f_max=f_end, sampling="final", **ORDERS)


def timed(f):
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--lal-n", type=int, default=200)
    args = ap.parse_args()
    pop = population(args.n)
    sub = tuple(x[:args.lal_n] for x in pop)
    threads = numba.get_num_threads()
    evolve_many(*(x[:2] for x in pop), 20.0, **ORDERS)   # load the compiled kernels
    print(f"{args.n} binaries (30 + 10 Msun-like, precessing) from 20 Hz; LAL and single evolve calls on "
          f"{args.lal_n}; numba threads {threads}; medians of {args.rounds} interleaved rounds\n")
    print(f"{'to':>8} {'many x' + str(threads):>12} {'many x1':>10} {'evolve loop':>12} {'LAL':>10} "
          f"{'many/LAL':>9} {'us/binary: Python':>18} {'loops':>6} {'steps':>6}")
    for label, f_end, lal_end in (("end", None, 0.0), ("100 Hz", 100.0, 100.0)):
        rates = {k: [] for k in ("many", "many1", "single", "lal", "python", "loops")}
        for _ in range(args.rounds):
            t = time.perf_counter()
            stats = evolve_many(*pop, 20.0, f_end=f_end, **ORDERS).stats
            rates["many"].append(args.n / (time.perf_counter() - t))
            rates["python"].append((stats["wall_time_s"] - stats["wall_time_integrate_s"]) / args.n * 1e6)
            rates["loops"].append(stats["wall_time_integrate_s"] / args.n * 1e6)
            numba.set_num_threads(1)
            try:
                rates["many1"].append(args.n / timed(lambda: evolve_many(*pop, 20.0, f_end=f_end, **ORDERS)))
            finally:
                numba.set_num_threads(threads)
            rates["single"].append(args.lal_n / timed(lambda: singles(*sub, f_end)))
            rates["lal"].append(args.lal_n / timed(lambda: lal_final(*sub, lal_end)))
        med = {k: statistics.median(v) for k, v in rates.items()}
        steps = np.mean(evolve_many(*sub, 20.0, f_end=f_end, **ORDERS).nsteps)
        print(f"{label:>8} {med['many']:>10.0f}/s {med['many1']:>8.0f}/s {med['single']:>10.0f}/s "
              f"{med['lal']:>8.0f}/s {med['many'] / med['lal']:>8.1f}x {med['python']:>18.1f} {med['loops']:>6.1f} "
              f"{steps:>6.1f}")

    freqs = np.array([10.0, 12.0, 15.0, 17.0, 25.0, 35.0, 50.0, 70.0, 100.0, 200.0])
    print(f"\n{freqs.size} frequencies {freqs.min():g}-{freqs.max():g} Hz per binary: binaries/s")
    print(f"{'frequencies=':>14} {'f_end loop':>12} {'LAL':>10} {'list/f_end':>11} {'list/LAL':>9}")
    rates = {k: [] for k in ("list", "loop", "lal")}
    for _ in range(args.rounds):
        rates["list"].append(args.n / timed(lambda: evolve_many(*pop, 20.0, frequencies=freqs, **ORDERS)))
        rates["loop"].append(args.n / timed(lambda: [evolve_many(*pop, 20.0, f_end=f, **ORDERS) for f in freqs]))
        rates["lal"].append(args.lal_n / timed(lambda: [lal_final(*sub, f) if f > 20.0 else lal_from(*sub, f)
                                                        for f in freqs]))
    med = {k: statistics.median(v) for k, v in rates.items()}
    print(f"{med['list']:>12.0f}/s {med['loop']:>10.0f}/s {med['lal']:>8.0f}/s {med['list'] / med['loop']:>10.1f}x "
          f"{med['list'] / med['lal']:>8.1f}x")


if __name__ == "__main__":
    main()
