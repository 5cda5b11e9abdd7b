r"""Benchmark of pnrotor's numba ODE integrators (a script, not a test).

This script owns the performance measurements of :mod:`pnrotor.ode`:

* our DOP853 against ``scipy.integrate.solve_ivp(method='DOP853')`` on the same problems with the
  same tolerances, controller constants and initial step (so both take the same steps): nfev,
  steps, wall time, their ratio, and the error against the exact solution;
* our per-step cost against the bare cost of 12 right-hand-side evaluations, measured in numba in
  the same run as a dependent chain of indirect calls through the same ``FunctionType``
  (the per-step overhead of the stepper: stage combinations, error norm, controller, bookkeeping);
* Gragg–Bulirsch–Stoer against DOP853 at several tolerances;
* the cold-start compile time (a fresh process with an empty numba cache directory,
  ``NUMBA_CACHE_DIR=<tmpdir>``) and the cached start time (a second process with the same cache).

Problems: the Kepler two-body orbit with eccentricity 0.6 over 20 periods (exact solution from
Kepler's equation), and Hairer's "Pleiades" 7-body problem (PLEI, Hairer, Nørsett & Wanner,
Solving ODEs I, Sec. II.10; n = 28) on [0, 3], whose reference solution is a run at tolerance 1e-14.

Run:  python benchmarks/bench_ode.py  [--quick]  [--no-cold]
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile
import textwrap
import time

import numpy as np
from numba import njit, types
from scipy.integrate import DOP853 as ScipyDOP853
from scipy.integrate import solve_ivp

from pnrotor.ode import RHS_SIG, bulirsch_stoer, dop853

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from ode_problems import kepler, kepler_exact  # noqa: E402  (the tests' problems, with exact answers)

# --------------------------------------------------------------------------------------------------
# problems
# --------------------------------------------------------------------------------------------------


@njit(RHS_SIG, cache=True)
def pleiades(t, y, p, dydt):
    """7 bodies in the plane, masses m_i = i, G = 1; y = (x1..x7, y1..y7, vx1..vx7, vy1..vy7)."""
    nb = 7
    for i in range(nb):
        dydt[i] = y[2 * nb + i]
        dydt[nb + i] = y[3 * nb + i]
        dydt[2 * nb + i] = 0.0
        dydt[3 * nb + i] = 0.0
    for i in range(nb):
        for j in range(i + 1, nb):
            dx = y[j] - y[i]
            dy = y[nb + j] - y[nb + i]
            r2 = dx * dx + dy * dy
            r3 = r2 * math.sqrt(r2)
            fx = dx / r3
            fy = dy / r3
            dydt[2 * nb + i] += (j + 1) * fx
            dydt[3 * nb + i] += (j + 1) * fy
            dydt[2 * nb + j] -= (i + 1) * fx
            dydt[3 * nb + j] -= (i + 1) * fy


ECC = 0.6
KEPLER_Y0 = np.array([1 - ECC, 0.0, 0.0, math.sqrt((1 + ECC) / (1 - ECC))])
PLEIADES_Y0 = np.array([3, 3, -1, -3, 2, -2, 2,
                        3, -3, 2, 0, 0, -4, 4,
                        0, 0, 0, 0, 0, 1.75, -1.5,
                        0, 0, 0, -1.25, 1, 0, 0], dtype=float)

# --------------------------------------------------------------------------------------------------
# bare cost of the right-hand side
# --------------------------------------------------------------------------------------------------

_FT = types.FunctionType(RHS_SIG)


@njit(types.float64(_FT, types.int64, types.float64[::1], types.float64[::1]), cache=True)
def bare_chain(rhs, count, y0, p):
    """count evaluations of rhs, each at a state that depends on the previous derivative (like the
    stages of a Runge–Kutta step), through the same first-class function call as the integrator."""
    n = y0.size
    y = y0.copy()
    d = np.empty(n)
    for _ in range(count):
        rhs(0.0, y, p, d)
        for i in range(n):
            y[i] = y0[i] + 1e-12 * d[i]
    return y[0]


def best_time(fn, repeat):
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def interleaved_best(fns, repeat):
    """Best-of-``repeat`` wall time of each function, measured in interleaved rounds so that load
    from other processes on a shared machine affects all of them alike."""
    best = [math.inf] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return best


def scipy_fun(rhs, p):
    """scipy-style f(t, y) calling the same numba right-hand side."""
    def f(t, y):
        d = np.empty(y.size)
        rhs(t, np.ascontiguousarray(y), p, d)
        return d
    return f


# --------------------------------------------------------------------------------------------------
# benchmark sections
# --------------------------------------------------------------------------------------------------

SCIPY_CONTROLLER = dict(safety=0.9, min_factor=0.2, max_factor=10.0)


def bench_vs_scipy(name, rhs, y0, T, tol, exact, repeat):
    p = np.empty(0)
    f = scipy_fun(rhs, p)
    h0 = ScipyDOP853(f, 0.0, y0, T, rtol=tol, atol=tol).h_abs
    ts = best_time(lambda: solve_ivp(f, (0.0, T), y0, method="DOP853", rtol=tol, atol=tol), max(1, repeat // 5))
    s = solve_ivp(f, (0.0, T), y0, method="DOP853", rtol=tol, atol=tol)
    run = lambda: dop853(rhs, 0.0, y0, T, atol=tol, rtol=tol, first_step=h0, t_eval="final", **SCIPY_CONTROLLER)
    r = run()
    to = best_time(run, repeat)
    ra = dop853(rhs, 0.0, y0, T, atol=tol, rtol=tol, first_step=h0, **SCIPY_CONTROLLER)  # all steps
    ta = best_time(lambda: dop853(rhs, 0.0, y0, T, atol=tol, rtol=tol, first_step=h0, **SCIPY_CONTROLLER), repeat)
    ref = exact(T)
    err_s = np.max(np.abs(s.y[:, -1] - ref))
    err_o = np.max(np.abs(r.y[-1] - ref))
    n_s = (s.nfev - 2) // 12
    # fixed cost of one call (argument checks, the functions' addresses): a run of
    # one step; per-step cost from the difference of two run lengths (cancels the fixed cost);
    # bare RHS cost in the same rounds, same number of evaluations as our integration
    tiny = lambda: dop853(rhs, 0.0, y0, 1e-3 * h0, atol=tol, rtol=tol, first_step=1e-3 * h0, t_eval="final",
                          **SCIPY_CONTROLLER)
    short = lambda: dop853(rhs, 0.0, y0, T / 4, atol=tol, rtol=tol, first_step=h0, t_eval="final",
                           **SCIPY_CONTROLLER)
    rs = short()
    bare_chain(rhs, 10, y0, p)
    t_long, t_short, t_fixed, t_bare, t_bare1 = interleaved_best(
        [run, short, tiny, lambda: bare_chain(rhs, r.nfev, y0, p), lambda: bare_chain(rhs, 1, y0, p)], 4 * repeat)
    tb = t_bare - t_bare1
    per_eval_bare = tb / r.nfev
    per_step_ours = (t_long - t_short) / (r.nsteps - rs.nsteps)
    per_step_bare12 = 12 * per_eval_bare
    print(f"\n== {name}: DOP853 vs scipy solve_ivp(DOP853), rtol = atol = {tol:g}, "
          f"scipy controller (0.9, 0.2, 10) and scipy's initial step for both ==")
    print(f"{'':24s}{'nfev':>9s}{'steps':>8s}{'accepted':>10s}{'wall [s]':>12s}{'ns/fev':>10s}{'|err| at T':>13s}")
    print(f"{'scipy DOP853':24s}{s.nfev:9d}{n_s:8d}{len(s.t) - 1:10d}{ts:12.5f}{ts / s.nfev * 1e9:10.1f}{err_s:13.3e}")
    print(f"{'pnrotor dop853 (final)':24s}{r.nfev:9d}{r.nsteps:8d}{r.naccepted:10d}{to:12.6f}{to / r.nfev * 1e9:10.1f}{err_o:13.3e}")
    print(f"{'pnrotor dop853 (steps)':24s}{ra.nfev:9d}{ra.nsteps:8d}{ra.naccepted:10d}{ta:12.6f}{ta / ra.nfev * 1e9:10.1f}")
    print(f"nfev: scipy = ours + nrejected + 1 (scipy also evaluates f at the end of rejected attempts, "
          f"and we were given the initial step): {s.nfev} = {r.nfev} + {r.nrejected} + 1 -> "
          f"{'yes' if s.nfev == r.nfev + r.nrejected + 1 else 'NO'}")
    print(f"wall-time ratio scipy / ours (final-state output): {ts / to:8.1f}x ; per RHS evaluation: "
          f"{(ts / s.nfev) / (to / r.nfev):8.1f}x")
    print(f"fixed cost per dop853() call (validation, the functions' addresses), from a 1-step run: "
          f"{t_fixed * 1e6:7.1f} us (included in the wall times above)")
    print(f"bare RHS (numba, dependent chain of FunctionType calls): {per_eval_bare * 1e9:7.1f} ns/eval; "
          f"12 evals = {per_step_bare12 * 1e9:7.1f} ns")
    print(f"our time per attempted step ((t(T) - t(T/4)) / (steps(T) - steps(T/4))): {per_step_ours * 1e9:7.1f} ns = "
          f"{per_step_ours / per_step_bare12:5.2f} x the bare 12 evaluations "
          f"(per-step overhead {(per_step_ours - per_step_bare12) * 1e9:6.1f} ns)")
    return dict(scipy=ts, ours=to, ratio=ts / to)


def bench_bs(name, rhs, y0, T, tols, exact, repeat):
    print(f"\n== {name}: Bulirsch-Stoer vs DOP853 (Hairer's controller defaults), rtol = 0, atol = tol ==")
    print(f"{'tol':>8s} {'method':16s}{'nfev':>9s}{'steps':>8s}{'rejected':>10s}{'wall [s]':>12s}{'|err| at T':>13s}")
    ref = exact(T)
    for tol in tols:
        for label, fn in (("dop853", dop853), ("bulirsch_stoer", bulirsch_stoer)):
            run = lambda: fn(rhs, 0.0, y0, T, atol=tol, t_eval="final")
            r = run()
            tw = best_time(run, repeat)
            err = np.max(np.abs(r.y[-1] - ref))
            print(f"{tol:8.0e} {label:16s}{r.nfev:9d}{r.nsteps:8d}{r.nrejected:10d}{tw:12.6f}{err:13.3e}")


COLD_SCRIPT = textwrap.dedent('''
    import time
    t0 = time.perf_counter()
    import math
    import numpy as np
    from numba import njit
    import pnrotor.ode as ode
    t1 = time.perf_counter()

    @njit(ode.RHS_SIG, cache=True)
    def kepler(t, y, p, dydt):
        r2 = y[0] * y[0] + y[1] * y[1]
        r3 = r2 * math.sqrt(r2)
        dydt[0] = y[2]
        dydt[1] = y[3]
        dydt[2] = -y[0] / r3
        dydt[3] = -y[1] / r3

    t2 = time.perf_counter()
    y0 = np.array([0.4, 0.0, 0.0, 2.0])
    r = ode.dop853(kepler, 0.0, y0, 10.0, atol=1e-10, t_eval="final")
    rb = ode.bulirsch_stoer(kepler, 0.0, y0, 10.0, atol=1e-10, t_eval="final")
    t3 = time.perf_counter()
    import sys
    core = sys.modules["pnrotor.ode.dop853"].core
    hits = sum(core.stats.cache_hits.values())
    misses = sum(core.stats.cache_misses.values())
    print(f"{t1 - t0:.3f} {t2 - t1:.3f} {t3 - t2:.3f} {t3 - t0:.3f} {hits} {misses}")
''')


def bench_cold_start():
    print("\n== start-up: fresh processes with NUMBA_CACHE_DIR=<new temporary directory> ==")
    print(f"{'':22s}{'import pnrotor.ode':>19s}{'compile user rhs':>18s}{'first dop853+BS':>17s}"
          f"{'total':>9s}{'core cache hits/misses':>25s}")
    with tempfile.TemporaryDirectory() as tmp:
        script = os.path.join(tmp, "cold_start.py")
        with open(script, "w") as fh:
            fh.write(COLD_SCRIPT)
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, "numba_cache"))
        for label in ("cold (empty cache)", "cached (2nd process)", "cached (3rd process)"):
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, script], env=env, capture_output=True, text=True, check=True)
            wall = time.perf_counter() - t0
            imp, comp, first, total, hits, misses = out.stdout.split()
            print(f"{label:22s}{float(imp):17.2f} s{float(comp):16.2f} s{float(first):15.3f} s{float(total):7.2f} s"
                  f"{hits + '/' + misses:>25s}   (process wall {wall:.2f} s)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repetitions and periods")
    ap.add_argument("--no-cold", action="store_true", help="skip the cold-start subprocess measurement")
    args = ap.parse_args()
    repeat = 5 if args.quick else 40
    periods = 5 if args.quick else 20

    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, "
          f"scipy {__import__('scipy').__version__}, numba {__import__('numba').__version__}, "
          f"{os.cpu_count()} cpus, load average {os.getloadavg()[0]:.2f}")
    T = periods * 2 * math.pi
    bench_vs_scipy(f"Kepler e = {ECC}, {periods} periods (n = 4)", kepler, KEPLER_Y0, T, 1e-10,
                   lambda t: kepler_exact(t, ECC)[0], repeat)

    ref = dop853(pleiades, 0.0, PLEIADES_Y0, 3.0, atol=1e-14, rtol=1e-14, t_eval="final").y[-1]
    bench_vs_scipy("Pleiades, t in [0, 3] (n = 28)", pleiades, PLEIADES_Y0, 3.0, 1e-10, lambda t: ref, repeat)

    bench_bs(f"Kepler e = {ECC}, {periods} periods", kepler, KEPLER_Y0, T, [1e-6, 1e-9, 1e-12],
             lambda t: kepler_exact(t, ECC)[0], repeat)
    bench_bs("Pleiades, t in [0, 3]", pleiades, PLEIADES_Y0, 3.0, [1e-6, 1e-9, 1e-12], lambda t: ref, repeat)

    if not args.no_cold:
        bench_cold_start()


if __name__ == "__main__":
    main()
