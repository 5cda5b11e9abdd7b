r"""How the approximants form v̇ (:mod:`pnrotor.approximants`): their v̇ functions, and the series N, D and Ê′ of
v̇ = (32ν/5) v⁹ N/D built with them, tides included, which the parameter vector holds
(:mod:`pnrotor.pn.system`).

A v̇ function is an ``@njit`` function of :data:`VDOT_SIG`, called by address from one compiled kernel
(:func:`point_particle_series`, :func:`vdot_series_each`), so it is compiled (or loaded from numba's cache) when a run
first uses its approximant, and adding one compiles nothing else anew.
"""

import importlib

import numpy as np
from numba import njit, types
from numba.core.registry import CPUDispatcher

from .. import approximants
from ..ode.common import A3, I1, addresses, function_of
from .energy import energy_derivative_series, energy_series
from .flux import flux_series
from .series import TIDAL_K, copy_into, divide, truncate

VDOT_SIG = types.void(A3, A3, I1, A3, A3)
"""The signature of a v̇ function ``f(Ep, F, kmax, N, D)``: from the truncated Ê′ and F̂ (NK, NB, NL) and the
truncation ``kmax`` (:func:`pnrotor.pn.series.kmax_from_orders`), write N and D (zeros on entry) of
v̇ = (32ν/5) v⁹ N/D, truncated by ``kmax``.  It may raise (it is called through its numba entry point)."""
vdot_function = function_of(VDOT_SIG)

_ADDRESSES = {}


def vdot_addresses(a):
    """(cfunc wrapper, numba entry) addresses of the v̇ function of the :class:`~pnrotor.approximants.Approximant` a
    (imported if named ``"module:function"``), compiled (or loaded from numba's cache) on first use: what
    :func:`point_particle_series` takes."""
    found = _ADDRESSES.get(a)
    if found is None:
        f = a.vdot
        if isinstance(f, str):
            module, _, name = f.partition(":")
            f = getattr(importlib.import_module(module), name)
        if not isinstance(f, CPUDispatcher):
            raise TypeError(f"approximant {a.name}'s vdot must be an @njit function of VDOT_SIG, got "
                            f"{type(f).__name__}")
        found = _ADDRESSES[a] = addresses(f, VDOT_SIG, raises=True)
    return found


# ---------------------------------------------------------------------------------------------------
# the series N, D and Ê′ of v̇
# ---------------------------------------------------------------------------------------------------

def vdot_series(X1, approximant, kmax, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """(N, D, Ê′) series of v̇ = (32ν/5) v⁹ N/D for the approximant, truncated by ``kmax``, tides included."""
    a = approximants.get(approximant)
    E, F = energy_series(X1, kappa1, kappa2, lambda1, lambda2), flux_series(X1, kappa1, kappa2, lambda1, lambda2)
    kmax = np.ascontiguousarray(kmax, dtype=np.int64)
    N, D, Ep = point_particle_series(E, F, kmax, *vdot_addresses(a))
    add_tides(a, E, F, kmax, N, D, Ep)
    return N, D, Ep


@njit(cache=True)
def point_particle_series(E_raw, F_raw, kmax, c_addr, jit_addr):
    """(N, D, Ê′) from the untruncated Ê and F̂ (NK, NB, NL) by the v̇ function at these addresses
    (:func:`vdot_addresses`), without their tidal terms (k ≥ TIDAL_K), which :func:`add_tides` adds."""
    E = truncate(E_raw.copy(), kmax)   # the point-particle and spin terms (k ≤ 9: no tidal term is kept)
    Ep = energy_derivative_series(E)   # the derivative keeps the powers of v, so it stays truncated
    F = truncate(F_raw.copy(), kmax)
    N = np.zeros_like(E)
    D = np.zeros_like(E)
    vdot_function(c_addr, jit_addr)(Ep, F, kmax, N, D)
    return N, D, Ep


@njit(cache=True)
def vdot_series_each(E_raw, F_raw, kmax, c_addr, jit_addr):
    """:func:`point_particle_series` of every binary i of E_raw[i], F_raw[i] → (N, D, Ê′), each (n, NK, NB, NL);
    the same arithmetic as a call per binary (no fastmath: nothing is fused or reordered), ~5 µs faster each.  The
    series are copied element by element (:func:`pnrotor.pn.series.copy_into`)."""
    N = np.empty_like(E_raw)
    D = np.empty_like(E_raw)
    Ep = np.empty_like(E_raw)
    for i in range(E_raw.shape[0]):
        n, d, ep = point_particle_series(E_raw[i], F_raw[i], kmax, c_addr, jit_addr)
        copy_into(n, N[i])
        copy_into(d, D[i])
        copy_into(ep, Ep[i])
    return N, D, Ep


@njit(cache=True)
def taylor_t1(Ep, F, kmax, N, D):
    """TaylorT1's v̇ (:data:`VDOT_SIG`): N = F̂, D = Ê′ as they are."""
    copy_into(F, N)
    copy_into(Ep, D)


@njit(cache=True)
def taylor_t4(Ep, F, kmax, N, D):
    """TaylorT4's v̇ (:data:`VDOT_SIG`): N = [F̂/Ê′] re-expanded and truncated, D = 1."""
    copy_into(divide(F, Ep, kmax), N)
    D[0, 0, 0] = 1.0


@njit(cache=True)
def taylor_t5(Ep, F, kmax, N, D):
    """TaylorT5's v̇ (:data:`VDOT_SIG`): N = 1, D = [Ê′/F̂] re-expanded and truncated (Ajith 2011)."""
    N[0, 0, 0] = 1.0
    copy_into(divide(Ep, F, kmax), D)


def add_tides(a, E_raw, F_raw, kmax, N, D, Ep):
    """Add the tidal terms of E_raw and F_raw (b = 0, TIDAL_K ≤ k ≤ kmax[3], linear in Λ, no logarithm) to N, D and
    Ê′ of the :class:`~pnrotor.approximants.Approximant` a in place: series of one binary (NK, NB, NL), or of n binaries, n first (numpy,
    elementwise: each binary's numbers are those of a call with its own series).

    ``a.tides`` 'as_is' (T1) adds them to F̂ and Ê′ as they are.  'N' (T4) and 'D' (T5) re-expand the ratio to first
    order in Λ, every tidal term kept to kmax[3] whatever the point-particle order: with Q = F̂/Ê′ (T4),
    Q_t = (F̂_t − Q_pp Ê′_t)/Ê′_pp, and the same with F̂ and Ê′ exchanged for T5 (series.divide's recursion,
    Q_k = (N_k − Σ_{i≥1} D_i Q_{k−i})/D_0, on the tidal powers).  Only the point-particle terms up to v² reach
    k ≤ 12 times a tidal term (there are no spin terms below v³ and no logarithms below v⁶), so Q_pp and Ê′_pp are
    taken at 1PN, without spins: LALSuite's fixed SpinTaylorT4 and T5 tidal coefficients
    (``XLALSimInspiralTaylorT4wdot_1{0,2}PNTidalCoeff``, ``XLALSimInspiralTaylorT2dtdv_1{0,2}PNTidalCoeff``), which
    tests/test_pn_tides.py checks these against.  In numpy on the coefficients, not compiled: they add
    nothing to a cold start."""
    top = min(int(kmax[3]), N.shape[-3] - 1)
    powers = range(TIDAL_K, top + 1)
    e_t = {k: 0.5 * (k + 2) * E_raw[..., k, 0, 0] for k in powers}   # Ê′ of the tidal energy terms
    f_t = {k: F_raw[..., k, 0, 0] for k in powers}
    if not any(np.any(e_t[k]) or np.any(f_t[k]) for k in powers):
        return
    if a.tides is None:
        raise ValueError(f"approximant {a.name} takes no tides: lambda1 and lambda2 must be 0 (or tidal_order 0)")
    if a.tides == "as_is":
        N_t, D_t = f_t, e_t
    else:
        e1 = [0.5 * (k + 2) * E_raw[..., k, 0, 0] for k in range(3)]   # the 1PN Ê′ and F̂
        f1 = [F_raw[..., k, 0, 0] for k in range(3)]
        num_pp, den_pp, num_t, den_t = (f1, e1, f_t, e_t) if a.tides == "N" else (e1, f1, e_t, f_t)
        q = []                           # Q_pp to v²
        for k in range(3):
            x = num_pp[k]
            for i in range(1, k + 1):
                x = x - den_pp[i] * q[k - i]
            q.append(x / den_pp[0])
        t = {}                           # Q_t
        for k in powers:
            x = num_t[k]
            for i in range(3):
                if k - i in den_t:
                    x = x - q[i] * den_t[k - i]
            for i in range(1, min(k - TIDAL_K, 2) + 1):
                x = x - den_pp[i] * t[k - i]
            t[k] = x / den_pp[0]
        N_t, D_t = (t, {}) if a.tides == "N" else ({}, t)
    for k in powers:
        for series, terms in ((N, N_t), (D, D_t), (Ep, e_t)):
            if k in terms:
                series[..., k, 0, 0] += terms[k]


def horizon_sign(a):
    """p[P_HORIZON] of the :class:`~pnrotor.approximants.Approximant` a with horizon absorption: 1 where the flux into
    the horizons F̂_H joins F̂ in N ('as_is', 'N': T1, T4), −1 where it leaves D = [Ê′/F̂] ('D': T5)
    (:func:`pnrotor.pn.rhs.add_horizon`); a ValueError for an approximant that takes none."""
    if a.tides is None:
        raise ValueError(f"approximant {a.name} takes no horizon_absorption")
    return -1.0 if a.tides == "D" else 1.0
