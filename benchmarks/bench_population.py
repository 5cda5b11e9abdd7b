"""Benchmark of populations (issue 35): `pnrotor.batch.population.run` on one machine and on a Dask cluster, against
one `evolve_many` call and against the `precession` package, with a projection to 10⁷ and 10⁸ binaries.

The binaries: precessing, total mass 40 M☉, q = m₂/m₁ uniform in [0.25, 1], spins of magnitude uniform in
[0, 0.9] in isotropic directions, from 20 Hz to f_max = 100 Hz (those whose inspiral ends first have reached False).
In interleaved rounds after a warm-up round (not counted), medians and ranges of:

* one `evolve_many` call on the arrays (pnrotor's threads: numba's count), the baseline;
* ``population.run`` of the same rows as a CSV table (parsed, checked, written to one file, fsynced): in this
  process (``jobs=1``, pnrotor's threads), on 2 local worker processes (``jobs=2``, one thread each; with chunks of
  --chunks rows) and on a Dask LocalCluster of 2 worker processes of one thread (started once, outside the rounds);
* with --batch-rows, the per-row batch path (`pnrotor.batch.run`, ``jobs=1``, sampling final) on that many rows;
* `precession.inspiral_orbav` (Gerosa et al., PyPI ``precession`` 2.1) on the first --precession-rows binaries,
  and `evolve_many` on the same binaries at matched PN content (TaylorT4 at 3.5PN with spin-orbit terms to 1.5PN
  and spin-spin to 2PN, ``precession='averaged'``: precession's ``PNorderpre=[0, 0.5]``, ``PNorderrad`` to 3.5):
  their rows/s, and θ₁, θ₂, Δφ and the time to 100 Hz compared.

Then one instrumented run (this process, one thread) gives the costs the projection uses: the worker's cost per row
(parsing and checks, `evolve_many`), the parent's (reading the table; storing a chunk; assembling it into the file),
and the file's bytes per row.  With --memory-rows N, a table of N rows runs through the CLI with --jobs 2 and the
peak resident memory of its processes is measured (psutil, every 0.2 s).  --write-docs writes the results into the
"Populations" section of docs/performance.md.

    python benchmarks/bench_population.py [--rows 40000] [--rounds 3] [--chunks 1000,3000,10000,20000]
        [--precession-rows 100] [--batch-rows 200] [--memory-rows 1000000] [--write-docs]
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
from pathlib import Path

import numba
import numpy as np

import report
from pnrotor import batch, hdf5, threads
from pnrotor.batch import population
from pnrotor.batch.table import TableFile
from pnrotor.pn.initial import total_mass_seconds
from pnrotor.pn.many import evolve_many

F_REF, F_MAX, M_TOTAL = 20.0, 100.0, 40.0
MATCHED = dict(approximant="T4", pn_order=3.5, spin_orbit_order=1.5, spin_spin_order=2.0, precession="averaged")
DOCS = report.DOCS


def binaries(n, seed=35):
    """(m1, m2, chi1, chi2) of n binaries of the module docstring, m1 ≥ m2."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(0.25, 1.0, n)
    m1 = M_TOTAL / (1.0 + q)
    spins = []
    for _ in range(2):
        direction = rng.normal(size=(n, 3))
        spins.append(direction / np.linalg.norm(direction, axis=1)[:, None] * rng.uniform(0.0, 0.9, n)[:, None])
    return m1, M_TOTAL - m1, spins[0], spins[1]


def write_csv(path, arrays, rows=None, sampling=""):
    m1, m2, chi1, chi2 = (x[:rows] for x in arrays)
    with open(path, "w") as f:
        f.write("m1,m2,chi1,chi2,f_ref,f_max,sampling\n")
        for a, b, c, d in zip(m1.tolist(), m2.tolist(), chi1.tolist(), chi2.tolist()):
            f.write(f'{a!r},{b!r},"{",".join(map(repr, c))}","{",".join(map(repr, d))}",{F_REF!r},{F_MAX!r},'
                    f"{sampling}\n")


def timed(function):
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def precession_run(arrays):
    """precession.inspiral_orbav from v at 20 Hz to v at 100 Hz (r = v⁻², its Newtonian separation) → (θ₁, θ₂, Δφ,
    t in M) at 100 Hz."""
    import precession

    m1, m2, chi1, chi2 = arrays
    n = m1.size
    v = [(np.pi * total_mass_seconds(m1, m2) * f) ** (1.0 / 3.0) for f in (F_REF, F_MAX)]
    a1, a2 = np.linalg.norm(chi1, axis=1), np.linalg.norm(chi2, axis=1)
    out = precession.inspiral_orbav(Lh=np.tile([0.0, 0.0, 1.0], (n, 1)), S1h=chi1 / a1[:, None],
                                    S2h=chi2 / a2[:, None], r=np.stack([v[0] ** -2, v[1] ** -2], axis=1), q=m2 / m1,
                                    chi1=a1, chi2=a2)
    return out["theta1"][:, -1], out["theta2"][:, -1], out["deltaphi"][:, -1], out["t"][:, -1]


def summary(times, rows):
    median = statistics.median(times)
    return median, rows / median, f"{min(times):.2f}-{max(times):.2f}"


def measure(args, folder):
    arrays = binaries(args.rows)
    table = folder / "population.csv"
    write_csv(table, arrays)
    small = [x[:args.precession_rows] for x in arrays]
    configs = {"evolve_many (one call, arrays)": lambda: evolve_many(*arrays, F_REF, f_end=F_MAX)}
    run = lambda **kw: population.run(table, folder / "out.h5", overwrite=True, **kw)  # noqa: E731
    configs["population.run jobs=1"] = lambda: run(jobs=1)
    for chunk in args.chunks:
        configs[f"population.run jobs=2, chunks of {chunk}"] = lambda chunk=chunk: run(jobs=2, chunk=chunk)
    configs["population.run Dask, 2 workers"] = lambda: run(scheduler=cluster.scheduler_address)
    if args.batch_rows:
        write_csv(folder / "batch.csv", arrays, args.batch_rows, "final")
        configs["batch.run jobs=1 (per row)"] = lambda: batch.run(folder / "batch.csv", folder / "batch.h5", jobs=1,
                                                                  overwrite=True)
    configs["precession.inspiral_orbav"] = lambda: precession_run(small)
    configs["evolve_many, matched PN (same rows)"] = lambda: evolve_many(*small, F_REF, f_end=F_MAX, **MATCHED)
    rows = {name: args.precession_rows if "precession" in name or "matched" in name else
            args.batch_rows if "batch.run" in name else args.rows for name in configs}

    import distributed

    started, cluster = timed(lambda: distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                                              dashboard_address=None))
    times = {name: [] for name in configs}
    load = [os.getloadavg()[0]]
    try:
        for round_ in range(args.rounds + 1):
            for name, config in configs.items():
                elapsed, result = timed(config)
                if round_:
                    times[name].append(elapsed)
                if name == "evolve_many (one call, arrays)":
                    reached = int(result.reached.sum())
    finally:
        cluster.close()
    load.append(os.getloadavg()[0])
    results = {name: summary(times[name], rows[name]) for name in configs}
    comparison = compare_with_precession(small)
    costs = instrumented(table, folder, args.rows)
    return {"rows": args.rows, "reached": reached, "cluster_start_s": started, "results": results, "load": load,
            "comparison": comparison, "costs": costs, "rounds": args.rounds}


def compare_with_precession(arrays):
    """Largest differences of θ₁, θ₂, Δφ (rad) and of the time to 100 Hz (relative), pnrotor at matched PN content
    and at its defaults against precession."""
    theta1, theta2, dphi, t = precession_run(arrays)
    found = {}
    for label, options in (("matched", MATCHED), ("defaults", {})):
        pop = evolve_many(*arrays, F_REF, f_end=F_MAX, **options)
        wrapped = np.abs(np.angle(np.exp(1j * (pop.phi12 - dphi))))   # φ₁₂ in [0, 2π], Δφ in [-π, π]
        found[label] = (np.nanmax(np.abs(pop.theta1 - theta1)), np.nanmax(np.abs(pop.theta2 - theta2)),
                        np.nanmax(wrapped), np.nanmax(np.abs(pop.t / t - 1.0)), int(pop.reached.sum()))
    return found


def instrumented(table, folder, rows):
    """The costs of a population run in this process on one thread: per row, the worker's (compute_chunk: parsing,
    checks, evolve_many) and the parent's reading of the table; per chunk, the parent's storing and assembling;
    the final file's bytes per row."""
    spent = {"read": 0.0, "compute": 0.0, "store": 0.0, "assemble": 0.0}
    records, compute, store, concatenate = (TableFile.records, population.compute_chunk, population.Plan._store,
                                            hdf5.concatenate)

    def timing(key, function):
        def wrapper(*args, **kwargs):
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                spent[key] += time.perf_counter() - start
        return wrapper

    def read(self):
        iterator = records(self)
        while True:
            start = time.perf_counter()
            record = next(iterator, None)
            spent["read"] += time.perf_counter() - start
            if record is None:
                return
            yield record

    patches = [(TableFile, "records", read), (population, "compute_chunk", timing("compute", compute)),
               (population.Plan, "_store", timing("store", store)), (hdf5, "concatenate", timing("assemble", concatenate))]
    for owner, name, value in patches:
        setattr(owner, name, value)
    threads.limit(1)
    try:
        outcome = population.run(table, folder / "instrumented.h5", overwrite=True)
    finally:
        threads.limit(None)
        for (owner, name, _), original in zip(patches, (records, compute, store, concatenate)):
            setattr(owner, name, original)
    chunks = -(-rows // population.CHUNK)
    return {"read_row_s": spent["read"] / rows, "compute_row_s": spent["compute"] / rows,
            "evolve_row_s": outcome.evolve_seconds / rows, "store_chunk_s": spent["store"] / chunks,
            "assemble_chunk_s": spent["assemble"] / chunks,
            "bytes_per_row": os.path.getsize(folder / "instrumented.h5") / outcome.written}


def projection(costs, cores=2):
    """Wall time of N binaries on M machines of `cores` cores like this one: the workers' N × compute / (M × cores),
    unless the parent, which reads the table and stores each chunk, is slower (N × (read + store / chunk)), plus
    the assembly of N / chunk chunks after the last → [(N, M, seconds, which bounds it)]."""
    parent = costs["read_row_s"] + costs["store_chunk_s"] / population.CHUNK
    found = []
    for n in (10 ** 7, 10 ** 8):
        for machines in (1, 10, 100, 1000):
            workers = n * costs["compute_row_s"] / (machines * cores)
            bound = "workers" if workers >= n * parent else "parent"
            found.append((n, machines, max(workers, n * parent) + n / population.CHUNK * costs["assemble_chunk_s"],
                          bound))
    return found


def memory(rows, jobs, folder):
    """Peak resident memory (MB) of `pnrotor evolve --batch T --population --jobs JOBS -q` on a table of `rows`
    binaries: the sum over its processes and the largest one, sampled every 0.2 s; its wall time."""
    import psutil

    write_csv(folder / "memory.csv", binaries(rows))
    command = [sys.executable, "-c", "import sys; from pnrotor.cli import main; sys.exit(main())", "evolve", "--batch",
               str(folder / "memory.csv"), "--population", "--jobs", str(jobs), "-q", "-o", str(folder / "memory.h5")]
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    peak_sum = peak_one = 0
    parent = psutil.Process(process.pid)
    while process.poll() is None:
        try:
            sizes = [p.memory_info().rss for p in [parent] + parent.children(recursive=True)]
        except psutil.Error:
            continue
        peak_sum, peak_one = max(peak_sum, sum(sizes)), max(peak_one, max(sizes))
        time.sleep(0.2)
    wall = time.perf_counter() - start
    out, err = process.communicate()
    if process.returncode not in (0, 1):
        raise RuntimeError(f"the memory run failed: {err}")
    return {"rows": rows, "jobs": jobs, "peak_sum_MB": peak_sum / 2 ** 20, "peak_one_MB": peak_one / 2 ** 20,
            "wall_s": wall, "last_line": out.strip().splitlines()[-1]}


def report(found, mem):
    """The results as lines of Markdown (printed, and written into docs/performance.md with --write-docs)."""
    lines = [f"Measured by `python benchmarks/bench_population.py {' '.join(sys.argv[1:])}` ({os.cpu_count()} cores, "
             f"numba threads {numba.get_num_threads()}, Python {sys.version.split()[0]}, load average "
             f"{found['load'][0]:.1f} at the start and {found['load'][1]:.1f} at the end of the rounds; "
             f"{found['rounds']} interleaved rounds after a warm-up, medians and ranges), {found['rows']:,} precessing "
             f"binaries of 40 M☉ from 20 to 100 Hz ({found['reached']:,} reach 100 Hz; the others end first: NaN "
             "states, `reached` False).", "",
             "| configuration | rows | median s (range) | rows/s | / one evolve_many |", "|---|---|---|---|---|"]
    base = found["results"]["evolve_many (one call, arrays)"][1]
    for name, (median, rate, spread) in found["results"].items():
        rows = found["rows"] if "precession" not in name and "matched" not in name and "batch.run" not in name else \
            round(rate * median)
        lines.append(f"| {name} | {rows:,} | {median:.2f} ({spread}) | {rate:,.0f} | {rate / base:.2f} |")
    lines += ["", f"The Dask LocalCluster started in {found['cluster_start_s']:.1f} s (once, not in the rows/s)."]
    prec = found["results"]["precession.inspiral_orbav"][1]
    matched = found["results"]["evolve_many, matched PN (same rows)"][1]
    lines += ["", f"`precession.inspiral_orbav` against `evolve_many` on the same {round(prec * found['results']['precession.inspiral_orbav'][0])} "
              f"binaries: {prec:,.1f} against {matched:,.0f} rows/s ({matched / prec:,.0f}×); the population run "
              f"(this process) gives {found['results']['population.run jobs=1'][1] / prec:,.0f}× precession's rows/s.",
              "Largest differences at 100 Hz from precession's (its default tolerances, rtol = atol = 1e-10):", "",
              "| pnrotor | θ₁ (rad) | θ₂ (rad) | φ₁₂ − Δφ (rad) | time to 100 Hz (relative) | reached |",
              "|---|---|---|---|---|---|"]
    for label, (d1, d2, dp, dt, reached) in found["comparison"].items():
        what = ("matched PN content: T4, 3.5PN, spin-orbit 1.5PN, spin-spin 2PN" if label == "matched" else
                "its defaults: spin-orbit 3.5PN, spin-spin 3PN, NLO precession")
        lines.append(f"| {what} | {d1:.1e} | {d2:.1e} | {dp:.1e} | {dt:.1e} | {reached} |")
    lines += ["", "At matched PN content the two integrate the same equations (precession's orbit-averaged ones, "
              "Gerosa & Kesden 2016 Sec. 4A: leading-order spin-orbit and 2PN spin-spin precession with J conserved "
              "and |L| Newtonian, TaylorT4 radiation reaction with 1.5PN spin-orbit and 2PN spin-spin terms): "
              "they agree to precession's tolerance.  pnrotor's defaults add the higher spin-orbit and spin-spin "
              "terms precession does not have (and |L| to 1PN); the difference is then that of the physics."]
    c = found["costs"]
    lines += ["", "Costs of one run in this process on one thread (what the projection uses): the worker's "
              f"{c['compute_row_s'] * 1e6:.0f} µs per row ({c['evolve_row_s'] * 1e6:.0f} in `evolve_many`, the rest "
              f"parsing and checking the rows and encoding the chunk's HDF5 file); the parent's "
              f"{c['read_row_s'] * 1e6:.1f} µs per row to read the table, {c['store_chunk_s']:.3f} s to write a chunk "
              f"of {population.CHUNK:,} rows (its file and its mark, fsynced) and {c['assemble_chunk_s']:.3f} s to "
              f"copy it into the final file; {c['bytes_per_row']:.0f} bytes per row in that file (uncompressed).", "",
              "Projection (machines of 2 cores like this one; the workers' time unless the single parent, which "
              "reads the table and stores each chunk, is slower, plus the assembly at the end; not measured: the "
              "network of a real cluster, which carries ~0.3 kB per row each way, and its scheduler):", "",
              "| binaries | machines | projected wall | bound by | file |", "|---|---|---|---|---|"]
    for n, machines, seconds, bound in projection(c):
        lines.append(f"| {n:.0e} | {machines} | {_duration(seconds)} | {bound} | {n * c['bytes_per_row'] / 1e9:.0f} GB |")
    if mem:
        lines += ["", f"Memory: {mem['rows']:,} rows through `pnrotor evolve --batch T --population --jobs "
                  f"{mem['jobs']} -q` in {mem['wall_s']:.0f} s: peak resident memory {mem['peak_sum_MB']:.0f} MB over "
                  f"its processes (the largest {mem['peak_one_MB']:.0f} MB), whatever the table's length (the table "
                  f"is read as chunks finish). Its last line: `{mem['last_line']}`."]
    return lines


def _duration(seconds):
    return f"{seconds / 3600:.1f} h" if seconds >= 7200 else f"{seconds / 60:.0f} min" if seconds >= 120 else \
        f"{seconds:.0f} s"


def write_docs(lines):
    """Replace the Populations section's numbers in docs/performance.md (made if absent), as report.py does."""
    text = DOCS.read_text() if DOCS.exists() else (
        "# Performance\n\nMeasured numbers, each section written by the benchmark it names (do not edit them by "
        "hand: run the benchmark).\n")
    DOCS.write_text(report.write(text, "bench_population.py", lines))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rows", type=int, default=40_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--chunks", default=f"1000,3000,{population.CHUNK},20000",
                        help="chunk sizes of the jobs=2 runs, comma-separated")
    parser.add_argument("--precession-rows", type=int, default=100)
    parser.add_argument("--batch-rows", type=int, default=200)
    parser.add_argument("--memory-rows", type=int, default=0)
    parser.add_argument("--memory-jobs", type=int, default=2)
    parser.add_argument("--write-docs", action="store_true")
    args = parser.parse_args()
    args.chunks = [int(x) for x in args.chunks.split(",")]
    with tempfile.TemporaryDirectory(prefix="bench_population_") as folder:
        with contextlib.redirect_stderr(io.StringIO()):   # Dask's and the warm-up's chatter
            found = measure(args, Path(folder))
        mem = memory(args.memory_rows, args.memory_jobs, Path(folder)) if args.memory_rows else None
    lines = report(found, mem)
    print("\n".join(lines))
    if args.write_docs:
        write_docs(lines)
        print(f"\nwrote the Populations section of {DOCS}")


if __name__ == "__main__":
    main()
