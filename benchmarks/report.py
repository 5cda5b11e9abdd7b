"""Write docs/performance.md's measurements: each section is the output of one benchmark of this folder, run here
with the arguments below, headed by the machine, the versions and the commit it ran on.

    python benchmarks/report.py                      # every section (hours: see SECTIONS' cost)
    python benchmarks/report.py bench_pn.py bench_ode.py     # those sections only; the others stay as they are
    python benchmarks/report.py --list               # the sections, their commands and costs

Every benchmark measures pnrotor against its baseline (LALSuite, scipy, precession, a numpy copy, …) in the same
run, interleaved, and prints medians with their ranges; this script only runs them and files their output.  A
section is the text between ``<!-- NAME: begin -->`` and ``<!-- NAME: end -->`` in docs/performance.md, NAME the
benchmark's file (the markers ``bench_population.py --write-docs`` also writes); a section not there yet is added at
the end.  Benchmarks that print Markdown (``markdown=True``) are inserted as they are, the others as a text block.
A benchmark that fails leaves its section as it was, and the script exits non-zero.
"""

import argparse
import datetime
import os
import platform
import subprocess
import sys
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

HERE = Path(__file__).resolve().parent
DOCS = HERE.parent / "docs" / "performance.md"


@dataclass
class Section:
    title: str
    args: tuple
    cost: str
    markdown: bool = False


SECTIONS = {
    "bench_ode.py": Section("The integrator: pnrotor's DOP853 against scipy's", ("--quick", "--no-cold"), "~1 min"),
    "bench_pn.py": Section("PN orbits against LALSuite's SpinTaylorT4", ("--no-compile",), "~1 min"),
    "bench_latency.py": Section("The Python around one evolve call", (), "~1 min"),
    "bench_result_checks.py": Section("What the result types' checks cost", ("--rounds", "7"), "~1 min"),
    "bench_formulations.py": Section("The verification mode: one evaluation of ω in each formulation", (), "~1 min"),
    "bench_modes.py": Section("Modes against LALSuite's SpinTaylorT4 modes", (), "~2 min"),
    "bench_many.py": Section("Populations in one call: evolve_many against LALSuite", (), "~2 min"),
    "bench_pn_precision.py": Section("PN work–precision against LALSuite and scipy", ("--quick",), "~1 min"),
    "bench_hdf5.py": Section("HDF5 files: writing and reading against computing", ("--typical-only",), "~1 min"),
    "bench_pipelines.py": Section("Analysis pipelines: PyCBC and gwsignal against LAL's SpinTaylorT4",
                                  ("--rounds", "9"), "~2 min"),
    "bench_long.py": Section("Long signals: pnrotor.polarizations against LALSuite", ("--rounds", "3"), "~5 min"),
    "bench_batch.py": Section("Batches on local processes", ("--durability",), "~6 min"),
    "bench_population.py": Section("Populations", ("--rows", "40000", "--rounds", "3", "--memory-rows", "1000000"),
                                   "~40 min", markdown=True),
    "bench_cold_start.py": Section("Cold start: the first run's compile", ("--repeat", "2"), "~5 min"),
    "bench_compile.py": Section("Where a cold start's compile time goes", (), "~10 min"),
}
"""Each benchmark run by this script → its section's title, the arguments it runs with, and about how long that took
on a 2-core machine at load ~3 (the long ones: estimates)."""

VERSIONS = ("numpy", "scipy", "numba", "h5py", "lalsuite", "pycbc", "matplotlib")


def machine():
    """One line: the processor, cores, load, Python and the versions that set the numbers, pnrotor's commit."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            model = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    versions = []
    for name in VERSIONS:
        try:
            versions.append(f"{name} {metadata.version(name)}")
        except metadata.PackageNotFoundError:
            pass
    commit = subprocess.run(["git", "-C", str(HERE), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", str(HERE.parent), "status", "--porcelain", "--untracked-files=no", "--", "src",
                            "benchmarks"], capture_output=True, text=True).stdout.strip()   # the code, not the docs
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"{model}, {os.cpu_count()} cores, load average {load} at the start; Python {platform.python_version()}, "
            f"{', '.join(versions)}; pnrotor at {commit}{' with local changes' if dirty else ''}")


def run(name):
    """Run benchmark `name` → the lines of its section (header and output), or raise RuntimeError."""
    section = SECTIONS[name]
    command = [sys.executable, str(HERE / name), *section.args]
    shown = " ".join(["python", f"benchmarks/{name}", *section.args])
    header = machine()
    started = datetime.datetime.now(datetime.timezone.utc)
    done = subprocess.run(command, capture_output=True, text=True, cwd=HERE.parent)
    if done.returncode != 0:
        raise RuntimeError(f"{shown} exited {done.returncode}: {done.stderr.strip()[-2000:]}")
    minutes = (datetime.datetime.now(datetime.timezone.utc) - started).total_seconds() / 60
    output = done.stdout.rstrip()
    lines = [f"Written by `python benchmarks/report.py {name}`, which ran `{shown}` on "
             f"{started:%Y-%m-%d %H:%M} UTC for {minutes:.1f} min: {header}.", ""]
    return lines + (output.splitlines() if section.markdown else ["```text", *output.splitlines(), "```"])


def markers(name):
    return f"<!-- {name}: begin -->", f"<!-- {name}: end -->"


def write(text, name, lines):
    """``text`` (performance.md) with the section of benchmark ``name`` replaced by ``lines`` (added if absent)."""
    begin, end = markers(name)
    block = "\n".join([begin, *lines, end])
    if begin in text:
        return text[:text.index(begin)] + block + text[text.index(end) + len(end):]
    return text.rstrip("\n") + f"\n\n## {SECTIONS[name].title}\n\n{block}\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", metavar="BENCHMARK", help=f"sections to write (default: all): "
                        f"{', '.join(SECTIONS)}")
    parser.add_argument("--list", action="store_true", help="print the sections, their commands and costs")
    args = parser.parse_args(argv)
    unknown = [name for name in args.names if name not in SECTIONS]
    if unknown:
        parser.error(f"unknown benchmark {', '.join(unknown)}; choose from {', '.join(SECTIONS)}")
    if args.list:
        for name, section in SECTIONS.items():
            print(f"{name:24s} {section.cost:>8s}  python benchmarks/{name} {' '.join(section.args)}")
        return 0
    failed = 0
    for name in args.names or list(SECTIONS):
        print(f"running {name} ({SECTIONS[name].cost}) ...", flush=True)
        try:
            lines = run(name)
        except RuntimeError as error:
            print(f"  failed, its section left as it was: {error}", file=sys.stderr)
            failed += 1
            continue
        DOCS.write_text(write(DOCS.read_text(), name, lines))   # after each, so a later failure keeps it
        print(f"  wrote its section of {DOCS}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
