"""What the invariant checks of the result types cost (`pnrotor.hdf5.check`, issue #36 item 1), against the same
calls with the check replaced by a no-op, interleaved in the same process, medians over rounds (and their range):

* ``pnrotor.modes`` of a typical run (30 + 10 M☉ from 20 Hz, sampled at 1/4096 s and at its steps), which checks
  the Evolution before its kernel;
* ``Modes.polarizations`` of those modes, which checks the Modes;
* ``pnrotor.evolve_many`` of 1,000 binaries to 60 Hz, whose Population is checked when built;
* ``pnrotor.integrate_angular_velocity`` of the paper's binary over 10 M, whose FrameHistory is checked when built;
* and, for scale, the check itself on a typical run, against ``pnrotor.evolve`` of it (which does not check:
  the reason is this ratio).

    python benchmarks/bench_result_checks.py [--rounds 21]
"""

import argparse
import statistics
import time
import warnings

import numpy as np


def best_of(call, repeat):
    """The shortest of ``repeat`` timed calls, in seconds."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=21)
    args = parser.parse_args()

    import pnrotor
    from pnrotor import hdf5
    from pnrotor.analytic import PrecessingNutatingBinary
    from pnrotor.waveform.modes import CoarseSamplingWarning

    warnings.simplefilter("ignore", CoarseSamplingWarning)
    binary = (30, 10, (0.5, 0.3, 0.2), (0.0, -0.4, 0.3), 20)
    fine, steps = pnrotor.evolve(*binary, sampling=1 / 4096), pnrotor.evolve(*binary)
    waves = {"1/4096": pnrotor.modes(fine), "steps": pnrotor.modes(steps)}
    rng = np.random.default_rng(1)
    m1, m2 = rng.uniform(5, 50, 1000), rng.uniform(5, 50, 1000)
    spins = rng.uniform(-0.5, 0.5, (1000, 3))
    omega = PrecessingNutatingBinary()
    cases = {
        "modes(), 9,986 samples": (lambda: pnrotor.modes(fine), 3),
        "modes(), 135 samples (steps)": (lambda: pnrotor.modes(steps), 20),
        "polarizations(), 9,986 samples": (lambda: waves["1/4096"].polarizations(0.3), 3),
        "polarizations(), 135 samples": (lambda: waves["steps"].polarizations(0.3), 20),
        "evolve_many(), 1,000 binaries": (lambda: pnrotor.evolve_many(m1, m2, spins, spins, 20, f_end=60), 1),
        "integrate_angular_velocity(), 10 M": (
            lambda: pnrotor.integrate_angular_velocity(omega, (0.0, 10.0), omega.rotor(0.0)), 20),
    }
    check = hdf5.check
    for call, repeat in cases.values():   # compile and warm up
        call()
    ratios = {name: [] for name in cases}
    seconds = {name: [] for name in cases}
    for _ in range(args.rounds):
        for name, (call, repeat) in cases.items():
            hdf5.check = lambda run, doing="cannot write", scan=True: None
            try:
                without = best_of(call, repeat)
            finally:
                hdf5.check = check
            with_check = best_of(call, repeat)
            ratios[name].append(with_check / without)
            seconds[name].append((with_check, without))
    print(f"pnrotor {pnrotor.__version__}: the result checks, {args.rounds} interleaved rounds, median [range]")
    print(f"{'call':38s} {'with the check':>16s} {'without':>12s} {'ratio':>22s}")
    for name in cases:
        r = ratios[name]
        w = statistics.median(x for x, _ in seconds[name])
        o = statistics.median(y for _, y in seconds[name])
        print(f"{name:38s} {w * 1e3:13.3f} ms {o * 1e3:9.3f} ms {statistics.median(r):8.3f} "
              f"[{min(r):.3f}, {max(r):.3f}]")

    checks, evolves = [], []
    for _ in range(args.rounds):
        checks.append(best_of(lambda: hdf5.check(steps, "x"), 50))
        evolves.append(best_of(lambda: pnrotor.evolve(*binary), 50))
    share = [c / e for c, e in zip(checks, evolves)]
    print(f"the check of a 135-sample Evolution {statistics.median(checks) * 1e3:.3f} ms, evolve() of it "
          f"{statistics.median(evolves) * 1e3:.3f} ms: {statistics.median(share):.1%} [{min(share):.1%}, "
          f"{max(share):.1%}] (why Evolution is not checked when built)")


if __name__ == "__main__":
    main()
