"""Latency of one ``pnrotor.pn.evolve`` call: the Python around the compiled integration, stage by stage (issue 14 §2).

Cases (SpinTaylorT4 truncation, ``lalsuite_orders("T4")``, everything else at evolve's defaults): a precessing
30 + 10 M☉ binary (χ₁ = (0.6, 0, 0.2), χ₂ = (0, −0.4, 0.1), f_ref = 20 Hz) and a nonspinning 1.4 + 1.4 M☉ one
(f_ref = 30 Hz), each with sampling 'final' and 'steps'.  Per case, medians of many calls (µs):

* ``settings``: :func:`pnrotor.pn.settings.settings` (input checks and units);
* ``build_system``: :func:`pnrotor.pn.evolve.build_system` (parameter vector, initial state, start check);
* ``integrator``: :func:`pnrotor.pn.evolve.integrate_half` minus the compiled DOP853 core called directly
  with the same prepared arguments (``core``): the Python of one integrator call (checks, result);
* ``sample``: :func:`pnrotor.pn.sampling.sample`; ``result``: ``Evolution.inputs``, the stats and the
  :class:`~pnrotor.pn.evolve.Evolution` (what ``evolve`` does after sampling);
* ``evolve``: the whole call, and ``overhead`` = evolve − core, the Python around one run (target ≤ 50 µs).

Then sampling cost in ns per sample against a plain numpy copy of the same output arrays, and LAL/pnrotor
time ratios on the same binaries: ``pnrotor.interop.lal.spintaylor_series`` at Δt = 1/4096 s against
``evolve(sampling=1/4096)`` (as benchmarks/bench_pn.py), and LAL's ``SimInspiralSpinTaylorPNEvolveOrbitOnlyFinal``
(fEnd = 0, timed only, as benchmarks/bench_many.py) against ``sampling='final'``.

    python benchmarks/bench_latency.py [--calls 2000] [--no-lal]
"""

import argparse
import statistics
import time

import numpy as np

from pnrotor.ode import AFTER_STEP_SIG, by_address
from pnrotor.ode.common import OUT_FINAL, OUT_STEPS, entry_point, function_addresses, no_after_step
from pnrotor.ode.dop853 import CORE_SIG, core
from pnrotor.pn import evolve, lalsuite_orders
from pnrotor.pn.evolve import CONTROLLER, OPTIONS, Evolution, _stats, build_system, half, integrate_half, termination
from pnrotor.pn.sampling import sample
from pnrotor.pn.settings import settings

ORDERS = lalsuite_orders("T4")
DT = 1.0 / 4096
BINARIES = {
    "precessing 30+10": (30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 20.0),
    "nonspinning 1.4+1.4": (1.4, 1.4, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 30.0),
}
DEFAULTS = dict(OPTIONS, **ORDERS)


def median_us(f, calls):
    """Median wall time of ``calls`` calls of f() in µs (after two warm-up calls)."""
    f()
    f()
    out = []
    for _ in range(calls):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return 1e6 * statistics.median(out)


def core_call(s, system, t_eval, dense):
    """The compiled DOP853 core of the forward half with the arguments ``dop853`` would prepare, as a thunk."""
    p, t_end, directions = half(s.v0, s.nu, s.v_min, system.p, True)
    n = system.y0.size
    functions = function_addresses(system.rhs, by_address(no_after_step, AFTER_STEP_SIG), system.events)
    args = (functions, 0.0, system.y0, t_end, p,
            np.full(n, s.atol), np.full(n, s.rtol), 0.0, np.inf, s.max_steps, np.empty(0),
            OUT_FINAL if t_eval == "final" else OUT_STEPS, dense, directions.size, directions,
            CONTROLLER["safety"], 1.0 / 3.0, CONTROLLER["max_factor"])
    compiled = entry_point(core, CORE_SIG)
    return lambda: compiled(*args)


def stages(binary, sampling, calls):
    """Median µs of each stage of one evolve call (module docstring)."""
    m1, m2, c1, c2, f = binary
    kw = dict(DEFAULTS, sampling=sampling, precession_phase_shift=ORDERS["precession_phase_shift"])
    s = settings(m1, m2, c1, c2, f, **kw)
    system = build_system(s)
    t_eval = "final" if sampling == "final" else None
    res = integrate_half(s, system, True, t_eval, False)[0]
    t_out, hist = sample(s, res, None)
    term = termination(res.status, res.event_index, "v_max", s.approximant)

    def result():
        inputs = s.inputs()
        stats = _stats(res, None, term, "not_integrated")
        v, Phi, x1, x2, R, ellh = hist
        return Evolution(t=np.asarray(t_out, dtype=np.float64), t_seconds=np.asarray(t_out) * s.M_sec, v=v,
                         Phi=Phi, chi1=x1, chi2=x2, R=R, ell_hat=ellh, termination=term, stats=stats, inputs=inputs)

    core = core_call(s, system, t_eval, False)
    out = {
        "settings": median_us(lambda: settings(m1, m2, c1, c2, f, **kw), calls),
        "build_system": median_us(lambda: build_system(s), calls),
        "integrate_half": median_us(lambda: integrate_half(s, system, True, t_eval, False), calls),
        "core": median_us(core, calls),
        "sample": median_us(lambda: sample(s, res, None), calls),
        "result": median_us(result, calls),
        "evolve": median_us(lambda: evolve(m1, m2, c1, c2, f, **kw), calls),
    }
    out["integrator"] = out["integrate_half"] - out["core"]
    out["overhead"] = out["evolve"] - out["core"]
    out["rows"] = len(t_out)
    return out


def sampling_cost(binary, sampling, calls):
    """(samples, ns/sample of sample(), ns/sample of copying the same output arrays with numpy)."""
    m1, m2, c1, c2, f = binary
    s = settings(m1, m2, c1, c2, f, **dict(DEFAULTS, sampling=sampling,
                                           precession_phase_shift=ORDERS["precession_phase_shift"]))
    system = build_system(s)
    dense = s.sampling in ("dt", "per_orbit")
    res = integrate_half(s, system, True, "final" if s.sampling == "final" else None, dense)[0]
    t_out, hist = sample(s, res, None)
    arrays = (t_out,) + hist
    n = len(t_out)
    ours = median_us(lambda: sample(s, res, None), calls)
    copy = median_us(lambda: [a.copy() for a in arrays], calls)
    return n, 1e3 * ours / n, 1e3 * copy / n


def lal_ratios(binary, calls):
    """(LAL Δt, pnrotor Δt, LAL OnlyFinal, pnrotor 'final') median ms."""
    import lal
    import lalsimulation as ls

    from pnrotor.interop.lal import spintaylor_series

    m1, m2, c1, c2, f = binary
    kw = ORDERS
    t4 = ls.GetApproximantFromString("SpinTaylorT4")

    def lal_final():
        ls.SimInspiralSpinTaylorPNEvolveOrbitOnlyFinal(DT, m1 * lal.MSUN_SI, m2 * lal.MSUN_SI, f, 0.0, *c1, *c2,
                                                       0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, -1, 0, 7,
                                                       0, t4)

    fns = {"lal_dt": lambda: spintaylor_series(m1, m2, c1, c2, f, "T4", DT)[0].data.length,
           "ours_dt": lambda: len(evolve(m1, m2, c1, c2, f, sampling=DT, **kw)),
           "lal_final": lal_final,
           "ours_final": lambda: len(evolve(m1, m2, c1, c2, f, sampling="final", **kw))}
    times = {k: [] for k in fns}
    for fn in fns.values():
        fn()
    for _ in range(calls):  # interleaved rounds
        for k, fn in fns.items():
            t = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t)
    return {k: 1e3 * statistics.median(v) for k, v in times.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--no-lal", action="store_true")
    args = ap.parse_args()

    cols = ("settings", "build_system", "integrator", "sample", "result", "core", "evolve", "overhead")
    print(f"Per-stage medians of {args.calls} calls (µs); integrator = integrate_half − core; "
          f"overhead = evolve − core")
    print(f"{'case':32s} {'rows':>5s} " + " ".join(f"{c:>12s}" for c in cols))
    for name, binary in BINARIES.items():
        for sampling in ("final", "steps"):
            r = stages(binary, sampling, args.calls)
            print(f"{name + ', ' + sampling:32s} {r['rows']:5d} " + " ".join(f"{r[c]:12.1f}" for c in cols))

    print("\nSampling cost (ns/sample): sample() vs copying the same output arrays (t, v, Φ, χ₁, χ₂, R, ℓ̂)")
    print(f"{'case':44s} {'samples':>8s} {'sample()':>9s} {'np copy':>8s} {'ratio':>6s}")
    for name, binary in BINARIES.items():
        for sampling in ("steps", DT, ("per_orbit", 4)):
            calls = max(20, args.calls // 20) if sampling != "steps" else args.calls
            n, ours, copy = sampling_cost(binary, sampling, calls)
            label = f"{name}, {'1/4096 s' if sampling == DT else sampling}"
            print(f"{label:44s} {n:8d} {ours:9.2f} {copy:8.2f} {ours / copy:6.2f}")

    if not args.no_lal:
        print("\nLAL / pnrotor (median ms of interleaved calls): Δt = 1/4096 s (spintaylor_series vs "
              "sampling=Δt), OnlyFinal vs sampling='final'")
        print(f"{'case':24s} {'LAL Δt':>8s} {'ours Δt':>8s} {'ratio':>6s} {'LAL fin':>8s} {'ours fin':>8s} {'ratio':>6s}")
        for name, binary in BINARIES.items():
            r = lal_ratios(binary, max(10, args.calls // 50))
            print(f"{name:24s} {r['lal_dt']:8.3f} {r['ours_dt']:8.3f} {r['lal_dt'] / r['ours_dt']:6.2f} "
                  f"{r['lal_final']:8.3f} {r['ours_final']:8.3f} {r['lal_final'] / r['ours_final']:6.2f}")


if __name__ == "__main__":
    main()
