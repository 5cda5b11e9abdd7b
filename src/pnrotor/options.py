"""The model and integration options of a PN run, in one place: :class:`Options` holds their names, defaults and
allowed ranges and checks them, for `pnrotor.evolve`, `pnrotor.evolve_many`, the streamed waveforms
(`pnrotor.stream`), the pipelines' plugins, batch tables and the CLI; the columns of a batch table (:data:`REQUIRED`,
:data:`DEFAULTS`, :data:`COLUMNS`) come from it.  Imports no numba, so that the CLI reads it before numba loads.

The PN orders follow the truncated series of :mod:`pnrotor.pn.series` (point-particle terms to 4.5PN), the
spin-orbit terms of Bohé et al. 2013 (to 4PN in the energy and flux) and the spin-spin terms to 3PN
(:mod:`pnrotor.pn.energy`, :mod:`pnrotor.pn.flux`, :mod:`pnrotor.pn.precession`); the tidal orders are those of
Vines, Flanagan & Hinderer 2011 (5PN, 6PN).  numpy is imported when the first Options is made, not before (the CLI's
parser loads neither numpy nor numba).
"""

import dataclasses
import functools

from pnrotor import approximants
from pnrotor.approximants import normalize_approximant

__all__ = ["Options", "options_of", "OPTION_DEFAULTS", "REQUIRED", "DEFAULTS", "COLUMNS", "TABLE_OPTIONS"]

MAX_ORDER = 4.5
"""The highest PN order of the point-particle terms (:mod:`pnrotor.pn.series`, k = 9)."""
MAX_SO_ORDER = 4.0
"""The highest spin-orbit order."""
MAX_SS_ORDER = 3.0
"""The highest spin-spin order."""
TIDAL_ORDERS = (0.0, 5.0, 6.0)
"""The tidal orders: none, 5PN (leading), 6PN (with the 1PN tidal terms; the default)."""
PRECESSION = ("averaged", "averaged_varpi", "instantaneous")
ROTORS = ("coprecessing", "orbital")
MAX_STEPS = 2**63 - 1
"""Largest max_steps: the integrator counts its steps in int64."""


@dataclasses.dataclass(frozen=True)
class Options:
    r"""The model and integration options of a PN run, checked when made: a ``ValueError`` names the first bad one and
    its allowed values.  Pass one as ``options=`` to `pnrotor.evolve`, `pnrotor.evolve_many` or `pnrotor.stream`;
    their keywords of the same names replace its fields for that call (``evolve(…, options=o, atol=1e-10)``).
    Immutable: ``dataclasses.replace(o, pn_order=3)`` makes another (checked again).  What a run used is in its
    ``inputs``, with the defaults resolved.

    Parameters
    ----------
    approximant : str
        A name of :mod:`pnrotor.approximants`' registry: 'T1' (TaylorT1, −F/E′ evaluated as a ratio), 'T4'
        (TaylorT4, the ratio re-expanded and truncated), 'T5' (TaylorT5, its inverse re-expanded and truncated);
        'TaylorT4', 'SpinTaylorT4', … and any case are accepted too.
    pn_order : float
        PN order of the nonspinning terms, 0 … 4.5 in steps of 0.5.
    spin_orbit_order, spin_spin_order : float or None
        PN orders of the terms linear and quadratic in the spins, −1 … 4 and −1 … 3 in steps of 0.5 (None:
        min(pn_order, 4) and min(pn_order, 3); −1 removes them).  They also select the precession terms (spin-orbit
        LO/NLO/NNLO at ≥ 1.5/2.5/3.5, spin-spin at ≥ 2/3).  `pnrotor.pn.lalsuite_orders` gives the truncation of
        LALSuite's SpinTaylorTn.
    atol, rtol : float
        DOP853 tolerances: absolute on every state component (> 0), relative (≥ 0).
    rotor : {'coprecessing', 'orbital'}
        Which rotor the precessing state holds (:mod:`pnrotor.pn.rhs`): the co-precessing R_p with
        R = R_p exp(Φẑ/2) (default, fast) or the full orbital-frame R.
    precession_phase_shift : bool or None
        Apply Φ̇ = v³ − |Ω_ℓ,LO|²/(4v³) (arXiv:1507.00406).  None: when spin_orbit_order ≥ 3.
    integrate_rotor : bool
        Use the precessing state even for nonspinning and aligned binaries.
    precession : {'averaged', 'averaged_varpi', 'instantaneous'}
        'averaged' (LALSuite's SpinTaylor model with lscorr = 0): orbit-averaged spin precession and
        Ω_ℓ = −ℓ̂ × (Ṡ₁ + Ṡ₂)/|L| (:mod:`pnrotor.pn.precession`).  'averaged_varpi': the same, but the spin-orbit part
        of Ω_ℓ is the orbit average ⟨ϖ n̂⟩ of Bohé et al. 2013's ϖ (Eqs. (4.3)–(4.4)); it differs from 'averaged' from
        NLO on.  'instantaneous': Ω = v³ℓ̂ + ϖn̂ with Bohé et al.'s ϖ (spin-orbit) and n̂-dependent spin-spin
        precession, on the full orbital rotor (implies rotor='orbital', no phase shift; :mod:`pnrotor.pn.rhs`).
    max_steps : int
        Step limit per half, 1 … 2⁶³ − 1.
    tidal_order : {None, 0, 5, 6}
        PN order of the tidal terms of Λ₁, Λ₂: 0 none, 5 the leading ones, 6 with their 1PN corrections (None: 6),
        kept whatever ``pn_order`` is, as LALSuite's tideO.
    horizon_absorption : bool
        Follow the flux into black-hole horizons, averaged over the orbit, for any spins (Alvi 2001 at leading order
        in the tidal coupling, exact in the spins: relative 2.5PN with spins, 4PN without;
        :func:`pnrotor.pn.flux.horizon_rates`): its energy in the energy balance at first order whatever
        ``pn_order`` is, its angular momentum in the spins' magnitudes (taken from the orbit: in ℓ̂'s precession
        too) and its energy in the masses.  Such a run integrates the precessing state, with the masses, even for
        nonspinning and aligned spins (``inputs['state']`` is 'precessing'; aligned spins stay aligned), and an
        `Evolution`'s ``stats`` hold the masses at both ends in M☉ (``m1_final_Msun``, ``m2_final_Msun``,
        ``m1_initial_Msun``, ``m2_initial_Msun``); the rates and the PN coefficients take the masses at f_ref.  A body
        with Λᵢ > 0 (a neutron star) has no horizon: it absorbs nothing.  Not with precession='instantaneous'.
        LALSuite has no such option.
    """

    approximant: str = "T4"
    pn_order: float = 3.5
    spin_orbit_order: float = None
    spin_spin_order: float = None
    atol: float = 1e-12
    rtol: float = 0.0
    rotor: str = "coprecessing"
    precession_phase_shift: bool = None
    integrate_rotor: bool = False
    precession: str = "averaged"
    max_steps: int = 2_000_000
    tidal_order: float = None
    horizon_absorption: bool = False

    def __post_init__(self):
        object.__setattr__(self, "resolved", _resolve(self))

    resolved = ()
    """The values a run uses, in the fields' order: the approximant's registered name, the orders as floats with
    their defaults applied, max_steps as int, 'instantaneous' precession's rotor and phase shift (set when made)."""


def options_of(options, keywords, caller):
    """The :class:`Options` of a call to ``caller`` (its name, for errors): ``options`` (None: the defaults) with the
    fields in ``keywords`` replaced; a TypeError for a keyword that is not an option, or for ``options`` not an
    Options."""
    unknown = [name for name in keywords if name not in OPTION_DEFAULTS]
    if unknown:
        raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r}")
    if options is None:
        if not keywords:
            return _made(approximants.generation, ())
        try:
            return _made(approximants.generation,
                         tuple((name, type(value), value, repr(value)) for name, value in keywords.items()))
        except TypeError:   # a value that cannot be a key (an array, an astropy Quantity): checked anew
            return Options(**keywords)
    if not isinstance(options, Options):
        raise TypeError(f"{caller}(): options must be a pnrotor.Options, got {type(options).__name__}")
    return dataclasses.replace(options, **keywords) if keywords else options


@functools.lru_cache(maxsize=64)
def _made(generation, items):
    """Options of the keywords (name, type, value, repr) ``items``, made once for calls that repeat them (making one
    costs ~5 µs, a tenth of a short run's Python work) while the approximants' registry is at ``generation``.  The type
    and the repr are in the key, so that 1 and True, 3 and 3.0, 0.0 and -0.0 stay apart."""
    return Options(**{name: value for name, _, value, _ in items})


def _resolve(o):
    """:attr:`Options.resolved` of ``o``, each field checked (a ValueError naming the first bad one)."""
    from pnrotor import values

    approximant = normalize_approximant(o.approximant)
    pn_order = _order(o.pn_order, "pn_order", 0.0, MAX_ORDER)
    so_order = (min(pn_order, MAX_SO_ORDER) if o.spin_orbit_order is None
                else _order(o.spin_orbit_order, "spin_orbit_order", -1.0, MAX_SO_ORDER))
    ss_order = (min(pn_order, MAX_SS_ORDER) if o.spin_spin_order is None
                else _order(o.spin_spin_order, "spin_spin_order", -1.0, MAX_SS_ORDER))
    tidal_order = check_tidal_order(o.tidal_order)
    rotor, atol, rtol = o.rotor, o.atol, o.rtol
    if rotor not in ROTORS:
        raise ValueError(f"rotor must be 'coprecessing' or 'orbital', got {rotor!r}")
    if not (values.real(atol) and values.real(rtol) and values.finite(atol) and values.finite(rtol) and atol > 0.0
            and rtol >= 0.0):
        raise ValueError(f"atol must be > 0 and rtol >= 0, both finite numbers; got atol = {atol!r}, rtol = {rtol!r}")
    if not (values.integer(o.max_steps) and 1 <= o.max_steps <= MAX_STEPS):
        raise ValueError(f"max_steps must be an integer from 1 to {MAX_STEPS}, got {o.max_steps!r}")
    if not isinstance(o.integrate_rotor, values.BOOLS):
        raise ValueError(f"integrate_rotor must be True or False, got {o.integrate_rotor!r}")
    shift = o.precession_phase_shift
    if shift is not None and not isinstance(shift, values.BOOLS):
        raise ValueError(f"precession_phase_shift must be None (on at spin-orbit order >= 3), True or False, got "
                         f"{shift!r}")
    if o.precession not in PRECESSION:
        raise ValueError(f"precession must be 'averaged', 'averaged_varpi' or 'instantaneous', got {o.precession!r}")
    if o.precession == "instantaneous":
        rotor = "orbital"
        shift = False
    if shift is None:
        shift = so_order >= 3.0
    if not isinstance(o.horizon_absorption, values.BOOLS):
        raise ValueError(f"horizon_absorption must be True or False, got {o.horizon_absorption!r}")
    if o.horizon_absorption and o.precession == "instantaneous":
        raise ValueError("horizon_absorption needs the orbit-averaged precession ('averaged' or 'averaged_varpi'): its "
                         "flux into the horizons is averaged over the orbit; got precession='instantaneous'")
    return (approximant, pn_order, so_order, ss_order, atol, rtol, rotor, shift, o.integrate_rotor, o.precession,
            int(o.max_steps), tidal_order, bool(o.horizon_absorption))


def check_tidal_order(x):
    """A tidal order: 0, 5 or 6 (None: 6)."""
    from pnrotor.values import float_or_nan

    if x is None:
        return 6.0
    value = float_or_nan(x)
    if value not in TIDAL_ORDERS:
        raise ValueError(f"tidal_order must be 0 (no tides), 5 or 6 (PN orders of the tidal terms; None: 6), got {x!r}")
    return value


def _order(x, name, lo, hi):
    """A PN order: a multiple of 0.5 in [lo, hi]."""
    from pnrotor.values import float_or_nan

    if x is None:
        raise ValueError(f"{name} is required")
    value = float_or_nan(x)
    if not (lo <= value <= hi) or abs(2 * value - round(2 * value)) > 1e-12:
        raise ValueError(f"{name} must be a multiple of 0.5 in [{lo}, {hi}], got {x!r}")
    return value


OPTION_DEFAULTS = {field.name: field.default for field in dataclasses.fields(Options)}
"""The fields of :class:`Options` and their defaults."""


REQUIRED = ("m1", "m2", "chi1", "chi2", "f_ref")
"""The columns every row of a batch table fills."""
_PER_RUN = {"f_min": None, "f_max": None, "sampling": "steps", "lambda1": 0.0, "lambda2": 0.0}
DEFAULTS = {name: _PER_RUN[name] if name in _PER_RUN else OPTION_DEFAULTS[name]
            for name in ("approximant", "pn_order", "spin_orbit_order", "spin_spin_order", "precession", "f_min",
                         "f_max", "sampling", "atol", "lambda1", "lambda2", "tidal_order", "horizon_absorption")}
"""The optional columns of a batch table (a DataFrame's for `pnrotor.evolve_many`, the CLI's options) and their
defaults: those of :class:`Options` and of `pnrotor.evolve`'s keywords (None: evolve's own choice)."""
COLUMNS = REQUIRED + tuple(DEFAULTS) + ("name",)
"""Columns of a batch CSV file (keys of a TOML ``[[binary]]`` table): the option names with ``_``."""
TABLE_OPTIONS = tuple(name for name in DEFAULTS if name in OPTION_DEFAULTS)
"""The options a batch table sets per row: `evolve_many` takes them as shared by its binaries (one call per
combination; one value per DataFrame)."""
