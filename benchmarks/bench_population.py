"""Benchmark of `pnrotor evolve --batch F --population` against `pnrotor evolve --batch F --jobs 1`, sampling final.

The binaries of bench_batch.py (precessing, 8–80 M☉, spins up to 0.9, from 20 Hz to the end of the inspiral),
every row with ``sampling=final``: the population mode on ``--population-rows`` of them (one `evolve_many`
call, numba's threads, one file of columns) and the batch path on the first ``--batch-rows`` (one `evolve`
and one HDF5 group per row; ``--jobs 1`` in this process, ``--jobs 2`` on a new pool of 2 workers).  All end
to end through the CLI in this process (CSV in, file out, fsynced), interleaved rounds, medians; rows/s and
their ratios.  The first round is a warm-up (numba's cache loaded) and not counted.

    python benchmarks/bench_population.py [--population-rows 2000] [--batch-rows 200] [--rounds 5]
"""

import argparse
import contextlib
import io
import os
import statistics
import sys
import tempfile
import time

import numba

from bench_batch import binaries, write_csv
from pnrotor.cli import main as cli_main


def time_cli(csv_path, *options):
    out = os.path.join(os.path.dirname(csv_path), "out.h5")
    start = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = cli_main(["evolve", "--batch", csv_path, "-o", out, "--overwrite", "-q", *options])
    elapsed = time.perf_counter() - start
    assert code == 0
    return elapsed


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--population-rows", type=int, default=2000)
    parser.add_argument("--batch-rows", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_population_") as folder:
        measure(args, folder)


def measure(args, folder):
    tasks = binaries(args.population_rows, 8.0, 80.0, "final")
    big, small = os.path.join(folder, "population.csv"), os.path.join(folder, "batch.csv")
    write_csv(big, tasks)
    write_csv(small, tasks[:args.batch_rows])
    configs = {"population": (big, args.population_rows, ("--population",)),
               "batch --jobs 1": (small, args.batch_rows, ("--jobs", "1")),
               "batch --jobs 2": (small, args.batch_rows, ("--jobs", "2"))}
    print(f"{os.cpu_count()} cores, numba threads {numba.get_num_threads()}, Python {sys.version.split()[0]}; "
          f"{args.rounds} interleaved rounds after a warm-up, medians; sampling final, end to end through the CLI")
    times = {name: [] for name in configs}
    for round_ in range(args.rounds + 1):
        for name, (path, _, options) in configs.items():
            elapsed = time_cli(path, *options)
            if round_:
                times[name].append(elapsed)
    rates = {}
    for name, (_, rows, _) in configs.items():
        median = statistics.median(times[name])
        rates[name] = rows / median
        print(f"  {name:<16} {rows:>6} rows  median {median:.3f} s  {rates[name]:>9.0f} rows/s   (rounds: "
              + " ".join(f"{t:.3f}" for t in times[name]) + ")")
    print(f"  population / batch: {rates['population'] / rates['batch --jobs 1']:.1f}x (--jobs 1), "
          f"{rates['population'] / rates['batch --jobs 2']:.1f}x (--jobs 2)")


if __name__ == "__main__":
    main()
