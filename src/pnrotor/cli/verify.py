"""`pnrotor verify`: integrate the angular velocity of the paper's precessing and nutating binary and
measure the frame error against its exact rotor (Boyle 2016, arXiv:1604.08139, Sec. V).

Runs `pnrotor.integrate_angular_velocity` on `pnrotor.analytic.PrecessingNutatingBinary` (the paper's
parameters) over [0, T], evaluates δ(t) of eq:error_norm at every step against the exact rotor
(eq:BinaryRotor), and prints the maximum δ with the integrator's work. The time to import pnrotor's
integrator and that of a first, short integration (which compiles the integrator and the right-hand side it
uses, or loads them from numba's cache) are printed apart from the timed run.
The integrator is imported only when the command runs, so that the CLI starts quickly.
With ``-o FILE.h5`` it writes the `FrameHistory`, whose ``inputs`` hold the binary's parameters
(`PrecessingNutatingBinary.describe`; `PrecessingNutatingBinary.from_inputs` rebuilds it), so that
``pnrotor plot FILE.h5`` draws δ(t).
Exit status 0 when the integration reached T with max δ ≤ ``--max-error``, 1 otherwise.
"""

import math
import time
from pathlib import Path

from pnrotor.cli import DAMPING, add_damping_option

DEFAULT_MAX_ERROR = 2e-10
"""Bound on max δ for the default run (rotor, DOP853, atol 1e-12, T = 10⁶)."""


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "verify",
        help="integrate the paper's precessing/nutating binary and check the frame error",
        description="Integrate the angular velocity of the precessing and nutating binary of Boyle 2016 "
        "(Sec. V-B) and compare with its exact rotor: prints max δ over [0, T] (eq:error_norm), wall time, "
        "evaluations and steps. Exit status 1 when max δ exceeds --max-error or the integration failed.",
    )
    parser.add_argument("--formulation", default="rotor",
                        help="rotor (default), generator, generator-noreset, vectors3, vectors2 or vectors-damped")
    parser.add_argument("--method", default="DOP853", help="DOP853 (default) or Bulirsch-Stoer (BS)")
    parser.add_argument("--atol", type=float, default=1e-12, help="absolute tolerance (default: 1e-12; rtol is 0)")
    parser.add_argument("--t-end", type=float, default=None, metavar="T",
                        help="end of the interval [0, T]; negative integrates backward (default: 1e6, 1000 orbits)")
    parser.add_argument("--max-error", type=float, default=DEFAULT_MAX_ERROR, metavar="E",
                        help=f"largest acceptable max δ (default: {DEFAULT_MAX_ERROR:g})")
    add_damping_option(parser)
    parser.add_argument("-o", "--output", metavar="FILE.h5",
                        help="write the FrameHistory, with the binary's parameters, to this HDF5 file "
                        "(pnrotor plot draws its δ(t))")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --output file")
    parser.set_defaults(func=run)


def run(args):
    if not (math.isfinite(args.max_error) and args.max_error >= 0):
        raise ValueError(f"--max-error must be a finite number ≥ 0, got {args.max_error!r}")
    start = time.perf_counter()
    from pnrotor.analytic import PrecessingNutatingBinary
    from pnrotor.formulations import get as get_formulation
    from pnrotor.integrate import integrate_angular_velocity, method_name

    binary = PrecessingNutatingBinary()
    t_end = binary.T if args.t_end is None else args.t_end
    if not math.isfinite(t_end) or t_end == 0:
        raise ValueError(f"--t-end must be finite and nonzero, got {t_end!r}")
    method = method_name(args.method)
    get_formulation(args.formulation)
    if args.output and not args.overwrite and Path(args.output).exists():
        raise FileExistsError(f"{args.output} exists; pass --overwrite to replace it")
    if args.output:
        from pnrotor import io

        io.format_of(args.output)
    if args.output and not Path(args.output).parent.is_dir():
        raise FileNotFoundError(f"folder {Path(args.output).parent} does not exist (-o {args.output}); create it first")
    R0 = binary.rotor(0.0)
    options = dict(formulation=args.formulation, method=method, atol=args.atol, damping=tuple(args.damping or DAMPING))
    imported = time.perf_counter()
    integrate_angular_velocity(binary, (0.0, math.copysign(1.0, t_end)), R0, **options)
    loaded = time.perf_counter()

    history = integrate_angular_velocity(binary, (0.0, t_end), R0, **options)
    delta = binary.frame_error(history.t, history.R)
    worst = int(delta.argmax())
    ok = history.status == 0 and delta[worst] <= args.max_error

    print(f"pnrotor verify: precessing/nutating binary (Boyle 2016, Sec. V-B) over t in [0, {t_end:g}]")
    print(f"  formulation      {history.formulation}, {history.method}, atol {history.atol:g}, rtol 0"
          + (f", damping λ {options['damping'][0]:g} μ {options['damping'][1]:g}" if args.formulation == "vectors-damped" else ""))
    print(f"  max δ            {delta[worst]:.3e} at t = {history.t[worst]:.10g}"
          f"   ({'≤' if delta[worst] <= args.max_error else '>'} {args.max_error:g})")
    print(f"  final δ          {delta[-1]:.3e} at t = {history.t[-1]:.10g}")
    print(f"  wall time        {history.wall_time:.4f} s integrating"
          f"  (apart: {imported - start:.2f} s importing, {loaded - imported:.3f} s first call, compiling or "
          "loading the compiled code)")
    print(f"  evaluations      {history.nfev}")
    print(f"  steps            {history.nsteps} ({history.naccepted} accepted, {history.nrejected} rejected)")
    if history.formulation == "generator":
        print(f"  generator resets {history.n_resets}")
    print(f"  status           {history.status}: {history.message}")
    if args.output:
        from pnrotor import io

        print(f"wrote {io.write(args.output, history, overwrite=args.overwrite)}")
    print("OK" if ok else "FAILED: " + ("integration did not reach T" if history.status else "max δ above the limit"))
    return 0 if ok else 1
