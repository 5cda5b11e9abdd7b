"""Fault injection (issue 15): batches and single runs stopped by signals at random moments, damaged files,
full disks, racing writers and lost Dask workers.

* batches: ``pnrotor evolve --batch`` of ``--rows`` binaries, killed with SIGKILL, SIGTERM or SIGINT at a
  random moment, then completed with ``--resume``: how many finished runs the kill kept (in the batch file being
  built in OUT.parts), whether the resumed file equals an uninterrupted batch bitwise, and worker processes left
  alive afterwards;
* single runs: ``pnrotor evolve`` of a BNS sampled at 1/4096 s (a ~200 MB file), signalled at a random
  moment of its write: temporary files left behind, the target's state (absent, or complete and readable);
* byte flips: ``--flips`` single-bit flips at random places of files of a precessing 30 + 10 M☉ run
  (sampled at its steps and at 1/4096 s) written by `pnrotor.hdf5.write` with its default checksums and with
  ``checksum=False``, each read back with `pnrotor.hdf5.read`: caught (a ValueError naming the file), read
  back identical (the flip hit unused bytes), silently wrong (read without error, a value changed) or a
  traceback (any other exception);
* disk full: the CLI writing to a 4 MiB tmpfs a ~30 MB run, uncompressed and gzipped (refused before writing),
  and a 1.4 MB run when the disk fills during the write: exit code, lines on stderr, traceback, files left;
* races: ``--races`` pairs of processes writing the same new file at the same instant: both succeeded;
* Dask: a batch on a local cluster whose worker processes are all killed (SIGKILL) at a random moment:
  whether it finishes and equals an uninterrupted batch.

    python benchmarks/faults.py [--trials 5] [--rows 40] [--jobs 2] [--seed 1] [--flips 500] [--races 300]
                                [--sections batches,single,flips,disk,races,dask]
"""

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SIGNALS = {"SIGKILL": signal.SIGKILL, "SIGTERM": signal.SIGTERM, "SIGINT": signal.SIGINT}


def table(path, rows):
    lines = ["m1,m2,chi1,chi2,f_ref,name"]
    lines += [f'{20 + i % 17},{8 + i % 5},"0.5,0.1,0.3","0,0.4,-0.2",{40 + i},r{i}' for i in range(rows)]
    path.write_text("\n".join(lines) + "\n")


def cli(*args, **kwargs):
    return subprocess.Popen([sys.executable, "-m", "pnrotor", "evolve", *map(str, args)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, **kwargs)


def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def children(pid):
    """Processes whose parent is pid (workers, a fork server) — read before the kill."""
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    if int(f.read().split(")")[-1].split()[1]) == pid:
                        out.append(int(entry))
            except (FileNotFoundError, IndexError, ValueError):
                pass
    return out


def same_file(a, b):
    from pnrotor import hdf5

    names = hdf5.list_runs(a)
    if names != hdf5.list_runs(b):
        return False
    for name in names:
        x, y = hdf5.read(a, name), hdf5.read(b, name)
        if not all(np.array_equal(getattr(x, k), getattr(y, k)) for k in ("t", "v", "Phi", "chi1", "chi2", "R")):
            return False
    return True


def kept_runs(out, rows):
    """Runs an interrupted batch kept: those of the batch file being built in OUT.parts (after completing or undoing
    what the kill interrupted, as --resume does), all rows if it finished, else none."""
    from pnrotor import hdf5

    parts = out.with_name(out.name + ".parts")
    if (parts / "runs.journal").exists():
        return len(hdf5.Journaled(parts / "runs.h5", parts / "runs.journal").names())
    return rows if out.exists() else 0


def batches(folder, args, rng):
    csv = folder / "t.csv"
    table(csv, args.rows)
    reference = folder / "reference.h5"
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pnrotor", "evolve", "--batch", csv, "-o", reference, "--jobs",
                    str(args.jobs), "-q"], check=True, capture_output=True)
    duration = time.perf_counter() - start
    print(f"batch of {args.rows} rows, --jobs {args.jobs}: {duration:.2f} s uninterrupted")
    print(f"{'signal':8s} {'trials':>6s} {'runs kept at kill (each)':>28s} {'resumed == uninterrupted':>25s} "
          f"{'processes left':>15s}")
    for name, signum in SIGNALS.items():
        kept, equal, orphans = [], 0, 0
        for trial in range(args.trials):
            out = folder / f"{name}-{trial}.h5"
            process = cli("--batch", csv, "-o", out, "--jobs", args.jobs, "-q")
            time.sleep(rng.uniform(0.3, 0.9) * duration)
            workers = children(process.pid)
            workers += [w for pid in workers for w in children(pid)]
            process.send_signal(signum)
            process.wait(timeout=60)
            time.sleep(2.0)
            orphans += sum(alive(w) for w in workers)
            kept.append(kept_runs(out, args.rows))
            if not out.exists():
                subprocess.run([sys.executable, "-m", "pnrotor", "evolve", "--batch", csv, "-o", out, "--jobs",
                                str(args.jobs), "-q", "--resume"], check=True, capture_output=True)
            equal += same_file(out, reference)
        print(f"{name:8s} {args.trials:6d} {str(kept):>28s} {equal:>22d}/{args.trials} {orphans:15d}")


def single_runs(folder, args, rng):
    from pnrotor import hdf5

    target = folder / "bns.h5"
    command = ["--m1", "1.4", "--m2", "1.3", "--chi1", "0,0,0", "--chi2", "0,0,0", "--f-ref", "20", "--sampling",
               "1/4096", "-o", target, "--overwrite", "-q"]
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pnrotor", "evolve", *map(str, command)], check=True, capture_output=True)
    duration = time.perf_counter() - start
    size = target.stat().st_size / 1e6
    print(f"\nsingle BNS run at 1/4096 s: {duration:.2f} s, file {size:.0f} MB")
    print(f"{'signal':8s} {'trials':>6s} {'temporaries left':>17s} {'target unreadable':>18s} {'exit codes'}")
    for name, signum in (("SIGTERM", signal.SIGTERM), ("SIGINT", signal.SIGINT), ("SIGHUP", signal.SIGHUP)):
        left = unreadable = 0
        codes = []
        for _ in range(args.trials):
            target.unlink(missing_ok=True)
            process = cli(*command)
            time.sleep(rng.uniform(0.5, 1.0) * duration)
            process.send_signal(signum)
            codes.append(process.wait(timeout=120))
            left += len([p for p in folder.iterdir() if p.name.endswith(".pnrotor-tmp")])
            if target.exists():
                try:
                    hdf5.read(target)
                except ValueError:
                    unreadable += 1
        print(f"{name:8s} {args.trials:6d} {left:17d} {unreadable:18d} {codes}")


def same_run(a, b):
    """Whether two runs hold the same values bitwise (arrays by their bytes; NaN equals NaN)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
    if isinstance(a, dict) or isinstance(b, dict):
        return isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys() and all(
            same_run(a[k], b[k]) for k in a)
    if hasattr(a, "__dataclass_fields__"):
        return type(a) is type(b) and all(same_run(getattr(a, k), getattr(b, k)) for k in vars(a))
    if isinstance(a, float) and isinstance(b, float):
        return np.float64(a).tobytes() == np.float64(b).tobytes()
    return type(a) is type(b) and a == b


def flips(folder, args, rng):
    import pnrotor
    from pnrotor import hdf5

    binary = dict(m1=30.0, m2=10.0, chi1=(0.5, 0.1, 0.3), chi2=(0.0, 0.4, -0.2), f_ref=20.0)
    print(f"\nbyte flips: {args.flips} single-bit flips per file, precessing 30 + 10 Msun from 20 Hz")
    print(f"{'sampling':<9} {'checksums':<9} {'file kB':>8} {'caught':>7} {'identical':>9} {'silently wrong':>14} "
          f"{'tracebacks':>10}")
    for label, sampling in (("steps", "steps"), ("1/4096 s", 1 / 4096)):
        run = pnrotor.evolve(**binary, sampling=sampling)
        for checksum in (True, False):
            base = folder / f"flips-{checksum}.h5"
            hdf5.write(base, run, checksum=checksum, overwrite=True)
            data = base.read_bytes()
            counts = dict(caught=0, identical=0, wrong=0, traceback=0)
            damaged = folder / "damaged.h5"
            for _ in range(args.flips):
                flipped = bytearray(data)
                flipped[rng.randrange(len(flipped))] ^= 1 << rng.randrange(8)
                damaged.write_bytes(bytes(flipped))
                try:
                    back = hdf5.read(damaged)
                except ValueError as error:
                    counts["caught" if str(damaged) in str(error) else "traceback"] += 1
                except Exception:  # noqa: BLE001 (what is counted)
                    counts["traceback"] += 1
                else:
                    counts["identical" if same_run(back, run) else "wrong"] += 1
            print(f"{label:<9} {'default' if checksum else 'no':<9} {len(data) / 1e3:8.1f} {counts['caught']:7d} "
                  f"{counts['identical']:9d} {counts['wrong']:14d} {counts['traceback']:10d}")


BNS = ["--m1", "1.4", "--m2", "1.3", "--chi1", "0,0,0", "--chi2", "0,0,0", "--f-ref", "30", "--sampling", "1/4096"]
"""A run of ~30 MB at 1/4096 s (~20 MB gzipped)."""


def disk(folder, args, rng):
    """The CLI writing to a 4 MiB tmpfs (mounting one needs root): refused before writing, or failing while
    writing; the goal is one line, exit 1, nothing left."""
    small = folder / "small"
    small.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(small)], capture_output=True).returncode:
        print("\ndisk full: skipped (cannot mount a tmpfs here)")
        return
    import shutil

    import pnrotor

    small_run = ["--m1", "30", "--m2", "10", "--chi1", "0.6,0,0.2", "--chi2", "0,-0.4,0.1", "--f-ref", "20",
                 "--sampling", "1/4096"]
    run = pnrotor.evolve(30, 10, (0.6, 0, 0.2), (0, -0.4, 0.1), 20.0, sampling=1 / 4096)
    raw = sum(getattr(run, k).nbytes for k in ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat"))
    cases = [("30 MB, uncompressed", BNS, [], False), ("30 MB, gzip", BNS, ["--compression", "gzip"], False),
             ("1.4 MB, fills while written", small_run, [], True),
             ("the same, --no-checksum", small_run, ["--no-checksum"], True)]
    try:
        print("\ndisk full: runs written to a 4 MiB tmpfs (\"fills while written\": 4 kB more free than the arrays, "
              "so the check before writing passes and the file's metadata does not fit)")
        print(f"{'write':<28} {'exit':>4} {'stderr lines':>12} {'traceback':>9} {'files left':>10}  message")
        for label, binary, extra, fill in cases:
            if fill:
                (small / "filler").write_bytes(bytes(shutil.disk_usage(small).free - raw - 4096))
            done = subprocess.run([sys.executable, "-m", "pnrotor", "evolve", *binary, *extra, "-o", small / "run.h5",
                                   "-q"], capture_output=True, text=True)
            err = done.stderr.strip().splitlines()
            left = [p for p in os.listdir(small) if p != "filler"]
            print(f"{label:<28} {done.returncode:4d} {len(err):12d} {'Traceback' in done.stderr!s:>9} "
                  f"{len(left):10d}  {err[-1][23:110] if err else ''}")
            for name in os.listdir(small):
                os.remove(small / name)
    finally:
        subprocess.run(["umount", str(small)], check=True)


def _race_writer(path_queue, results, barrier):
    import pnrotor
    from pnrotor import hdf5

    run = pnrotor.evolve(30.0, 10.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 100.0)
    while (path := path_queue.get()) is not None:
        barrier.wait()
        try:
            hdf5.write(path, run)
            results.put(True)
        except FileExistsError:
            results.put(False)


def races(folder, args, rng):
    """Two processes write the same new file at the same instant, ``--races`` times (no overwrite): how often
    both report success (one would silently replace the other)."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    paths, results, barrier = context.Queue(), context.Queue(), context.Barrier(2)
    writers = [context.Process(target=_race_writer, args=(paths, results, barrier)) for _ in range(2)]
    for writer in writers:
        writer.start()
    both = none = 0
    for i in range(args.races):
        for _ in writers:
            paths.put(folder / f"race{i}.h5")
        succeeded = results.get() + results.get()
        both += succeeded == 2
        none += succeeded == 0
    for _ in writers:
        paths.put(None)
    for writer in writers:
        writer.join()
    left = len([p for p in folder.iterdir() if p.name.endswith(".pnrotor-tmp")])
    print(f"\nracing writers: {args.races} pairs writing the same new file: both succeeded {both}, neither "
          f"{none}, temporaries left {left}")


def dask(folder, args, rng):
    """A batch on a local Dask cluster (2 workers, each under a nanny) whose worker processes are killed with
    SIGKILL in the middle: does the batch finish, equal to an uninterrupted one?"""
    try:
        from distributed import LocalCluster
    except ImportError:
        print("\nDask: skipped (no distributed)")
        return
    from pnrotor import batch

    csv = folder / "dask.csv"
    table(csv, args.rows)
    reference = folder / "dask-reference.h5"
    batch.run(csv, reference, jobs=1)
    print(f"\nDask, {args.rows} rows, 2 workers, every worker process killed once at a random moment")
    print(f"{'trial':>5} {'written':>7} {'failed':>6} {'equal':>5} {'seconds':>7}")
    for trial in range(args.trials):
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            import threading

            pids = [w.process.pid for w in cluster.workers.values()]
            pids = [child for pid in pids for child in children(pid)]   # the worker processes under the nannies
            delay = rng.uniform(0.5, 2.0)
            killer = threading.Timer(delay, lambda: [os.kill(pid, signal.SIGKILL) for pid in pids])
            out = folder / f"dask-{trial}.h5"
            start = time.perf_counter()
            killer.start()
            outcome = batch.run(csv, out, scheduler=cluster.scheduler_address)
            killer.join()
            seconds = time.perf_counter() - start
            equal = out.exists() and same_file(out, reference)
            print(f"{trial:5d} {outcome.written:7d} {len(outcome.failed):6d} {equal!s:>5} {seconds:7.1f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--rows", type=int, default=40)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--flips", type=int, default=500, help="bit flips per file in the flips section")
    parser.add_argument("--races", type=int, default=300, help="racing writer pairs in the races section")
    parser.add_argument("--sections", default="batches,single,flips,disk,races,dask",
                        help="comma-separated sections to run")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    sections = {"batches": batches, "single": single_runs, "flips": flips, "disk": disk, "races": races,
                "dask": dask}
    chosen = args.sections.split(",")
    if not set(chosen) <= sections.keys():
        parser.error(f"--sections takes a comma-separated list of {', '.join(sections)}")
    with tempfile.TemporaryDirectory() as tmp:
        for name in chosen:
            sections[name](Path(tmp), args, rng)


if __name__ == "__main__":
    main()
