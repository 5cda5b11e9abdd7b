"""Benchmark of `pnrotor evolve --batch`: runs per second in this process and on a pool of local workers.

Batches of N varied precessing binaries from 20 Hz (seeded; spins up to 0.9 in random directions),
each evolved to the end of the inspiral:

* ``bbh-steps``: total masses 8–80 M☉, mass ratio 1–8, every integrator step (~200 samples; ~0.5 ms
  per run);
* ``bbh-1/4096``: the same binaries sampled uniformly at 1/4096 s (~2·10⁴ samples per run: sampling and
  sending the arrays back weigh in);
* ``light-steps``: total masses 2.5–12 M☉ (BNS to NSBH), every step (10³–10⁴ steps: the integration
  dominates).

Each batch runs

* serially, in this process (a loop over `pnrotor.batch.backends.results_serial`, what ``--jobs 1`` does);
* on a process pool of 1 and of 2 workers (`results_pool`, what ``--jobs N`` does) for each
  `multiprocessing` start method, start-up of the workers included (a new pool per batch, as in the CLI);
* end to end through the CLI, ``pnrotor evolve --batch FILE.csv --jobs 1`` and ``--jobs 2`` (in this
  process: reading the CSV, evolving, writing the batch file), which shows what a user gets.

Timings are medians over interleaved rounds (every configuration once per round), which is robust on a
shared machine.

``--durability`` (alone: ``--durability --workloads bbh-1/4096 --contexts``) times what keeping finished runs
durable costs, for the Δt-sampled workload: ``pnrotor.batch.run`` (``--jobs 1`` and ``2``; every run added to the
batch file being built as it finishes, its bytes written once, io.journal) against a same-run baseline that
computes the same runs (in this process, or on a pool of 2) and writes the same bytes once, into one batch file with
`pnrotor.hdf5.batch` (fsynced), and prints the ratio; beside them two other ways to keep finished runs: a part file
per run then an HDF5 copy of each into the batch file (what pnrotor did before), and a part file per run indexed by
a batch file of external links (``h5py.ExternalLink``), with the time to read every run back from each file. Apart: the start-up of a pool alone (1 and 2 workers, until each has loaded the PN code
and answered an empty task), and for forkserver also that of the first pool of a fresh process (which
starts the server and loads the PN code in it).

    python benchmarks/bench_batch.py [--runs 40] [--rounds 5] [--contexts fork forkserver spawn] [--durability]
"""

import argparse
import contextlib
import io
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from pnrotor.cli import main as cli_main
from pnrotor.batch.backends import results_pool, results_serial, start_method


WORKLOADS = {"bbh-steps": (8.0, 80.0, "steps"), "bbh-1/4096": (8.0, 80.0, 1 / 4096),
             "light-steps": (2.5, 12.0, "steps")}


def binaries(n, m_low, m_high, sampling, seed=2016):
    rng = np.random.default_rng(seed)
    tasks = []
    for i in range(n):
        total, q = float(rng.uniform(m_low, m_high)), float(rng.uniform(1.0, 8.0))
        m1 = total * q / (1 + q)
        spins = []
        for _ in range(2):
            direction = rng.normal(size=3)
            spins.append(tuple((rng.uniform(0.0, 0.9) * direction / np.linalg.norm(direction)).tolist()))
        tasks.append((i, dict(m1=m1, m2=total - m1, chi1=spins[0], chi2=spins[1], f_ref=20.0, sampling=sampling)))
    return tasks


def write_csv(path, tasks):
    with open(path, "w") as f:
        f.write("m1,m2,chi1,chi2,f_ref,sampling\n")
        for _, p in tasks:
            sampling = p["sampling"] if isinstance(p["sampling"], str) else repr(p["sampling"])
            f.write(f"{p['m1']!r},{p['m2']!r},\"{','.join(map(repr, p['chi1']))}\",\"{','.join(map(repr, p['chi2']))}\","
                    f"{p['f_ref']!r},{sampling}\n")


def time_cli(csv_path, jobs):
    out = os.path.join(os.path.dirname(csv_path), "out.h5")
    start = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = cli_main(["evolve", "--batch", csv_path, "--jobs", str(jobs), "-o", out, "--overwrite", "-q"])
    elapsed = time.perf_counter() - start
    assert code == 0
    return elapsed


def time_batch(tasks, mode, jobs=1, context=None):
    start = time.perf_counter()
    results = list(results_serial(tasks) if mode == "serial" else results_pool(tasks, jobs, context))
    elapsed = time.perf_counter() - start
    assert len(results) == len(tasks) and all(ok for _, ok, _ in results), [r for r in results if not r[1]][:1]
    return elapsed, results


def durability(tasks, csv_path, folder, rounds, samples):
    """Wall times of a batch (of ``samples`` samples in all) and of ways to write its runs (module docstring),
    interleaved, medians."""
    import shutil

    import h5py

    from pnrotor import batch, hdf5

    names = [row.name for row in batch.read_batch(csv_path, {})]   # the batch's names of its rows
    out = os.path.join(folder, "out.h5")

    def computed(jobs):
        results = list(results_serial(tasks) if jobs == 1 else results_pool(tasks, jobs))
        return {names[i]: run for i, _, run in results}

    def once(jobs):
        with hdf5.batch(out, overwrite=True) as runs:
            for name, run in sorted(computed(jobs).items()):
                runs.add(name, run)

    def parts_then_copy():
        parts = os.path.join(folder, "parts")
        os.makedirs(parts, exist_ok=True)
        for name, run in computed(1).items():
            with hdf5.batch(os.path.join(parts, name + ".h5"), overwrite=True, durable=False) as part:
                part.add(name, run)
        with hdf5.batch(out, overwrite=True) as runs:
            for name in sorted(names):
                runs.copy_from(os.path.join(parts, name + ".h5"), name, verify=False)
        shutil.rmtree(parts)

    def external_links():
        parts = os.path.join(folder, "runs")
        shutil.rmtree(parts, ignore_errors=True)
        os.makedirs(parts)
        for name, run in computed(1).items():
            with hdf5.batch(os.path.join(parts, name + ".h5"), overwrite=True) as part:   # each fsynced
                part.add(name, run)
        with h5py.File(out, "w") as index:
            for name in sorted(names):
                index[name] = h5py.ExternalLink(os.path.join("runs", name + ".h5"), name)
        fd = os.open(out, os.O_RDONLY)
        os.fsync(fd)
        os.close(fd)

    def read_all():
        with h5py.File(out, "r") as f:
            for name in sorted(names):
                for dataset in ("t", "v", "R", "chi1"):
                    f[name][dataset][...]

    def timed(function):
        start = time.perf_counter()
        function()
        return time.perf_counter() - start

    ways = {"batch.run --jobs 1 (journaled)": lambda: batch.run(csv_path, out, jobs=1, overwrite=True),
            "baseline: serial + write once": lambda: once(1),
            "batch.run --jobs 2 (journaled)": lambda: batch.run(csv_path, out, jobs=2, overwrite=True),
            "baseline: pool 2 + write once": lambda: once(2),
            "part files + HDF5 copy (before)": parts_then_copy,
            "part files + external links": external_links}
    times = {way: [] for way in ways}
    reads = {"one file": [], "external links": []}
    for _ in range(rounds):
        for way, function in ways.items():
            times[way].append(timed(function))
            if way.startswith("batch.run --jobs 2"):
                reads["one file"].append(timed(read_all))
            elif way.startswith("part files + external"):
                reads["external links"].append(timed(read_all))
    print(f"\ndurability: {len(tasks)} runs sampled at 1/4096 s, {samples} samples, {rounds} interleaved rounds, "
          "medians (all rounds, s)")
    median = {way: statistics.median(values) for way, values in times.items()}
    for way, values in times.items():
        print(f"  {way:<34} {median[way]:>7.3f} s   " + " ".join(f"{t:.3f}" for t in values))
    for jobs, baseline in ((1, "serial"), (2, "pool 2")):
        ratio = median[f"batch.run --jobs {jobs} (journaled)"] / median[f"baseline: {baseline} + write once"]
        print(f"  --jobs {jobs}: batch / writing its bytes once = {ratio:.2f}")
    for what, values in reads.items():
        print(f"  reading t, v, R, chi1 of every run, {what:<15} {statistics.median(values):.3f} s   "
              + " ".join(f"{t:.3f}" for t in values))
    shutil.rmtree(os.path.join(folder, "runs"), ignore_errors=True)


def time_startup(jobs, context):
    """Seconds from creating a pool of `jobs` workers until each has loaded the PN code and answered."""
    start = time.perf_counter()
    list(results_pool([(i, None) for i in range(jobs)], jobs, context, chunksize=1))
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--contexts", nargs="*", default=["fork", "forkserver", "spawn"])
    parser.add_argument("--workloads", nargs="+", default=list(WORKLOADS), choices=list(WORKLOADS))
    parser.add_argument("--durability", action="store_true", help="also time the cost of durable batches")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, Python {sys.version.split()[0]}; {args.runs} precessing binaries from 20 Hz per "
          f"batch, {args.rounds} interleaved rounds, medians; CLI default start method: {start_method()}")

    start = time.perf_counter()
    import pnrotor.pn.evolve  # noqa: F401 - numba's cache, loaded once here

    print(f"import of the PN code in this process: {time.perf_counter() - start:.2f} s")
    configs = [("serial", 1, None)] + [("pool", jobs, c) for c in args.contexts for jobs in (1, 2)]
    configs += [("cli", 1, None), ("cli", 2, None)] if args.contexts else []
    folder = tempfile.mkdtemp(prefix="bench_batch_")
    for workload in args.workloads:
        m_low, m_high, sampling = WORKLOADS[workload]
        tasks = binaries(args.runs, m_low, m_high, sampling)
        csv_path = os.path.join(folder, "batch.csv")
        write_csv(csv_path, tasks)
        _, reference = time_batch(tasks[:2], "serial")  # first calls: type dispatch
        _, reference = time_batch(tasks, "serial")
        samples = sum(len(r) for _, _, r in reference)
        evolve_s = sum(r.stats["wall_time_s"] for _, _, r in reference)
        if args.durability and not isinstance(sampling, str):
            durability(tasks, csv_path, folder, args.rounds, samples)
        times = {config: [] for config in configs}
        for _ in range(args.rounds):
            for config in configs:
                mode, jobs, context = config
                if mode == "cli":
                    times[config].append(time_cli(csv_path, jobs))
                    continue
                elapsed, results = time_batch(tasks, mode, jobs, context)
                times[config].append(elapsed)
                if mode == "pool":  # the same histories as in this process, bitwise
                    got = {i: r for i, _, r in results}
                    for i, _, r in reference:
                        assert got[i].R.tobytes() == r.R.tobytes() and got[i].t.tobytes() == r.t.tobytes()
        print(f"\n{workload}: {samples} samples in all ({samples / args.runs:.0f} per run), "
              f"evolve's own wall time {evolve_s:.3f} s in all ({1e3 * evolve_s / args.runs:.2f} ms per run)")
        serial = statistics.median(times[("serial", 1, None)])
        print(f"  {'mode':<26} {'median s':>9} {'runs/s':>8} {'vs serial':>9}   (all rounds, s)")
        for config in configs:
            mode, jobs, context = config
            median = statistics.median(times[config])
            label = {"serial": "serial, this process", "pool": f"pool {jobs} ({context})",
                     "cli": f"CLI --jobs {jobs} (+ CSV, file)"}[mode]
            print(f"  {label:<26} {median:>9.3f} {args.runs / median:>8.1f} {serial / median:>8.2f}x   "
                  + " ".join(f"{t:.3f}" for t in times[config]))
        for context in args.contexts:
            one, two = (statistics.median(times[("pool", j, context)]) for j in (1, 2))
            print(f"  {context}: 2 workers / 1 worker speed-up {one / two:.2f}x")
        if ("cli", 1, None) in times:
            one, two = (statistics.median(times[("cli", j, None)]) for j in (1, 2))
            print(f"  CLI: --jobs 2 / --jobs 1 speed-up {one / two:.2f}x")

    print("\nworker start-up (pool created → every worker has loaded the PN code and answered), medians:")
    startups = {(c, j): [] for c in args.contexts for j in (1, 2)}
    for _ in range(args.rounds):
        for key in startups:
            startups[key].append(time_startup(key[1], key[0]))
    for (context, jobs), values in startups.items():
        note = " (server already running)" if context == "forkserver" else ""
        print(f"  {context:<11} {jobs} worker{'s' * (jobs > 1)}: {statistics.median(values):.3f} s{note}   "
              + " ".join(f"{t:.3f}" for t in values))
    if "forkserver" in args.contexts:  # the first pool of a process also starts the server, which loads the PN code
        code = ("import time; t = time.perf_counter(); import bench_batch as b; t0 = time.perf_counter(); "
                "b.time_startup(1, 'forkserver'); print(time.perf_counter() - t0)")
        cold = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                     cwd=os.path.dirname(os.path.abspath(__file__))).stdout) for _ in range(args.rounds)]
        print(f"  forkserver  1 worker, first pool of a process: {statistics.median(cold):.3f} s   "
              + " ".join(f"{t:.3f}" for t in cold))
    return 0


if __name__ == "__main__":
    sys.exit(main())
