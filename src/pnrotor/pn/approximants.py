r"""The approximants as data: how each forms v̇ from Ê′ and F̂, its names and its LALSuite counterpart.

Energy balance gives v̇ = −F/E′ = (32ν/5) v⁹ N(v)/D(v), with E = −(νv²/2)Ê and F = (32/5)ν²v¹⁰F̂
(:mod:`~pnrotor.pn.energy`, :mod:`~pnrotor.pn.flux`).  An approximant is its choice of the truncated series N, D:

    TaylorT1: N = F̂, D = Ê′ evaluated as they are;
    TaylorT4: N = [F̂/Ê′] re-expanded and truncated, D = 1;
    TaylorT5: N = 1, D = [Ê′/F̂] re-expanded and truncated (the inverse, Ajith 2011, arXiv:1107.1267).

Each is an :class:`Approximant` in :data:`REGISTRY`: its names, its v̇ function (an ``@njit`` function of
:data:`VDOT_SIG` that writes N and D from the truncated Ê′ and F̂), where first-order additions to F̂ and Ê′ (the
tides, the horizon flux) go, and LALSuite's name and truncation for it.  Settings
(:func:`normalize_approximant`), :func:`pnrotor.pn.evolve.lalsuite_orders`, the terminations, the CLI and the
HDF5 schema read the registry; the right-hand sides and events never see the approximant: they evaluate N and D
stored in the parameter vector (:mod:`pnrotor.pn.rhs`).  The v̇ function is called by address from one compiled
kernel (:func:`vdot_series`, :func:`vdot_series_each`), so it is compiled (or loaded from numba's cache) when a
run first uses its approximant, and adding one compiles nothing else anew.
"""

from dataclasses import dataclass

import numpy as np
from numba import njit, types
from numba.core.registry import CPUDispatcher

from ..ode.common import A3, I1, addresses, function_of
from .energy import energy_derivative_series, energy_series
from .flux import flux_series
from .series import TIDAL_K, copy_into, divide, truncate

VDOT_SIG = types.void(A3, A3, I1, A3, A3)
"""The signature of a v̇ function ``f(Ep, F, kmax, N, D)``: from the truncated Ê′ and F̂ (NK, NB, NL) and the
truncation ``kmax`` (:func:`pnrotor.pn.series.kmax_from_orders`), write N and D (zeros on entry) of
v̇ = (32ν/5) v⁹ N/D, truncated by ``kmax``.  It may raise (it is called through its numba entry point)."""
vdot_function = function_of(VDOT_SIG)

TIDES = ("as_is", "N", "D")
"""Where terms added to F̂ and Ê′ at first order go (:attr:`Approximant.tides`)."""


@dataclass(frozen=True, eq=False)
class Approximant:
    """One approximant of :data:`REGISTRY`.

    ``name``: what ``approximant=`` takes and results record ('T4'); ``vdot``: its v̇ function (:data:`VDOT_SIG`);
    ``description``: one line for help texts and the schema; ``aliases``: other names accepted (any case);
    ``tides``: how the tidal terms of F̂ and Ê′ and the horizon flux (both first order: :func:`add_tides`,
    :func:`add_horizon_flux`) enter N and D: 'as_is' (N ∋ F̂, D ∋ Ê′ as they are), 'N' (N is the re-expanded
    F̂/Ê′), 'D' (D is the re-expanded Ê′/F̂), or None (the approximant takes neither: a ValueError);
    ``pole``: the termination when D falls to DEN_EPS (event 5; 'energy_balance' where D is Ê′ itself);
    ``lal_name``, ``lal_orders``: LALSuite's approximant of this model and the options that give its truncation
    at phaseO = 7, spinO = −1 (:func:`pnrotor.pn.evolve.lalsuite_orders`), or None.  Equal only to itself (a
    cache keyed on it forgets an entry replaced under the same name)."""

    name: str
    vdot: object
    description: str
    aliases: tuple = ()
    tides: str = None
    pole: str = "vdot_divergent"
    lal_name: str = None
    lal_orders: dict = None


REGISTRY = {}
"""name → :class:`Approximant`, in the order of :func:`register`."""


def register(approximant):
    """Add an :class:`Approximant` to :data:`REGISTRY` (a ValueError if one of its names is taken, a TypeError if
    its v̇ function is not an ``@njit`` function); return it."""
    a = approximant
    if not isinstance(a.vdot, CPUDispatcher):
        raise TypeError(f"an approximant's vdot must be an @njit function of VDOT_SIG, got {type(a.vdot).__name__}")
    if a.tides not in TIDES + (None,):
        raise ValueError(f"tides must be one of {TIDES} or None, got {a.tides!r}")
    for name in (a.name,) + tuple(a.aliases):
        if _key(name) in _NAMES:
            raise ValueError(f"approximant name {name!r} is taken by {_NAMES[_key(name)]!r}")
    REGISTRY[a.name] = a
    _NAMES.update({_key(name): a.name for name in (a.name,) + tuple(a.aliases)})
    return a


def unregister(name):
    """Remove the approximant ``name`` (and its aliases) from :data:`REGISTRY`."""
    a = REGISTRY.pop(name)
    for alias in (a.name,) + tuple(a.aliases):
        del _NAMES[_key(alias)]


_NAMES = {}
"""Every accepted name, upper case and stripped → the approximant's name."""


def _key(name):
    return str(name).strip().upper()


def normalize_approximant(approximant):
    """The registered name of ``approximant``, given by its name or an alias in any case ('T4' from 't4', 'TaylorT4',
    'SpinTaylorT4'); else a ValueError listing them."""
    name = _NAMES.get(_key(approximant))
    if name is None:
        raise ValueError(f"approximant must be one of {', '.join(REGISTRY)} (or "
                         f"{', '.join(alias for a in REGISTRY.values() for alias in a.aliases)}), got {approximant!r}")
    return name


def get(approximant):
    """The :class:`Approximant` of a name or alias (:func:`normalize_approximant`), or ``approximant`` itself if it is
    one."""
    if isinstance(approximant, Approximant):
        return approximant
    return REGISTRY[normalize_approximant(approximant)]


_ADDRESSES = {}


def vdot_addresses(a):
    """(cfunc wrapper, numba entry) addresses of the :class:`Approximant` a's v̇ function, compiled (or loaded from
    numba's cache) on first use; what :func:`vdot_series` takes."""
    found = _ADDRESSES.get(a.vdot)
    if found is None:
        found = _ADDRESSES[a.vdot] = addresses(a.vdot, VDOT_SIG, raises=True)
    return found


# ---------------------------------------------------------------------------------------------------
# the series N, D and Ê′ of v̇
# ---------------------------------------------------------------------------------------------------

def vdot_series(X1, approximant, kmax, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """(N, D, Ê′) series of v̇ = (32ν/5) v⁹ N/D for the approximant, truncated by ``kmax``, tides included."""
    a = get(approximant)
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
    Ê′ of the :class:`Approximant` a in place: series of one binary (NK, NB, NL), or of n binaries, n first (numpy,
    elementwise: each binary's numbers are those of a call with its own series).

    ``a.tides`` 'as_is' (T1) adds them to F̂ and Ê′ as they are.  'N' (T4) and 'D' (T5) re-expand the ratio to first
    order in Λ, every tidal term kept to kmax[3] whatever the point-particle order: with Q = F̂/Ê′ (T4),
    Q_t = (F̂_t − Q_pp Ê′_t)/Ê′_pp, and the same with F̂ and Ê′ exchanged for T5 (series.divide's recursion,
    Q_k = (N_k − Σ_{i≥1} D_i Q_{k−i})/D_0, on the tidal powers).  Only the point-particle terms up to v² reach
    k ≤ 12 times a tidal term (there are no spin terms below v³ and no logarithms below v⁶), so Q_pp and Ê′_pp are
    taken at 1PN, without spins: LALSuite's fixed SpinTaylorT4 and T5 tidal coefficients
    (``XLALSimInspiralTaylorT4wdot_1{0,2}PNTidalCoeff``, ``XLALSimInspiralTaylorT2dtdv_1{0,2}PNTidalCoeff``), which
    tests/test_pn_tides.py checks these against.  In numpy on the coefficients, not compiled (series.divide's
    general products compiled into the v̇ kernel added ~40 s to a cold start, these loops compiled ~4 s, measured
    under load; in numpy they add nothing to it)."""
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


def add_horizon_flux(a, horizon, N, D):
    """N, D of the :class:`Approximant` a with the flux into the horizons F̂_H = {k: c}
    (:func:`pnrotor.pn.flux.horizon_flux`) added to the energy balance at first order: F̂ + F̂_H in N ('as_is', 'N':
    T1, T4), D − F̂_H ('D': T5, D = Ê′/F̂ re-expanded); new arrays (the given ones may be shared)."""
    if a.tides is None:
        raise ValueError(f"approximant {a.name} takes no horizon_absorption")
    N, D = N.copy(), D.copy()
    for k, c in horizon.items():
        if a.tides == "D":
            D[k, 0, 0] -= c
        else:
            N[k, 0, 0] += c
    return N, D


register(Approximant("T1", taylor_t1, "TaylorT1: -F/E' evaluated as a ratio", ("TaylorT1", "SpinTaylorT1"),
                     tides="as_is", pole="energy_balance", lal_name="SpinTaylorT1",
                     lal_orders={"pn_order": 3.5, "spin_orbit_order": 2.5, "spin_spin_order": 3.0,
                                 "precession_phase_shift": True}))
register(Approximant("T4", taylor_t4, "TaylorT4: -F/E' re-expanded, truncated", ("TaylorT4", "SpinTaylorT4"),
                     tides="N", lal_name="SpinTaylorT4",
                     lal_orders={"pn_order": 3.5, "spin_orbit_order": 3.0, "spin_spin_order": 3.0,
                                 "precession_phase_shift": True}))
register(Approximant("T5", taylor_t5, "TaylorT5: -E'/F re-expanded, truncated, inverted",
                     ("TaylorT5", "SpinTaylorT5"), tides="D", lal_name="SpinTaylorT5",
                     lal_orders={"pn_order": 3.5, "spin_orbit_order": 3.0, "spin_spin_order": 3.0,
                                 "precession_phase_shift": True}))
