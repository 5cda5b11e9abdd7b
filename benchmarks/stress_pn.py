r"""Post-Newtonian extremes of ``pnrotor.evolve``: what happens at the corners of its parameter space.

Every run goes through :func:`run`, which calls ``evolve`` and checks the invariants of its result:
a crash is an exception (a ``ValueError`` too, except in the cases that start past the end of the
inspiral, where a clear input error is the expected outcome), a non-finite value in any output array, a
v that does not increase, a ``'nonfinite'`` termination, or a termination name outside the documented
set.  The measured errors are

* spin drift: max over t and i of ||χᵢ(t)| − |χᵢ(0)|| (the precession conserves |χᵢ|);
* ℓ̂ opening: the angle between ℓ̂(t) and ℓ̂(0) (at the end, or its maximum over the history);
* ΔΦ: the phase difference between two runs that should agree.

Cases: mass ratios q = 1, 20, 100 (nonspinning and precessing); |χ| = 0.999 aligned, anti-aligned and
in-plane; the up-down configuration (exact, and with χ₁ tilted by 1e-8 rad, against up-up with the
same tilt); spins exactly zero vs 1e-300; a 1.4 + 1.4 M☉ binary neutron star from 10 Hz sampled
'final', 'steps' and at Δt = 1/4096 s (wall time, steps, peak memory); starting at or past the end of
the PN inspiral; and a sweep of random precessing binaries.

``cases(quick=False)`` yields one row per case (keys: area, case, tried, crashes, outcome,
worst_error, growth) for benchmarks/stress.py, which prints the table:

    python benchmarks/stress.py --only pn [--quick]
"""

import math
import time
import tracemalloc
from collections import Counter

import numpy as np

from pnrotor import evolve
from pnrotor.pn.evolve import TERMINATION_MESSAGES
from pnrotor.pn.initial import MTSUN_SI

APPROXIMANTS = ("T1", "T4", "T5")
FAILURES = ("nonfinite",)             # named, but a non-finite state: counted as a crash
Z = np.array([0.0, 0.0, 1.0])
TILT = 1e-8
SWEEP_SEED = 20261124
SWEEP_V_REF_MAX = 0.3                  # f_ref is lowered to v = 0.3 if above (below every end of the inspiral)


def angle(a, b):
    """Angle between (arrays of) 3-vectors, accurate for tiny angles."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def tilted(chi, tilt):
    """A spin of magnitude chi along ẑ tilted by ``tilt`` rad towards x̂ (chi < 0: along −ẑ)."""
    return [abs(chi) * math.sin(tilt), 0.0, chi * math.cos(tilt)]


def run(m1, m2, chi1, chi2, f_ref, may_refuse=False, **kw):
    """One ``evolve`` call → dict: ``outcome`` (termination name, 'ValueError' or the exception type),
    ``crash``, ``message``, ``wall`` (s), ``e`` (the Evolution or None) and, for a result,
    ``spin_drift``, ``ell_end`` (∠(ℓ̂(end), ℓ̂(0))), ``ell_max`` (its max over the history),
    ``finite``, ``nsteps``.  A ValueError is a crash unless ``may_refuse``."""
    t0 = time.perf_counter()
    try:
        e = evolve(m1, m2, chi1, chi2, f_ref, **kw)
    except ValueError as exc:
        return dict(outcome="ValueError", crash=not may_refuse, message=str(exc), wall=time.perf_counter() - t0,
                    e=None)
    except Exception as exc:   # noqa: BLE001 — any other exception is what this module counts
        return dict(outcome=type(exc).__name__, crash=True, message=str(exc), wall=time.perf_counter() - t0,
                    e=None)
    wall = time.perf_counter() - t0
    arrays = (e.t, e.t_seconds, e.v, e.Phi, e.chi1, e.chi2, e.R, e.ell_hat)
    finite = all(np.all(np.isfinite(a)) for a in arrays) and len(e) > 0
    named = e.termination in TERMINATION_MESSAGES and e.stats["termination_backward"] in TERMINATION_MESSAGES
    chi0 = [np.linalg.norm(np.asarray(c, dtype=float)) for c in (chi1, chi2)]
    with np.errstate(invalid="ignore"):
        drift = max(float(np.max(np.abs(np.linalg.norm(x, axis=1) - c))) for x, c in zip((e.chi1, e.chi2), chi0))
        ell = angle(e.ell_hat, np.asarray(e.inputs["ell_hat"]))
    increasing = bool(np.all(np.diff(e.v) > 0))
    return dict(outcome=e.termination, crash=not (finite and named and increasing) or e.termination in FAILURES,
                message="", wall=wall, e=e, spin_drift=drift, ell_end=float(ell[-1]), ell_max=float(np.max(ell)),
                finite=finite, nsteps=e.stats["nsteps"])


def counts(runs):
    """'name ×k, …' over the runs' outcomes."""
    return ", ".join(f"{k} ×{n}" for k, n in Counter(r["outcome"] for r in runs).most_common())


def worst(runs, key):
    vals = [r[key] for r in runs if key in r]
    return max(vals) if vals else None


def span(runs, key, fmt):
    vals = [r[key] for r in runs if key in r]
    if not vals:
        return "—"
    lo, hi = min(vals), max(vals)
    return fmt.format(lo) if fmt.format(lo) == fmt.format(hi) else fmt.format(lo) + "–" + fmt.format(hi)


def row(area, case, runs, error=None, growth="—", note=""):
    """One table row from a list of :func:`run` results (``error``: the worst error, named in ``case``)."""
    outcome = counts(runs) + (f"; {note}" if note else "")
    return dict(area=area, case=case, tried=len(runs), crashes=sum(r["crash"] for r in runs), outcome=outcome,
                worst_error=error, growth=growth)


def v_end(runs):
    return [dict(v=float(r["e"].v[-1])) for r in runs if r["e"] is not None]


# ---------------------------------------------------------------------------------------------------
# cases
# ---------------------------------------------------------------------------------------------------

PRECESSING = ([0.6, 0.0, 0.3], [-0.3, 0.5, 0.1])


def mass_ratio_cases(quick):
    """q = 1, 20, 100 with m₂ = 1 M☉ from 20 Hz, T1/T4/T5, nonspinning and precessing."""
    for q in (1, 20, 100):
        m1, m2 = float(q), 1.0
        M = (m1 + m2) * MTSUN_SI
        v_ref = (math.pi * M * 20.0) ** (1 / 3)
        for label, (c1, c2) in (("nonspinning", ([0, 0, 0], [0, 0, 0])), ("precessing χ₁ = (0.6, 0, 0.3), "
                                                                          "χ₂ = (−0.3, 0.5, 0.1)", PRECESSING)):
            runs = [run(m1, m2, c1, c2, 20.0, approximant=a) for a in APPROXIMANTS]
            note = (f"v_ref {v_ref:.3f} → v_end {span(v_end(runs), 'v', '{:.3f}')}; "
                    f"{span(runs, 'nsteps', '{:d}')} steps, {span(runs, 'wall', '{:.3f}')} s")
            if q == 100:
                note += "; the whole run lies beyond v = 0.3 and ends past the test-mass ISCO v = 1/√6 = 0.408"
            case = f"q = {q} ({m1:g} + {m2:g} M☉), {label}, 20 Hz, T1/T4/T5"
            if label == "nonspinning":
                yield row("PN mass ratio", case + " [error: ∠(ℓ̂, ℓ̂₀)]", runs, worst(runs, "ell_max"), note=note)
            else:
                yield row("PN mass ratio", case + " [error: max ||χ|−|χ₀||]", runs, worst(runs, "spin_drift"),
                          note=note)


def spin_cases(quick):
    """|χ| = 0.999 aligned, anti-aligned, in-plane (precessing state throughout), 30 + 10 M☉ from 20 Hz."""
    a = 0.999
    for label, c1, c2 in (("aligned ↑↑", [0, 0, a], [0, 0, a]), ("anti-aligned ↓↓", [0, 0, -a], [0, 0, -a]),
                          ("in-plane χ₁ ∥ x̂, χ₂ ∥ ŷ", [a, 0, 0], [0, a, 0])):
        runs = [run(30.0, 10.0, c1, c2, 20.0, f_min=10.0, approximant=ap, integrate_rotor=True)
                for ap in APPROXIMANTS]
        note = f"ℓ̂ moves up to {span(runs, 'ell_max', '{:.2g}')} rad; v_end {span(v_end(runs), 'v', '{:.3f}')}"
        yield row("PN spin", f"|χ| = 0.999 {label}, 30 + 10 M☉, 10–20 Hz →, T1/T4/T5, precessing state "
                  "[error: max ||χ|−|χ₀||]", runs, worst(runs, "spin_drift"), note=note)


def stall_cases(quick):
    """T4 with |χ| = 0.999 aligned: N (the re-expanded F̂/Ê′) has a simple root at v* = 0.6305, where
    v̇ ∝ v* − v and v would approach v* only exponentially (the final Φ used to depend on atol by tens of
    radians); the run ends where v̇(v) peaks ('vdot_peak'), before v*."""
    runs = [run(30.0, 10.0, [0, 0, 0.999], [0, 0, 0.999], 20.0, approximant="T4", atol=atol, integrate_rotor=irot)
            for atol in (1e-10, 1e-12, 1e-14) for irot in (False, True)]
    phi = [float(r["e"].Phi[-1]) for r in runs]
    yield row("PN spin", "|χ| = 0.999 aligned ↑↑, 30 + 10 M☉ from 20 Hz, T4, atol 1e-10/1e-12/1e-14 × aligned/"
              "precessing state: the end before the root v* = 0.6305 of T4's flux ratio [error: spread of Φ at "
              "the end (rad)]", runs, max(phi) - min(phi), note=f"v_end {span(v_end(runs), 'v', '{:.6f}')}")


def up_down_cases(quick):
    """Up-down (χ₁ ↑, χ₂ ↓ along ℓ̂; unstable for r < r_ud+ = (√χ₁ + √(qχ₂))⁴/(1 − q)² M, Gerosa et al.
    2015: 27.6 M here, v > 0.19) exact and tilted by 1e-8 rad, against up-up with the same tilt."""
    m1, m2, a = 20.0, 10.0, 0.9
    exact = [run(m1, m2, [0, 0, a], [0, 0, -a], f, integrate_rotor=True) for f in (5.0, 10.0, 20.0)]
    yield row("PN up-down", "χ₁ = 0.9ẑ, χ₂ = −0.9ẑ exactly, 20 + 10 M☉ from 5/10/20 Hz, precessing state "
              "[error: max ∠(ℓ̂, ẑ)]", exact, worst(exact, "ell_max"))
    for label, c2 in (("up-down χ₂ = −0.9ẑ", [0, 0, -a]), ("up-up χ₂ = 0.9ẑ", [0, 0, a]), ("χ₂ = 0", [0, 0, 0])):
        runs = [run(m1, m2, tilted(a, TILT), c2, f) for f in (5.0, 10.0, 20.0)]
        tilt_end = [dict(t=float(angle(r["e"].chi1[-1], r["e"].ell_hat[-1]))) for r in runs if r["e"] is not None]
        growth = (f"from a 1e-8 rad tilt: ℓ̂ opens {span(runs, 'ell_end', '{:.2g}')} rad, χ₁'s tilt from ℓ̂ "
                  f"ends at {span(tilt_end, 't', '{:.2g}')} rad")
        yield row("PN up-down", f"χ₁ = 0.9 tilted 1e-8 rad from ẑ, {label}, 20 + 10 M☉ from 5/10/20 Hz "
                  "[error: ℓ̂ opening at the end]", runs, worst(runs, "ell_end"), growth=growth)


def tiny_spin_cases(quick):
    """Spins exactly zero vs 1e-300 (and 1e-13 in-plane, just above the aligned threshold |χ⊥|² ≤ 1e-28)."""
    kw = dict(f_min=10.0, integrate_rotor=True)
    for approximant in APPROXIMANTS:
        ref = run(30.0, 10.0, [0, 0, 0], [0, 0, 0], 20.0, approximant=approximant, **kw)
        for label, c in (("1e-300 along (1, 1, 1)", [1e-300] * 3), ("1e-13 in-plane", [1e-13, 0, 0])):
            r = run(30.0, 10.0, c, c, 20.0, approximant=approximant, **kw)
            if r["e"] is not None and ref["e"] is not None:
                n = min(len(r["e"]), len(ref["e"]))
                r["dphi"] = float(np.max(np.abs(r["e"].Phi[:n] - ref["e"].Phi[:n])))
                r["content"] = r["e"].inputs["spin_content"]
            yield row("PN tiny spins", f"χ₁ = χ₂ = {label} vs exactly 0, 30 + 10 M☉, 10–20 Hz →, {approximant}, "
                      "precessing state [error: max |ΔΦ| (rad)]", [ref, r], r.get("dphi"),
                      note=f"classified {r.get('content')}; lengths {len(ref['e'])} vs {len(r['e'])}")


HISTORY_BYTES = 17 * 8   # t, t_seconds, v, Φ, χ₁(3), χ₂(3), R(4), ℓ̂(3): 17 float64 per sample


def bns_cases(quick):
    """1.4 + 1.4 M☉ from 10 Hz: wall time, steps and the peak of numpy allocations (tracemalloc; the
    integrator's numba buffers, ∝ steps, are not traced) per sampling."""
    final = {}
    for label, chi, samplings in (("nonspinning", [0, 0, 0], ("final", "steps", 1 / 4096)),
                                  ("precessing χ₁ = χ₂ = (0.05, 0, 0.02)", [0.05, 0, 0.02], ("final", "steps"))):
        for sampling in samplings:
            tracemalloc.start()
            r = run(1.4, 1.4, chi, chi, 10.0, sampling=sampling)
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            e = r["e"]
            name = sampling if isinstance(sampling, str) else "Δt = 1/4096 s"
            error, growth = None, "—"
            if e is not None:
                if sampling == "final":
                    final[label] = e
                    # the same run from 20 Hz: 'final' memory must not grow with the length of the run
                    tracemalloc.start()
                    evolve(1.4, 1.4, chi, chi, 20.0, sampling="final")
                    peak20 = tracemalloc.get_traced_memory()[1]
                    tracemalloc.stop()
                    growth = f"peak {peak20} B from 20 Hz vs {peak} B from 10 Hz (bounded: 1 sample)"
                else:
                    if sampling == "steps":
                        error = float(abs(e.v[-1] - final[label].v[0]) + abs(e.Phi[-1] - final[label].Phi[0]))
                    growth = (f"∝ samples: {HISTORY_BYTES} B × {len(e)} = {HISTORY_BYTES * len(e) / 1e6:.3g} MB kept, "
                              f"peak {peak / len(e):.0f} B/sample")
            note = (f"{len(e)} samples, {e.stats['nsteps']} steps, {r['wall']:.3f} s, peak {peak / 1e6:.3g} MB"
                    if e is not None else r["message"])
            error_name = " [error: |Δv| + |ΔΦ| at the end vs 'final']" if sampling == "steps" else ""
            yield row("PN BNS memory", f"1.4 + 1.4 M☉ from 10 Hz, {label}, sampling {name}{error_name}", [r],
                      error, growth=growth, note=note)


def validity_cases(quick):
    """30 + 30 M☉ at f_ref beyond the end of the inspiral, and restarted exactly at (and 1e-6 around)
    the frequency where a run from 20 Hz terminated: a ValueError naming f_ref or a named termination."""
    spins = (("nonspinning", ([0, 0, 0], [0, 0, 0])), ("precessing", PRECESSING),
             ("anti-aligned 0.99", ([0, 0, -0.99], [0, 0, -0.99])))
    for label, (c1, c2) in spins:
        runs = [run(30.0, 30.0, c1, c2, f, may_refuse=True, approximant=a) for a in APPROXIMANTS
                for f in (100.0, 300.0, 500.0, 1000.0)]
        unclear = [r for r in runs if r["outcome"] == "ValueError" and "f_ref" not in r["message"]]
        yield row("PN end of validity", f"30 + 30 M☉, {label}, f_ref = 100/300/500/1000 Hz, T1/T4/T5", runs,
                  note=f"{len(unclear)} ValueErrors without 'f_ref'")
        restarts = []
        for a in APPROXIMANTS:
            e = evolve(30.0, 30.0, c1, c2, 20.0, approximant=a, sampling="final")
            end = dict(ell_hat=e.ell_hat[-1], n_hat=e.n_hat[-1], approximant=a, sampling="final")
            restarts += [run(30.0, 30.0, e.chi1[-1], e.chi2[-1], e.f_gw[-1] * (1 + d), may_refuse=True, **end)
                         for d in (-1e-6, 0.0, 1e-6)]
        yield row("PN end of validity", f"30 + 30 M☉, {label}: restart from the end state of a 20 Hz run at its "
                  "frequency × (1 − 1e-6, 1, 1 + 1e-6), T1/T4/T5", restarts,
                  note=f"{span(restarts, 'nsteps', '{:d}')} steps when integrated")


def random_binaries(n, seed=SWEEP_SEED):
    """n random (m1, m2, χ₁, χ₂, f_ref, approximant): m in [1, 100] M☉ with q ≤ 20, isotropic spin
    directions with |χ| uniform in [0, 0.99], f_ref uniform in [10, 60] Hz lowered to v = 0.3 if above."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        m1, m2 = sorted(rng.uniform(1.0, 100.0, 2), reverse=True)
        if m1 / m2 > 20.0:
            continue
        d = rng.normal(size=(2, 3))
        chi = d / np.linalg.norm(d, axis=1)[:, None] * rng.uniform(0.0, 0.99, (2, 1))
        f_cap = SWEEP_V_REF_MAX ** 3 / (math.pi * (m1 + m2) * MTSUN_SI)
        f_ref = min(rng.uniform(10.0, 60.0), f_cap)
        out.append((float(m1), float(m2), chi[0], chi[1], f_ref, APPROXIMANTS[len(out) % 3]))
    return out


def sweep_cases(quick):
    n = 100 if quick else 5000
    binaries = random_binaries(n)
    t0 = time.perf_counter()
    runs = [run(m1, m2, c1, c2, f, approximant=a, sampling="final") for m1, m2, c1, c2, f, a in binaries]
    wall = time.perf_counter() - t0
    yield row("PN random binaries", f"{n} random precessing binaries (seed {SWEEP_SEED}), m ∈ [1, 100] M☉, q ≤ 20, "
              "|χ| ≤ 0.99 isotropic, f_ref ∈ [10, 60] Hz (v ≤ 0.3), T1/T4/T5, sampling 'final' "
              "[error: max ||χᵢ(end)|−|χᵢ(0)||]", runs, worst(runs, "spin_drift"),
              note=f"R finite in {sum(r.get('finite', False) for r in runs)}; {n / wall:.0f} runs/s "
                   f"({wall:.1f} s); max {worst(runs, 'nsteps')} steps")


SECTIONS = (mass_ratio_cases, spin_cases, stall_cases, up_down_cases, tiny_spin_cases, bns_cases, validity_cases,
            sweep_cases)


def cases(quick=False):
    """Yield the table rows (dicts with area, case, tried, crashes, outcome, worst_error, growth)."""
    evolve(10.0, 10.0, [0.1, 0, 0], [0, 0, 0], 20.0, sampling="final")   # load the compiled code first
    for section in SECTIONS:
        yield from section(quick)

