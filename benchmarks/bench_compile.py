"""Where a cold start's compile time goes: numba's compile events of a run, and what calling a kernel costs to compile.

Each part runs in a fresh process with NUMBA_CACHE_DIR pointing at an empty folder (cold).

* ``run``: one ``pnrotor.pn.evolve`` of the README's main job (precessing 30 + 10 M☉ from 20 Hz, SpinTaylorT4
  truncation, every step), the DOP853 core included (the CLI compiles it in a second process; here it is
  compiled in this one, first).  Per compiled function: the seconds of its compile events (their sum, and its
  own share without the compiles nested in it), as numba reports them (``numba:compile`` events).
* calling compiled kernels: two set-up kernels of every run (``pn.system._store_series``, ``pn.ends.earlier_end``)
  compiled alone, then a loop defined here that calls both (the shape of a population's set-up in one call),
  and the same loop with one array slice assignment added, each in a fresh process.  numba links every callee's
  module into the caller's and optimizes and emits machine code for the whole call tree again
  (``numba.core.codegen``: ``finalize`` links the libraries, then ``_optimize_final_module``), so even a loop
  over compiled kernels costs about a second; an array slice assignment (``a[i, :4] = b[i, :4]``) compiles
  numba's shape-mismatch error path, its string formatting included (``ol_raise_with_shape_context_cpu``), in
  ~4 s.  ``earlier_end`` calls the run's events function (2-3 s to compile) by address, and compiles in well
  under a second: what is called by address is not compiled again.

    python benchmarks/bench_compile.py [--top 25]
"""

import argparse
import os
import subprocess
import sys
import tempfile
import textwrap

_LISTENER = """
import time
from numba.core import event

records, stack = [], []


class Listener(event.Listener):
    def on_start(self, ev):
        stack.append(time.perf_counter())

    def on_end(self, ev):
        seconds = time.perf_counter() - stack.pop()
        f = getattr(ev.data["dispatcher"], "py_func", None)
        records.append((f"{f.__module__}.{f.__qualname__}" if f else str(ev.data["dispatcher"]), seconds, len(stack)))


event.register("numba:compile", Listener())
"""

_RUN = _LISTENER + """
wall = time.perf_counter()
from pnrotor.ode.dop853 import compile_core
from pnrotor.pn import evolve, lalsuite_orders
compile_core()
evolve(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 20.0, **lalsuite_orders("T4"))
wall = time.perf_counter() - wall
totals, own = {}, {}
for i, (name, seconds, depth) in enumerate(records):   # a compile's nested compiles end before it, one deeper
    totals[name] = totals.get(name, 0.0) + seconds
    nested, j = 0.0, i - 1
    while j >= 0 and records[j][2] > depth:
        nested += records[j][1] if records[j][2] == depth + 1 else 0.0
        j -= 1
    own[name] = own.get(name, 0.0) + seconds - nested
top = sorted(totals, key=totals.get, reverse=True)[:TOP]
print(f"{'compiled function':62} {'total s':>8} {'own s':>8}")
for name in top:
    print(f"{name[-62:]:62} {totals[name]:8.2f} {own[name]:8.2f}")
print(f"outermost compiles {sum(s for _, s, d in records if d == 0):.2f} s; the whole run {wall:.2f} s")
"""

_LINKING = _LISTENER + """
import numpy as np
from numba import njit
from pnrotor.ode import EVENTS_SIG, by_address
from pnrotor.pn import ends, lalsuite_orders, layout, rhs, system
from pnrotor.pn.evolve import OPTIONS, build_system
from pnrotor.pn.settings import settings
from pnrotor.pn.series import kmax_from_orders

s = settings(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 20.0, **{**OPTIONS, **lalsuite_orders("T4")})
t = time.perf_counter()
events = by_address(rhs.events_precessing, EVENTS_SIG)
parts = system.cached_spin_independent_parts((s.X1, s.approximant, tuple(kmax_from_orders(3.5, 3.0, 3.0).tolist()), 3.0,
                                        3.0, 1.0, 1.0, 1.0, 1.0, s.rotor, True, "torque"))
print(f"events function and spin-independent parts: {time.perf_counter() - t:.2f} s")
head, N, D, Ep = parts
p, basis, y0 = np.zeros(layout.P_SIZE), np.ones(9), np.array([0.2] + [0.1] * 6 + [1.0, 0.0, 0.0, 0.0, 0.0])
for name, call in (("_store_series alone", lambda: system._store_series(N, D, Ep, basis, False, p, 0.2)),
                   ("earlier_end alone (events by address)", lambda: ends.earlier_end(*events.addresses, y0, p))):
    t = time.perf_counter()
    call()
    print(f"{name:56} {time.perf_counter() - t:6.2f} s")


fold = False   # an argument, not a constant in the loop: a constant is typed Literal[bool] there and
               # _store_series would be compiled again for it


@njit
def loop(N, D, Ep, bases, P, Y0, c_addr, jit_addr, checks, fold):
    for i in range(P.shape[0]):
        checks[i, 0], checks[i, 1], checks[i, 2], checks[i, 3] = system._store_series(N, D, Ep, bases[i], fold,
                                                                                         P[i], Y0[i, 0])
        checks[i, 4] = ends.earlier_end(c_addr, jit_addr, Y0[i], P[i])
        if SLICE:
            P[i, :4] = Y0[i, :4]   # an array slice assignment


before = len(records)
t = time.perf_counter()
loop(N, D, Ep, basis[None], p[None].copy(), y0[None], *events.addresses, np.empty((1, 5)), fold)
nested = sorted(((s, name) for name, s, depth in records[before:] if depth == 1), reverse=True)[:3]
print(f"{LABEL:56} {time.perf_counter() - t:6.2f} s; nested compiles: "
      + ", ".join(f"{name.split('.')[-1] if 'pnrotor' in name else name} {s:.2f} s" for s, name in nested))
"""


def fresh(code):
    """Run ``code`` in a new Python with an empty numba cache; its output."""
    with tempfile.TemporaryDirectory() as cache:
        return subprocess.run([sys.executable, "-c", code], env=dict(os.environ, NUMBA_CACHE_DIR=cache), check=True,
                              capture_output=True, text=True).stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=25, help="compiled functions listed for the run")
    args = ap.parse_args()
    print("Cold run of the main job (evolve, the DOP853 core compiled first in the same process):")
    print(textwrap.indent(fresh(f"TOP = {args.top}\n" + _RUN), "  "))
    print("Compiling a caller of compiled kernels:")
    for label, slicing in (("a loop calling both (both already compiled)", False),
                           ("the same loop with one array slice assignment", True)):
        out = fresh(f"LABEL, SLICE = {label!r}, {slicing}\n" + _LINKING)
        print(textwrap.indent(out if not slicing else out.splitlines()[-1] + "\n", "  "))


if __name__ == "__main__":
    main()
