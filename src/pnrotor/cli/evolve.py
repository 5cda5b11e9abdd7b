"""`pnrotor evolve`: evolve one precessing binary (or a batch of them) in PN theory and write HDF5.

One run: ``pnrotor evolve --m1 30 --m2 10 --chi1 0.6,0,0.2 --chi2 0,-0.4,0.1 --f-ref 20`` calls
`pnrotor.evolve` with these arguments, prints a one-screen summary (masses, spins, approximant,
duration, orbits, initial and final v and GW frequency, the termination of each half with its message,
the integrator's work, wall time) and writes the `Evolution` with `pnrotor.hdf5.write` to ``-o FILE``,
by default ``waveforms/NAME.h5`` in the current folder, NAME built from the parameters
(`default_name`; ``waveforms/`` is created if missing, an explicit ``-o`` folder is not). An existing
file is refused before anything is computed unless ``--overwrite``.

Batch: ``pnrotor evolve --batch params.csv`` (or ``.toml``) runs one binary per CSV row or TOML
``[[binary]]`` table, with columns/keys named like the options (`COLUMNS`; vectors as ``"x,y,z"``
strings in CSV, arrays in TOML; options given on the command line are the defaults of empty cells).
The file's structure (columns, names) is checked before anything runs. Runs go to ``--jobs`` local
worker processes (default: every core; ``--jobs 1`` runs in this process) or, with ``--scheduler
ADDRESS``, to a Dask cluster (the ``pnrotor[dask]`` extra). This process alone writes the batch file,
with `pnrotor.hdf5.batch`, each result as it arrives (one group per run, named by the ``name`` column or
`default_name`; local workers write their runs into part files, whose groups it copies), under a
temporary name that is renamed to ``-o FILE`` (default ``waveforms/BATCH-STEM.h5``) only when the batch
is complete, so Ctrl-C never leaves a partial file.
A row that fails (bad value, evolve's ``ValueError``) is listed with its row number and message and
the others are still written; exit status 1 then, 2 when the batch file itself is unusable.

The PN code (numba) is imported only when a run starts, so that the CLI starts quickly.
"""

import contextlib
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from pnrotor.cli import UsageError

DEFAULT_FOLDER = "waveforms"

DEFAULTS = {
    "approximant": "T4", "pn_order": 3.5, "spin_orbit_order": None, "spin_spin_order": None,
    "precession": "averaged", "f_min": None, "f_max": None, "sampling": "steps", "atol": 1e-12,
}
"""Defaults of the optional run parameters (those of `pnrotor.evolve`; None: evolve's own choice)."""

REQUIRED = ("m1", "m2", "chi1", "chi2", "f_ref")
COLUMNS = REQUIRED + tuple(DEFAULTS) + ("name",)
"""Columns of a batch CSV file (keys of a TOML ``[[binary]]`` table): the option names with ``_``."""

PRECESSION = ("averaged", "averaged_varpi", "instantaneous")
SCHEDULER_TIMEOUT = "10s"
"""How long to wait for a Dask scheduler to answer."""


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "evolve",
        help="evolve a precessing binary (or a batch of them) and write its history to HDF5",
        description="Evolve a quasi-circular, precessing compact binary in post-Newtonian theory "
        "(pnrotor.evolve) from f_ref backward to --f-min and forward to --f-max or the end of the inspiral, "
        "print a summary and write the history to waveforms/NAME.h5 (or -o). With --batch, many binaries "
        "from a CSV or TOML file, in parallel, into one batch file.",
    )
    binary = parser.add_argument_group("binary (one run)")
    binary.add_argument("--m1", type=float, metavar="MSUN", help="mass of body 1 in solar masses")
    binary.add_argument("--m2", type=float, metavar="MSUN", help="mass of body 2 in solar masses")
    binary.add_argument("--chi1", metavar="X,Y,Z", help="dimensionless spin of body 1 at f_ref, |chi1| <= 1")
    binary.add_argument("--chi2", metavar="X,Y,Z", help="dimensionless spin of body 2 at f_ref, |chi2| <= 1")
    binary.add_argument("--f-ref", type=float, metavar="HZ",
                        help="GW frequency (twice the orbital) at which the spins are given; t = 0 there")
    model = parser.add_argument_group("model and output (with --batch: defaults for empty cells)")
    model.add_argument("--approximant", help="T1, T4 (default) or T5 (also TaylorT4, SpinTaylorT4, ...)")
    model.add_argument("--pn-order", type=float, metavar="ORDER",
                       help="PN order of the nonspinning terms, 0 ... 4.5 (default 3.5)")
    model.add_argument("--spin-orbit-order", type=float, metavar="ORDER",
                       help="PN order of the spin-orbit terms, -1 ... 4 (default min(pn-order, 4); -1: none)")
    model.add_argument("--spin-spin-order", type=float, metavar="ORDER",
                       help="PN order of the spin-spin terms, -1 ... 3 (default min(pn-order, 3); -1: none)")
    model.add_argument("--precession", choices=PRECESSION, help="spin precession model (default: averaged)")
    model.add_argument("--f-min", type=float, metavar="HZ",
                       help="also integrate backward from f_ref down to this GW frequency")
    model.add_argument("--f-max", type=float, metavar="HZ",
                       help="stop at this GW frequency (default: at the end of the inspiral, which is named)")
    model.add_argument("--sampling", metavar="S",
                       help="steps (every integrator step, default), final (only the final state), a time step in "
                       "seconds (e.g. 1/4096 or 0.000244) or per_orbit:N (N points per orbit)")
    model.add_argument("--atol", type=float, help="absolute tolerance of the integrator (default 1e-12; rtol 0)")
    output = parser.add_argument_group("output")
    output.add_argument("-o", "--output", metavar="FILE.h5",
                        help="output file (default: waveforms/NAME.h5, NAME from the parameters, or waveforms/STEM.h5 "
                        "for --batch STEM.csv); its folder must exist")
    output.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    output.add_argument("--compression", choices=("gzip", "lzf"), help="compress the datasets (default: none)")
    output.add_argument("--checksum", action="store_true",
                        help="store a Fletcher-32 checksum per chunk, so damaged bytes are an error on reading "
                        "(about 2x the write time uncompressed)")
    output.add_argument("-q", "--quiet", action="store_true",
                        help="print only the output file, failures and the batch's last line; no progress bar")
    batch = parser.add_argument_group("batch")
    batch.add_argument("--batch", metavar="FILE", help=f"CSV or TOML file of binaries; columns {', '.join(COLUMNS)}")
    batch.add_argument("--jobs", type=int, metavar="N",
                       help="local worker processes (default: os.cpu_count(); 1 runs in this process)")
    batch.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the batch on this Dask scheduler (e.g. tcp://host:8786); needs pnrotor[dask]")
    parser.set_defaults(func=run)


def run(args):
    if args.batch is not None:
        return _run_batch(args)
    for option in ("jobs", "scheduler"):
        if getattr(args, option) is not None:
            raise UsageError(f"--{option} applies to --batch runs only")
    return _run_one(args)


# --------------------------------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------------------------------


def parse_vector(text, name):
    """Three finite floats from ``"x,y,z"`` (or a sequence of three numbers); the error names `name`."""
    items = text.split(",") if isinstance(text, str) else text
    try:
        if isinstance(items, (str, bytes)) or len(items) != 3 or any(isinstance(x, bool) for x in items):
            raise ValueError
        vector = tuple(float(x) for x in items)
    except (TypeError, ValueError):
        vector = ()
    if len(vector) != 3 or not all(math.isfinite(x) for x in vector):
        raise UsageError(f"{name} must be three finite numbers separated by commas, such as 0.6,0,0.2; got {text!r}")
    return vector


def parse_sampling(value, name="--sampling"):
    """`pnrotor.evolve`'s ``sampling`` from 'steps', 'final', 'per_orbit:N' or Δt seconds ('1/4096', '0.000244')."""
    if not isinstance(value, str):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        raise UsageError(f"{name} must be a string or a number of seconds, got {value!r}")
    text = value.strip().lower()
    if text in ("steps", "final"):
        return text
    if text.startswith("per_orbit:"):
        count = text.partition(":")[2].strip()
        if not count.isdigit() or int(count) < 1:
            raise UsageError(f"{name} per_orbit:N needs a positive integer N, got {value!r}")
        return ("per_orbit", int(count))
    try:
        numerator, slash, denominator = text.partition("/")
        return float(numerator) / float(denominator) if slash else float(text)
    except (ValueError, ZeroDivisionError):
        raise UsageError(f"{name} must be steps, final, per_orbit:N or a time step in seconds such as 1/4096, "
                         f"got {value!r}") from None


def _number(x):
    """Shortest exact text of a float, without a trailing '.0' (30.0 → '30', 1/4096 → '0.000244140625')."""
    text = repr(float(x) + 0.0)  # + 0.0: no '-0'
    return text[:-2] if text.endswith(".0") else text


def default_name(p):
    """Readable, deterministic, filesystem-safe name of a run from its parameters (`pnrotor.evolve`'s
    keywords): approximant, masses, spins and f_ref, then every option that differs from its default,
    e.g. ``T4_m30_m10_chi1-0.6,0,0.2_chi2-0,-0.4,0.1_f20`` or ``..._f20_fmin10_dt0.000244140625``."""
    from pnrotor.pn.evolve import normalize_approximant

    vector = ",".join
    parts = [normalize_approximant(p["approximant"]), f"m{_number(p['m1'])}", f"m{_number(p['m2'])}",
             f"chi1-{vector(map(_number, p['chi1']))}", f"chi2-{vector(map(_number, p['chi2']))}",
             f"f{_number(p['f_ref'])}"]
    for key, tag in (("f_min", "fmin"), ("f_max", "fmax"), ("pn_order", "pn"), ("spin_orbit_order", "so"),
                     ("spin_spin_order", "ss"), ("atol", "atol")):
        if p[key] is not None and p[key] != DEFAULTS[key]:
            parts.append(f"{tag}{_number(p[key])}")
    if p["precession"] != DEFAULTS["precession"]:
        parts.append(str(p["precession"]))
    sampling = p["sampling"]
    if isinstance(sampling, tuple):
        parts.append(f"perorbit{sampling[1]}")
    elif isinstance(sampling, float):
        parts.append(f"dt{_number(sampling)}")
    elif sampling != "steps":
        parts.append(str(sampling))
    return "_".join(parts)


def _output_path(args, stem):
    """The output file, checked before anything is computed: (path, whether its folder is the default)."""
    if args.output is not None:
        path = Path(args.output)
        if path.is_dir():
            raise IsADirectoryError(f"{path} is a folder; give a file name such as {path / (stem + '.h5')}")
        if not path.parent.is_dir():
            raise FileNotFoundError(f"folder {path.parent} does not exist (-o {path}); create it first")
        default = False
    else:
        path, default = Path(DEFAULT_FOLDER) / f"{stem}.h5", True
    if path.exists() and not args.overwrite:
        raise FileExistsError(f"{path} exists; pass --overwrite to replace it")
    return path, default


# --------------------------------------------------------------------------------------------------
# one run
# --------------------------------------------------------------------------------------------------


def _run_one(args):
    start = time.perf_counter()
    missing = [f"--{key.replace('_', '-')}" for key in REQUIRED if getattr(args, key) is None]
    if missing:
        raise UsageError(f"missing {', '.join(missing)} (or give --batch FILE)")
    params = {key: getattr(args, key) for key in REQUIRED}
    params["chi1"] = parse_vector(args.chi1, "--chi1")
    params["chi2"] = parse_vector(args.chi2, "--chi2")
    for key, default in DEFAULTS.items():
        value = getattr(args, key)
        params[key] = default if value is None else value
    params["sampling"] = parse_sampling(params["sampling"])
    path, default_folder = _output_path(args, default_name(params))

    run = _evolve_row(params)
    if default_folder:
        path.parent.mkdir(exist_ok=True)
    from pnrotor import hdf5

    hdf5.write(path, run, overwrite=args.overwrite, compression=args.compression, checksum=args.checksum)
    if not args.quiet:
        print("\n".join(summary(run, time.perf_counter() - start)))
    print(f"wrote {path}")
    return 0


def _evolve_row(params):
    from pnrotor.pn.evolve import evolve

    return evolve(**params)


def _span(run):
    """(t_start, t_end in M, v_start, v_end, orbits, whether the orbits span the whole integration).

    Times and v are those of the whole integration whatever the sampling (without f_min the start is f_ref,
    where Φ = 0). The orbits (Φ_end − Φ_start)/2π are exact when the samples include both ends (sampling
    'steps', or 'final' without f_min); otherwise they are counted between the first and last samples (a
    Δt or per-orbit grid), or None (one sample that is not the start)."""
    stats, inputs = run.stats, run.inputs
    backward = stats["termination_backward"] != "not_integrated"
    t0, t1 = stats["t_initial"], stats["t_final"]
    n = len(run)
    if not backward:
        v0, phi0 = inputs["v_ref"], 0.0
    elif n and run.t[0] == t0:
        v0, phi0 = run.v[0].item(), run.Phi[0].item()
    elif stats["termination_backward"] == "f_min":
        v0, phi0 = (math.pi * inputs["M_seconds"] * inputs["f_min_Hz"]) ** (1 / 3), None
    else:
        v0, phi0 = (run.v[0].item() if n else math.nan), None
    v1 = stats["v_final"]
    phi1 = run.Phi[-1].item() if n and run.t[-1] == t1 else None
    if phi0 is not None and phi1 is not None:
        return t0, t1, v0, v1, (phi1 - phi0) / (2 * math.pi), True
    if n >= 2:
        return t0, t1, v0, v1, (run.Phi[-1] - run.Phi[0]).item() / (2 * math.pi), False
    return t0, t1, v0, v1, None, False


def _orbits_text(orbits, exact):
    if orbits is None:
        return "orbits unknown (one sample, not the start)"
    return f"{orbits:.6g} orbits" if exact else f"~{orbits:.6g} orbits (first to last sample)"


def summary(run, wall=None):
    """The lines `pnrotor evolve` prints about one run."""
    i, s = run.inputs, run.stats
    M = i["M_seconds"]
    t0, t1, v0, v1, orbits, exact = _span(run)
    f0, f1 = (v**3 / (math.pi * M) for v in (v0, v1))
    vec = lambda a: "(" + ", ".join(f"{x:.6g}" for x in a) + ")"  # noqa: E731
    lines = [
        f"pnrotor evolve: {i['m1_Msun']:g} + {i['m2_Msun']:g} Msun, chi1 {vec(i['chi1'])}, chi2 {vec(i['chi2'])}, "
        f"f_ref {i['f_ref_Hz']:g} Hz ({i['spin_content']})",
        f"  model          {i['approximant']}, PN order {i['pn_order']:g} (spin-orbit {i['spin_orbit_order']:g}, "
        f"spin-spin {i['spin_spin_order']:g}), precession {i['precession']}, atol {i['atol']:g}",
        f"  duration       {(t1 - t0) * M:.6g} s = {t1 - t0:.6g} M  (t from {t0:.6g} to {t1:.6g} M)",
        f"  ΔΦ/2π          {_orbits_text(orbits, exact)}",
        f"  v              {v0:.6g} -> {v1:.6g}",
        f"  GW frequency   {f0:.6g} Hz -> {f1:.6g} Hz",
        f"  forward        {run.termination}: {s['termination_message']}",
        f"  backward       {s['termination_backward']}: {s['termination_backward_message']}",
        f"  work           {s['nfev']} evaluations, {s['nsteps']} steps ({s['naccepted']} accepted, "
        f"{s['nrejected']} rejected)",
        f"  samples        {len(run)} ({_sampling_text(i)})",
        f"  wall time      {s['wall_time_s']:.3g} s evolving"
        + (f", {wall:.3g} s in all (imports and writing included)" if wall is not None else ""),
    ]
    return lines


def _sampling_text(inputs):
    mode, value = inputs["sampling"], inputs["sampling_value"]
    return {"dt": f"every {value:.6g} s", "per_orbit": f"{value:g} per orbit"}.get(mode, mode)


# --------------------------------------------------------------------------------------------------
# batch: reading and checking the file
# --------------------------------------------------------------------------------------------------


class Row:
    """One binary of a batch: its number and label, its `pnrotor.evolve` parameters and group name, or the
    error that stops it."""

    def __init__(self, number, label):
        self.number, self.label = number, label
        self.params = self.name = self.error = None

    def __repr__(self):
        return f"{self.label} ({self.name})" if self.name else self.label


def read_batch(path, cli_defaults):
    """The rows of a CSV or TOML batch file, each with parameters and name or its error.

    Problems of the file itself (missing, unreadable, unknown or missing columns, repeated names) raise
    `UsageError`/`FileNotFoundError`; a bad value only marks its row."""
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder, not a batch file")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        records = _csv_records(path)
    elif suffix == ".toml":
        records = _toml_records(path)
    else:
        raise UsageError(f"batch file {path} must be .csv or .toml")
    if not records:
        raise UsageError(f"batch file {path} holds no binaries")
    rows = []
    for number, (label, record) in enumerate(records, 1):
        row = Row(number, label)
        try:
            row.params, row.name = _row_parameters(record, cli_defaults)
        except (UsageError, ValueError) as error:
            row.error = str(error)
        rows.append(row)
    seen = {}
    for row in rows:
        if row.name is not None:
            if row.name in seen:
                raise UsageError(f"batch file {path}: {seen[row.name].label} and {row.label} have the same name "
                                 f"{row.name!r}; give each a distinct name column")
            seen[row.name] = row
    return rows


def _check_columns(keys, where):
    unknown = [key for key in keys if key not in COLUMNS]
    if unknown:
        raise UsageError(f"{where}: unknown column{'s' * (len(unknown) > 1)} {', '.join(map(repr, unknown))}; "
                         f"the columns are {', '.join(COLUMNS)}")
    missing = [key for key in REQUIRED if key not in keys]
    if missing:
        raise UsageError(f"{where}: missing column{'s' * (len(missing) > 1)} {', '.join(missing)}")


def _csv_records(path):
    import csv

    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise UsageError(f"batch file {path} is empty")
            header = [name.strip() for name in header]
            _check_columns(header, f"batch file {path}")
            duplicated = sorted({name for name in header if header.count(name) > 1})
            if duplicated:
                raise UsageError(f"batch file {path}: repeated column {', '.join(duplicated)}")
            records = []
            for cells in reader:
                if not any(cell.strip() for cell in cells):
                    continue
                if len(cells) != len(header):
                    raise UsageError(f"batch file {path} line {reader.line_num}: {len(cells)} fields for "
                                     f"{len(header)} columns (quote vectors: \"0.6,0,0.2\")")
                record = {key: cell.strip() for key, cell in zip(header, cells) if cell.strip()}
                records.append((f"row {len(records) + 1} (line {reader.line_num})", record))
    except UnicodeDecodeError as error:
        raise UsageError(f"batch file {path} is not UTF-8 text ({error})") from None
    except csv.Error as error:
        raise UsageError(f"batch file {path} is not valid CSV ({error})") from None
    return records


def _toml_records(path):
    import tomllib

    try:
        with open(path, "rb") as f:
            document = tomllib.load(f)
    except tomllib.TOMLDecodeError as error:
        raise UsageError(f"batch file {path} is not valid TOML ({error})") from None
    extra = [key for key in document if key != "binary"]
    tables = document.get("binary")
    if extra or not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        raise UsageError(f"batch file {path} must hold [[binary]] tables only"
                         + (f"; found {', '.join(map(repr, extra))}" if extra else ""))
    records = []
    for number, table in enumerate(tables, 1):
        _check_columns(list(table), f"batch file {path} [[binary]] {number}")
        records.append((f"row {number} ([[binary]] {number})", table))
    return records


def _row_parameters(record, cli_defaults):
    """`pnrotor.evolve` keywords and the group name of one batch record; CLI options fill empty cells."""
    params = {}
    for key in REQUIRED:
        value = record[key] if key in record else None
        if value is None:
            raise UsageError(f"{key} is empty")
        params[key] = parse_vector(value, key) if key.startswith("chi") else _float(value, key)
    for key, default in DEFAULTS.items():
        value = record.get(key, cli_defaults.get(key))
        if value is None:
            params[key] = default
        elif key == "sampling":
            params[key] = parse_sampling(value, "sampling")
        elif key in ("approximant", "precession"):
            params[key] = str(value)
        else:
            params[key] = _float(value, key)
    name = record.get("name")
    if name is None:
        name = default_name(params)
    elif not isinstance(name, str) or name in (".", "") or "/" in name or "\x00" in name:
        raise UsageError(f"name {name!r} is not a valid group name (non-empty, no '/', not '.')")
    else:
        default_name(params)  # checks the approximant before the run
    return params, name


def _float(value, key):
    if isinstance(value, bool):
        raise UsageError(f"{key} must be a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise UsageError(f"{key} must be a number, got {value!r}") from None


# --------------------------------------------------------------------------------------------------
# batch: running
# --------------------------------------------------------------------------------------------------


def attempt(params):
    """evolve(**params) → (True, Evolution) or (False, message): one row's failure must not stop the batch."""
    try:
        return True, _evolve_row(params)
    except Exception as error:  # noqa: BLE001 - reported per row
        return False, str(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"


def attempt_chunk(chunk):
    """`attempt` on each (index, params) of a chunk → [(index, ok, Evolution or message)]."""
    return [(index, *attempt(params)) for index, params in chunk]


class Stored:
    """A run that a worker wrote into the part file `path` as group `group`, with the `brief` of it."""

    def __init__(self, path, group, brief):
        self.path, self.group, self.brief = path, group, brief


def brief(run):
    """What the batch summary needs of a run: small enough to send back from a worker instead of the run."""
    return {"span": _span(run), "M_seconds": run.inputs["M_seconds"], "termination": run.termination,
            "samples": len(run), "nfev": run.stats["nfev"], "wall_time_s": run.stats["wall_time_s"]}


def write_chunk(chunk, folder, storage):
    """`attempt` on each (index, params) of a chunk, the runs written into a part file in `folder` (group =
    index, `pnrotor.hdf5.batch` with the options `storage`) → [(index, ok, Stored or message)]. Encoding
    HDF5 costs several times a typical run, so the workers do it and the parent only copies the groups into
    the batch file (`Batch.copy_from`, HDF5's object copy, which keeps their layout and filters)."""
    from pnrotor import hdf5

    path = Path(folder) / f"part-{chunk[0][0]}.h5"
    results = []
    # a scratch file: not fsynced (that made 200 runs at 1/4096 s with --jobs 2 take ~20% longer)
    with hdf5.batch(path, durable=False, **storage) as part:
        for index, params in chunk:
            ok, result = attempt(params)
            if ok:
                part.add(str(index), result)
                result = Stored(path, str(index), brief(result))
            results.append((index, ok, result))
    return results


def _ignore_interrupts():
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle: it stops the workers


def _preload():
    _ignore_interrupts()
    import pnrotor.pn.evolve  # noqa: F401 - numba's kernels, loaded once per worker


def results_serial(tasks):
    """Yield (index, ok, result) for each (index, params), computed in this process."""
    for index, params in tasks:
        yield (index, *attempt(params))


def chunk_size(n_tasks, jobs):
    """Rows per task sent to a worker: about 4 tasks per worker for load balance, at most 8 rows each."""
    return max(1, min(8, n_tasks // (4 * jobs)))


def start_method():
    """How worker processes start: 'fork' on Linux when this process runs no other thread (a worker then
    starts in ~0.02 s with the PN code already loaded, against ~0.6 s for 'forkserver' and ~0.8 s for
    'spawn', benchmarks/bench_batch.py); otherwise 'forkserver' (forking a process with threads can
    deadlock the child), or 'spawn' where there is no forkserver (Windows)."""
    import multiprocessing
    import threading

    methods = multiprocessing.get_all_start_methods()
    if sys.platform.startswith("linux") and "fork" in methods and threading.active_count() == 1:
        return "fork"
    return "forkserver" if "forkserver" in methods else "spawn"


def results_pool(tasks, jobs, context=None, chunksize=None, parts=None, storage=None):
    """Start `jobs` worker processes on `tasks` [(index, params)] and return a generator of (index, ok, result),
    in the order the chunks finish.

    The workers (started by `multiprocessing` method `context`, default `start_method`) load the PN code once
    and take `chunksize` rows per task. They send back each run, or with `parts` (a folder) write the runs
    of each chunk to a part file there (with the `pnrotor.hdf5.batch` options `storage`, a dict) and send
    back a `Stored`; the part file is removed once its rows
    have been consumed. Closing the generator early (Ctrl-C) cancels the queued tasks and stops the workers.
    The workers are started here, before the caller starts any thread (a progress bar's)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    size = chunksize or chunk_size(len(tasks), jobs)
    chunks = [tasks[i : i + size] for i in range(0, len(tasks), size)]
    mp_context = multiprocessing.get_context(context or start_method())
    if mp_context.get_start_method() == "forkserver":
        mp_context.set_forkserver_preload(["pnrotor.pn.evolve"])  # loaded once, in the server
    pool = ProcessPoolExecutor(max_workers=min(jobs, len(chunks)), mp_context=mp_context, initializer=_preload)
    futures = {}
    try:
        for chunk in chunks:
            if parts is None:
                futures[pool.submit(attempt_chunk, chunk)] = chunk
            else:
                futures[pool.submit(write_chunk, chunk, parts, storage or {})] = chunk
    except BrokenProcessPool:
        pass  # a worker died at start-up: the chunks not submitted are reported below
    except BaseException:
        _stop(pool)
        raise
    unsubmitted = chunks[len(futures):]
    return _pool_results(pool, futures, unsubmitted, parts)


def _stop(pool):
    pool.shutdown(wait=False, cancel_futures=True)
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        process.terminate()
    pool.shutdown(wait=True)


def _pool_results(pool, futures, unsubmitted, parts):
    from concurrent.futures import as_completed
    from concurrent.futures.process import BrokenProcessPool

    completed = False
    try:
        for future in as_completed(futures):
            try:
                results = future.result()
            except BrokenProcessPool as error:
                results = [(index, False, f"worker process died ({error})") for index, _ in futures[future]]
            yield from results
            if parts is not None:
                (Path(parts) / f"part-{futures[future][0][0]}.h5").unlink(missing_ok=True)
        for chunk in unsubmitted:
            yield from ((index, False, "worker process died at start-up") for index, _ in chunk)
        completed = True
    finally:
        if completed:
            pool.shutdown(wait=True)
        else:
            _stop(pool)


def results_dask(tasks, address):
    """Connect to the Dask scheduler at `address`, submit one task per (index, params) and return a generator
    of (index, ok, result) as they finish (the runs themselves come back; this process writes them)."""
    try:
        from distributed import Client
    except ImportError:
        raise UsageError("--scheduler needs Dask's distributed scheduler: pip install 'pnrotor[dask]'") from None
    try:
        client = Client(address, timeout=SCHEDULER_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError) as error:
        raise UsageError(f"cannot connect to the Dask scheduler at {address}: {error}") from None
    return _dask_results(client, tasks)


def _dask_results(client, tasks):
    from distributed import as_completed

    with client:
        futures = client.map(attempt_chunk, [[task] for task in tasks], pure=False)
        chunk_of = {future.key: [task] for future, task in zip(futures, tasks)}
        for future in as_completed(futures, loop=client.loop):
            try:
                results = future.result()
            except Exception as error:  # noqa: BLE001 - a lost worker, reported per row
                results = [(index, False, f"Dask task failed: {type(error).__name__}: {error}")
                           for index, _ in chunk_of[future.key]]
            yield from results


class _InterruptFlag:
    """Ctrl-C is remembered and raised as KeyboardInterrupt at once, or by `check` after a `deferred` block
    (inside one, also when `interruptible` waits for its next item).

    Python drops (prints as "Exception ignored") a KeyboardInterrupt raised inside a weakref callback or
    ``__del__``, which h5py runs while the batch is written; raised there, Ctrl-C would be lost and the
    interrupted batch would run on to the end. So while writing the handler only records it."""

    def __init__(self):
        import signal

        self.seen, self.defer, self.previous = False, False, None
        try:
            self.previous = signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread: no handler of ours
            pass

    def _handle(self, signum, frame):
        self.seen = True
        if not self.defer:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def deferred(self):
        self.defer = True
        try:
            yield
        finally:
            self.defer = False
        self.check()

    def interruptible(self, iterator):
        """Yield the items of `iterator`; Ctrl-C is raised at once while the next one is computed or awaited."""
        while True:
            defer, self.defer = self.defer, False
            try:
                self.check()
                item = next(iterator)
            except StopIteration:
                return
            finally:
                self.defer = defer
            yield item

    def check(self):
        if self.seen:
            raise KeyboardInterrupt

    def restore(self):
        if self.previous is not None:
            import signal

            signal.signal(signal.SIGINT, self.previous)
            self.previous = None


def _run_batch(args):
    start = time.perf_counter()
    for option in ("m1", "m2", "chi1", "chi2", "f_ref"):
        if getattr(args, option) is not None:
            raise UsageError(f"--{option.replace('_', '-')} cannot be combined with --batch; give it as the column "
                             f"{option} of the batch file")
    if args.jobs is not None and args.scheduler is not None:
        raise UsageError("--jobs applies to local runs; a Dask cluster (--scheduler) sets its own parallelism")
    jobs = (os.cpu_count() or 1) if args.jobs is None else args.jobs
    if jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {jobs}")
    storage = dict(compression=args.compression, checksum=args.checksum)
    cli_defaults = {key: getattr(args, key) for key in DEFAULTS}
    if cli_defaults["sampling"] is not None:
        cli_defaults["sampling"] = parse_sampling(cli_defaults["sampling"])
    rows = read_batch(args.batch, cli_defaults)
    path, default_folder = _output_path(args, Path(args.batch).stem)
    tasks = [(i, row.params) for i, row in enumerate(rows) if row.error is None]
    parts = None
    if args.scheduler is not None:
        where = f"Dask scheduler {args.scheduler}"
        results = results_dask(tasks, args.scheduler)
    elif jobs == 1 or len(tasks) <= 1:
        where = "this process"
        results = results_serial(tasks)
    else:
        where = f"{min(jobs, len(tasks))} worker processes"
        if tasks and default_folder:
            Path(DEFAULT_FOLDER).mkdir(exist_ok=True)
        parts = tempfile.mkdtemp(prefix=f"{path.name}.", suffix=".pnrotor-tmp", dir=path.parent)
        results = results_pool(tasks, jobs, parts=parts, storage=storage)
    if not args.quiet:
        bad = len(rows) - len(tasks)
        print(f"pnrotor evolve --batch {args.batch}: {len(rows)} binaries"
              + (f" ({bad} with bad values)" if bad else "") + f", on {where}")

    from pnrotor import hdf5

    lines = {}
    evolve_seconds = 0.0
    interrupted = _InterruptFlag()
    try:
        if tasks and default_folder:
            Path(DEFAULT_FOLDER).mkdir(exist_ok=True)
        # without a run to write no file (and no folder) is needed: an empty list stands in for the batch
        batch = contextlib.nullcontext([])
        if tasks:
            batch = hdf5.batch(path, overwrite=args.overwrite, **storage)
        with interrupted.deferred(), batch as writer, \
                _progress_bar(len(tasks), enabled=not args.quiet and sys.stderr.isatty()) as bar:
            for index, ok, result in interrupted.interruptible(results):
                row = rows[index]
                if ok:
                    if isinstance(result, Stored):
                        writer.copy_from(result.path, result.group, row.name)
                        result = result.brief
                    else:
                        writer.add(row.name, result)
                        result = brief(result)
                    evolve_seconds += result["wall_time_s"]
                    lines[index] = _batch_line(row, result)
                else:
                    row.error = result
                bar.update()
    finally:
        results.close()  # stops the workers early after an error or Ctrl-C
        if parts is not None:
            shutil.rmtree(parts, ignore_errors=True)
        interrupted.restore()
    failed = [row for row in rows if row.error is not None]
    if not args.quiet:
        print("\n".join(lines[i] for i in sorted(lines)))
    for row in failed:
        print(f"  FAILED {row!r}: {row.error}")
    wall = time.perf_counter() - start
    count = len(writer)
    written = f"wrote {count} run{'s' * (count != 1)} to {path}" if count else "wrote no file"
    print(f"{written}; {len(failed)} failed; {wall:.3g} s in all ({evolve_seconds:.3g} s evolving, "
          f"{count / wall:.3g} runs/s)")
    return 1 if failed else 0


def _progress_bar(total, enabled):
    """A tqdm bar on stderr, without tqdm's monitor thread (a thread would make later worker pools avoid
    'fork'), or a stand-in that does nothing."""
    if not enabled:
        return contextlib.nullcontext(type("NoBar", (), {"update": lambda self, n=1: None})())
    from tqdm import tqdm

    class Bar(tqdm):
        monitor_interval = 0

    return Bar(total=total, unit="run", file=sys.stderr, desc="evolve")


def _batch_line(row, brief):
    t0, t1, v0, v1, orbits, exact = brief["span"]
    return (f"  {row.label}  {row.name}: {(t1 - t0) * brief['M_seconds']:.6g} s, {_orbits_text(orbits, exact)}, "
            f"v {v0:.4g} -> {v1:.4g}, {brief['termination']}, {brief['samples']} samples, {brief['nfev']} evaluations")
