r"""``evolve_many``: a population of binaries, each integrated to one end, in a compiled loop on pnrotor's threads.

What population studies need from each binary is one state or a few: the spins and ℓ̂ at a target
frequency (forward or backward from f_ref), the state at a list of frequencies, or the state at the end of
the inspiral.  :func:`evolve_many` gives exactly what :func:`pnrotor.pn.evolve.evolve` would give for each
of those states, binary by binary:

* per chunk of :data:`CHUNK` binaries, the inputs are checked and converted as ``evolve``'s first stage would
  (the shared options once), for all binaries in one pass of numpy (:func:`~pnrotor.pn.settings.population_settings`,
  bitwise each binary's :func:`~pnrotor.pn.settings.binary_settings`; a binary it does not pass goes to
  binary_settings, which words the refusal); the part of the parameter vectors that depends on the masses and κᵢ
  alone is built in one pass too (:func:`pnrotor.pn.system.spin_independent_parts`), and the parameter vectors,
  initial states and start checks that ``evolve`` builds one at a time (:func:`~pnrotor.pn.evolve.build_system`)
  in one compiled call per right-hand side (:func:`~pnrotor.pn.evolve.build_rows`); a binary whose inputs are
  invalid gets termination ``'invalid'`` and the error's text as its message, NaN in its state, and the others go
  on.  Python per binary is left to libm's pow (v at the frequencies, the Newtonian times:
  :func:`~pnrotor.pn.initial.elementwise`), the screen of the start checks, the end names, and, where they apply,
  a list of frequencies (each binary's targets sorted on either side) and the refusals;
* the integrations run in calls of one compiled ``nogil`` loop, eight halves per call, per right-hand side and
  chunk, on :mod:`pnrotor.threads`' threads (numba's thread count, :func:`pnrotor.threads.thread_count`), each
  a call of the DOP853 core with output of the final state only (and of the dense output where a list has
  nearer targets), grouped by right-hand side (the [v, Φ] system of nonspinning and aligned binaries, the
  precessing one);
* the final state becomes (v, Φ, χ₁, χ₂, R, ℓ̂) by the kernel of :func:`pnrotor.pn.sampling.sample`.

A list of K frequencies costs one integration per direction, not K: each half runs to its farthest target
with dense output, and every nearer target is found on the step that crosses it as the integrator would
find its terminal event there (:func:`_nearer_targets`).

The results are bitwise those of single ``evolve`` calls (tests/test_pn_many.py): the same parameter
vector, initial state, tolerances, controller and events go to the same compiled core; a nearer target is
located by the same root finder on the same step's interpolant from the same event values, since a run to a
farther v takes the same steps up to there (the events do not change the steps).  One proviso: the backward
half runs within the time bound of its farthest target, which is longer than a nearer target's (2× the
Newtonian time, :func:`~pnrotor.pn.evolve.half`); a single run that hit its own bound would end sooner.
"""

import dataclasses
import gc
import math
import time
from contextlib import contextmanager

import numpy as np
from numba import njit

from .. import numba_cache, threads
from ..ode.common import (FV_TEVENT, IV_EVENT, IV_NFEV, IV_NOUT, IV_NSEG, IV_NSTEPS, IV_STATUS, OUT_FINAL,
                          default_hook, events_function, function_addresses)
from ..ode.dop853 import core as dop853_core
from ..ode.events import crossed, locate_root
from ..ode.result import STATUS_EVENT, contd8
from . import initial as _ini
from ..options import OPTION_DEFAULTS, TABLE_OPTIONS, Options, options_of
from .evolve import (CONTROLLER_ARGS, TERMINATION_MESSAGES, check_start, ended_at, tolerances, build_rows, end_name,
                     half, kmax_of, population_parts, termination, warn_if_unresolved)
from .sampling import fill_history, output_mode
from .settings import Binaries, binary_settings, checked, population_settings, target_v
from .inputs import from_frame, is_frame, per_binary, population_size, target_table
from .layout import EV_V_END, N_EVENTS, P_VEND
from pnrotor.results.populations import FIELDS, INSPIRAL_ENDS, STATE, Population, spin_angles

__all__ = ["evolve_many", "Population", "spin_angles", "INSPIRAL_ENDS"]

CHUNK = 4096
"""Binaries prepared and integrated together: bounds the memory of their parameter vectors (~10 kB each)."""
_HALVES = 8
"""Halves a thread integrates per call of :func:`_integrate_all`: 1-2 ms of integration for a call's ~3 µs of
dispatch, and at most that left for one thread at the end (or after an interrupt)."""



PER_BINARY = ("m1_Msun", "m2_Msun", "chi1", "chi2", "f_ref_Hz", "ell_hat", "n_hat", "kappa1", "kappa2", "lambda1",
              "lambda2", "f_end_Hz", "frequencies_Hz")
"""The inputs of a :class:`Population` given per binary (its other inputs are the options all binaries share)."""


@njit(nogil=True, cache=True)
def _integrate_all(lo, hi, functions, Y0, P, t_end, directions, atol, rtol, max_steps, safety,
                   min_factor, max_factor, mode, R0, ell0, c1, c2, rows, near_v, near_rows, t, v, Phi, chi1, chi2,
                   R, ell, counts, no_t, out_mode):
    """Each half k = lo … hi−1 of the group (state Y0[k], parameters P[k]) integrated by the DOP853 core with
    ``functions`` (:data:`pnrotor.ode.common.FUNCTIONS_LAYOUT`) to its end; its final state into row rows[k] of the
    outputs (t, v, …, ℓ̂) and (status, event index, step attempts, evaluations) into
    counts[rows[k]]; the states at the nearer targets v = near_v[k, j] into the rows near_rows[k, j] (−1:
    none), by :func:`_nearer_targets` on the dense output, computed only for halves that have them.  ``no_t``
    (empty) stands for the unused times, and ``out_mode`` (OUT_FINAL) comes as an argument so that the core is
    called with the types of its one signature (written as a constant here, numba compiled a second core,
    ~7 s)."""
    n_events = directions.shape[1]
    events = events_function(functions[4], functions[5])
    for k in range(lo, hi):
        want_dense = near_rows.shape[1] > 0 and near_rows[k, 0] >= 0
        t_out, y_out, seg_t, seg_h, seg_c, iv, fv, _ = dop853_core(
            functions, 0.0, Y0[k], t_end[k], P[k], atol, rtol, 0.0, np.inf, max_steps, no_t,
            out_mode, want_dense, n_events, directions[k], safety, min_factor, max_factor)
        last = iv[IV_NOUT] - 1
        final = y_out[last:last + 1]
        for j in range(-1, near_rows.shape[1]):
            i = rows[k] if j < 0 else near_rows[k, j]
            if i < 0:
                break
            if j < 0:
                ti, yi, status, event = t_out[last], final, iv[IV_STATUS], iv[IV_EVENT]
            else:
                ti, yi, status, event = _nearer_targets(events, P[k], near_v[k, j], directions[k, EV_V_END],
                                                        seg_t, seg_h, seg_c, iv, fv, t_out[last], final)
            t[i] = ti
            fill_history(mode, no_t, no_t, seg_c, no_t, False, yi, R0[k], ell0[k], c1[k], c2[k], i, v, Phi, chi1,
                          chi2, R, ell)
            counts[i, 0] = status
            counts[i, 1] = event
            counts[i, 2] = iv[IV_NSTEPS]
            counts[i, 3] = iv[IV_NFEV]


@njit(cache=True)
def _nearer_targets(events, p_run, v_target, direction, seg_t, seg_h, seg_c, iv, fv, t_final, final):
    """(t, state (1, n), status, event index) that a run stopping at ``v_target`` (event 0 of the events, in
    ``direction``) would end with, from a run to a farther v with dense output: the first step across
    v_target, with the event values v − v_target at its ends (the start of the next step, or y + (y_new − y) =
    y_new for the last one, exact as |v| changes by far less than 2× in a step), the root of the same
    :func:`~pnrotor.ode.events.locate_root` and the same ``contd8``.  Unless another event of that last
    step comes strictly first, as the core decides, or v_target is never crossed: then the run's own end."""
    p = p_run.copy()
    p[P_VEND] = v_target
    n = seg_c.shape[2]
    yint = np.empty(n)
    gtmp = np.empty(N_EVENTS)
    nseg = iv[IV_NSEG]
    for s in range(nseg):
        rc = seg_c[s]
        last = s + 1 == nseg
        g_a = rc[0, 0] - v_target
        g_b = (rc[0, 0] + rc[1, 0] if last else seg_c[s + 1, 0, 0]) - v_target
        if not crossed(g_a, g_b, direction):
            continue
        t_a, h = seg_t[s], seg_h[s]
        t_b = t_a + h if last else seg_t[s + 1]
        root = locate_root(events, p, EV_V_END, t_a, t_b, g_a, g_b, t_a, h, rc, yint, gtmp)
        if last and iv[IV_STATUS] == STATUS_EVENT and iv[IV_EVENT] != EV_V_END and (fv[FV_TEVENT] - root) * h < 0.0:
            break
        y = np.empty((1, n))
        contd8(rc, (root - t_a) / h, y[0])
        return root, y, STATUS_EVENT, EV_V_END
    return t_final, final, iv[IV_STATUS], iv[IV_EVENT]


def _integrate_group(rhs, events, mode, atol, rtol, max_steps, Y0, P, t_end, directions, R0, ell, chi1, chi2, rows,
                     near_v, near_r, out, counts):
    """Halves k = 0 … n−1 of one right-hand side (initial states Y0[k], parameter vectors P[k], t_end[k], event
    directions[k], the run's R₀, ℓ̂, χ₁, χ₂ at f_ref, output row rows[k], nearer targets near_v[k] in rows
    near_r[k]) integrated by :func:`_integrate_all` into the rows of ``out`` and ``counts`` → the seconds its
    compiled loops took.  The loop runs on :func:`pnrotor.threads.run`'s threads (a ``nogil`` kernel), each taking
    the next :data:`_HALVES` halves as it is free: numba's parallel loop (``prange``) ran no faster and took
    longer to compile cold, and an even split left one thread idle at the end."""
    atol_a, rtol_a = tolerances(Y0.shape[1], atol, rtol)
    args = (function_addresses(rhs, default_hook("after_step"), events), Y0, P, t_end, directions,
            atol_a, rtol_a, max_steps, *CONTROLLER_ARGS, mode, R0, ell, chi1, chi2, rows, near_v, near_r, out.t, out.v,
            out.Phi, out.chi1, out.chi2, out.R, out.ell_hat, counts, np.empty(0), OUT_FINAL)
    start = time.perf_counter()
    if not _integrate_all.overloads:   # it is compiled with the DOP853 core inside: load the core that the CLI may
        numba_cache.wait_for_aside("core")   # be compiling in another process, not compile it twice; and here,
        _integrate_all(0, 0, *args)          # once, before the threads call it
    n = Y0.shape[0]
    starts = iter(range(0, n, _HALVES))   # shared by the threads (next() holds the GIL)
    stopped = []   # an exception on one thread (a signal's: the CLI's SIGTERM): the others take no further block

    def work(_lo, _hi):
        try:
            for lo in starts:
                if stopped:
                    return
                _integrate_all(lo, min(lo + _HALVES, n), *args)
        except BaseException:
            stopped.append(True)
            raise

    threads.run(work, [(0, n)] * max(1, min(threads.thread_count(), -(-n // _HALVES))),
                stop=lambda: stopped.append(True))
    return time.perf_counter() - start


@contextmanager
def _collector_paused():
    """Python's cyclic garbage collector paused (restored after): the loop over binaries allocates ~10 objects
    per binary and frees none, so the collections it triggers walk ever more of them, and find no cycle."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _first_error(opts, m1, m2, chi1, chi2, f_ref, f, ell_hat, n_hat, kappa1, kappa2, lambda1, lambda2):
    """The message of the first check ``evolve``'s settings fail for this binary with the target f as f_max (f_min
    below f_ref), or None: for a binary that is invalid, its own message unless the target's check comes first."""
    backward = f < f_ref
    try:
        binary_settings(opts, m1, m2, chi1, chi2, f_ref, f if backward else None, None if backward else f, ell_hat,
                        n_hat, kappa1, kappa2, lambda1, lambda2)
    except ValueError as e:
        return str(e)
    return None


def _refused_targets(f, m1, m2, f_ref):
    """{k: message} of the listed frequencies that ``evolve`` would refuse as f_max or f_min for a binary it
    accepts, by the same check (:func:`~pnrotor.pn.settings.target_v`: v beyond v at f_ref, and within the PN
    range); the binary's other targets go on."""
    refused = {}
    if not (m1 > 0.0 and m2 > 0.0 and math.isfinite(m1 + m2) and 0.0 < f_ref < math.inf):
        return refused    # the binary itself is invalid (settings says why)
    M_sec = _ini.total_mass_seconds(m1, m2)
    v0 = _ini.v_from_frequency(f_ref, M_sec)
    for k, x in enumerate(f):
        try:
            _ini.hertz(x, f"frequencies[{k}]")
            target_v(x, f"frequencies[{k}]", x >= f_ref, f_ref, v0, M_sec)
        except ValueError as e:
            refused[k] = str(e)
    return refused


def evolve_many(m1, m2=None, chi1=None, chi2=None, f_ref=None, *, f_end=None, frequencies=None, ell_hat=(0.0, 0.0, 1.0),
                n_hat=(1.0, 0.0, 0.0), kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0, options=None, **keywords):
    r"""Evolve N binaries from f_ref → :class:`Population` of their states at the end of the inspiral, at
    f_end or at a list of frequencies (module docstring), NaN where a binary did not reach its target (its
    ``reached`` False, the state where it stopped in ``stopped_at``).

    Parameters
    ----------
    m1 : array_like (N,) or scalar, or a pandas DataFrame
        A DataFrame is a table of binaries with the columns of a batch table (`pnrotor.options.COLUMNS`):
        ``m1``, ``m2``, ``chi1``, ``chi2`` (cells of three numbers, or ``"x,y,z"`` text), ``f_ref`` per binary;
        optional ``f_max`` (the state there, forward) or ``f_min`` (backward), at most one per row (NaN: none; with
        neither, the end of the inspiral), instead of f_end; optional columns of the shared options
        (``approximant``, ``pn_order``, ``spin_orbit_order``, ``spin_spin_order``, ``precession``, ``atol``,
        ``tidal_order``, ``horizon_absorption``) holding one value each (empty cells ignored), used as that
        keyword; ``sampling`` empty or ``final``; ``name`` ignored.  m2, chi1, chi2 and f_ref are then not given.
    m1, m2, f_ref : array_like (N,) or scalar
        Masses (M☉) and reference GW frequencies (Hz), as for :func:`~pnrotor.pn.evolve.evolve` (astropy
        Quantities are converted).  N is the length of the inputs given per binary (these, the spins, f_end, …,
        which must agree), 1 if every input is shared.
    chi1, chi2 : array_like (N, 3) or (3,)
        Spins at f_ref, inertial frame.
    f_end : None, scalar or array_like (N,)
        The GW frequency to integrate to: above f_ref forward (``evolve``'s f_max), below f_ref backward
        (its f_min); None (or NaN for a binary) integrates forward to the end of the inspiral.
    frequencies : None or array_like (K,) or (N, K)
        Instead of f_end: K GW frequencies (Hz; shared or per binary), in any order and on either side of
        f_ref; the state at each, as ``evolve`` with f_max (or f_min) there would end.  The outputs gain a K
        axis.  A frequency ``evolve`` would refuse (not finite and positive, f_ref, one that gives its v, or one
        outside the PN range) gives an ``'invalid'`` entry with evolve's message; the binary's other targets go
        on.
    ell_hat, n_hat : array_like (N, 3) or (3,)
        ℓ̂ and n̂ at f_ref.
    kappa1, kappa2 : array_like (N,) or scalar
        Spin-induced quadrupole constants.
    lambda1, lambda2 : array_like (N,) or scalar
        Dimensionless tidal deformabilities Λᵢ (0 for black holes).
    options : Options, optional
        The model and integration options (:class:`pnrotor.Options`), shared by all binaries (with
        ``horizon_absorption`` every binary is on the precessing state, its spins at the state's frequency changed by
        what the horizons absorbed; the masses it leaves are not kept).
    **keywords
        Any field of :class:`pnrotor.Options` by name, replacing that of ``options``.

    Notes
    -----
    The number of threads is :func:`pnrotor.threads.thread_count`'s (numba's: ``numba.set_num_threads``,
    ``NUMBA_NUM_THREADS``; at most :func:`pnrotor.threads.limit`'s).  Invalid shared
    options or array shapes raise a ValueError; an invalid binary does not (module docstring).
    """
    wall0 = time.perf_counter()
    backward = None   # a binary's target behind f_ref (f_min): by default where it lies below f_ref
    if is_frame(m1):
        frame = m1
        fields = dataclasses.asdict(options) if isinstance(options, Options) else {}
        called = {**OPTION_DEFAULTS, **fields, **keywords}   # the call's options by name, for the frame's to agree
        m1, m2, chi1, chi2, f_ref, f_end, backward, lambda1, lambda2 = from_frame(
            frame, dict(m2=m2, chi1=chi1, chi2=chi2, f_ref=f_ref), f_end, frequencies, called,
            dict(lambda1=lambda1, lambda2=lambda2))
        keywords = {**keywords, **{name: called[name] for name in TABLE_OPTIONS if name in frame.columns}}
    else:
        missing = [name for name, x in (("m2", m2), ("chi1", chi1), ("chi2", chi2), ("f_ref", f_ref)) if x is None]
        if missing:
            raise TypeError(f"evolve_many() missing {', '.join(missing)} (or give m1 as a pandas DataFrame)")
    n = population_size(dict(m1=m1, m2=m2, f_ref=f_ref, kappa1=kappa1, kappa2=kappa2, lambda1=lambda1,
                              lambda2=lambda2, f_end=f_end),
                         dict(chi1=chi1, chi2=chi2, ell_hat=ell_hat, n_hat=n_hat), dict(frequencies=frequencies))
    m1a, m2a, fref = (per_binary(x, n, name, unit=unit) for x, name, unit in
                      ((m1, "m1", "M_sun"), (m2, "m2", "M_sun"), (f_ref, "f_ref", "Hz")))
    targets, listed = target_table(f_end, frequencies, n)
    K = targets.shape[1]
    k1, k2 = per_binary(kappa1, n, "kappa1"), per_binary(kappa2, n, "kappa2")
    l1, l2 = per_binary(lambda1, n, "lambda1"), per_binary(lambda2, n, "lambda2")
    c1, c2, ell, nh = (per_binary(x, n, name, (3,)) for x, name in
                       ((chi1, "chi1"), (chi2, "chi2"), (ell_hat, "ell_hat"), (n_hat, "n_hat")))
    # the shared options fail for every binary alike: check them once (a binary of the table could itself be
    # invalid, which must not raise); a reference binary carries them to population_parts
    given = options_of(options, keywords, "evolve_many")
    opts = checked(given, "final")
    reference = binary_settings(opts, 10.0, 10.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 20.0, None, None,
                                (0.0, 0.0, 1.0), (1.0, 0.0, 0.0), 1.0, 1.0)

    # one row per (binary, target), row i·K + k; reshaped to (N, K) at the end
    nr = n * K
    state = dict(t=np.full(nr, np.nan), t_seconds=np.full(nr, np.nan), v=np.full(nr, np.nan), Phi=np.full(nr, np.nan),
                 chi1=np.full((nr, 3), np.nan), chi2=np.full((nr, 3), np.nan), R=np.full((nr, 4), np.nan),
                 ell_hat=np.full((nr, 3), np.nan))
    out = Population(**state, termination=np.full(nr, "invalid", dtype=object), reached=np.zeros(nr, dtype=bool),
                     message=np.full(nr, "", dtype=object), nsteps=np.zeros(nr, dtype=np.int64),
                     nfev=np.zeros(nr, dtype=np.int64), stopped_at=state,   # the states' own arrays until the end
                     inputs={**dataclasses.asdict(given),
                             **dict(zip(PER_BINARY, (m1a, m2a, c1, c2, fref, ell, nh, k1, k2, l1, l2))),
                             ("frequencies_Hz" if listed else "f_end_Hz"): targets if listed else targets[:, 0]})
    ends, M_sec = np.full(nr, None, dtype=object), np.full(nr, np.nan)
    counts = np.zeros((nr, 4), dtype=np.int64)
    with np.errstate(all="ignore"):   # an invalid binary's row is never used: settings refuses it first
        X1 = m1a / (m1a + m2a)
    # per binary in Python floats and lists, for the lists of targets and the refusals (numpy on a few numbers costs
    # ~0.5-1 µs per operation); with the collector paused: the lists cost 14 µs per binary with it walking them
    with _collector_paused():
        f_all, m1l, m2l, frl, k1l, k2l, l1l, l2l, c1l, c2l, elll, nhl = (
            x.tolist() for x in (targets, m1a, m2a, fref, k1, k2, l1, l2, c1, c2, ell, nh))
    kmax = kmax_of(reference)
    mode = {aligned: output_mode(aligned, reference.rotor) for aligned in (True, False)}
    skips, aheads, behinds = [{}] * n, [None] * n, [None] * n   # per binary: a list's refused targets, the others

    def settings_of(i, f_min, f_max):
        """binary_settings of binary i (a ValueError if it is invalid) with f_min and f_max (NaN: none)."""
        return binary_settings(opts, m1l[i], m2l[i], c1l[i], c2l[i], frl[i], None if f_min != f_min else f_min,
                               None if f_max != f_max else f_max, elll[i], nhl[i], k1l[i], k2l[i], l1l[i], l2l[i])

    def refuse(i, e):
        """Binary i invalid (the ValueError e): its message on its rows, or a refused target's where that check
        comes first in evolve's order."""
        out.message[i * K:(i + 1) * K] = str(e)
        for k, why in skips[i].items():
            if _first_error(opts, m1l[i], m2l[i], c1l[i], c2l[i], frl[i], f_all[i][k], elll[i], nhl[i], k1l[i],
                            k2l[i], l1l[i], l2l[i]) not in (None, str(e)):
                out.message[i * K + k] = why

    integrating, unresolved = 0.0, False
    with _collector_paused():
        for start in range(0, n, CHUNK):
            stop = min(start + CHUNK, n)
            if listed:   # f_min, f_max: the farthest kept target on each side
                f_lo, f_hi = np.full(stop - start, np.nan), np.full(stop - start, np.nan)
                for i in range(start, stop):
                    f, fr = f_all[i], frl[i]
                    skips[i] = _refused_targets(f, m1l[i], m2l[i], fr)
                    kept = [k for k in range(K) if k not in skips[i]]
                    behinds[i] = [k for k in kept if f[k] < fr]
                    aheads[i] = [k for k in kept if not f[k] < fr]
                    f_ahead = [f[k] for k in aheads[i] if f[k] == f[k]]
                    if behinds[i]:
                        f_lo[i - start] = min(f[k] for k in behinds[i])
                    if f_ahead:
                        f_hi[i - start] = max(f_ahead)
            else:        # one target: behind f_ref backward, else (or NaN: to the end) forward
                f = targets[start:stop, 0]
                back = f < fref[start:stop] if backward is None else backward[start:stop]
                f_lo, f_hi = np.where(back, f, np.nan), np.where(back, np.nan, f)
            b = population_settings(opts, m1a[start:stop], m2a[start:stop], c1[start:stop], c2[start:stop],
                                    fref[start:stop], f_lo, f_hi, ell[start:stop], nh[start:stop], k1[start:stop],
                                    k2[start:stop], l1[start:stop], l2[start:stop])
            for j in np.flatnonzero(~b.valid).tolist():   # binary_settings decides and words the refusals
                try:
                    b.put(j, settings_of(start + j, f_lo[j].item(), f_hi[j].item()))
                except ValueError as e:
                    refuse(start + j, e)
            with np.errstate(all="ignore"):
                parts = population_parts(reference, X1[start:stop], k1[start:stop], k2[start:stop], l1[start:stop],
                                         l2[start:stop])
            for aligned in (True, False):
                g = np.flatnonzero(b.valid & (b.aligned == aligned))   # rows of the chunk with this right-hand side
                if not g.size:
                    continue
                bg = Binaries(*(x[g] for x in b))
                rhs, events, P, Y0, bases, checks = build_rows(opts, bg, parts, g)
                unresolved = unresolved or warn_if_unresolved(opts.atol, opts.rtol, Y0)   # once per call
                keep = np.ones(g.size, dtype=bool)
                for q, c in enumerate(checks.tolist()):
                    if ended_at(*c[:4]) or c[4]:
                        j = g[q].item()
                        try:
                            check_start(settings_of(start + j, f_lo[j].item(), f_hi[j].item()), kmax, bases[q], *c)
                        except ValueError as e:
                            refuse(start + j, e)
                            keep[q] = False
                ids = start + g[keep]
                if listed:
                    hq, hfwd, hrow, nearer = [], [], [], []
                    for q, i in zip(np.flatnonzero(keep).tolist(), ids.tolist()):
                        M_sec[i * K:(i + 1) * K] = bg.M_sec[q]
                        for k, why in skips[i].items():
                            out.message[i * K + k] = why
                        for forward, ks in ((True, aheads[i]), (False, behinds[i])):
                            if not ks:
                                continue
                            # the farthest target ends the integration; the others are found on its dense output
                            v_k = sorted((_ini.v_from_frequency(f_all[i][k], bg.M_sec[q].item()), i * K + k)
                                         for k in ks)
                            if not forward:
                                v_k.reverse()
                            for _, r in v_k:
                                ends[r] = end_name(forward, True)   # (listed targets are finite)
                            hq.append(q)
                            hfwd.append(forward)
                            hrow.append(v_k[-1][1])
                            nearer.append(v_k[:-1])
                    hq, hrow = np.array(hq, dtype=np.int64), np.array(hrow, dtype=np.int64)
                    hfwd = np.array(hfwd, dtype=bool)
                    width = max((len(x) for x in nearer), default=0)
                    near_r, near_v = np.full((hq.size, width), -1, dtype=np.int64), np.full((hq.size, width), np.nan)
                    for h, x in enumerate(nearer):
                        for w, (vk, r) in enumerate(x):
                            near_v[h, w], near_r[h, w] = vk, r
                else:
                    hq, hrow = np.flatnonzero(keep), ids
                    hfwd = np.isnan(f_lo[g[keep]])
                    M_sec[ids] = bg.M_sec[keep]
                    ends[ids] = [end_name(fw, not math.isnan(hi)) for fw, hi in zip(hfwd.tolist(),
                                                                                    f_hi[g[keep]].tolist())]
                    near_r, near_v = np.empty((hq.size, 0), dtype=np.int64), np.empty((hq.size, 0))
                # the halves' parameter vectors (~5 kB each): P itself where each row has one half, in order
                Ph = P if np.array_equal(hq, np.arange(P.shape[0])) else P[hq]
                t_end, directions = np.empty(hq.size), np.empty((hq.size, N_EVENTS))
                for forward in (True, False):
                    sel = np.flatnonzero(hfwd == forward)
                    q = hq[sel]
                    p, t_end[sel], directions[sel] = half(bg.v0[q], bg.nu[q], bg.v_min[q], Ph if forward else Ph[sel],
                                                          forward)
                    if not forward:   # a copy with v_end = v_min
                        Ph[sel] = p
                integrating += _integrate_group(rhs, events, mode[aligned], float(opts.atol), float(opts.rtol),
                                                opts.max_steps,
                                                Y0[hq], Ph, t_end, directions, bg.R0[hq], bg.ell_hat[hq],
                                                bg.chi1[hq], bg.chi2[hq], hrow, near_v, near_r, out, counts)
    named = {}    # (status, event, end) → (termination, reached): a few kinds among many rows
    for r, key in enumerate(zip(counts[:, 0].tolist(), counts[:, 1].tolist(), ends.tolist())):
        if key[2] is not None:
            if key not in named:
                name = termination(*key, reference.approximant)
                # the end of the inspiral (end 'v_max': no target frequency) is reached by any of its ends
                named[key] = name, name == key[2] or key[2] == "v_max" and name in INSPIRAL_ENDS
            out.termination[r], out.reached[r] = named[key]
            out.message[r] = TERMINATION_MESSAGES[out.termination[r]]
    out.nsteps[:], out.nfev[:] = counts[:, 2], counts[:, 3]
    out.t_seconds[:] = out.t * M_sec
    for name in STATE:   # the states where the integrations stopped; those that did not reach their target: NaN
        x = getattr(out, name)
        out.stopped_at[name] = x.copy()   # (the dict was `state`, the states' arrays themselves)
        x[~out.reached] = np.nan
    if listed:
        for name in FIELDS:
            x = getattr(out, name)
            setattr(out, name, x.reshape((n, K) + x.shape[1:]))
        for name, x in out.stopped_at.items():
            out.stopped_at[name] = x.reshape((n, K) + x.shape[1:])
    out.stats = {"wall_time_s": time.perf_counter() - wall0, "wall_time_integrate_s": integrating}
    return out
