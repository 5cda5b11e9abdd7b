"""Benchmark of pnrotor.hdf5 on real runs: computing, writing and reading a 10⁶-sample history.

The acceptance: writing and reading a 10⁶-sample history each take less time than computing it. Two runs
of --samples samples each, computed by pnrotor:

* FrameHistory: `pnrotor.integrate_angular_velocity` of the paper's precessing and nutating binary
  (`PrecessingNutatingBinary`, rotor formulation, DOP853, atol 1e-12) over [0, 10⁶] with ``t_eval`` at
  --samples uniform times (t, R: 40 MB of float64 at 10⁶);
* Evolution: `pnrotor.evolve` of a precessing 1.4 + 1.4 M☉ binary (χ₁ = (0.1, 0, 0.05),
  χ₂ = (0, −0.1, 0.05)) from 20 Hz to the end of the inspiral (~161 s), TaylorT4 at 3.5PN, sampled
  uniformly with the Δt that gives --samples samples (t, t_seconds, v, Phi, chi1, chi2, R, ell_hat:
  136 MB at 10⁶).

Compute time is that call, warm (numba's code loaded and a first call made). Each run is written without
compression, with gzip and with lzf (the write time includes fsync and the atomic rename) and read back
with `pnrotor.hdf5.read`. Every time is the best of --repeat; the table gives the ratios write/compute and
read/compute (below 1: the acceptance holds). The files go to a temporary folder under --dir (default:
waveforms/, the real output folder, so the disk is the one real runs write to).

    python benchmarks/bench_hdf5.py [--samples 1000000] [--repeat 3] [--dir waveforms]
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import pnrotor
from pnrotor import hdf5
from pnrotor.analytic import PrecessingNutatingBinary

BNS = dict(m1=1.4, m2=1.4, chi1=(0.1, 0.0, 0.05), chi2=(0.0, -0.1, 0.05), f_ref=20.0)


def frame_history(samples):
    """A function computing the FrameHistory of `samples` uniform samples."""
    binary = PrecessingNutatingBinary()
    t_eval = np.linspace(0.0, binary.T, samples)
    return lambda: pnrotor.integrate_angular_velocity(binary, (0.0, binary.T), binary.rotor(0.0), t_eval=t_eval)


def evolution(samples):
    """A function computing the Evolution of the BNS sampled at Δt giving `samples` samples."""
    duration = pnrotor.evolve(**BNS, sampling="final").t_seconds[-1]
    dt = duration / (samples - 0.5)  # samples at t = k Δt, k = 0 … samples − 1 ≤ duration / Δt
    return lambda: pnrotor.evolve(**BNS, sampling=dt)


def best_time(function, repeat):
    """(smallest wall time of `repeat` calls, the last call's result)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=10**6, help="samples per run (default: 10⁶)")
    parser.add_argument("--repeat", type=int, default=3, help="time each step this many times, keep the best")
    parser.add_argument("--dir", default=str(Path(__file__).resolve().parents[1] / "waveforms"),
                        help="folder for the temporary files (default: waveforms/)")
    args = parser.parse_args()
    if args.samples < 2 or args.repeat < 1:
        parser.error("--samples must be ≥ 2 and --repeat ≥ 1")

    print(f"--samples {args.samples}, best of {args.repeat}, files in a temporary folder under {args.dir}")
    header = (f"{'run':<13} {'samples':>8} {'compute s':>9} {'compression':<11} {'data MB':>8} {'file MB':>8} "
              f"{'write s':>8} {'read s':>8} {'write/compute':>13} {'read/compute':>12}")
    print(header)
    with tempfile.TemporaryDirectory(dir=args.dir, prefix="bench_hdf5.") as folder:
        for name, make in (("FrameHistory", frame_history), ("Evolution", evolution)):
            compute = make(args.samples)
            compute()  # warm: numba's code loaded, first-call dispatch done
            computing, run = best_time(compute, args.repeat)
            data = sum(value.nbytes for value in vars(run).values() if isinstance(value, np.ndarray)) / 1e6
            for compression in hdf5.COMPRESSIONS:
                path = Path(folder) / f"{name}-{compression}.h5"
                writing, _ = best_time(lambda: hdf5.write(path, run, compression=compression, overwrite=True),
                                       args.repeat)
                reading, _ = best_time(lambda: hdf5.read(path), args.repeat)
                size = path.stat().st_size / 1e6
                print(f"{name:<13} {run.t.size:>8} {computing:9.3f} {str(compression):<11} {data:8.1f} {size:8.1f} "
                      f"{writing:8.3f} {reading:8.3f} {writing / computing:13.2f} {reading / computing:12.2f}")


if __name__ == "__main__":
    main()
