"""`pnrotor evolve`: evolve one precessing binary (or a batch of them) in PN theory and write HDF5.

One run: ``pnrotor evolve --m1 30 --m2 10 --chi1 0.6,0,0.2 --chi2 0,-0.4,0.1 --f-ref 20`` calls
`pnrotor.evolve` with these arguments, prints a one-screen summary (masses, spins, approximant,
duration, orbits, initial and final v and GW frequency, the termination of each half with its message,
the integrator's work, wall time) and writes the `Evolution` with `pnrotor.hdf5.write` to ``-o FILE``,
by default ``waveforms/NAME.h5`` in the current folder, NAME built from the parameters
(`default_name`; ``waveforms/`` is created if missing, an explicit ``-o`` folder is not). An existing
file is refused before anything is computed unless ``--overwrite``.  ``--chi1``/``--chi2`` default to zero.

Batch: ``pnrotor evolve --batch params.csv`` (or ``.toml``) runs one binary per CSV row or TOML
``[[binary]]`` table, with columns/keys named like the options (`COLUMNS`; vectors as ``"x,y,z"``
strings in CSV, arrays in TOML; options given on the command line are the defaults of empty cells).
The file's structure (columns, names) is checked before anything runs. Runs go to ``--jobs`` local
worker processes (default: every core; ``--jobs 1`` runs in this process) or, with ``--scheduler
ADDRESS``, to a Dask cluster (the ``pnrotor[dask]`` extra). This process alone writes the batch file
(one group per run, named by the ``name`` column or `default_name`) at ``-o FILE`` (default
``waveforms/BATCH-STEM.h5``) when the batch is complete; finished runs are kept in ``FILE.parts`` as
they finish, so an interrupted batch is completed with ``--resume``: all of that is `pnrotor.batch`,
which this module calls.
A row that fails (bad value, evolve's ``ValueError``) is listed with its row number and message and
the others are still written; exit status 1 then, 2 when the batch file itself is unusable.

Population: ``pnrotor evolve --batch params.csv --population`` computes only each row's state at its target (an
empty sampling cell means final) with `pnrotor.evolve_many`, chunk by chunk of the table (CSV, TOML, Parquet or
HDF5, never read whole), in this process on pnrotor's threads, on ``--jobs`` worker processes or on a Dask cluster
(``--scheduler``), and writes them as one table of columns, a `PopulationTable` (`pnrotor.batch.population`, which
this module calls): the state at f_max, at f_min (integrated backward) or at the end of the inspiral.  Finished
chunks are kept in ``FILE.parts`` as they finish, and ``--resume`` completes an interrupted population.  The modes
options are usage errors with it; -o, --overwrite, the storage options, -q and the exit status are as for batches.

The PN code (numba) is imported only when a run starts, so that the CLI starts quickly.
"""

import dataclasses
import math
import sys
import time
from pathlib import Path

from pnrotor import approximants
from pnrotor.batch.table import COLUMNS, DEFAULTS, REQUIRED, default_name, parse_sampling, parse_vector
from pnrotor.cli import UsageError
from pnrotor.options import OPTION_DEFAULTS, MAX_ORDER, MAX_SO_ORDER, MAX_SS_ORDER, PRECESSION

DEFAULT_FOLDER = "waveforms"
ELL_MAX, AMPLITUDE_ORDER = 8, 3.5
"""--ell-max and --amplitude-order when not given: copies of `pnrotor.modes`' defaults, so that parsing the command
line does not import numba (tests/test_cli_evolve.py checks that they agree)."""
SPINS = ("chi1", "chi2")
"""The options of `REQUIRED` that a single run may leave out: zero spins."""

NOT_WITH_POPULATION = ("modes", "ell_max", "amplitude_order", "distance", "polarizations", "inclination", "phi_ref")
"""Options of the other batch modes, refused with --population."""


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
    binary.add_argument("--chi1", metavar="X,Y,Z", help="dimensionless spin of body 1 at f_ref, |chi1| <= 1 "
                        "(default 0,0,0)")
    binary.add_argument("--chi2", metavar="X,Y,Z", help="dimensionless spin of body 2 at f_ref, |chi2| <= 1 "
                        "(default 0,0,0)")
    binary.add_argument("--f-ref", type=float, metavar="HZ",
                        help="GW frequency (twice the orbital) at which the spins are given; t = 0 there")
    model = parser.add_argument_group("model and output (with --batch: defaults for empty cells)")
    model.add_argument("--approximant", help=f"{approximants.names()} (default {DEFAULTS['approximant']}; also "
                       "TaylorT4, SpinTaylorT4, ...)")
    model.add_argument("--pn-order", type=float, metavar="ORDER",
                       help=f"PN order of the nonspinning terms, 0 ... {MAX_ORDER:g} "
                       f"(default {OPTION_DEFAULTS['pn_order']:g})")
    model.add_argument("--spin-orbit-order", type=float, metavar="ORDER",
                       help=f"PN order of the spin-orbit terms, -1 ... {MAX_SO_ORDER:g} (default min(pn-order, "
                       f"{MAX_SO_ORDER:g}); -1: none)")
    model.add_argument("--spin-spin-order", type=float, metavar="ORDER",
                       help=f"PN order of the spin-spin terms, -1 ... {MAX_SS_ORDER:g} (default min(pn-order, "
                       f"{MAX_SS_ORDER:g}); -1: none)")
    model.add_argument("--precession", choices=PRECESSION,
                       help=f"spin precession model (default: {OPTION_DEFAULTS['precession']})")
    model.add_argument("--f-min", type=float, metavar="HZ",
                       help="also integrate backward from f_ref down to this GW frequency")
    model.add_argument("--f-max", type=float, metavar="HZ",
                       help="stop at this GW frequency (default: at the end of the inspiral, which is named)")
    model.add_argument("--sampling", metavar="S",
                       help="steps (every integrator step, default), final (only the final state), a time step in "
                       "seconds (e.g. 1/4096 or 0.000244) or per_orbit:N (N points per orbit)")
    model.add_argument("--atol", type=float, help=f"absolute tolerance of the integrator (default "
                       f"{OPTION_DEFAULTS['atol']:g}; rtol {OPTION_DEFAULTS['rtol']:g})")
    model.add_argument("--lambda1", type=float, metavar="LAMBDA",
                       help="dimensionless tidal deformability of body 1 (as LALSuite's lambda1; default 0)")
    model.add_argument("--lambda2", type=float, metavar="LAMBDA",
                       help="dimensionless tidal deformability of body 2 (default 0)")
    model.add_argument("--tidal-order", type=float, metavar="ORDER",
                       help="PN order of the tidal terms: 0 (none), 5 or 6 (default 6)")
    model.add_argument("--horizon-absorption", action="store_true", default=None,
                       help="follow the energy and angular momentum the black holes' horizons absorb (tidal heating, "
                       "Alvi 2001, averaged over the orbit): in the energy balance, the spins and the masses")
    output = parser.add_argument_group("output")
    output.add_argument("-o", "--output", metavar="FILE.h5",
                        help="output file (default: waveforms/NAME.h5, NAME from the parameters, or waveforms/STEM.h5 "
                        "for --batch STEM.csv); its folder must exist")
    output.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    output.add_argument("--compression", choices=("gzip", "lzf"), help="compress the datasets (default: none)")
    output.add_argument("--no-checksum", dest="checksum", action="store_false", default=True,
                        help="no Fletcher-32 checksums, for scratch files (faster writes; damaged bytes then read "
                        "back as wrong numbers); by default each chunk has one, so damage is an error on reading")
    output.add_argument("--checksum", action="store_true", default=True, help="the default; kept for old scripts")
    waves = parser.add_argument_group("waveform modes")
    waves.add_argument("--modes", action="store_true",
                       help="also compute the modes h_lm (pnrotor.modes) and write the file with two groups, "
                       "run and modes (with --batch: NAME and NAME.modes per row); for a waveform sample finely "
                       "(--sampling 1/4096 or per_orbit:16): the default steps are far apart")
    waves.add_argument("--ell-max", type=int, metavar="L", help=f"modes l = 2 ... L, L <= 8 (default {ELL_MAX})")
    waves.add_argument("--amplitude-order", type=float, metavar="A",
                       help=f"PN amplitude order 0, 0.5, ..., 4 (default {AMPLITUDE_ORDER})")
    waves.add_argument("--distance", type=float, metavar="MPC",
                       help="store the modes as strain at this distance in Mpc (default: r h / M); the distance of "
                       "--polarizations")
    waves.add_argument("--polarizations", action="store_true",
                       help="also compute h+, hx (pnrotor.stream(...).polarizations) seen at --inclination and "
                       "--phi-ref as strain at --distance, from the modes l <= --ell-max, and write them as the group "
                       "polarizations; needs a time step --sampling DT (one run, not --batch)")
    waves.add_argument("--inclination", type=float, metavar="RAD",
                       help="inclination of the line of sight of --polarizations, in radians")
    waves.add_argument("--phi-ref", type=float, metavar="RAD",
                       help="reference phase of --polarizations in radians (default 0): the line of sight is "
                       "(inclination, pi/2 - phi_ref) in the frame of the run, as LALSuite's")
    output.add_argument("-q", "--quiet", action="store_true",
                        help="print only the output file, failures and the batch's last line; no progress bar")
    batch = parser.add_argument_group("batch")
    batch.add_argument("--batch", metavar="FILE", help=f"CSV or TOML file of binaries (with --population also Parquet or "
                       f"HDF5); columns {', '.join(COLUMNS)}")
    batch.add_argument("--jobs", type=int, metavar="N",
                       help="local worker processes (default: os.cpu_count(), with --population 1; 1 runs in this "
                       "process)")
    batch.add_argument("--resume", action="store_true",
                       help="complete an interrupted batch from the finished runs (chunks) kept in OUTPUT.parts")
    batch.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the batch on this Dask scheduler (e.g. tcp://host:8786); needs pnrotor[dask]")
    batch.add_argument("--population", action="store_true",
                       help="final states only, for population synthesis: the rows computed by pnrotor.evolve_many in "
                       "chunks (in this process on pnrotor's threads, on --jobs worker processes or a Dask --scheduler; "
                       "kept in OUTPUT.parts as they finish, so --resume completes an interrupted run) and written as "
                       "one table, a column per quantity (docs/hdf5-schema.md); each row's state at f_max, at f_min "
                       "(integrated backward) or at the end of the inspiral, NaN where the row did not reach it; "
                       "sampling must be final (an empty cell means final); not with --modes")
    parser.set_defaults(func=run)


def _warn_if_cold(here=True, population=False, modes=False, streamed=False):
    """One line on stderr before numba compiles pnrotor's kernels for the first time, not a silent wait; if
    this process runs the evolutions (``here``), the biggest kernel, the DOP853 core, is compiled in a second
    process meanwhile (`pnrotor.numba_cache.compile_aside`; worker processes compile their own), and so are the
    kernels of the ``modes`` it will write, in a third; this process first compiles two of the core's callees, which
    the core's process then loads (`pnrotor.ode.dop853.compile_core_parts`).  A ``population`` run also compiles
    `evolve_many`'s loop around the core (which loads the core compiled aside): the line is said when either is
    missing."""
    from pnrotor import numba_cache

    core = numba_cache.is_cold()
    kernel = "waves" if streamed else "modes"   # a uniform run's waves are computed as they are written
    waves = modes and numba_cache.is_cold("stream._waves" if streamed else "amplitudes._sum", "waveform")
    if core or waves or population and numba_cache.is_cold("many._integrate_all", "pn"):
        # on a 2-core VM in its fast and slow phases (benchmarks/bench_cold_start.py)
        wait = "~35-45" if population else "~20-35" if waves else "~10-25"
        print(f"pnrotor: compiling its numba kernels for this machine, once ({wait} s idle, up to ~3x that on a busy "
              "machine); later runs load them in a few seconds", file=sys.stderr, flush=True)
        if here and core:
            numba_cache.compile_aside("core")
        if here and waves:
            numba_cache.compile_aside(kernel)
        if here and core:
            from pnrotor.ode.dop853 import compile_core_parts

            compile_core_parts()


def run(args):
    for option in ("resume", "population"):
        if getattr(args, option) and args.batch is None:
            raise UsageError(f"--{option} applies to --batch runs only")
    for option in ("ell_max", "amplitude_order", "distance"):
        if getattr(args, option) is not None and not (args.modes or args.polarizations or args.population):
            raise UsageError(f"--{option.replace('_', '-')} applies to --modes and --polarizations runs only")
    for option in ("inclination", "phi_ref"):
        if getattr(args, option) is not None and not (args.polarizations or args.population):
            raise UsageError(f"--{option.replace('_', '-')} applies to --polarizations runs only")
    if args.polarizations and args.batch is not None and not args.population:
        raise UsageError("--polarizations applies to one run, not to --batch")
    if args.batch is not None:
        return _run_batch(args)
    for option in ("jobs", "scheduler"):
        if getattr(args, option) is not None:
            raise UsageError(f"--{option} applies to --batch runs only")
    return _run_one(args)


def _output_path(args, stem):
    """The output file, checked before anything is computed: (path, whether its folder is the default)."""
    if args.output is not None:
        from pnrotor import io

        path = Path(args.output)
        if path.is_dir():
            raise IsADirectoryError(f"{path} is a folder; give a file name such as {path / (stem + '.h5')}")
        io.format_of(path)
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
    from pnrotor.batch import backends

    start = time.perf_counter()
    missing = [f"--{key.replace('_', '-')}" for key in REQUIRED if getattr(args, key) is None and key not in SPINS]
    if missing:
        raise UsageError(f"missing {', '.join(missing)} (or give --batch FILE)")
    params = {key: getattr(args, key) for key in REQUIRED}
    for key in SPINS:   # a nonspinning body by default
        params[key] = (0.0, 0.0, 0.0) if params[key] is None else parse_vector(params[key], f"--{key}")
    for key, default in DEFAULTS.items():
        value = getattr(args, key)
        params[key] = default if value is None else value
    params["sampling"] = parse_sampling(params["sampling"])
    uniform = isinstance(params["sampling"], float)
    path, default_folder = _output_path(args, default_name(params))
    if args.modes or args.polarizations:
        from pnrotor.results.waves import angle
        from pnrotor.waveform import modes

        ell_max, order2, distance = modes.check_arguments(*_modes_options(args))
    if args.polarizations:
        if not uniform:
            raise UsageError("--polarizations needs a time step --sampling DT (e.g. 1/4096): h+, hx on a uniform grid")
        if args.inclination is None or distance is None:
            raise UsageError("--polarizations needs --inclination (radians) and --distance (Mpc)")
        line_of_sight = dict(inclination=angle(args.inclination, "--inclination"),
                             phi_ref=angle(args.phi_ref or 0.0, "--phi-ref"))

    from pnrotor.pn.evolve import check_inputs

    check_inputs(**params)   # an input error says so at once, before the cold cache's line and compiling
    _warn_if_cold(modes=args.modes or args.polarizations, streamed=uniform)
    if uniform:   # computed a block at a time as it is written: the memory of a block, not of the run
        from pnrotor.waveform.stream import stream

        source = stream(**{key: value for key, value in params.items() if key != "sampling"},
                        delta_t=params["sampling"])
        run, samples = source.evolution(), len(source)
        groups = [("run", run)]
        if args.modes:
            groups.append(("modes", source.modes(ell_max, order2 / 2, distance)))
        if args.polarizations:
            groups.append(("polarizations", source.polarizations(**line_of_sight, distance=distance, ell_max=ell_max,
                                                                 amplitude_order=order2 / 2)))
    else:
        run = backends.evolve_row(params)
        samples = len(run)
        groups = [("run", run)]
        if args.modes:
            import warnings

            with warnings.catch_warnings(record=True) as caught:   # each on one line, as the command's other messages
                warnings.simplefilter("always")
                groups.append(("modes", modes.modes(run, ell_max, order2 / 2, distance)))
            for warning in caught:
                print(f"pnrotor evolve: warning: {warning.message}", file=sys.stderr)
    if default_folder:
        path.parent.mkdir(exist_ok=True)
    from pnrotor import hdf5

    storage = dict(compression=args.compression, checksum=args.checksum)
    if len(groups) > 1:
        with hdf5.batch(path, overwrite=args.overwrite, **storage) as batch:
            for name, result in groups:
                batch.add(name, result)
    else:
        from pnrotor import io

        io.write(path, run, overwrite=args.overwrite, **storage)
    if not args.quiet:
        print("\n".join(summary(_ends(run) if uniform else run, time.perf_counter() - start, samples)))
        if args.modes:
            print(f"  modes          l <= {ell_max}, amplitude order {order2 / 2:g}, "
                  + (f"strain at {distance:g} Mpc" if distance is not None else "r h / M"))
        if args.polarizations:
            print(f"  polarizations  h+, hx at inclination {line_of_sight['inclination']:g} rad, phi_ref "
                  f"{line_of_sight['phi_ref']:g} rad, strain at {distance:g} Mpc, from the modes l <= {ell_max} "
                  f"(amplitude order {order2 / 2:g})")
        if len(groups) > 1:
            print(f"  groups         {', '.join(name for name, _ in groups)}")
    print(f"wrote {path}")
    return 0


def _ends(streamed):
    """The first and the last sample of a streamed evolution, as an Evolution of two rows (of one if it has one):
    what `summary` needs of it (`Evolution.span` reads only those and whether there are two)."""
    import numpy as np

    n = len(streamed)
    if n == 1:
        return streamed.block(0, 1)
    first, last = streamed.block(0, 1), streamed.block(n - 1, n)
    rows = {name: np.concatenate((np.asarray(getattr(first, name)), np.asarray(getattr(last, name))))
            for name in ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat")}
    return dataclasses.replace(first, **rows)


def _modes_options(args):
    """(ell_max, amplitude_order, distance) of the command line, the defaults filled in."""
    return (ELL_MAX if args.ell_max is None else args.ell_max,
            AMPLITUDE_ORDER if args.amplitude_order is None else args.amplitude_order, args.distance)


def _orbits_text(orbits, exact):
    if orbits is None:
        return "orbits unknown (one sample, not the start)"
    return f"{orbits:.6g} orbits" if exact else f"~{orbits:.6g} orbits (first to last sample)"


def summary(run, wall=None, samples=None):
    """The lines `pnrotor evolve` prints about one run (of ``samples`` samples, if given: a run of which only the ends
    are given)."""
    i, s = run.inputs, run.stats
    M = i["M_seconds"]
    t0, t1, v0, v1, orbits, exact = run.span()
    f0, f1 = (v**3 / (math.pi * M) for v in (v0, v1))
    vec = lambda a: "(" + ", ".join(f"{x:.6g}" for x in a) + ")"  # noqa: E731
    lines = [
        f"pnrotor evolve: {i['m1_Msun']:g} + {i['m2_Msun']:g} Msun, chi1 {vec(i['chi1'])}, chi2 {vec(i['chi2'])}, "
        f"f_ref {i['f_ref_Hz']:g} Hz ({i['spin_content']})",
        f"  model          {i['approximant']}, PN order {i['pn_order']:g} (spin-orbit {i['spin_orbit_order']:g}, "
        f"spin-spin {i['spin_spin_order']:g}), precession {i['precession']}, atol {i['atol']:g}"
        + _tides_text(i) + (", horizon absorption" if i.get("horizon_absorption") else ""),
        f"  duration       {(t1 - t0) * M:.6g} s = {t1 - t0:.6g} M  (t from {t0:.6g} to {t1:.6g} M)",
        f"  ΔΦ/2π          {_orbits_text(orbits, exact)}",
        f"  v              {v0:.6g} -> {v1:.6g}",
        f"  GW frequency   {f0:.6g} Hz -> {f1:.6g} Hz",
        f"  forward        {run.termination}: {s['termination_message']}",
        f"  backward       {s['termination_backward']}: {s['termination_backward_message']}",
        f"  work           {s['nfev']} evaluations, {s['nsteps']} steps ({s['naccepted']} accepted, "
        f"{s['nrejected']} rejected)",
        *([f"  masses         m1 {s['m1_initial_Msun']:.9g} -> {s['m1_final_Msun']:.9g} Msun, m2 "
           f"{s['m2_initial_Msun']:.9g} -> {s['m2_final_Msun']:.9g} Msun (the horizons' absorption)"]
          if "m1_final_Msun" in s else []),
        f"  samples        {len(run) if samples is None else samples} ({_sampling_text(i)})",
        f"  wall time      {s['wall_time_s']:.3g} s evolving"
        + (f", {wall:.3g} s in all (imports and writing included)" if wall is not None else ""),
    ]
    return lines


def _tides_text(inputs):
    """', tides Λ₁ …, Λ₂ … to 6PN' for a run with tidal deformabilities (none in files written before them)."""
    if not (inputs.get("lambda1") or inputs.get("lambda2")) or not inputs.get("tidal_order"):
        return ""
    return f", tides lambda1 {inputs['lambda1']:g}, lambda2 {inputs['lambda2']:g} to {inputs['tidal_order']:g}PN"


def _sampling_text(inputs):
    mode, value = inputs["sampling"], inputs["sampling_value"]
    return {"dt": f"every {value:.6g} s", "per_orbit": f"{value:g} per orbit"}.get(mode, mode)


# --------------------------------------------------------------------------------------------------
# batch: pnrotor.batch does the work
# --------------------------------------------------------------------------------------------------


def _table_defaults(args):
    """The model options of the command line, the defaults of a batch table's empty cells (None: not given)."""
    defaults = {key: getattr(args, key) for key in DEFAULTS}
    if defaults["sampling"] is not None:
        defaults["sampling"] = parse_sampling(defaults["sampling"])
    return defaults


def _run_batch(args):
    start = time.perf_counter()
    for option in ("m1", "m2", "chi1", "chi2", "f_ref"):
        if getattr(args, option) is not None:
            raise UsageError(f"--{option.replace('_', '-')} cannot be combined with --batch; give it as the column "
                             f"{option} of the batch file")
    if args.jobs is not None and args.scheduler is not None:
        raise UsageError("--jobs applies to local runs; a Dask cluster (--scheduler) sets its own parallelism")
    if args.jobs is not None and args.jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {args.jobs}")
    if args.population:
        return _run_population(args, start)
    from pnrotor import batch

    rows = batch.read_batch(args.batch, _table_defaults(args))
    path, default_folder = _output_path(args, Path(args.batch).stem)
    plan = batch.plan(rows, path, jobs=args.jobs, scheduler=args.scheduler, overwrite=args.overwrite,
                      compression=args.compression, checksum=args.checksum, create_folder=default_folder,
                      resume=args.resume,
                      modes=_modes_options(args) if args.modes else None)
    if not args.quiet:
        bad = len(plan.rows) - len(plan.tasks)
        print(f"pnrotor evolve --batch {args.batch}: {_binaries(len(plan.rows))}"
              + (f" ({bad} with bad values)" if bad else "") + f", on {plan.where}"
              + ("; with their modes (groups NAME and NAME.modes)" if args.modes else ""))
    _warn_if_cold(here=plan.where == "this process", modes=args.modes)
    outcome = plan.run(progress=not args.quiet and sys.stderr.isatty())
    if not args.quiet:
        print("\n".join(_batch_line(plan.rows[i], outcome.briefs[i]) for i in sorted(outcome.briefs)))
    return _totals(outcome, path, start, "run", "runs")


def _binaries(n):
    return f"{n} binar{'y' if n == 1 else 'ies'}"


def _run_population(args, start):
    given = [f"--{option.replace('_', '-')}" for option in NOT_WITH_POPULATION
             if getattr(args, option) is not None and getattr(args, option) is not False]
    if given:
        raise UsageError(f"{', '.join(given)} cannot be combined with --population (final states only: no histories, "
                         "so no modes)")
    defaults = _table_defaults(args)
    if defaults["sampling"] not in (None, "final"):
        raise UsageError(f"--sampling must be final with --population (final states only), got {args.sampling!r}")
    from pnrotor.batch import population

    path, default_folder = _output_path(args, Path(args.batch).stem)
    plan = population.plan(args.batch, path, jobs=args.jobs, scheduler=args.scheduler, resume=args.resume,
                           overwrite=args.overwrite, compression=args.compression, checksum=args.checksum,
                           defaults=defaults, create_folder=default_folder)
    if not args.quiet:
        chunks = len(plan.tasks)
        print(f"pnrotor evolve --batch {args.batch} --population: {_binaries(plan.table.rows)}, final states by "
              f"evolve_many in {chunks} chunk{'s' * (chunks != 1)} of up to {plan.chunk} rows, on {plan.where}")
    _warn_if_cold(here=plan.where == "this process", population=True)
    outcome = plan.run(progress=not args.quiet and sys.stderr.isatty())
    return _totals(outcome, path, start, "final state", "rows")


def _totals(outcome, path, start, item, per):
    """Print a batch's failures and its last line (``item``: what the file holds per row, ``per``: the rate's
    unit) → the exit status, 1 if a row failed."""
    for row in outcome.failed:
        print(f"  FAILED {row!r}: {row.error}")
    wall = time.perf_counter() - start
    count = outcome.written
    written = f"wrote {count} {item}{'s' * (count != 1)} to {path}" if count else "wrote no file"
    print(f"{written}; {len(outcome.failed)} failed; {wall:.3g} s in all ({outcome.evolve_seconds:.3g} s evolving, "
          f"{count / wall:.3g} {per}/s)")
    return 1 if outcome.failed else 0


def _batch_line(row, brief):
    t0, t1, v0, v1, orbits, exact = brief["span"]
    return (f"  {row.label}  {row.name}: {(t1 - t0) * brief['M_seconds']:.6g} s, {_orbits_text(orbits, exact)}, "
            f"v {v0:.4g} -> {v1:.4g}, {brief['termination']}, {brief['samples']} samples, {brief['nfev']} evaluations")
