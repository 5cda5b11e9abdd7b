r"""The parameter vector ``p`` of the post-Newtonian system (:mod:`pnrotor.pn.layout`), which its right-hand sides
and events (:mod:`pnrotor.pn.rhs`) read: the approximant, PN orders and spin content are *data* there, so one
compiled function serves every approximant and order.

``p`` holds the series N, D of v̇ = (32ν/5) v⁹ N/D and Ê′ (:mod:`pnrotor.pn.vdot`), every truncated term
zeroed (:mod:`pnrotor.pn.series`), each behind a header of the powers of v that hold spin and logarithmic terms
(:func:`~pnrotor.pn.series.fold_and_store`), and the precession coefficients (:mod:`pnrotor.pn.precession`).
:func:`make_parameters` builds it for one binary, :func:`start_rows` for many binaries at once (``evolve_many``),
both from the parts that do not depend on the spins (:func:`spin_independent_parts`).
"""

import functools
import math

import numpy as np
from numba import njit

from .. import approximants
from . import vdot
from .ends import earlier_end
from .energy import energy_series
from .flux import flux_series
from .layout import (DEN_EPS, N_SS, P_DEN, P_DEN_EPS, P_EP, P_HORIZON, P_HX1, P_HX2, P_ISS1, P_ISS2, P_L, P_NU, P_NUM, P_OMEGA_L, P_ROTOR,
                     P_SHIFT, P_SIZE, P_SO1, P_SO2, P_SPINTOL, P_SS1, P_SS2, P_VARPI1, P_VARPI2, P_VDOT0, P_VEND, P_W1,
                     P_X1, P_X2, SPIN_TOL, Y_V)
from .precession import (SPIN_ORBIT_ORDERS, SPIN_SPIN, angular_momentum_coefficients, phase_shift_weights,
                         precession_terms, spin_orbit_precession, spin_spin_precession_3pn_instantaneous, truncated,
                         varpi_coefficients)
from .rhs import add_horizon, horizon_flux, vdot_peak
from .series import eval_at, fold_and_store, shape_of, v_derivative


@njit(cache=True)
def _store_series(N, D, Ep, basis, fold, p, v0):
    """Store N, D, Ê′ (folded for the aligned RHS) in p; return N, D, Ê′ and event 6 at v0 (N, D with the flux into
    the horizons where p[P_HORIZON] asks for it, at the spin invariants ``basis``)."""
    # offsets as np.int64: a plain constant would compile fold_and_store once per offset (Literal[int])
    fold_and_store(N, basis, fold, p, np.int64(P_NUM))
    fold_and_store(D, basis, fold, p, np.int64(P_DEN))
    fold_and_store(Ep, basis, fold, p, np.int64(P_EP))
    Nv, Dv = v_derivative(N), v_derivative(D)
    n0, d0 = eval_at(N, v0, basis), eval_at(D, v0, basis)
    n0_v, d0_v = eval_at(Nv, v0, basis), eval_at(Dv, v0, basis)
    if p[P_HORIZON] != 0.0:
        f, f_v = horizon_flux(p, v0, basis[1], basis[5], basis[2], basis[7])
        n0, n0_v, d0, d0_v = add_horizon(p, f, f_v, n0, n0_v, d0, d0_v)
    peak0 = vdot_peak(n0, d0, n0_v, d0_v)
    return n0, d0, eval_at(Ep, v0, basis), peak0


def make_parameters(X1, approximant, kmax, *, so_order, ss_order, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0,
                    v_end=1.0, spin_tol=SPIN_TOL, rotor="coprecessing", phase_shift=False, aligned_basis=None,
                    omega_l="torque", basis=None, v_check=None, horizon=False):
    """Build the parameter vector p.

    ``kmax``: from :func:`pnrotor.pn.series.kmax_from_orders`.  ``aligned_basis``: the nine
    invariants for the aligned/nonspinning right-hand side (folded into the series), or None for the
    precessing one.
    With ``v_check`` (and the invariants ``basis`` at that point) it returns (p, (N, D, Ê′, event 6) at
    v_check) instead of p, for checking the initial point.
    ``spin_tol``: how far |χᵢ|² may exceed 1 before events 3/4 end the run (:func:`pnrotor.pn.layout.spin_tolerance`).
    ``horizon``: the flux into the horizons in the energy balance and the spins' and masses' rates
    (:func:`pnrotor.pn.flux.horizon_rates`; p[P_HORIZON], :func:`pnrotor.pn.rhs.add_horizon`), for the precessing
    right-hand side with the state [v, χ₁, χ₂, R, Φ, m₁, m₂] (not with ``aligned_basis``).
    Everything but v_end, spin_tol and the stored series comes from :func:`cached_spin_independent_parts` (cached).
    :func:`start_rows` builds the same p for many binaries at once.
    """
    a = approximants.get(approximant)
    head, N, D, Ep = cached_spin_independent_parts(
        (X1, a, tuple(np.asarray(kmax).tolist()), so_order, ss_order, kappa1, kappa2,
         math.copysign(1.0, kappa1), math.copysign(1.0, kappa2), lambda1, lambda2, rotor, bool(phase_shift), omega_l,
         bool(horizon)))
    p = np.zeros(P_SIZE)
    p[:P_NUM] = head
    p[P_VEND] = v_end
    p[P_SPINTOL] = spin_tol
    fold = aligned_basis is not None
    if horizon and fold:
        raise ValueError("horizon absorption needs the precessing right-hand side: no aligned_basis")
    b = np.asarray(aligned_basis if fold else (basis if basis is not None else _UNIT_BASIS), dtype=np.float64)
    at_v = _store_series(N, D, Ep, b, fold, p, 0.5 if v_check is None else float(v_check))
    return p if v_check is None else (p, at_v)


@njit(cache=True)
def start_rows(heads, N, D, Ep, rows, bases, fold, v_end, spin_tol, c_addr, jit_addr, Y0, P, checks):
    """:func:`make_parameters` with ``v_check`` and :func:`earlier_end` for binaries i = 0 … n−1 (``evolve_many``'s
    set-up of a population, ``pnrotor.pn.evolve.build_rows``): P[i] (zeros on entry) is binary i's parameter
    vector, from row rows[i] of the spin-independent parts (heads, N, D, Ê′ of :func:`spin_independent_parts`),
    its spin invariants bases[i] (folded into the series if ``fold``, the aligned right-hand side), its end v_end[i]
    and ``spin_tol``; checks[i] = (N, D, Ê′, event 6) at v₀ = Y0[i, 0] and the :func:`earlier_end` of its initial
    state Y0[i] with the events at these addresses.  The head is copied element by element: an array slice
    assignment would compile numba's shape-mismatch error path, ~4 s on a cold cache (benchmarks/bench_compile.py)."""
    for i in range(P.shape[0]):
        j = rows[i]
        for k in range(P_NUM):
            P[i, k] = heads[j, k]
        P[i, P_VEND] = v_end[i]
        P[i, P_SPINTOL] = spin_tol
        checks[i, 0], checks[i, 1], checks[i, 2], checks[i, 3] = _store_series(N[j], D[j], Ep[j], bases[i], fold,
                                                                                P[i], Y0[i, Y_V])
        checks[i, 4] = earlier_end(c_addr, jit_addr, Y0[i], P[i])


@functools.lru_cache(maxsize=64)
def cached_spin_independent_parts(key):
    """:func:`spin_independent_parts` of one binary, ``key`` = (X1, approximant (make_parameters gives its
    :class:`~pnrotor.approximants.Approximant`, so an entry registered anew under a name is not served from the
    cache), kmax as a tuple, so_order,
    ss_order, κ₁, κ₂, the signs of κ₁ and κ₂ (a κ of −0.0 gives other signed zeros), Λ₁, Λ₂, rotor, phase_shift,
    omega_l, horizon), as (p head, N, D, Ê′), kept in a small LRU cache (repeated runs of one binary, or of one mass
    ratio, skip its ~65 µs of Python; code that replaces a coefficient function must call
    ``cached_spin_independent_parts.cache_clear()``).  The arrays are shared: make_parameters copies the head and only
    reads the series."""
    X1, approximant, kmax, so_order, ss_order, kappa1, kappa2, _, _, lambda1, lambda2, rotor, phase_shift, omega_l, \
        horizon = key
    p, N, D, Ep = spin_independent_parts(X1, kappa1, kappa2, approximant, kmax, so_order, ss_order, rotor,
                                         phase_shift, omega_l, lambda1, lambda2, horizon)
    return p[0], N[0], D[0], Ep[0]


def spin_independent_parts(X1, kappa1, kappa2, approximant, kmax, so_order, ss_order, rotor, phase_shift, omega_l,
                           lambda1=0.0, lambda2=0.0, horizon=False):
    """Everything :func:`make_parameters` (and :func:`start_rows`) builds that does not depend on the spins or
    v_end, for n binaries that share the options and differ in X1, κ₁, κ₂, Λ₁, Λ₂ (arrays (n,), or floats for one
    binary; ``approximant`` a name or its :class:`~pnrotor.approximants.Approximant`): (heads (n, P_NUM), p
    before the series, without v_end; N, D, Ê′ (n, NK, NB, NL), the series of
    :func:`pnrotor.pn.vdot.vdot_series`).  Arrays take one pass of numpy over the binaries
    (``evolve_many``).  The numbers are built with the binaries
    last (p[j] = x is then a row) and turned binaries-first at the end (only the head of p: transposing all of it
    costs more).  Binary i gets bitwise the numbers of a
    call with its floats: the coefficient functions are elementwise and use only +, −, ×, / (powers are
    written as products, since numpy's x ** k is not libm's pow on every CPU)."""
    a = approximants.get(approximant)
    if rotor not in ("coprecessing", "orbital"):
        raise ValueError(f"rotor must be 'coprecessing' or 'orbital', got {rotor!r}")
    if omega_l not in ("torque", "varpi"):
        raise ValueError(f"omega_l must be 'torque' or 'varpi', got {omega_l!r}")

    def put(off, values):
        for j, x in enumerate(values):
            p[off + j] = x

    X2 = 1.0 - X1
    nu = X1 * X2
    p = np.zeros((P_NUM,) + shape_of(X1))    # p[j, i] of binary i
    p[P_X1] = X1
    p[P_X2] = X2
    p[P_NU] = nu
    p[P_VDOT0] = 32.0 * nu / 5.0
    p[P_ROTOR] = 1.0 if rotor == "orbital" else 0.0
    p[P_SHIFT] = 1.0 if phase_shift else 0.0
    p[P_OMEGA_L] = 1.0 if omega_l == "varpi" else 0.0
    if horizon:   # a body with a tidal deformability is a neutron star: no horizon
        p[P_HORIZON] = vdot.horizon_sign(a)
        p[P_HX1] = np.where(np.asarray(lambda1) == 0.0, X1, 0.0)
        p[P_HX2] = np.where(np.asarray(lambda2) == 0.0, X2, 0.0)
    put(P_W1, phase_shift_weights(X1, X2))
    inc = precession_terms(so_order, ss_order)
    for so, ss, w, iss, (Xi, Xj, ki) in ((P_SO1, P_SS1, P_VARPI1, P_ISS1, (X1, X2, kappa1)),
                                          (P_SO2, P_SS2, P_VARPI2, P_ISS2, (X2, X1, kappa2))):
        put(so, truncated(spin_orbit_precession(Xi, Xj), SPIN_ORBIT_ORDERS, so_order))
        put(w, truncated(varpi_coefficients(Xi, Xj), SPIN_ORBIT_ORDERS, so_order))
        for k, (order, coefficients) in enumerate(SPIN_SPIN):   # the series of c_j, of c_j⊥ and of c_i⊥
            if order <= ss_order:
                for c, value in enumerate(coefficients(Xi, Xj, ki)):
                    p[ss + c * N_SS + k] = value
        if inc["ss_2pn"]:
            # instantaneous Kidder/Racine: Ωᵢ ∋ v⁶[−Xⱼ²χⱼ + 3Xⱼ²(n̂·χⱼ)n̂ + 3νκᵢ(n̂·χᵢ)n̂]
            put(iss, (-(Xj * Xj), 3.0 * (Xj * Xj), 3.0 * nu * ki))
        if inc["ss_3pn"]:
            put(iss + 3, spin_spin_precession_3pn_instantaneous(Xi, Xj, ki))
    put(P_L, truncated(angular_momentum_coefficients(nu), SPIN_ORBIT_ORDERS[1:], so_order))
    p[P_DEN_EPS] = DEN_EPS
    E, F = energy_series(X1, kappa1, kappa2, lambda1, lambda2), flux_series(X1, kappa1, kappa2, lambda1, lambda2)
    kmax, at = np.array(kmax, dtype=np.int64), vdot.vdot_addresses(a)
    if not shape_of(X1):   # one binary (evolve): vdot_series_each would cost 3.5 s more to compile, cold
        N, D, Ep = vdot.point_particle_series(E, F, kmax, *at)
        if lambda1 or lambda2:
            vdot.add_tides(a, E, F, kmax, N, D, Ep)
        return p[None], N[None], D[None], Ep[None]
    E, F = (np.ascontiguousarray(np.moveaxis(x, -1, 0)) for x in (E, F))
    N, D, Ep = vdot.vdot_series_each(E, F, kmax, *at)
    if np.any(lambda1) or np.any(lambda2):
        vdot.add_tides(a, E, F, kmax, N, D, Ep)
    return np.ascontiguousarray(p.T), N, D, Ep



_UNIT_BASIS = np.array([1.0, 0, 0, 0, 0, 0, 0, 0, 0])
