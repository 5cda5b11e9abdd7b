"""Benchmark of pnrotor.hdf5: write and read times and file sizes of 10⁶-sample runs.

Two run shapes: a `FrameHistory` (t, R: 40 MB of float64) whose rotor is the paper's precessing and
nutating binary (eq:BinaryRotor, built here from `pnrotor.quaternion`), and an Evolution-shaped run
(t, t_seconds, v, Phi, chi1, chi2, R, ell_hat: 136 MB) with smooth post-Newtonian-like curves. Each is
written without compression, with gzip and with lzf; the write time includes fsync and the atomic rename.
Times are the best of --repeat runs; the files go to a temporary folder under --dir (default: waveforms/,
the real output folder, so the disk is the one real runs write to).

To compare with the time to compute a run, time `pnrotor.integrate_angular_velocity` or `pnrotor.evolve`
for the same number of samples; this script says when neither exists yet and then reports I/O only.

    python benchmarks/bench_hdf5.py [--samples 1000000] [--repeat 3] [--dir waveforms]
"""

import argparse
import dataclasses
import importlib
import importlib.util
import tempfile
import time
from pathlib import Path

import numpy as np

from pnrotor import hdf5
from pnrotor import quaternion as q
from pnrotor.history import FrameHistory


@dataclasses.dataclass
class EvolutionShaped:
    """The array fields the coming `pnrotor.pn.evolve.Evolution` is expected to carry."""

    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: str
    stats: dict
    inputs: dict


def binary_rotor(t):
    """R = R0 R1 R4 R1⁻¹ R3 R2 R3⁻¹ R1 of eq:BinaryRotor with the constants of eq:precession_constants."""
    omega_orb, omega_prec, alpha, nu = 2 * np.pi / 1000, 2 * np.pi / 10000, np.pi / 8, np.pi / 80
    alpha_dot = 2 * alpha / 100000
    x, z = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    R0 = q.exp(-3 * alpha / 10 * x / 2)
    R1, R3 = q.exp(np.outer(omega_orb * t / 2, z)), q.exp(np.outer(omega_prec * t / 2, z))
    R2, R4 = q.exp(np.outer((alpha + alpha_dot * t) / 2, x)), q.exp(nu * x / 2)
    R = R0
    for factor in (R1, R4, q.conjugate(R1), R3, R2, q.conjugate(R3), R1):
        R = q.multiply(R, factor)
    return R


def frame_history(n):
    t = np.linspace(0.0, 1.0e6, n)
    return FrameHistory(
        t=t, R=binary_rotor(t), formulation="rotor", method="dop853", atol=1e-12, rtol=1e-12, nfev=10**6,
        nsteps=80000, naccepted=79000, nrejected=1000, n_resets=0, status=0, message="success", wall_time=1.0,
        inputs={"omega": "PrecessingNutatingBinary", "t_end": 1.0e6},
    )


def evolution_shaped(n):
    t = np.linspace(-1.0e6, 0.0, n)
    t_merger = t[0] + (t[-1] - t[0]) * 256 / 255  # Newtonian chirp v ∝ (t_merger − t)^(−1/8), v: 0.2 → 0.4
    v = 0.2 * ((t_merger - t) / (t_merger - t[0])) ** (-1 / 8)
    Phi = np.cumsum(v**3) * (t[1] - t[0])
    precession = 0.01 * Phi
    ell = np.stack([0.3 * np.cos(precession), 0.3 * np.sin(precession), np.ones(n)], axis=1)
    ell /= np.linalg.norm(ell, axis=1)[:, None]
    chi1 = 0.7 * np.stack([np.cos(precession + 1), np.sin(precession + 1), 0.5 + 0 * t], axis=1)
    return EvolutionShaped(
        t=t, t_seconds=t * 20 * 4.925490947641267e-06, v=v, Phi=Phi, chi1=chi1, chi2=-0.5 * chi1,
        R=binary_rotor(t - t[0]), ell_hat=ell, termination="f_max reached",
        stats={"nfev": 200000, "nsteps": 16000, "naccepted": 15800, "nrejected": 200, "wall_time": 1.0},
        inputs={"m1": 12.0, "m2": 8.0, "chi1": (0.35, 0.0, 0.35), "f_min": 10.0, "approximant": "SpinTaylorT4"},
    )


def best_time(function, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=10**6)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--dir", default=str(Path(__file__).resolve().parents[1] / "waveforms"))
    args = parser.parse_args()
    hdf5.KINDS["EvolutionShaped"] = f"{__name__}:EvolutionShaped"
    runs = {"FrameHistory": frame_history(args.samples), "Evolution-shaped": evolution_shaped(args.samples)}

    print(f"{args.samples} samples, best of {args.repeat}, files in a temporary folder under {args.dir}")
    print(f"{'run':<17} {'compression':<11} {'data MB':>8} {'file MB':>8} {'write s':>8} {'read s':>8} {'write MB/s':>10} {'read MB/s':>9}")
    with tempfile.TemporaryDirectory(dir=args.dir, prefix="bench_hdf5.") as folder:
        for name, run in runs.items():
            data = sum(value.nbytes for value in vars(run).values() if isinstance(value, np.ndarray)) / 1e6
            for compression in hdf5.COMPRESSIONS:
                path = Path(folder) / f"{name}-{compression}.h5"
                write = best_time(lambda: hdf5.write(path, run, compression=compression, overwrite=True), args.repeat)
                read = best_time(lambda: hdf5.read(path), args.repeat)
                size = path.stat().st_size / 1e6
                print(f"{name:<17} {str(compression):<11} {data:8.1f} {size:8.1f} {write:8.3f} {read:8.3f} "
                      f"{data / write:10.0f} {data / read:9.0f}")
    computing = [name for name in ("pnrotor.integrate_angular_velocity", "pnrotor.evolve") if _exists(name)]
    if computing:
        print(f"compare with the time {', '.join(computing)} takes for {args.samples} samples")
    else:
        print("pnrotor.integrate_angular_velocity and pnrotor.evolve do not exist yet: I/O times only, no comparison")


def _exists(dotted):
    module, _, attribute = dotted.rpartition(".")
    return importlib.util.find_spec(module) is not None and hasattr(importlib.import_module(module), attribute)


if __name__ == "__main__":
    main()
