"""Benchmark of the verification mode's per-evaluation costs: what one right-hand-side evaluation costs
inside DOP853 for each formulation, and for each kind of ω (the binary's cached path, a user's numba
function, a plain Python callable), with the first-call (load or compile) times apart.

The paper's study as a whole (accuracy against cost, scipy baseline) is ``pnrotor bench``; this script
reproduces the numbers quoted in the docstrings of `pnrotor.formulations` and `pnrotor.integrate`.
Times are the best of --repeat interleaved rounds (robust on a shared machine).

    python benchmarks/bench_formulations.py [--t-end 1e5] [--atol 1e-12] [--repeat 5]
"""

import argparse
import os
import sys
import time

import numpy as np

from pnrotor import integrate_angular_velocity
from pnrotor.formulations import FORMULATIONS

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from test_integrate import BINARY, numba_omega, python_omega  # noqa: E402  (the binary's ω as a user's)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--t-end", type=float, default=1e5)
    parser.add_argument("--atol", type=float, default=1e-12)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    R0 = BINARY.rotor(0.0)
    cases = [(f"{name}, binary", BINARY, name) for name in FORMULATIONS]
    cases += [("rotor, user numba ω", numba_omega, "rotor"), ("rotor, Python ω", python_omega, "rotor")]

    first = {}
    for label, omega, formulation in cases:
        start = time.perf_counter()
        integrate_angular_velocity(omega, (0.0, 10.0), R0, formulation, atol=args.atol)
        first[label] = time.perf_counter() - start
    best = {label: np.inf for label, _, _ in cases}
    nfev = {}
    for _ in range(args.repeat):
        for label, omega, formulation in cases:
            h = integrate_angular_velocity(omega, (0.0, args.t_end), R0, formulation, atol=args.atol)
            best[label] = min(best[label], h.wall_time)
            nfev[label] = h.nfev

    print(f"DOP853, atol {args.atol:g}, t in [0, {args.t_end:g}], best of {args.repeat}")
    print(f"  {'case':32s} {'first call s':>12s} {'wall s':>9s} {'nfev':>8s} {'ns/eval':>8s}")
    for label, _, _ in cases:
        print(f"  {label:32s} {first[label]:12.3f} {best[label]:9.4f} {nfev[label]:8d} "
              f"{best[label] / nfev[label] * 1e9:8.0f}")


if __name__ == "__main__":
    main()
