r"""``evolve_many``: a population of binaries, each integrated to one end, in one compiled parallel loop.

What population studies need from each binary is one state: the spins and ℓ̂ at a target frequency
(forward or backward from f_ref), or the state at the end of the inspiral.  :func:`evolve_many` gives
exactly what :func:`pnrotor.pn.evolve.evolve` would give for that state, binary by binary:

* each binary's inputs are checked and its system built by the same stages as ``evolve``
  (:func:`~pnrotor.pn.settings.settings`, :func:`~pnrotor.pn.evolve.build_system`,
  :func:`~pnrotor.pn.evolve.half`); a binary whose inputs are invalid gets termination ``'invalid'``
  and the error's text as its message, NaN in its state, and the others go on;
* the integrations run in one ``numba.prange`` loop over the binaries (threads across cores), each a call
  of the DOP853 core with output of the final state only, grouped by right-hand side (the [v, Φ]
  system of nonspinning and aligned binaries, the precessing one);
* the final state becomes (v, Φ, χ₁, χ₂, R, ℓ̂) by the kernel of :func:`pnrotor.pn.sampling.sample`.

The results are bitwise those of single ``evolve`` calls (tests/test_pn_many.py): the same parameter
vector, initial state, tolerances, controller and events go to the same compiled core.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange

from ..ode import AFTER_STEP_SIG, by_address
from ..ode.dop853 import IV_EVENT, IV_NFEV, IV_NOUT, IV_NSTEPS, IV_STATUS, OUT_FINAL, _dop853_core, no_after_step
from .evolve import _CONTROLLER, TERMINATION_MESSAGES, _tolerances, build_system, half, termination
from .sampling import _fill_history, output_mode
from .settings import settings

__all__ = ["evolve_many", "Population"]


@dataclass
class Population:
    """The end state of every binary of :func:`evolve_many` (row i is binary i; NaN where ``termination``
    is ``'invalid'``).

    Attributes
    ----------
    t : (N,) time of the state in units of each binary's total mass M (t = 0 at f_ref)
    t_seconds : (N,) the same in seconds
    v, Phi : (N,) PN parameter and orbital phase (Φ = 0 at f_ref)
    chi1, chi2 : (N, 3) dimensionless spins, inertial frame
    R : (N, 4) unit orbital-frame rotor (n̂ = R x̂ R⁻¹, ℓ̂ = R ẑ R⁻¹)
    ell_hat : (N, 3) orbital angular momentum direction
    termination : (N,) str — why each integration stopped (:mod:`pnrotor.pn.evolve`), or ``'invalid'``
    message : (N,) str — the termination's message, or the error naming the bad input
    nsteps, nfev : (N,) int — the integrator's step attempts and right-hand-side evaluations
    inputs : dict — the options shared by every binary
    """

    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: np.ndarray
    message: np.ndarray
    nsteps: np.ndarray
    nfev: np.ndarray
    inputs: dict = field(default_factory=dict)

    def __len__(self):
        return self.t.size


@njit(parallel=True, cache=True)
def _integrate_all(rhs, after_step, events, Y0, P, t_end, directions, atol, rtol, max_steps, safety,
                   min_factor, max_factor, mode, R0, ell0, c1, c2, rows, t, v, Phi, chi1, chi2, R, ell, counts,
                   no_t, no_coef, out_mode, want_dense):
    """Binary k of the group (state Y0[k], parameters P[k]) integrated to its end; its final state into row
    rows[k] of the outputs (t, v, …, ℓ̂) and (status, event index, step attempts, evaluations) into
    counts[rows[k]]; ``no_t`` (empty) and ``no_coef`` stand for the unused times and dense output, and
    ``out_mode`` (OUT_FINAL), ``want_dense`` (False) come as arguments so that the core is called with the
    types of its one signature (written as constants here, numba compiled a second core, ~7 s)."""
    n_events = directions.shape[1]
    for k in prange(Y0.shape[0]):
        t_out, y_out, _, _, _, iv, _, _ = _dop853_core(
            rhs, after_step, events, 0.0, Y0[k], t_end[k], P[k], atol, rtol, 0.0, np.inf, max_steps, no_t,
            out_mode, want_dense, n_events, directions[k], safety, min_factor, max_factor)
        last = iv[IV_NOUT] - 1
        i = rows[k]
        t[i] = t_out[last]
        _fill_history(mode, no_t, no_t, no_coef, no_t, False, y_out[last:last + 1], R0[k], ell0[k], c1[k],
                      c2[k], i, v, Phi, chi1, chi2, R, ell)
        counts[i, 0] = iv[IV_STATUS]
        counts[i, 1] = iv[IV_EVENT]
        counts[i, 2] = iv[IV_NSTEPS]
        counts[i, 3] = iv[IV_NFEV]


def _per_binary(x, n, name, shape=()):
    """x broadcast to (n,) + shape as float64, or a ValueError naming the parameter."""
    try:
        return np.ascontiguousarray(np.broadcast_to(np.asarray(x, dtype=np.float64), (n,) + shape))
    except (TypeError, ValueError):
        want = "(N,) or a scalar" if not shape else f"(N, {shape[0]}) or ({shape[0]},)"
        raise ValueError(f"{name} must have shape {want} with N = {n} binaries, "
                         f"got {np.shape(x)}") from None


def evolve_many(m1, m2, chi1, chi2, f_ref, *, f_end=None, ell_hat=(0.0, 0.0, 1.0), n_hat=(1.0, 0.0, 0.0),
                kappa1=1.0, kappa2=1.0, approximant="T4", pn_order=3.5, spin_orbit_order=None,
                spin_spin_order=None, atol=1e-12, rtol=0.0, rotor="coprecessing", precession_phase_shift=None,
                integrate_rotor=False, precession="averaged", max_steps=2_000_000):
    r"""Evolve N binaries from f_ref to one end each → :class:`Population` (module docstring).

    Parameters
    ----------
    m1, m2, f_ref : array_like (N,) or scalar
        Masses (M☉) and reference GW frequencies (Hz), as for :func:`~pnrotor.pn.evolve.evolve`.
    chi1, chi2 : array_like (N, 3) or (3,)
        Spins at f_ref, inertial frame.
    f_end : None, scalar or array_like (N,)
        The GW frequency to integrate to: above f_ref forward (``evolve``'s f_max), below f_ref backward
        (its f_min); None (or NaN for a binary) integrates forward to the end of the inspiral.
    ell_hat, n_hat : array_like (N, 3) or (3,)
        ℓ̂ and n̂ at f_ref.
    kappa1, kappa2 : array_like (N,) or scalar
        Spin-induced quadrupole constants.
    approximant, pn_order, spin_orbit_order, spin_spin_order, atol, rtol, rotor, precession_phase_shift, \
integrate_rotor, precession, max_steps
        As for :func:`~pnrotor.pn.evolve.evolve`, shared by all binaries.

    The number of threads is numba's (``numba.set_num_threads``, ``NUMBA_NUM_THREADS``).  Invalid shared
    options raise a ValueError; an invalid binary does not (module docstring).
    """
    try:
        shape = np.broadcast_shapes(np.shape(m1), np.shape(m2), np.shape(f_ref))
    except ValueError:
        shape = ()
    if len(shape) != 1 or shape[0] == 0:
        raise ValueError(f"m1, m2 and f_ref must be 1-D arrays of the same length N >= 1 (one per binary) or "
                         f"scalars, got shapes {np.shape(m1)}, {np.shape(m2)}, {np.shape(f_ref)}")
    n = shape[0]
    m1a, m2a, fref = (_per_binary(x, n, name) for x, name in ((m1, "m1"), (m2, "m2"), (f_ref, "f_ref")))
    fend = _per_binary(np.nan if f_end is None else f_end, n, "f_end")
    k1, k2 = _per_binary(kappa1, n, "kappa1"), _per_binary(kappa2, n, "kappa2")
    c1, c2, ell, nh = (_per_binary(x, n, name, (3,)) for x, name in
                       ((chi1, "chi1"), (chi2, "chi2"), (ell_hat, "ell_hat"), (n_hat, "n_hat")))
    shared = dict(approximant=approximant, pn_order=pn_order, spin_orbit_order=spin_orbit_order,
                  spin_spin_order=spin_spin_order, atol=atol, rtol=rtol, sampling="final", rotor=rotor,
                  precession_phase_shift=precession_phase_shift, integrate_rotor=integrate_rotor,
                  precession=precession, max_steps=max_steps)
    # the shared options fail for every binary alike: check them once, with a reference binary (a binary of the
    # table could itself be invalid, which must not raise)
    approximant = settings(10.0, 10.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 20.0, f_min=None, f_max=None,
                           ell_hat=(0.0, 0.0, 1.0), n_hat=(1.0, 0.0, 0.0), kappa1=1.0, kappa2=1.0,
                           **shared).approximant

    out = Population(t=np.full(n, np.nan), t_seconds=np.full(n, np.nan), v=np.full(n, np.nan),
                     Phi=np.full(n, np.nan), chi1=np.full((n, 3), np.nan), chi2=np.full((n, 3), np.nan),
                     R=np.full((n, 4), np.nan), ell_hat=np.full((n, 3), np.nan),
                     termination=np.full(n, "invalid", dtype=object), message=np.full(n, "", dtype=object),
                     nsteps=np.zeros(n, dtype=np.int64), nfev=np.zeros(n, dtype=np.int64),
                     inputs={k: v for k, v in shared.items() if k != "sampling"})
    groups, ends, M_sec = {}, [None] * n, np.full(n, np.nan)
    for i in range(n):
        forward = not fend[i] < fref[i]   # NaN (no f_end) integrates forward
        target = None if math.isnan(fend[i]) else float(fend[i])
        try:
            s = settings(m1a[i], m2a[i], c1[i], c2[i], fref[i], f_min=None if forward else target,
                         f_max=target if forward else None, ell_hat=ell[i], n_hat=nh[i], kappa1=k1[i],
                         kappa2=k2[i], **shared)
            system = build_system(s)
        except ValueError as e:
            out.message[i] = str(e)
            continue
        p, t_end, directions, ends[i] = half(s, system, forward)
        M_sec[i] = s.M_sec
        key = (system.rhs, system.events, output_mode(s), system.y0.size)
        groups.setdefault(key, []).append((i, system.y0, p, t_end, directions, s))
    counts = np.zeros((n, 4), dtype=np.int64)
    after_step = by_address(no_after_step, AFTER_STEP_SIG)
    for (rhs, events, mode, size), members in groups.items():
        atol_a, rtol_a = _tolerances(size, float(atol), float(rtol))
        rows, y0, p, t_end, directions, ss = zip(*members)
        _integrate_all(rhs, after_step, events, np.array(y0), np.array(p), np.array(t_end), np.array(directions),
                       atol_a, rtol_a, int(max_steps), *_CONTROLLER, mode,
                       np.array([s.R0 for s in ss]), np.array([s.ell_hat for s in ss]),
                       np.array([s.chi1 for s in ss]), np.array([s.chi2 for s in ss]),
                       np.array(rows, dtype=np.int64), out.t, out.v, out.Phi, out.chi1, out.chi2, out.R,
                       out.ell_hat, counts, np.empty(0), np.empty((1, 8, 1)), OUT_FINAL, False)
    for i in range(n):
        if ends[i] is not None:
            status, event = counts[i, :2]
            out.termination[i] = termination(status, event, ends[i], approximant)
            out.message[i] = TERMINATION_MESSAGES[out.termination[i]]
    out.nsteps[:], out.nfev[:] = counts[:, 2], counts[:, 3]
    out.t_seconds[:] = out.t * M_sec
    return out
