"""The numerical study of Boyle 2016 (arXiv:1604.08139, Sec. V-B, Figs. 2 and 3): every formulation ×
integrator × tolerance on the precessing, nutating binary, with scipy as the baseline.

:func:`sweep` integrates the angular velocity of the binary (:mod:`pnrotor.analytic`) over [0, T] with
every formulation (:mod:`pnrotor.formulations`) × {DOP853, Bulirsch–Stoer} × absolute tolerance and
measures δ(t) of eq:error_norm at every step against the exact rotor (eq:BinaryRotor).  In the same
run, scipy's ``solve_ivp`` DOP853 integrates the rotor equation (eq:integrate-spinor, with the same
compiled right-hand side) as the baseline; scipy cannot run with rtol = 0 and raises it to 100 ε ≈
2.2e-14, so pnrotor's rotor/DOP853 is also run at that rtol for a comparison at equal tolerances.  A
stiffness probe runs vectors-damped at several damping rates.  Wall times are the best of ``repeat``
runs; the first, short run of each formulation and method is timed apart (``compile_s``).

:func:`findings` recomputes the paper's findings from the rows (costs relative to the rotor at equal
tolerance and at equal accuracy, :func:`cost_at`); :func:`figures` draws Figs. 2 and 3 (matplotlib,
the ``plot`` extra).  ``pnrotor bench`` is the command-line front.
"""

import math
import sys
import time
import warnings

from pnrotor.files import replaced_on_success

FULL = {"t_end": 1e6, "atols": [10.0 ** -k for k in range(4, 15)]}
QUICK = {"t_end": 1e5, "atols": [1e-4, 1e-8, 1e-12]}

COLUMNS = ["formulation", "method", "atol", "max_delta", "wall_s", "nfev", "steps", "resets",
           "rtol", "accepted", "rejected", "final_delta", "compile_s", "status", "t_final", "t_end",
           "damping", "study"]
"""CSV columns: the study's quantities first, then the rest of each run's record. ``study`` is
``sweep`` (the main table), ``baseline`` (scipy), ``equal-rtol`` (pnrotor at scipy's rtol) or
``damping`` (the stiffness probe); ``damping`` is λ = μ for vectors-damped rows."""

DAMPING_PROBE = {"atol": 1e-8, "t_end": 1e5, "rates": [0.0, 0.001, 0.01, 0.1, 1.0]}
"""Stiffness probe: vectors-damped with λ = μ = each rate (0 is vectors2), at one tolerance, over
min(T, t_end) (the stiff runs take ~10⁵ steps per 10⁵ time units at rate 1)."""

TARGET_DELTAS = (1e-6, 1e-10)
"""Accuracies (max δ) at which costs are compared, interpolated between tolerances."""

SCIPY = "scipy-DOP853"
SCIPY_RTOL = 100 * sys.float_info.epsilon
"""scipy's solve_ivp raises any smaller rtol to this (with a warning)."""
CURVE_POINTS = 2000


# --------------------------------------------------------------------------------------------------
# the sweep
# --------------------------------------------------------------------------------------------------


def sweep(t_end, atols, repeat, damping, with_scipy):
    """Run every configuration; return the CSV rows (dicts) and the δ(t) curves of rotor/DOP853 by atol."""
    from tqdm import tqdm

    from pnrotor.analytic import PrecessingNutatingBinary
    from pnrotor.formulations import FORMULATIONS
    from pnrotor.integrate import METHODS

    binary = PrecessingNutatingBinary()
    plan = [dict(formulation=f, method=m, atol=a, rtol=0.0, t_end=t_end, damping=damping, study="sweep")
            for f in FORMULATIONS for m in METHODS for a in atols]
    if with_scipy:  # each scipy run right after pnrotor's at the same tolerances: the same machine state
        plan += [dict(formulation="rotor", method=m, atol=a, rtol=SCIPY_RTOL, t_end=t_end, damping=damping,
                      study=study) for a in atols for m, study in (("DOP853", "equal-rtol"), (SCIPY, "baseline"))]
    probe_t = min(t_end, DAMPING_PROBE["t_end"])
    plan += [dict(formulation="vectors-damped", method=m, atol=DAMPING_PROBE["atol"], rtol=0.0, t_end=probe_t,
                  damping=(rate, rate), study="damping") for m in METHODS for rate in DAMPING_PROBE["rates"]]
    rows, curves, compile_s = [], {}, {}
    for config in tqdm(plan, desc="pnrotor bench", unit="run"):
        if config["method"] == SCIPY:
            row, t, R = _scipy_run(binary, config, repeat)
        else:
            row, t, R = _pnrotor_run(binary, config, repeat, compile_s)
        delta = binary.frame_error(t, R)
        row.update(max_delta=float(delta.max()), final_delta=float(delta[-1]), t_final=float(t[-1]),
                   t_end=config["t_end"], study=config["study"],
                   damping=config["damping"][0] if config["formulation"] == "vectors-damped" else "")
        rows.append(row)
        if (config["formulation"], config["method"], config["study"]) == ("rotor", "DOP853", "sweep"):
            curves[config["atol"]] = _envelope(t, delta)
    return rows, curves


def _pnrotor_run(binary, config, repeat, compile_s):
    """One configuration with pnrotor; the first run of each formulation and method, over [0, 1], is
    timed into ``compile_s`` (loading cached code, or compiling it)."""
    from pnrotor.integrate import integrate_angular_velocity

    R0 = binary.rotor(0.0)
    options = dict(formulation=config["formulation"], method=config["method"], damping=config["damping"],
                   atol=config["atol"], max_steps=10_000_000)
    key = config["formulation"], config["method"]
    if key not in compile_s:
        start = time.perf_counter()
        integrate_angular_velocity(binary, (0.0, 1.0), R0, **options)
        compile_s[key] = time.perf_counter() - start
    walls = []
    for _ in range(repeat):
        h = integrate_angular_velocity(binary, (0.0, config["t_end"]), R0, rtol=config["rtol"], **options)
        walls.append(h.wall_time)
    row = dict(formulation=h.formulation, method=h.method, atol=h.atol, rtol=h.rtol, wall_s=min(walls),
               compile_s=compile_s[key], nfev=h.nfev, steps=h.nsteps, accepted=h.naccepted,
               rejected=h.nrejected, resets=h.n_resets, status=h.status)
    return row, h.t, h.R


def _scipy_run(binary, config, repeat):
    """scipy's solve_ivp DOP853 on dR/dt = ½ ω R with pnrotor's compiled right-hand side for the binary."""
    import numpy as np
    from scipy.integrate import solve_ivp

    from pnrotor.formulations import get

    rotor = get("rotor")
    R0 = binary.rotor(0.0)
    rhs, p_omega = binary.integrand(rotor)
    p = np.array(p_omega)

    def fun(t, y):
        dydt = np.empty(4)
        rhs(t, y, p, dydt)
        return dydt

    walls = []
    for _ in range(repeat):
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "rtol too small": scipy uses max(rtol, 100 ε)
            sol = solve_ivp(fun, (0.0, config["t_end"]), R0, method="DOP853", atol=config["atol"],
                            rtol=config["rtol"])
        walls.append(time.perf_counter() - start)
    # scipy's DOP853 spends 12 evaluations on every step attempt, accepted or not, plus 2 at the start
    attempts = (sol.nfev - 2) // 12
    accepted = len(sol.t) - 1
    row = dict(formulation="rotor", method=SCIPY, atol=config["atol"], rtol=config["rtol"], wall_s=min(walls),
               compile_s=0.0, nfev=sol.nfev, steps=attempts, accepted=accepted, rejected=attempts - accepted,
               resets=0, status=sol.status)
    return row, sol.t, rotor.rotors(sol.y.T, R0, sol.t, binary.angular_velocity)


def _envelope(t, delta):
    """(t, δ) reduced to at most CURVE_POINTS points, keeping the largest δ of each bin."""
    import numpy as np

    if len(t) <= CURVE_POINTS:
        return t, delta
    edges = np.linspace(0, len(t), CURVE_POINTS + 1).astype(int)
    idx = np.array([a + int(np.argmax(delta[a:b])) for a, b in zip(edges[:-1], edges[1:])])
    return t[idx], delta[idx]


# --------------------------------------------------------------------------------------------------
# findings
# --------------------------------------------------------------------------------------------------


def _find(rows, formulation, method, atol, study="sweep"):
    for row in rows:
        if (row["formulation"], row["method"], row["atol"], row["study"]) == (formulation, method, atol, study):
            return row
    return None


def _ratio(rows, key, num, den, atols):
    """Geometric mean over atols of row[key] of configuration num over den (both must have succeeded)."""
    logs = []
    for atol in atols:
        a, b = _find(rows, *num, atol), _find(rows, *den, atol)
        if a and b and a["status"] == 0 and b["status"] == 0 and a[key] > 0 and b[key] > 0:
            logs.append(math.log(a[key] / b[key]))
    return math.exp(sum(logs) / len(logs)) if logs else math.nan


def cost_at(rows, formulation, method, key, target):
    """row[key] needed for max δ = target, interpolated log-log between the two successful sweep runs
    of (formulation, method) whose errors bracket it (the most accurate such pair); NaN if none do."""
    pts = sorted((r["max_delta"], r[key]) for r in rows if r["study"] == "sweep" and r["status"] == 0
                 and (r["formulation"], r["method"]) == (formulation, method) and r[key] > 0)
    for (d1, c1), (d2, c2) in zip(pts, pts[1:]):
        if d1 <= target <= d2 and d1 < d2:
            w = math.log(target / d1) / math.log(d2 / d1)
            return math.exp((1 - w) * math.log(c1) + w * math.log(c2))
    return math.nan


def findings(rows, t_end):
    """Lines with the key rows and the paper's findings, computed from the bench rows."""
    sweep_rows = [r for r in rows if r["study"] == "sweep"]
    atols = sorted({r["atol"] for r in sweep_rows}, reverse=True)
    # formulations and methods in the order the sweep ran them (that of FORMULATIONS and METHODS)
    formulations = list(dict.fromkeys(r["formulation"] for r in sweep_rows))
    methods = list(dict.fromkeys(r["method"] for r in sweep_rows))
    ref = 1e-12 if 1e-12 in atols else atols[-1]
    lines = [f"Key rows (T = {t_end:g}; max δ over all steps; wall = best of the timed runs):",
             f"  {'formulation':18s} {'method':15s} {'atol':>7s} {'rtol':>7s} {'max δ':>9s} {'wall s':>8s} "
             f"{'nfev':>9s} {'steps':>7s} {'resets':>6s} status"]
    for row in rows:
        if (row["atol"] == ref and row["study"] != "damping") or row["study"] == "baseline":
            lines.append(f"  {row['formulation']:18s} {row['method']:15s} {row['atol']:7.0e} {row['rtol']:7.1e} "
                         f"{row['max_delta']:9.2e} {row['wall_s']:8.4f} {row['nfev']:9d} {row['steps']:7d} "
                         f"{row['resets']:6d} {row['status']}")
    lines += ["", "Findings:"]
    rotor = _find(rows, "rotor", "DOP853", ref)
    scipy = _find(rows, "rotor", SCIPY, ref, "baseline")
    matched = _find(rows, "rotor", "DOP853", ref, "equal-rtol")
    if rotor:
        lines.append(f"  rotor + DOP853 at atol {ref:g}: max δ {rotor['max_delta']:.3g}, {rotor['nfev']} evaluations, "
                     f"{rotor['wall_s']:.4f} s (+ {rotor['compile_s']:.3f} s first call, apart)")
    if rotor and scipy:
        lines.append(f"  scipy solve_ivp DOP853 (rtol raised to {scipy['rtol']:.2g}): max δ {scipy['max_delta']:.3g}, "
                     f"{scipy['nfev']} evaluations, {scipy['wall_s']:.3f} s: "
                     f"{scipy['wall_s'] / rotor['wall_s']:.0f}× pnrotor's wall time")
        if matched:
            lines.append(f"  pnrotor at scipy's tolerances (rtol {matched['rtol']:.2g}): {matched['nfev']} evaluations "
                         f"vs scipy's {scipy['nfev']}; {scipy['wall_s'] / matched['wall_s']:.0f}× faster")
    succeeded = [r for r in sweep_rows if r["status"] == 0]
    rotor_runs = [r for r in succeeded if (r["formulation"], r["method"]) == ("rotor", "DOP853")]
    if rotor_runs:
        b = min(succeeded, key=lambda r: r["max_delta"])
        rb = min(rotor_runs, key=lambda r: r["max_delta"])
        lines.append(f"  best max δ, rotor + DOP853: {rb['max_delta']:.3g} (atol {rb['atol']:g}); over all runs: "
                     f"{b['max_delta']:.3g} ({b['formulation']}, {b['method']}, atol {b['atol']:g})")
    others = [f for f in formulations if f != "rotor"]
    for method in methods:
        lines.append(f"  {method}, cost relative to the rotor (evaluations / wall time):")
        ev = ", ".join(f"{f} {_ratio(rows, 'nfev', (f, method), ('rotor', method), atols):.2f}"
                       f" / {_ratio(rows, 'wall_s', (f, method), ('rotor', method), atols):.2f}" for f in others)
        lines.append(f"    at equal atol (geometric mean): {ev}")
        for target in TARGET_DELTAS:
            cells = []
            for f in others:
                ratios = [cost_at(rows, f, method, key, target) / cost_at(rows, "rotor", method, key, target)
                          for key in ("nfev", "wall_s")]
                cells.append(f"{f} " + (" / ".join(f"{x:.2f}" for x in ratios) if math.isfinite(ratios[0]) else "n/a"))
            lines.append(f"    at equal accuracy, max δ = {target:g} (interpolated): " + ", ".join(cells))
        lines.append(f"    generator without reset / with reset: "
                     f"{_ratio(rows, 'nfev', ('generator-noreset', method), ('generator', method), atols):.2f}× "
                     f"evaluations at equal atol")
        for r in sweep_rows:
            if r["method"] == method and r["status"] != 0:
                lines.append(f"    {r['formulation']} at atol {r['atol']:g} stopped at t = {r['t_final']:.10g} "
                             f"(status {r['status']})")
    probe = [r for r in rows if r["study"] == "damping"]
    if probe:
        lines.append(f"  damping (vectors-damped, λ = μ, atol {probe[0]['atol']:g}, T = {probe[0]['t_end']:g}; "
                     f"evaluations, steps, max δ):")
        for method in methods:
            cells = [f"{r['damping']:g}: {r['nfev']}, {r['steps']}, {r['max_delta']:.1e}"
                     + ("" if r["status"] == 0 else f" (status {r['status']})")
                     for r in probe if r["method"] == method]
            lines.append(f"    {method}: " + "; ".join(cells))
    lines.append("  Bulirsch-Stoer / DOP853 (steps, evaluations, wall time):")
    for name in ("rotor", "generator", "vectors3"):
        bs, dp = (name, "Bulirsch-Stoer"), (name, "DOP853")
        at_atol = [_ratio(rows, key, bs, dp, atols) for key in ("steps", "nfev", "wall_s")]
        target = TARGET_DELTAS[-1]
        at_delta = [cost_at(rows, *bs, key, target) / cost_at(rows, *dp, key, target)
                    for key in ("steps", "nfev", "wall_s")]
        lines.append(f"    {name}: at equal atol {' / '.join(f'{x:.2f}' for x in at_atol)}; "
                     f"at max δ = {target:g} "
                     + (" / ".join(f"{x:.2f}" for x in at_delta) if math.isfinite(at_delta[0]) else "n/a"))
    return lines


# --------------------------------------------------------------------------------------------------
# figures
# --------------------------------------------------------------------------------------------------


def figures(outdir, rows, curves, t_end):
    """Figs. 2 and 3 of the paper from the rows and δ(t) curves of :func:`sweep` into ``outdir`` → their paths."""
    from matplotlib.figure import Figure

    paths = []
    fig = Figure(figsize=(8, 5), layout="constrained")
    ax = fig.add_subplot()
    for atol, (t, delta) in sorted(curves.items(), reverse=True):
        ax.semilogy(t, delta, lw=0.8, label=f"atol {atol:g}")
    ax.set_xlabel("t")
    ax.set_ylabel("δ(t)")
    ax.set_title(f"Rotor, DOP853: frame error δ(t) (eq:error_norm), T = {t_end:g}")
    ax.legend(fontsize="small", ncol=2)
    paths.append(outdir / "error_vs_time.png")
    with replaced_on_success(paths[-1]) as temporary:
        fig.savefig(temporary, dpi=110)

    fig = Figure(figsize=(15, 5), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    shown = [r for r in rows if r["study"] in ("sweep", "baseline")]
    configs = sorted({(r["formulation"], r["method"]) for r in shown}, key=lambda c: (c[1] == SCIPY, c))
    colors = {}
    for formulation, method in configs:
        sel = sorted((r for r in shown if (r["formulation"], r["method"]) == (formulation, method)),
                     key=lambda r: r["atol"])
        ok = [r for r in sel if r["status"] == 0]
        failed = [r for r in sel if r["status"] != 0]
        style = {"DOP853": "-", "Bulirsch-Stoer": "--", SCIPY: ":"}[method]
        color = "black" if method == SCIPY else colors.setdefault(formulation, f"C{len(colors)}")
        for ax, key in zip(axes, ("wall_s", "nfev", "steps")):
            ax.loglog([r[key] for r in ok], [r["max_delta"] for r in ok], style, marker="o", ms=3,
                      color=color, label=f"{formulation}, {method}" if method != SCIPY else "scipy DOP853 (rotor)")
            ax.loglog([r[key] for r in failed], [r["max_delta"] for r in failed], "x", color=color)
    for ax, label in zip(axes, ("wall time [s]", "right-hand-side evaluations", "steps")):
        ax.set_xlabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("max δ")
    axes[2].legend(fontsize="x-small")
    fig.suptitle(f"Maximum frame error vs cost, T = {t_end:g} (solid DOP853, dashed Bulirsch–Stoer; "
                 "× runs that stopped before T)")
    paths.append(outdir / "max_error.png")
    with replaced_on_success(paths[-1]) as temporary:
        fig.savefig(temporary, dpi=110)
    return paths
