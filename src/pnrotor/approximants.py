r"""The approximants, as a registry: each one's names, how it forms v̇ from Ê′ and F̂, and its LALSuite counterpart.

Energy balance gives v̇ = −F/E′ = (32ν/5) v⁹ N(v)/D(v), with E = −(νv²/2)Ê and F = (32/5)ν²v¹⁰F̂
(:mod:`pnrotor.pn.energy`, :mod:`pnrotor.pn.flux`).  An approximant is its choice of the truncated series N, D, made
by its v̇ function (:mod:`pnrotor.pn.vdot`):

    TaylorT1: N = F̂, D = Ê′ evaluated as they are;
    TaylorT4: N = [F̂/Ê′] re-expanded and truncated, D = 1;
    TaylorT5: N = 1, D = [Ê′/F̂] re-expanded and truncated (the inverse, Ajith 2011, arXiv:1107.1267).

Each is an :class:`Approximant` in :data:`REGISTRY`.  :class:`pnrotor.Options` (:func:`normalize_approximant`),
:func:`pnrotor.pn.evolve.lalsuite_orders`, the terminations, the v̇ series (:mod:`pnrotor.pn.vdot`), the CLI and the
HDF5 schema read it; the right-hand sides and events never see the approximant (they evaluate N and D stored in the
parameter vector, :mod:`pnrotor.pn.rhs`).  Imports nothing (no numba), so that the CLI and the HDF5 schema can read it
before numba loads: the built-in entries name their v̇ functions as ``"module:function"``.
"""

from dataclasses import dataclass

TIDES = ("as_is", "N", "D")
"""Where terms added to F̂ and Ê′ at first order go (:attr:`Approximant.tides`)."""


@dataclass(frozen=True, eq=False)
class Approximant:
    """One approximant of :data:`REGISTRY`.

    ``name``: what ``approximant=`` takes and results record ('T4'); ``vdot``: its v̇ function, an ``@njit`` function
    of :data:`pnrotor.pn.vdot.VDOT_SIG`, or its ``"module:function"`` (imported when a run first uses it);
    ``description``: one line for help texts and the schema; ``aliases``: other names accepted (any case);
    ``tides``: how the tidal terms of F̂ and Ê′ and the horizon flux (both to first order:
    :func:`pnrotor.pn.vdot.add_tides`, :func:`pnrotor.pn.vdot.horizon_sign`) enter N and D: 'as_is' (N ∋ F̂,
    D ∋ Ê′ as they are), 'N' (N is the re-expanded F̂/Ê′), 'D' (D is the re-expanded Ê′/F̂), or None (the approximant
    takes neither: a ValueError); ``pole``: the termination when D falls to DEN_EPS (event 5; 'energy_balance' where
    D is Ê′ itself); ``lal_name``, ``lal_orders``: LALSuite's approximant of this model and the options that give its
    truncation at phaseO = 7, spinO = −1 (:func:`pnrotor.pn.evolve.lalsuite_orders`), or None.  Equal only to itself
    (a cache keyed on it forgets an entry registered anew under the same name)."""

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

_NAMES = {}
"""Every accepted name, upper case and stripped → the approximant's name."""

generation = 0
"""How many times :data:`REGISTRY` has changed: what was made from it (`pnrotor.Options`) is made anew after a
change."""


def _key(name):
    return str(name).strip().upper()


def register(approximant):
    """Add an :class:`Approximant` to :data:`REGISTRY` (a ValueError if one of its names is taken or its ``tides`` is
    not one of :data:`TIDES` or None); return it."""
    a = approximant
    if a.tides not in TIDES + (None,):
        raise ValueError(f"tides must be one of {TIDES} or None, got {a.tides!r}")
    names = (a.name,) + tuple(a.aliases)
    for name in names:
        if _key(name) in _NAMES:
            raise ValueError(f"approximant name {name!r} is taken by {_NAMES[_key(name)]!r}")
    global generation
    REGISTRY[a.name] = a
    _NAMES.update({_key(name): a.name for name in names})
    generation += 1
    return a


def unregister(name):
    """Remove the approximant ``name`` (and its aliases) from :data:`REGISTRY`."""
    global generation
    a = REGISTRY.pop(name)
    for alias in (a.name,) + tuple(a.aliases):
        del _NAMES[_key(alias)]
    generation += 1


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


def names():
    """The registered names as a help text or the HDF5 schema lists them: 'T1, T4 or T5'."""
    *first, last = REGISTRY
    return f"{', '.join(first)} or {last}" if first else last


_LAL_ORDERS = {"pn_order": 3.5, "spin_orbit_order": 3.0, "spin_spin_order": 3.0, "precession_phase_shift": True}

register(Approximant("T1", "pnrotor.pn.vdot:taylor_t1", "TaylorT1: -F/E' evaluated as a ratio",
                     ("TaylorT1", "SpinTaylorT1"), tides="as_is", pole="energy_balance", lal_name="SpinTaylorT1",
                     lal_orders={**_LAL_ORDERS, "spin_orbit_order": 2.5}))
register(Approximant("T4", "pnrotor.pn.vdot:taylor_t4", "TaylorT4: -F/E' re-expanded and truncated",
                     ("TaylorT4", "SpinTaylorT4"), tides="N", lal_name="SpinTaylorT4", lal_orders=_LAL_ORDERS))
register(Approximant("T5", "pnrotor.pn.vdot:taylor_t5", "TaylorT5: -E'/F re-expanded and truncated, inverted",
                     ("TaylorT5", "SpinTaylorT5"), tides="D", lal_name="SpinTaylorT5", lal_orders=_LAL_ORDERS))
