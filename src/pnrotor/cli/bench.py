"""`pnrotor bench`: the numerical study of Boyle 2016 (arXiv:1604.08139, Sec. V-B, Figs. 2 and 3) in
one run, from :mod:`pnrotor.study`.

Every formulation × {DOP853, Bulirsch–Stoer} × absolute tolerance 1e-4 … 1e-14 on the precessing,
nutating binary over [0, T], T = 10⁶ (1000 orbits), with scipy's ``solve_ivp`` DOP853 on the rotor
equation as the baseline (:func:`pnrotor.study.sweep`).  The time to import pnrotor's integrator is
printed apart (its kernels compile, or load from numba's cache, on first use: each configuration's first call,
``compile_s``, is kept out of its timings).  Writes ``bench.csv``
to DIR and, with matplotlib (the plot extra), figures like the paper's: ``error_vs_time.png`` (δ(t)
per tolerance for the rotor with DOP853, Fig. 2) and ``max_error.png`` (max δ against wall time,
evaluations and steps, Fig. 3). Then prints the key rows and the paper's findings recomputed from
these numbers (:func:`pnrotor.study.findings`).

``pnrotor bench --pn`` runs the work–precision study of the coupled PN system instead
(:mod:`pnrotor.pn_study`: pnrotor at atol 1e-6 … 1e-14 against LALSuite's SpinTaylorT4 and scipy on four
binaries), writing ``pn_work_precision.json`` and, with matplotlib, ``pn_work_precision.png`` to DIR.
"""

import csv
import math
import time
from pathlib import Path

from pnrotor.cli import DAMPING, UsageError, add_damping_option
from pnrotor.files import replaced_on_success


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "bench",
        help="the paper's study: every formulation × integrator × tolerance, with scipy as baseline",
        description="Integrate the precessing/nutating binary of Boyle 2016 with every formulation, DOP853 and "
        "Bulirsch-Stoer, atol 1e-4 ... 1e-14, plus scipy's solve_ivp DOP853 on the rotor equation; write a CSV "
        "and (with matplotlib) figures like the paper's, and print the findings.",
    )
    parser.add_argument("--pn", action="store_true",
                        help="the work-precision study of the coupled PN system instead: pnrotor at atol 1e-6 ... "
                        "1e-14 against LALSuite's SpinTaylorT4 (with the lal extra) and scipy on a BBH, a "
                        "precessing BBH, an NSBH and a BNS (--quick: ~1 min)")
    parser.add_argument("--quick", action="store_true",
                        help="T = 1e5 and atol 1e-4, 1e-8, 1e-12, one repetition (under a minute); with --pn "
                        "atol 1e-6, 1e-8, ..., 1e-14 and 3 rounds")
    parser.add_argument("-o", "--output", metavar="DIR", default="pnrotor-bench",
                        help="folder for bench.csv and the figures, created if needed; files in it are "
                        "replaced (default: pnrotor-bench)")
    parser.add_argument("--t-end", type=float, metavar="T", help="integrate over [0, T] (default: 1e6, quick 1e5)")
    parser.add_argument("--atols", type=float, nargs="+", metavar="ATOL", help="absolute tolerances to sweep")
    parser.add_argument("--repeat", type=int, help="timed runs per configuration, best kept (default: 3, quick 1; "
                        "with --pn: interleaved rounds, median kept, default 7, quick 3)")
    add_damping_option(parser)
    parser.add_argument("--no-scipy", action="store_true", help="skip the scipy baseline")
    parser.set_defaults(func=run)


def run(args):
    if args.pn:
        return run_pn(args)
    from pnrotor import study

    config = study.QUICK if args.quick else study.FULL
    t_end = config["t_end"] if args.t_end is None else args.t_end
    atols = config["atols"] if args.atols is None else args.atols
    repeat = (1 if args.quick else 3) if args.repeat is None else args.repeat
    if not (math.isfinite(t_end) and t_end > 0):
        raise UsageError(f"--t-end must be a positive number, got {t_end!r}")
    if not all(math.isfinite(a) and a > 0 for a in atols):
        raise UsageError(f"--atols must be positive numbers, got {atols!r}")
    if repeat < 1:
        raise UsageError(f"--repeat must be at least 1, got {repeat}")
    outdir = _output_folder(args.output)

    start = time.perf_counter()
    import pnrotor.analytic  # noqa: F401  (kernels compile, or load from numba's cache, on first use)
    import pnrotor.integrate  # noqa: F401
    load_s = time.perf_counter() - start
    rows, curves = study.sweep(t_end, sorted(atols, reverse=True), repeat, tuple(args.damping or DAMPING), not args.no_scipy)
    path = outdir / "bench.csv"
    with replaced_on_success(path) as temporary, open(temporary, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=study.COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {path}")
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print("matplotlib is not installed (pip install 'pnrotor[plot]'): figures skipped")
    else:
        for figure in study.figures(outdir, rows, curves, t_end):
            print(f"wrote {figure}")
    print()
    print(f"pnrotor's integrator imported in {load_s:.2f} s, before and apart from every timing below (its kernels "
          "compile, or load from numba's cache, in each configuration's first call: compile_s in bench.csv)")
    print("\n".join(study.findings(rows, t_end)))
    return 0


def run_pn(args):
    """``--pn``: :func:`pnrotor.pn_study.main` with the options that apply to it."""
    if args.t_end is not None or args.atols is not None or args.damping is not None:
        raise UsageError("--t-end, --atols and --damping are for the paper's study, not --pn")
    if args.repeat is not None and args.repeat < 1:
        raise UsageError(f"--repeat must be at least 1, got {args.repeat}")
    outdir = _output_folder(args.output)
    from pnrotor import pn_study

    argv = ["--json", str(outdir / "pn_work_precision.json")]
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print("matplotlib is not installed (pip install 'pnrotor[plot]'): figure skipped")
    else:
        argv += ["--figure", str(outdir / "pn_work_precision.png")]
    argv += ["--quick"] * args.quick + ["--no-scipy"] * args.no_scipy
    if args.repeat is not None:
        argv += ["--rounds", str(args.repeat)]
    pn_study.main(argv)
    return 0


def _output_folder(path):
    """The folder ``path``, created if needed; a UsageError if it is a file."""
    outdir = Path(path)
    if outdir.exists() and not outdir.is_dir():
        raise UsageError(f"{outdir} exists and is not a folder")
    outdir.mkdir(parents=True, exist_ok=True)
    return outdir
