"""Cold start: the README's main job, and a nonspinning run, in fresh processes with an empty numba cache.

Each job is the CLI as a user types it (``pnrotor evolve …``, HDF5 file written into a temporary folder),
run in a new process with NUMBA_CACHE_DIR pointing at an empty folder (cold: numba compiles what the run
needs), then again with that folder filled (warm: numba loads it).  Baselines measured in the same run:
``python -c "import numpy, h5py"``, the floor any Python tool with these dependencies pays, and the same
plus numba calling one trivial ``@njit(cache=True)`` function (cold and warm, as the jobs): numba's own
floor (its import, and the set-up of its compiler's registries that the first compiled or cached function
pays).  Wall times include starting Python, imports and writing the file.

    python benchmarks/bench_cold_start.py [--repeat 2]
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

JOBS = {
    "main job (precessing 30 + 10)": ["--m1", "30", "--m2", "10", "--chi1", "0.6,0,0.2", "--chi2", "0,-0.4,0.1",
                                      "--f-ref", "20"],
    "nonspinning 10 + 10": ["--m1", "10", "--m2", "10", "--chi1", "0,0,0", "--chi2", "0,0,0", "--f-ref", "20"],
}


def wall(cmd, env):
    t = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


_FLOOR_MODULE = """from numba import njit


@njit(cache=True)
def one(x):
    return x + 1.0
"""


def numba_floor(env, folder):
    """(cold, warm) wall seconds of importing numpy, h5py and numba and calling one trivial cached function."""
    with open(os.path.join(folder, "floor_kernel.py"), "w") as f:
        f.write(_FLOOR_MODULE)
    cmd = [sys.executable, "-c", f"import sys; sys.path.insert(0, {folder!r}); import numpy, h5py, floor_kernel; "
                                 "floor_kernel.one(1.0)"]
    return wall(cmd, env), wall(cmd, env)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2, help="fresh caches per job (median reported)")
    args = ap.parse_args()
    baseline = statistics.median(wall([sys.executable, "-c", "import numpy, h5py"], dict(os.environ))
                                 for _ in range(3))
    print(f"baseline python -c 'import numpy, h5py': {baseline:.2f} s\n")
    print(f"{'job':32} {'cold s':>8} {'warm s':>8}")
    floors = []
    for _ in range(3):
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as folder:
            floors.append(numba_floor(dict(os.environ, NUMBA_CACHE_DIR=cache), folder))
    print(f"{'numba floor (one @njit)':32} {statistics.median(c for c, _ in floors):8.2f} "
          f"{statistics.median(w for _, w in floors):8.2f}")
    for name, options in JOBS.items():
        cold, warm = [], []
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
                env = dict(os.environ, NUMBA_CACHE_DIR=cache)
                cmd = [sys.executable, "-m", "pnrotor", "evolve", *options, "-o", os.path.join(out, "run.h5")]
                cold.append(wall(cmd, env))
                warm.append(wall(cmd + ["--overwrite"], env))
        print(f"{name:32} {statistics.median(cold):8.2f} {statistics.median(warm):8.2f}")


if __name__ == "__main__":
    main()
