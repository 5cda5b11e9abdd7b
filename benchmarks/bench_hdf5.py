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
compression, with gzip and with lzf, each with ``checksum=False`` and with checksums (the default; the
write time includes the layout check, fsync and the atomic rename) and read back with `pnrotor.hdf5.read`
(which checks the layout). Every time
is the best of --repeat; the table gives the ratios write/compute and read/compute (below 1: the
acceptance holds). The files go to a temporary folder under --dir (default: waveforms/, the real output
folder, so the disk is the one real runs write to).

A second table breaks an uncompressed write of each run down: plain h5py writing the same arrays
(contiguous or chunked as `pnrotor.hdf5` chunks them, with and without Fletcher-32, at three chunk sizes,
with and without an fsync at the end) and `pnrotor.hdf5.write` with and without checksums. The variants
are interleaved in random order, --repeat rounds, best and median kept (the machine may be shared).

A third table, typical runs: `pnrotor.evolve` of a precessing 30 + 10 M☉ binary (χ₁ = (0.5, 0.1, 0.3),
χ₂ = (0, 0.4, −0.2)) from f_ref = 20 Hz, sampled at 1/4096 s and at its integrator's steps (the CLI's
default), each written uncompressed with and without checksums, durably (`write`, fsyncs) and not
(``batch(durable=False)``, scratch files), interleaved, max(--repeat, 15) rounds: best and median times and
the ratio with/without checksums, against the compute time; and the layout check alone
(`pnrotor.hdf5.layout_problems`, part of every write and read) on each run and on the 10⁶-sample Evolution.

    python benchmarks/bench_hdf5.py [--samples 1000000] [--repeat 3] [--dir waveforms] [--no-breakdown]
                                    [--typical-only]
"""

import argparse
import os
import random
import statistics
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

import pnrotor
from pnrotor import hdf5
from pnrotor.analytic import PrecessingNutatingBinary

BNS = dict(m1=1.4, m2=1.4, chi1=(0.1, 0.0, 0.05), chi2=(0.0, -0.1, 0.05), f_ref=20.0)
TYPICAL = dict(m1=30.0, m2=10.0, chi1=(0.5, 0.1, 0.3), chi2=(0.0, 0.4, -0.2), f_ref=20.0)


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


def h5py_write(arrays, chunk_bytes=None, fletcher32=False, fsync=False):
    """A function writing `arrays` with plain h5py to a path: contiguous, or in chunks of at most
    `chunk_bytes` along the first axis (equal, as `pnrotor.hdf5` makes them), fsynced if `fsync`."""
    def write(path):
        with h5py.File(path, "w") as f:
            for name, array in arrays.items():
                options = {}
                if chunk_bytes:
                    rows = array.shape[0]
                    nchunks = -(-rows * array.itemsize * (array.size // rows) // chunk_bytes)
                    options = dict(chunks=(-(-rows // nchunks),) + array.shape[1:], fletcher32=fletcher32)
                f.create_dataset(name, data=array, **options)
        if fsync:
            fd = os.open(path, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
    return write


def breakdown(name, run, folder, repeat):
    """Print where an uncompressed write of `run` goes: the variants interleaved, best and median."""
    arrays = {key: value for key, value in vars(run).items() if isinstance(value, np.ndarray)}
    copies = [key for key, value in arrays.items() if not (value.flags.c_contiguous and value.dtype == np.float64)]
    MiB = 1 << 20
    variants = {
        "h5py contiguous, no fsync": h5py_write(arrays),
        "h5py contiguous + fsync": h5py_write(arrays, fsync=True),
        "h5py chunks 1 MiB, no fsync": h5py_write(arrays, MiB),
        "h5py chunks 256 KiB + fletcher32, no fsync": h5py_write(arrays, MiB // 4, True),
        "h5py chunks 1 MiB + fletcher32, no fsync": h5py_write(arrays, MiB, True),
        "h5py chunks 4 MiB + fletcher32, no fsync": h5py_write(arrays, 4 * MiB, True),
        "h5py chunks 1 MiB + fletcher32 + fsync": h5py_write(arrays, MiB, True, fsync=True),
        "pnrotor.hdf5.write (contiguous, fsync)": lambda path: hdf5.write(path, run, overwrite=True),
        "pnrotor.hdf5.write checksum=True": lambda path: hdf5.write(path, run, overwrite=True, checksum=True),
    }
    times = {variant: [] for variant in variants}
    for _ in range(repeat):
        for i, variant in random.sample(list(enumerate(variants)), len(variants)):
            path = Path(folder) / f"breakdown-{i}.h5"
            path.unlink(missing_ok=True)
            start = time.perf_counter()
            variants[variant](path)
            times[variant].append(time.perf_counter() - start)
    layout = "all C-contiguous float64, passed to HDF5 unconverted" if not copies else f"converted: {copies}"
    print(f"\n{name}: uncompressed write, {sum(a.nbytes for a in arrays.values()) / 1e6:.1f} MB in {len(arrays)} "
          f"arrays ({layout}), {repeat} interleaved rounds")
    print(f"{'variant':<44} {'best s':>7} {'median s':>8}")
    for variant, measured in times.items():
        print(f"{variant:<44} {min(measured):7.3f} {statistics.median(measured):8.3f}")


def layout_check_time(run, repeat=20):
    """Best time of `pnrotor.hdf5.layout_problems` on `run` (what write and read add to check it)."""
    values = {name: getattr(run, name) for name in vars(run) if name not in hdf5.NOT_WRITTEN}
    return best_time(lambda: hdf5.layout_problems(type(run), values), repeat)[0]


def typical(folder, repeat):
    """Print the write cost of checksums on typical runs (interleaved rounds, best and median), with the fsyncs
    of a durable write (`write`) and without them (``batch(..., durable=False)``, as for scratch files)."""
    print(f"\ntypical runs: precessing 30 + 10 Msun from 20 Hz, uncompressed writes, {repeat} interleaved rounds")
    print(f"{'sampling':<10} {'samples':>8} {'MB':>6} {'compute s':>9} {'check s':>8} {'fsync':<5} "
          f"{'no checksum s (best/median)':>28} {'checksum s (best/median)':>25} {'ratio best/median':>18}")

    def write(path, run, checksum, durable):
        if durable:
            hdf5.write(path, run, checksum=checksum, overwrite=True)
        else:
            with hdf5.batch(path, checksum=checksum, overwrite=True, durable=False) as runs:
                runs.add("run", run)

    for label, sampling in (("1/4096 s", 1 / 4096), ("steps", "steps")):
        compute = lambda: pnrotor.evolve(**TYPICAL, sampling=sampling)  # noqa: E731
        compute()
        computing, run = best_time(compute, repeat)
        variants = [(checksum, durable) for checksum in (False, True) for durable in (True, False)]
        times = {variant: [] for variant in variants}
        for _ in range(repeat):
            for checksum, durable in random.sample(variants, len(variants)):
                path = Path(folder) / f"typical-{checksum}-{durable}.h5"
                start = time.perf_counter()
                write(path, run, checksum, durable)
                times[checksum, durable].append(time.perf_counter() - start)
        mb = sum(value.nbytes for value in vars(run).values() if isinstance(value, np.ndarray)) / 1e6
        for durable in (True, False):
            best = {c: min(times[c, durable]) for c in (False, True)}
            median = {c: statistics.median(times[c, durable]) for c in (False, True)}
            print(f"{label:<10} {run.t.size:>8} {mb:6.2f} {computing:9.4f} {layout_check_time(run):8.5f} "
                  f"{'yes' if durable else 'no':<5} {best[False]:13.4f} / {median[False]:<12.4f} "
                  f"{best[True]:11.4f} / {median[True]:<11.4f} "
                  f"{best[True] / best[False]:8.2f} / {median[True] / median[False]:<.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=10**6, help="samples per run (default: 10⁶)")
    parser.add_argument("--repeat", type=int, default=3, help="time each step this many times, keep the best")
    parser.add_argument("--dir", default=str(Path(__file__).resolve().parents[1] / "waveforms"),
                        help="folder for the temporary files (default: waveforms/)")
    parser.add_argument("--no-breakdown", action="store_true", help="skip the table of write variants")
    parser.add_argument("--typical-only", action="store_true", help="only the table of typical runs")
    args = parser.parse_args()
    if args.samples < 2 or args.repeat < 1:
        parser.error("--samples must be ≥ 2 and --repeat ≥ 1")

    print(f"--samples {args.samples}, best of {args.repeat}, files in a temporary folder under {args.dir}")
    header = (f"{'run':<13} {'samples':>8} {'compute s':>9} {'compression':<11} {'checksum':<8} {'data MB':>8} "
              f"{'file MB':>8} "
              f"{'write s':>8} {'read s':>8} {'write/compute':>13} {'read/compute':>12}")
    runs = {}
    with tempfile.TemporaryDirectory(dir=args.dir, prefix="bench_hdf5.") as folder:
        typical(folder, max(args.repeat, 15))
        if args.typical_only:
            return
        print(f"\n{header}")
        for name, make in (("FrameHistory", frame_history), ("Evolution", evolution)):
            compute = make(args.samples)
            compute()  # warm: numba's code loaded, first-call dispatch done
            computing, run = best_time(compute, args.repeat)
            data = sum(value.nbytes for value in vars(run).values() if isinstance(value, np.ndarray)) / 1e6
            runs[name] = run
            print(f"{name}: layout check {layout_check_time(run, 5):.4f} s")
            for checksum in (False, True):
                for compression in hdf5.COMPRESSIONS:
                    path = Path(folder) / f"{name}-{compression}-{checksum}.h5"
                    writing, _ = best_time(lambda: hdf5.write(path, run, compression=compression, checksum=checksum,
                                                              overwrite=True), args.repeat)
                    reading, _ = best_time(lambda: hdf5.read(path), args.repeat)
                    size = path.stat().st_size / 1e6
                    print(f"{name:<13} {run.t.size:>8} {computing:9.3f} {str(compression):<11} "
                          f"{'yes' if checksum else 'no':<8} {data:8.1f} {size:8.1f} {writing:8.3f} {reading:8.3f} "
                          f"{writing / computing:13.2f} {reading / computing:12.2f}")
                    path.unlink()
        if not args.no_breakdown:
            for name, run in runs.items():
                breakdown(name, run, folder, max(args.repeat, 5))


if __name__ == "__main__":
    main()
