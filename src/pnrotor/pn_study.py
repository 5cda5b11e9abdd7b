r"""Work–precision of the coupled post-Newtonian system (``pnrotor bench --pn``): pnrotor's DOP853 at atol 1e-6 … 1e-14
(1e-15 and 5e-16 for the reference and its check), LALSuite's
SpinTaylorT4 and scipy's ``solve_ivp`` (DOP853, LSODA) on pnrotor's right-hand side (issue 14 §4).

Cases (``CASES``): an aligned-spin BBH (30 + 30 M☉), a precessing BBH (30 + 10 M☉, χ₁ = (0.6, 0, 0.2),
χ₂ = (0, −0.4, 0.1)), a precessing NSBH (10 + 1.4 M☉) from f_ref = 20 Hz and a BNS with small precessing
spins (1.4 + 1.4 M☉) from 40 Hz, each to the end of the T4 inspiral (fEnd = 0 / no f_max).  Every run uses
the same model — T4 with LALSuite's SpinTaylorT4 truncation (``pnrotor.pn.lalsuite_orders("T4")``: 3.5PN,
spin-orbit 3PN, spin-spin 3PN, precession phase shift on) — and the same output: uniform samples
t = kΔt, Δt = 1/4096 s, t = 0 at f_ref (pnrotor's dense output, LAL's grid from fStart, scipy's t_eval).
``--cases BNS-precessing-20Hz`` adds the same BNS from 20 Hz (2570 orbits).

Error against a converged reference: ``compensated_reference``, the same 12-stage 8th-order DOP853 formula
(``pnrotor.ode.tableau``) on pnrotor's right-hand side, on a fixed mesh = pnrotor's accepted steps at atol
1e-15 ∪ the output grid, every interval halved, with the state carried as y + lo (TwoSum compensated
summation) and the mesh times given, not accumulated.  Its own error is the difference to the same on the
unhalved mesh (≤ 1e-11 rad here).  Before pnrotor's DOP853 compensated its own state update, float64
round-off of y + h Σ bⱼkⱼ (~ulp(Φ) per step, and an early δv is a time shift the chirp turns into phase) set
a floor of ~1e-10–2e-9 rad on these long runs that no atol removed (pnrotor at 1e-15 and 5e-16 differed by
1.2e-9 rad); with it they differ by 2e-11–5e-11.

Both the reference and every run are compared on pnrotor's own grid (``Evolution.t`` of the atol-1e-15 run,
t = kΔt bit for bit).  Runs at different tolerances end at slightly different times (the terminal
event moves with the error), so every comparison is over the common span only: the first
min(N_run, N_ref) samples.  Per sample:

* frame error: the rotation angle of R_a R_b⁻¹ from its vector part, 2·atan2(|vec|, |scalar|) (= 2·asin|vec|
  for unit rotors; not 2·acos(scalar), which floors at ~4e-8 rad), R the orbital frame rotor
  (n̂ = R x̂ R⁻¹, ℓ̂ = R ẑ R⁻¹); it includes the orbital phase (a rotation about ℓ̂) and ℓ̂'s direction;
* phase error |ΔΦ|;

and the table gives the maxima over the common span.  LAL's frame is n̂ = cos Φ E1 + sin Φ (L̂N × E1),
ℓ̂ = L̂N (normalized, n̂ projected orthogonal to it), turned into a rotor by Shepperd's method
(``pnrotor.quaternion.from_matrix``).  scipy's states are turned into R as pnrotor's sampling does
(coprecessing state: R = R_p exp(Φẑ/2), normalized; aligned: R = R₀ exp(Φẑ/2)).

Work: wall time per run, the median (and the minimum, robust when other processes load the machine) over
``--rounds`` interleaved rounds (every round runs every case and
every configuration once, in a new random order, so load from other processes and the cost of the
previous run's memory traffic spread evenly).  Each timing includes the whole Python
call and freeing its own output:

* pnrotor: ``evolve(…, atol=…, sampling=Δt, **lalsuite_orders("T4"))`` (setup, integration, dense output,
  rotor reconstruction); the column "integr." is its integration alone (``stats['wall_time_integrate_s']``);
* LAL: ``pnrotor.interop.lal.spintaylor_series`` (``SimInspiralSpinTaylorPNEvolveOrbit``, SpinTaylorT4,
  its fixed internal accuracy), as in benchmarks/bench_pn.py;
* scipy: settings + ``build_system`` + ``solve_ivp(f, (0, t_end), y0, method, rtol=tol, atol=tol,
  t_eval=grid)`` + rotor reconstruction, f wrapping the numba ``rhs_precessing`` / ``rhs_aligned`` in a
  Python function that returns a new array; t_end is the reference's last grid sample (no events).

nfev: right-hand-side evaluations (pnrotor: both halves; scipy: ``nfev``; LAL does not report it).

Then (a) per case, the loosest pnrotor atol whose frame error is ≤ LAL's and the speed-up LAL/pnrotor there
(and at the default atol 1e-12); (b) the loosest atol whose frame error is ≤ 1e-9 rad in every case, with its
cost relative to 1e-12.

    pnrotor bench --pn [--quick] [-o DIR] [--repeat ROUNDS] [--no-scipy]     (DIR/pn_work_precision.json, .png)
    python benchmarks/bench_pn_precision.py [--rounds 7] [--quick] [--cases …] [--no-scipy] [--no-lal]
                                            [--json out.json] [--figure diagram.png]

LAL's rows need the ``lal`` extra (skipped with a note without it), the figure the ``plot`` extra.
"""

import argparse
import json
import random
import statistics
import sys
import time

import numpy as np

from pnrotor.files import replaced_on_success

DT = 1.0 / 4096
ATOL_REF, ATOL_CHECK = 1e-15, 5e-16
REFINE = 2
ATOLS = [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14]
ATOLS_QUICK = [1e-6, 1e-8, 1e-10, 1e-12, 1e-14]
SCIPY = [("DOP853", 1e-8), ("DOP853", 1e-10), ("DOP853", 1e-12), ("LSODA", 1e-8), ("LSODA", 1e-10),
         ("LSODA", 1e-12)]
SCIPY_QUICK = [("DOP853", 1e-10), ("LSODA", 1e-10)]
TARGET = 1e-9
DEFAULT_ATOL = 1e-12

CASES = {
    # name: (m1, m2 in M☉, χ₁, χ₂, f_ref in Hz, description)
    "BBH-aligned": (30.0, 30.0, [0, 0, 0.3], [0, 0, -0.2], 20.0, "30+30, chi1z=0.3, chi2z=-0.2"),
    "BBH-precessing": (30.0, 10.0, [0.6, 0, 0.2], [0, -0.4, 0.1], 20.0,
                       "30+10, chi1=(0.6,0,0.2), chi2=(0,-0.4,0.1)"),
    "NSBH-precessing": (10.0, 1.4, [0.5, 0.2, 0.4], [0.03, 0, 0.02], 20.0,
                        "10+1.4, chi1=(0.5,0.2,0.4), chi2=(0.03,0,0.02)"),
    "BNS-precessing": (1.4, 1.4, [0.02, 0.01, 0.03], [0, -0.03, 0.02], 40.0,
                       "1.4+1.4, chi1=(0.02,0.01,0.03), chi2=(0,-0.03,0.02)"),
    # not run by default (6.6e5 samples, 2570 orbits, ~40 s)
    "BNS-precessing-20Hz": (1.4, 1.4, [0.02, 0.01, 0.03], [0, -0.03, 0.02], 20.0,
                            "1.4+1.4, chi1=(0.02,0.01,0.03), chi2=(0,-0.03,0.02)"),
}
DEFAULT_CASES = ["BBH-aligned", "BBH-precessing", "NSBH-precessing", "BNS-precessing"]


# ---------------------------------------------------------------------------------------------------
# error measures
# ---------------------------------------------------------------------------------------------------

def frame_angle(Ra, Rb):
    """Rotation angle of Ra Rb⁻¹ for unit rotor arrays (N, 4): 2·atan2(|vec|, |scalar|), accurate down to
    ~1e-16 rad (the vector part is formed directly, b₀ a⃗ − a₀ b⃗ − a⃗ × b⃗, not from the scalar)."""
    a0, av = Ra[:, 0], Ra[:, 1:]
    b0, bv = Rb[:, 0], Rb[:, 1:]
    vec = b0[:, None] * av - a0[:, None] * bv - np.cross(av, bv)
    sca = a0 * b0 + np.einsum("ij,ij->i", av, bv)
    return 2.0 * np.arctan2(np.linalg.norm(vec, axis=1), np.abs(sca))


def errors(R, Phi, ref):
    """(max frame angle, max |ΔΦ|, samples compared) over the common span with the reference."""
    n = min(Phi.size, ref["Phi"].size)
    return (float(np.max(frame_angle(R[:n], ref["R"][:n]))), float(np.max(np.abs(Phi[:n] - ref["Phi"][:n]))), n)


# ---------------------------------------------------------------------------------------------------
# the three codes
# ---------------------------------------------------------------------------------------------------

def run_pnrotor(case, atol):
    from pnrotor.pn import evolve, lalsuite_orders
    m1, m2, c1, c2, f, _ = case
    return evolve(m1, m2, c1, c2, f, atol=atol, sampling=DT, **lalsuite_orders("T4"))


def lal_frame(case):
    """(R (N, 4), Φ (N,)) of LAL's SpinTaylorT4 orbit."""
    from pnrotor.interop.lal import spintaylor_orbit
    from pnrotor.quaternion import from_matrix
    m1, m2, c1, c2, f, _ = case
    L = spintaylor_orbit(m1, m2, c1, c2, f, "T4", DT)
    ell = L["ell"] / np.linalg.norm(L["ell"], axis=1)[:, None]
    e1, phi = L["e1"], L["Phi"]
    n = np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * np.cross(ell, e1)
    n -= np.einsum("ij,ij->i", n, ell)[:, None] * ell
    n /= np.linalg.norm(n, axis=1)[:, None]
    lam = np.cross(ell, n)
    return from_matrix(np.stack((n, lam, ell), axis=-1)), phi


def lal_call(case):
    from pnrotor.interop.lal import spintaylor_series
    m1, m2, c1, c2, f, _ = case
    return spintaylor_series(m1, m2, c1, c2, f, "T4", DT)[0].data.length


def case_settings(case, atol=ATOL_REF):
    """pnrotor's :class:`~pnrotor.pn.settings.Settings` of a case, as ``evolve`` builds them here."""
    from pnrotor.pn import lalsuite_orders
    from pnrotor.pn.evolve import OPTIONS
    from pnrotor.pn.settings import settings
    m1, m2, c1, c2, f, _ = case
    return settings(m1, m2, c1, c2, f, **{**OPTIONS, "sampling": DT}, atol=atol, **lalsuite_orders("T4"))


def rotor_from_states(Y, s):
    """(R (N, 4), Φ (N,)) from state rows Y as pnrotor's sampling builds them: aligned y = [v, Φ],
    R = R₀ exp(Φẑ/2); coprecessing y = [v, χ₁, χ₂, R_p, Φ], R = R_p exp(Φẑ/2), normalized."""
    from pnrotor.pn import layout
    if s.use_aligned:
        phi = Y[:, layout.YA_PHI]
        q = np.broadcast_to(s.R0, (phi.size, 4))
    else:
        phi = Y[:, layout.Y_PHI]
        q = Y[:, layout.Y_R:layout.Y_R + 4]
    c, sn = np.cos(0.5 * phi), np.sin(0.5 * phi)
    w, x, y, z = q.T
    R = np.column_stack((w * c - z * sn, x * c + y * sn, y * c - x * sn, z * c + w * sn))
    R /= np.linalg.norm(R, axis=1)[:, None]
    return R, np.array(phi)


_KERNEL = []


def _compensated_kernel():
    """numba: the 12-stage 8th-order DOP853 formula on a given mesh, with the state kept as an unevaluated
    sum y + lo (TwoSum after every step), so adding tiny increments to v and Φ loses nothing (the mesh
    times are given, not accumulated); rows of ``out`` at the mesh points flagged in ``is_out``."""
    if _KERNEL:
        return _KERNEL[0]
    from numba import njit

    from pnrotor.ode import tableau as tab
    ns = tab.N_STAGES
    A = np.ascontiguousarray(tab.A[:ns, :ns])
    B = np.ascontiguousarray(tab.B)
    C = np.ascontiguousarray(tab.C[:ns])

    @njit
    def kernel(rhs, mesh, is_out, y0, p, out):
        n = y0.size
        y = y0.copy()
        lo = np.zeros(n)
        K = np.empty((ns, n))
        ys = np.empty(n)
        j = 0
        if is_out[0]:
            out[0, :] = y
            j = 1
        for m in range(mesh.size - 1):
            t = mesh[m]
            h = mesh[m + 1] - t
            for st in range(ns):
                for i in range(n):
                    acc = 0.0
                    for r in range(st):
                        acc += A[st, r] * K[r, i]
                    ys[i] = y[i] + (lo[i] + h * acc)
                rhs(t + C[st] * h, ys, p, K[st])
            for i in range(n):
                acc = 0.0
                for st in range(ns):
                    acc += B[st] * K[st, i]
                inc = lo[i] + h * acc
                yn = y[i] + inc
                bb = yn - y[i]
                lo[i] = (y[i] - (yn - bb)) + (inc - bb)
                y[i] = yn
            if is_out[m + 1]:
                for i in range(n):
                    out[j, i] = y[i] + lo[i]
                j += 1
        return j

    _KERNEL.append(kernel)
    return kernel


def compensated_reference(case, grid, steps, refine):
    """(R, Φ) at the times ``grid`` (pnrotor's own output times) from the compensated 8th-order formula on
    the mesh grid ∪ steps (pnrotor's accepted steps at atol 1e-15, up to the last grid time), every
    interval split into ``refine`` equal parts."""
    from pnrotor.pn import rhs
    from pnrotor.pn.evolve import build_system
    s = case_settings(case)
    system = build_system(s)
    rhs = rhs.rhs_aligned if s.use_aligned else rhs.rhs_precessing
    base = np.union1d(grid, steps[steps < grid[-1]])
    if refine > 1:
        h = np.diff(base)
        sub = base[:-1, None] + h[:, None] * (np.arange(refine) / refine)[None, :]
        mesh = np.append(sub.ravel(), base[-1])
    else:
        mesh = base
    is_out = np.isin(mesh, grid)
    out = np.empty((grid.size, system.y0.size))
    j = _compensated_kernel()(rhs, mesh, is_out, system.y0, system.p, out)
    if j != grid.size:
        raise RuntimeError(f"compensated reference: {j} of {grid.size} output rows")
    return rotor_from_states(out, s)


def run_scipy(case, method, tol, n_samples):
    """scipy solve_ivp on pnrotor's right-hand side, sampled at the first ``n_samples`` grid times
    → (R, Φ, nfev)."""
    from scipy.integrate import solve_ivp

    from pnrotor.pn import rhs
    from pnrotor.pn.evolve import build_system
    s = case_settings(case, tol)
    system = build_system(s)
    rhs = rhs.rhs_aligned if s.use_aligned else rhs.rhs_precessing
    p = system.p

    def f_py(t, y):
        dydt = np.empty(y.size)
        rhs(t, y, p, dydt)
        return dydt

    grid = np.arange(n_samples, dtype=np.float64) * (DT / s.M_sec)   # pnrotor's grid, bit for bit
    r = solve_ivp(f_py, (0.0, grid[-1]), system.y0, method=method, rtol=tol, atol=tol, t_eval=grid)
    if not r.success or r.t.size != grid.size:
        raise RuntimeError(f"solve_ivp {method} failed: {r.message}")
    R, phi = rotor_from_states(r.y.T, s)
    return R, phi, int(r.nfev)


# ---------------------------------------------------------------------------------------------------
# driver
# ---------------------------------------------------------------------------------------------------

def timed(fn):
    """Wall time of fn() including freeing its result; returns (seconds, small summary of the result).  pnrotor's
    cache of a binary's spin-independent set-up is emptied first: every call pays it, as for a new binary."""
    from pnrotor.pn.system import cached_spin_independent_parts

    cached_spin_independent_parts.cache_clear()
    t = time.perf_counter()
    out = fn()
    summary = out.stats["wall_time_integrate_s"] if hasattr(out, "stats") else None
    del out
    return time.perf_counter() - t, summary


def measure_errors(name, case, atols, scipy_cfgs, use_lal):
    """Every configuration run once (also the warm-up): errors against the reference, nfev, samples.
    Returns (reference info, rows)."""
    from pnrotor.pn import evolve, lalsuite_orders
    m1, m2, c1, c2, f, _ = case
    pn_ref = run_pnrotor(case, ATOL_REF)
    grid = pn_ref.t
    steps = evolve(m1, m2, c1, c2, f, atol=ATOL_REF, sampling="steps", **lalsuite_orders("T4")).t
    t = time.perf_counter()
    R, phi = compensated_reference(case, grid, steps, REFINE)
    ref = dict(R=R, Phi=phi)
    t_ref = time.perf_counter() - t
    R1, phi1 = compensated_reference(case, grid, steps, 1)
    fe, pe, _ = errors(R1, phi1, ref)
    pn_chk = run_pnrotor(case, ATOL_CHECK)
    fe2, pe2, _ = errors(pn_chk.R, pn_chk.Phi, dict(R=pn_ref.R, Phi=pn_ref.Phi))
    info = dict(n=len(pn_ref), t_final_s=pn_ref.stats["t_final"] * pn_ref.inputs["M_seconds"],
                termination=pn_ref.termination, state=pn_ref.inputs["state"], mesh=int(np.union1d(grid, steps).size),
                ref_seconds=t_ref, ref_frame=fe, ref_phase=pe, pn_check_frame=fe2, pn_check_phase=pe2,
                pn_check_dt_end_s=(pn_chk.stats["t_final"] - pn_ref.stats["t_final"]) * pn_ref.inputs["M_seconds"])
    del pn_ref, pn_chk, R1, phi1
    rows = []
    for atol in atols + [ATOL_REF, ATOL_CHECK]:
        row = dict(method="pnrotor", tol=atol, key=("pnrotor", atol))
        try:
            e = run_pnrotor(case, atol)
            fe_, pe_, n_ = errors(e.R, e.Phi, ref)
            row.update(frame=fe_, phase=pe_, n_cmp=n_, n=len(e), nfev=e.stats["nfev"], termination=e.termination)
            del e
        except Exception as ex:  # noqa: BLE001  (report, keep going)
            row["error"] = f"{type(ex).__name__}: {ex}"
        rows.append(row)
    if use_lal:
        row = dict(method="LAL T4", tol=None, key=("lal", None))
        try:
            R, phi = lal_frame(case)
            fe_, pe_, n_ = errors(R, phi, ref)
            row.update(frame=fe_, phase=pe_, n_cmp=n_, n=phi.size, nfev=None)
        except Exception as ex:  # noqa: BLE001
            row["error"] = f"{type(ex).__name__}: {ex}"
        rows.append(row)
    for method, tol in scipy_cfgs:
        row = dict(method=f"scipy {method}", tol=tol, key=(method, tol))
        try:
            R, phi, nfev = run_scipy(case, method, tol, info["n"])
            fe_, pe_, n_ = errors(R, phi, ref)
            row.update(frame=fe_, phase=pe_, n_cmp=n_, n=phi.size, nfev=nfev)
        except Exception as ex:  # noqa: BLE001
            row["error"] = f"{type(ex).__name__}: {ex}"
        rows.append(row)
    return info, rows


def callable_of(row, case, n_ref):
    kind, tol = row["key"]
    if kind == "pnrotor":
        return lambda: run_pnrotor(case, tol)
    if kind == "lal":
        return lambda: lal_call(case)
    return lambda: run_scipy(case, kind, tol, n_ref)


def fmt(x, spec):
    """format(x, spec), or a dash padded to the width of spec when x is None."""
    return format(x, spec) if x is not None else "—".rjust(int(spec.split(".")[0].rstrip("dfe") or 0))


def print_case(name, case, info, rows):
    print(f"\n{name}: {case[5]}, f_ref {case[4]:g} Hz → {info['termination']} at t = {info['t_final_s']:.4f} s "
          f"({info['state']} state), {info['n']} samples at Δt = 1/4096 s")
    print(f"  reference: compensated 8th-order formula on pnrotor's atol-{ATOL_REF:g} steps ∪ the grid "
          f"({info['mesh']} points) halved ({info['ref_seconds']:.2f} s); its error (vs the unhalved mesh): "
          f"frame {info['ref_frame']:.2e}, phase {info['ref_phase']:.2e} rad")
    print(f"  (pnrotor atol {ATOL_REF:g} vs {ATOL_CHECK:g}, the plain-float64 check: "
          f"frame {info['pn_check_frame']:.2e}, phase {info['pn_check_phase']:.2e} rad, ends {info['pn_check_dt_end_s']:+.1e} s apart)")
    print("  errors: maxima over the span common to the run and the reference (the first min(N, N_ref) samples)")
    print(f"  {'method':14s} {'tol':>7s} {'wall ms':>9s} {'min ms':>8s} {'integr.':>8s} {'frame err':>10s} {'phase err':>10s} "
          f"{'nfev':>7s} {'samples':>8s}")
    for r in rows:
        tol = "fixed" if r["tol"] is None else f"{r['tol']:.0e}"
        if "error" in r:
            print(f"  {r['method']:14s} {tol:>7s}  FAILED: {r['error']}")
            continue
        short = "" if r["n"] == info["n"] else f" ({r['n'] - info['n']:+d})"
        print(f"  {r['method']:14s} {tol:>7s} {fmt(r.get('ms'), '9.2f')} {fmt(r.get('min_ms'), '8.2f')} "
              f"{fmt(r.get('integr_ms'), '8.2f')} "
              f"{r['frame']:10.2e} {r['phase']:10.2e} {fmt(r['nfev'], '7d')} {r['n']:8d}{short}")


def main(argv=None):
    """Run the study with command-line arguments ``argv`` (default: sys.argv), print its tables and write the
    JSON and the figure if asked."""
    ap = argparse.ArgumentParser(prog="bench_pn_precision.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=None, help="interleaved timing rounds (default 7; 3 with --quick)")
    ap.add_argument("--quick", action="store_true", help="atol 1e-6, 1e-8, …, 1e-14; scipy at 1e-10 only; 3 rounds")
    ap.add_argument("--cases", nargs="+", default=DEFAULT_CASES, choices=list(CASES),
                    help="default: the first four; BNS-precessing-20Hz is the long case (~1 min more)")
    ap.add_argument("--no-scipy", action="store_true")
    ap.add_argument("--no-lal", action="store_true")
    ap.add_argument("--json", default=None)
    ap.add_argument("--figure", default=None, help="also draw the diagram (frame error against wall time, one panel "
                    "per case) into this image file; needs matplotlib (pnrotor[plot])")
    args = ap.parse_args(argv)
    rounds = args.rounds if args.rounds is not None else (3 if args.quick else 7)
    if rounds < 1:
        ap.error(f"--rounds must be at least 1, got {rounds}")
    atols = ATOLS_QUICK if args.quick else ATOLS
    scipy_cfgs = [] if args.no_scipy else (SCIPY_QUICK if args.quick else SCIPY)
    use_lal = not args.no_lal
    if use_lal:
        try:
            import lalsimulation  # noqa: F401
        except ImportError:
            print("lalsimulation not importable: LAL rows skipped", file=sys.stderr)
            use_lal = False

    wall0 = time.perf_counter()
    results = {}
    for name in args.cases:
        info, rows = measure_errors(name, CASES[name], atols, scipy_cfgs, use_lal)
        results[name] = dict(info=info, rows=rows)

    # interleaved timing rounds: every case, every configuration, in turn
    for name in args.cases:
        for r in results[name]["rows"]:
            r["times"], r["integr"] = [], []
    jobs = [(name, r) for name in args.cases for r in results[name]["rows"] if "error" not in r]
    rng = random.Random(14)
    for _ in range(rounds):
        rng.shuffle(jobs)      # a new order every round: no configuration always follows the same one
        for name, r in jobs:
            dt, integ = timed(callable_of(r, CASES[name], results[name]["info"]["n"]))
            r["times"].append(dt)
            if integ is not None:
                r["integr"].append(integ)
    for name in args.cases:
        for r in results[name]["rows"]:
            if r.get("times"):
                r["ms"] = 1e3 * statistics.median(r["times"])
                r["min_ms"] = 1e3 * min(r["times"])
            if r.get("integr"):
                r["integr_ms"] = 1e3 * statistics.median(r["integr"])
            r.pop("key", None)

    print(f"Work–precision, T4 with LALSuite's SpinTaylorT4 truncation, Δt = 1/4096 s; wall times: median of "
          f"{rounds} interleaved rounds")
    for name in args.cases:
        print_case(name, CASES[name], results[name]["info"], results[name]["rows"])

    def pn_rows(name):
        return {r["tol"]: r for r in results[name]["rows"] if r["method"] == "pnrotor" and "error" not in r}

    # (a) pnrotor at LAL's accuracy
    summary = {}
    if use_lal:
        print("\n(a) pnrotor at LAL's accuracy: loosest atol with frame error ≤ LAL's (both vs the reference)")
        print(f"  {'case':19s} {'LAL frame':>10s} {'LAL ms':>8s} {'atol':>7s} {'frame':>9s} {'ms':>8s} "
              f"{'LAL/pnrotor':>11s} {'(min)':>6s}   at atol 1e-12: {'ms':>7s} {'LAL/pnrotor':>11s}")
        for name in args.cases:
            lal = next((r for r in results[name]["rows"] if r["method"] == "LAL T4"), None)
            pn = pn_rows(name)
            if lal is None or "error" in lal:
                print(f"  {name:19s} LAL failed")
                continue
            ok = [a for a in sorted(pn, reverse=True) if pn[a]["frame"] <= lal["frame"]]
            d = pn.get(DEFAULT_ATOL)
            dtxt = f"{d['ms']:7.2f} {lal['ms'] / d['ms']:10.2f}×" if d else ""
            if not ok:
                print(f"  {name:19s} {lal['frame']:10.2e} {lal['ms']:8.2f}  no pnrotor atol reaches LAL's accuracy")
                continue
            a = ok[0]
            summary[name] = dict(lal_frame=lal["frame"], lal_ms=lal["ms"], atol=a, frame=pn[a]["frame"],
                                 ms=pn[a]["ms"], speedup=lal["ms"] / pn[a]["ms"],
                                 speedup_min=lal["min_ms"] / pn[a]["min_ms"],
                                 speedup_default=lal["ms"] / d["ms"] if d else None)
            print(f"  {name:19s} {lal['frame']:10.2e} {lal['ms']:8.2f} {a:7.0e} {pn[a]['frame']:9.2e} "
                  f"{pn[a]['ms']:8.2f} {lal['ms'] / pn[a]['ms']:10.2f}× {lal['min_ms'] / pn[a]['min_ms']:5.2f}×   {'':15s}{dtxt}")
            ratio = lal["ms"] / pn[a]["ms"]
            how = f"{ratio:.1f}× faster" if ratio >= 1 else f"{1 / ratio:.1f}× slower"
            rmin = lal["min_ms"] / pn[a]["min_ms"]
            print(f"  {'':19s} → at LAL's accuracy pnrotor is {how} (atol {a:.0e}; {rmin:.1f}× by the minimum times)")

    # (b) default atol
    print(f"\n(b) default atol: worst frame / phase error over the cases, cost relative to atol {DEFAULT_ATOL:g}")
    common = sorted(set.intersection(*(set(pn_rows(n)) for n in args.cases)), reverse=True)
    print(f"  {'atol':>7s} {'worst frame':>11s} {'(case)':19s} {'worst phase':>11s} {'Σ ms':>8s} {'Σ min':>8s} "
          f"{'Σ integr.':>9s} {'Σ nfev':>8s} {'ms/ms(1e-12)':>12s} {'min/min':>7s} {'nfev/nfev(1e-12)':>16s}")
    tot = {}
    for a in common:
        rs = {n: pn_rows(n)[a] for n in args.cases}
        worst = max(rs, key=lambda n: rs[n]["frame"])
        tot[a] = dict(frame=rs[worst]["frame"], case=worst, phase=max(r["phase"] for r in rs.values()),
                      ms=sum(r["ms"] for r in rs.values()), min_ms=sum(r["min_ms"] for r in rs.values()),
                      integr=sum(r["integr_ms"] for r in rs.values()),
                      nfev=sum(r["nfev"] for r in rs.values()))
    for a in common:
        t, d = tot[a], tot.get(DEFAULT_ATOL)
        rel = f"{t['ms'] / d['ms']:12.2f} {t['min_ms'] / d['min_ms']:7.2f} {t['nfev'] / d['nfev']:16.2f}" if d else ""
        print(f"  {a:7.0e} {t['frame']:11.2e} {t['case']:19s} {t['phase']:11.2e} {t['ms']:8.2f} {t['min_ms']:8.2f} "
              f"{t['integr']:9.2f} "
              f"{t['nfev']:8d} {rel}")
    print("  smallest frame error reached per case (where tightening atol stops helping: round-off in the "
          "state)")
    for n in args.cases:
        pn = pn_rows(n)
        a = min(pn, key=lambda b: pn[b]["frame"])
        print(f"    {n:19s} {pn[a]['frame']:.2e} rad at atol {a:g}; at atol ≤ 1e-12: "
              + ", ".join(f"{pn[b]['frame']:.1e}" for b in sorted(pn, reverse=True) if b <= 1e-12))
    good = [a for a in common if tot[a]["frame"] <= TARGET and all(tot[b]["frame"] <= TARGET for b in common if b < a)]
    if good:
        a = good[0]
        d = tot.get(DEFAULT_ATOL)
        extra = (f"; vs {DEFAULT_ATOL:g}: {tot[a]['ms'] / d['ms']:.2f}× the wall time (median; "
                 f"{tot[a]['min_ms'] / d['min_ms']:.2f}× by the minimum), {tot[a]['integr'] / d['integr']:.2f}× the "
                 f"integration time, "
                 f"{tot[a]['nfev'] / d['nfev']:.2f}× the evaluations" if d else "")
        print(f"  loosest atol with frame error ≤ {TARGET:g} rad in every case, of the atols "
              f"{', '.join(f'{b:g}' for b in common)}: {a:g} (worst {tot[a]['frame']:.2e} rad, {tot[a]['case']}){extra}")
    else:
        print(f"  no atol keeps the frame error ≤ {TARGET:g} rad in every case")
    print(f"\nscript run time {time.perf_counter() - wall0:.1f} s")

    if args.json:
        out = dict(rounds=rounds, dt=DT, atol_ref=ATOL_REF, atol_check=ATOL_CHECK,
                   cases={n: dict(inputs=list(CASES[n]), **{k: v for k, v in results[n].items()}) for n in args.cases},
                   lal_accuracy=summary, default_atol={f"{a:g}": v for a, v in tot.items()},
                   recommended_atol=good[0] if good else None, atols_tried=common)
        with replaced_on_success(args.json) as temporary, open(temporary, "w") as fh:
            json.dump(out, fh, indent=1, default=float)
        print(f"wrote {args.json}")
    if args.figure:
        figure(results, args.cases, args.figure)


def figure(results, cases, path):
    """The work–precision diagram: per case, frame error against median wall time, a line per method through
    its tolerances."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.8), squeeze=False)
    for ax, name in zip(axes[0], cases):
        rows = [r for r in results[name]["rows"] if "error" not in r and "ms" in r]
        for method in dict.fromkeys(r["method"] for r in rows):
            mine = sorted((r for r in rows if r["method"] == method), key=lambda r: -(r["tol"] or 0.0))  # by atol
            ax.loglog([r["ms"] for r in mine], [r["frame"] for r in mine], "o" if len(mine) == 1 else "o-",
                      label=method, ms=4)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("wall time (ms)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("frame error (rad)")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    with replaced_on_success(path) as temporary:
        fig.savefig(temporary, dpi=120)
    print(f"wrote {path}")
