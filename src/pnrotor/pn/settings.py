r"""First stage of a PN run: the user's inputs, checked, converted and completed → :class:`Settings`.

:func:`settings` turns what :func:`pnrotor.pn.evolve.evolve` was given (masses in M☉ or astropy
Quantities, GW frequencies in Hz, spins, frame, model options, sampling) into one record in geometric
units (G = c = M = 1, :mod:`pnrotor.pn.initial`): v at f_ref, f_min and f_max, the initial rotor R₀
(x̂, ŷ, ẑ) → (n̂, λ̂, ℓ̂), the mass ratio, the PN orders with their defaults, and the spin content
(nonspinning, aligned or precessing) that decides which right-hand side is compiled in.  It does so in
two parts: :func:`checked` (the model and integration options, a :class:`pnrotor.Options`, and the sampling, which
the binaries of ``evolve_many`` share and it checks once) and :func:`binary_settings` (the binary);
:func:`population_settings` does the second for arrays of binaries at once (bitwise the same numbers), leaving the
binaries it does not pass to binary_settings.  Every bad input is a ``ValueError`` naming the parameter and its
allowed range.  No numba here: the later stages (:mod:`pnrotor.pn.evolve`, :mod:`pnrotor.pn.sampling`) take a
:class:`Settings`.
"""

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import values
from ..options import Options, options_of
from . import initial as _ini

MAX_MASS_RATIO = 1e6
"""Largest m1/m2 or m2/m1: runs stay meaningful to ~1e4 (a precessing q = 1e6 binary from v = 0.2 already
exhausts max_steps), and beyond ~1e150 the mass fractions' squares underflow."""
V_MIN = 1e-3
"""Smallest v at f_ref or f_min: from v ≈ 0.01 down the PN inspiral spans ≳ 10⁹ orbits and the integration
ends at step_underflow or max_steps; far lower (v⁸ < 1e-308) it would divide by zero."""


@dataclass(eq=False)
class Settings:
    """A run's inputs after checking: physical values (M☉, Hz, s), model options and what follows from them.

    ``f_min``/``f_max`` are None when not given (``v_min`` None, ``v_max`` = 1); ``sampling`` is 'steps',
    'final', 'dt' (``sampling_value`` Δt in s) or 'per_orbit' (``sampling_value`` n); ``ell_hat``,
    ``n_hat`` are exactly orthonormal and R0 maps x̂ → n̂, ẑ → ℓ̂; ``spin_content`` is 'nonspinning',
    'aligned' or 'precessing' (aligned spins have their round-off in-plane parts removed); ``M_sec`` is
    G M/c³ in s, ``X1`` = m₁/M, ``nu`` = X₁X₂; ``lambda1``, ``lambda2`` the dimensionless tidal deformabilities Λᵢ
    and ``tidal_order`` 0, 5 or 6."""

    m1: float
    m2: float
    chi1: np.ndarray
    chi2: np.ndarray
    f_ref: float
    f_min: float
    f_max: float
    ell_hat: np.ndarray
    n_hat: np.ndarray
    kappa1: float
    kappa2: float
    lambda1: float
    lambda2: float
    approximant: str    # from here to sampling_value: the fields of Checked, in its order
    pn_order: float
    spin_orbit_order: float
    spin_spin_order: float
    atol: float
    rtol: float
    rotor: str
    precession_phase_shift: bool
    integrate_rotor: bool
    precession: str
    max_steps: int
    tidal_order: float
    horizon_absorption: bool
    sampling: str
    sampling_value: float
    M_sec: float
    X1: float
    nu: float
    v0: float
    v_min: float
    v_max: float
    R0: np.ndarray
    spin_content: str

    @property
    def use_aligned(self):
        """Whether the run integrates only [v, Φ] (nonspinning or aligned spins, neither integrate_rotor nor
        horizon_absorption, whose spins change)."""
        return self.spin_content != "precessing" and not (self.integrate_rotor or self.horizon_absorption)

    def inputs(self):
        """`Evolution.inputs`: every input, with units in the key names; only floats, ints, bools, strings and
        lists of floats (absent f_min/f_max and the value of 'steps'/'final' sampling are NaN)."""
        nan = math.nan
        return {
            "m1_Msun": self.m1, "m2_Msun": self.m2, "chi1": self.chi1.tolist(), "chi2": self.chi2.tolist(),
            "f_ref_Hz": self.f_ref, "f_min_Hz": nan if self.f_min is None else self.f_min,
            "f_max_Hz": nan if self.f_max is None else self.f_max, "approximant": self.approximant,
            "pn_order": self.pn_order, "spin_orbit_order": self.spin_orbit_order,
            "spin_spin_order": self.spin_spin_order, "ell_hat": self.ell_hat.tolist(), "n_hat": self.n_hat.tolist(),
            "kappa1": self.kappa1, "kappa2": self.kappa2, "lambda1": self.lambda1, "lambda2": self.lambda2,
            "tidal_order": self.tidal_order, "atol": float(self.atol), "rtol": float(self.rtol),
            "sampling": self.sampling,
            "sampling_value": nan if self.sampling_value is None else float(self.sampling_value),
            "rotor": self.rotor, "precession_phase_shift": bool(self.precession_phase_shift),
            "integrate_rotor": bool(self.integrate_rotor), "precession": self.precession,
            "horizon_absorption": bool(self.horizon_absorption),
            "max_steps": int(self.max_steps), "M_seconds": self.M_sec, "v_ref": self.v0,
            "spin_content": self.spin_content, "state": "aligned" if self.use_aligned else "precessing",
        }


Checked = NamedTuple("Checked", [(field.name, field.type) for field in dataclasses.fields(Options)]
                     + [("sampling", str), ("sampling_value", float)])
Checked.__doc__ = """A run's options as it uses them: the fields of :class:`pnrotor.Options`, with the values of
:attr:`pnrotor.Options.resolved`, then the parsed sampling (mode, value) — what the binaries of ``evolve_many`` share.
Fields as in :class:`Settings` (a NamedTuple: a frozen dataclass cost ~2 µs more per run to build)."""


def settings(m1, m2, chi1, chi2, f_ref, caller="evolve", /, *, f_min, f_max, ell_hat, n_hat, kappa1, kappa2, lambda1,
             lambda2, sampling, options=None, **keywords):
    """Check and convert :func:`pnrotor.pn.evolve.evolve`'s arguments (its docstring has their meaning and
    defaults; ``options`` and ``keywords`` as :func:`pnrotor.options.options_of`'s for ``caller``, the name of the
    function called, for errors) → :class:`Settings`; a ``ValueError`` naming the first bad one (the options
    first)."""
    o = checked(options_of(options, keywords, caller), sampling)
    return binary_settings(o, m1, m2, chi1, chi2, f_ref, f_min, f_max, ell_hat, n_hat, kappa1, kappa2, lambda1,
                           lambda2)


def checked(options, sampling):
    """:class:`Checked` of a :class:`pnrotor.Options` and a ``sampling`` (a ValueError listing its forms)."""
    return Checked(*options.resolved, *parse_sampling(sampling))


def binary_settings(o, m1, m2, chi1, chi2, f_ref, f_min, f_max, ell_hat, n_hat, kappa1, kappa2, lambda1=0.0,
                    lambda2=0.0):
    """:class:`Settings` of one binary run with :class:`Checked` ``o`` (the rest of :func:`settings`'s checks,
    those of the binary; ``evolve_many`` checks the options once and calls this per binary)."""
    m1, m2, f_ref, f_min, f_max = masses_and_frequencies(m1, m2, f_ref, f_min, f_max)
    c1 = _ini.spin_vector(chi1, "chi1")
    c2 = _ini.spin_vector(chi2, "chi2")
    ell, n = _ini.orthonormal_frame(ell_hat, n_hat)
    kappa1 = _nonnegative(kappa1, "kappa1", _KAPPA)
    kappa2 = _nonnegative(kappa2, "kappa2", _KAPPA)
    lambda1 = _nonnegative(lambda1, "lambda1", _LAMBDA)
    lambda2 = _nonnegative(lambda2, "lambda2", _LAMBDA)
    M_sec, X1, v0, v_min, v_max = frequencies(m1, m2, f_ref, f_min, f_max)
    spin_content, c1, c2 = _spin_content(c1, c2, ell)
    return Settings(m1, m2, c1, c2, f_ref, f_min, f_max, ell, n, kappa1, kappa2, lambda1, lambda2, *o, M_sec, X1,
                    X1 * (1.0 - X1), v0, v_min, v_max, _frame_rotor(ell.tobytes() + n.tobytes()).copy(), spin_content)


class Binaries(NamedTuple):
    """The per-binary fields of :class:`Settings` for a population (:func:`population_settings`), row i binary i:
    M_sec, X1, nu, v0 (n,); v_min (n,), NaN without f_min; v_max (n,), 1 without f_max; chi1, chi2, ell_hat (n, 3);
    R0 (n, 4); ``aligned`` (n,), Settings.use_aligned; ``valid`` (n,), whether the row holds a binary's values."""

    M_sec: np.ndarray
    X1: np.ndarray
    nu: np.ndarray
    v0: np.ndarray
    v_min: np.ndarray
    v_max: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    ell_hat: np.ndarray
    R0: np.ndarray
    aligned: np.ndarray
    valid: np.ndarray

    def put(self, i, s):
        """Row i from the Settings s of binary i."""
        for name in ("M_sec", "X1", "nu", "v0", "v_max", "chi1", "chi2", "ell_hat", "R0"):
            getattr(self, name)[i] = getattr(s, name)
        self.v_min[i] = math.nan if s.v_min is None else s.v_min
        self.aligned[i] = s.use_aligned
        self.valid[i] = True


def population_settings(o, m1, m2, chi1, chi2, f_ref, f_min, f_max, ell_hat, n_hat, kappa1, kappa2, lambda1=0.0,
                        lambda2=0.0):
    """:func:`binary_settings` of n binaries with :class:`Checked` ``o`` over float64 arrays ((n,), (n, 3); NaN in
    f_min and f_max for none) → :class:`Binaries`.  Where a binary passes every check of binary_settings, its row is
    valid and holds bitwise that function's numbers (the same operations in the same order, elementwise; pow as
    libm's, :func:`~pnrotor.pn.initial.elementwise`); every other row is left invalid for binary_settings to
    refuse, with its message (``evolve_many``)."""
    n = m1.shape[0]
    with np.errstate(all="ignore"):
        def positive(x):
            return np.isfinite(x) & (x > 0.0)

        def unit(a):
            norm = np.sqrt(a[:, 0] * a[:, 0] + a[:, 1] * a[:, 1] + a[:, 2] * a[:, 2])
            return a / norm[:, None], np.isfinite(a).all(axis=1) & ~(np.abs(norm - 1.0) > _ini.FRAME_TOL)

        ok = positive(m1) & positive(m2) & positive(f_ref) & ~(np.maximum(m1, m2) > MAX_MASS_RATIO * np.minimum(m1, m2))
        ok &= np.isfinite(kappa1) & (kappa1 >= 0.0) & np.isfinite(kappa2) & (kappa2 >= 0.0)
        ok &= np.isfinite(lambda1) & (lambda1 >= 0.0) & np.isfinite(lambda2) & (lambda2 >= 0.0)
        for c in (chi1, chi2):
            square = c[:, 0] * c[:, 0] + c[:, 1] * c[:, 1] + c[:, 2] * c[:, 2]
            ok &= np.isfinite(c).all(axis=1) & ~(square > 1.0 + 1e-14)
        ell, ok_l = unit(ell_hat)
        nh, ok_n = unit(n_hat)
        dot = ell[:, 0] * nh[:, 0] + ell[:, 1] * nh[:, 1] + ell[:, 2] * nh[:, 2]
        ok &= ok_l & ok_n & ~(np.abs(dot) > _ini.FRAME_TOL)
        nh = nh - dot[:, None] * ell
        nh = nh / np.sqrt(nh[:, 0] * nh[:, 0] + nh[:, 1] * nh[:, 1] + nh[:, 2] * nh[:, 2])[:, None]
        M_sec = (m1 + m2) * _ini.MTSUN_SI
        X1 = m1 / (m1 + m2)

        def v_at(f, given):
            return _ini.elementwise(_ini.v_from_frequency, np.where(given, f, 1.0), np.where(given, M_sec, 1.0))

        v0 = v_at(f_ref, ok)
        ok &= (v0 < 1.0) & (v0 >= V_MIN)
        has_min, has_max = ~np.isnan(f_min), ~np.isnan(f_max)
        ok &= ~has_min | positive(f_min)
        ok &= ~has_max | positive(f_max)
        v_min, v_max = v_at(f_min, ok & has_min), v_at(f_max, ok & has_max)
        ok &= ~has_min | ((v_min >= V_MIN) & (v_min < v0))
        ok &= ~has_max | ((v_max <= 1.0) & (v_max > v0))
        # _spin_content
        a1 = chi1[:, 0] * ell[:, 0] + chi1[:, 1] * ell[:, 1] + chi1[:, 2] * ell[:, 2]
        a2 = chi2[:, 0] * ell[:, 0] + chi2[:, 1] * ell[:, 1] + chi2[:, 2] * ell[:, 2]

        def in_plane(c, a):
            d = c - a[:, None] * ell
            return d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2] > 1e-28

        precessing = ((chi1 != 0.0).any(axis=1) | (chi2 != 0.0).any(axis=1)) & (in_plane(chi1, a1) | in_plane(chi2, a2))
        c1 = np.where(precessing[:, None], chi1, a1[:, None] * ell)
        c2 = np.where(precessing[:, None], chi2, a2[:, None] * ell)
    R0 = np.full((n, 4), np.nan)
    frames = np.ascontiguousarray(np.concatenate([ell, nh], axis=1))
    first = np.flatnonzero(ok)[:1]
    if first.size:   # the frames that equal the first valid row's bitwise (usually all) take its rotor
        same = (frames.view(np.int64) == frames[first].view(np.int64)).all(axis=1) & ok
        R0[same] = _frame_rotor(frames[first[0]].tobytes())
        for i in np.flatnonzero(ok & ~same).tolist():
            R0[i] = _frame_rotor(frames[i].tobytes())
    return Binaries(M_sec, X1, X1 * (1.0 - X1), v0, np.where(has_min, v_min, np.nan), np.where(has_max, v_max, 1.0),
                    c1, c2, ell, R0, ~precessing & (not (o.integrate_rotor or o.horizon_absorption)), ok)


@functools.lru_cache(maxsize=16)
def _frame_rotor(ell_n):
    """:func:`pnrotor.pn.initial.frame_rotor` of ℓ̂, n̂ given as the bytes of the two float64 arrays, cached
    (exact key, so signed zeros too): runs usually share their frame, and the rotor costs ~4 µs."""
    ell_n = np.frombuffer(ell_n)
    return _ini.frame_rotor(ell_n[:3], ell_n[3:])


_KAPPA = "1 for a black hole, ~2-20 for neutron stars"
_LAMBDA = "the dimensionless tidal deformability: 0 for a black hole, ~10-5000 for neutron stars"


def _nonnegative(value, name, meaning):
    """A finite number ≥ 0: κᵢ (``meaning`` :data:`_KAPPA`) or Λᵢ (:data:`_LAMBDA`)."""
    x = values.float_or_nan(value)
    if not (math.isfinite(x) and x >= 0.0):
        raise ValueError(f"{name} must be a finite number >= 0 ({meaning}), got {value!r}")
    return x


def masses_and_frequencies(m1, m2, f_ref, f_min, f_max):
    """m1, m2 in M☉ and f_ref, f_min, f_max (None allowed) in Hz as ``evolve`` takes them (floats or astropy
    Quantities), each checked finite and positive (a ValueError naming it)."""
    return (_ini.solar_masses(m1, "m1"), _ini.solar_masses(m2, "m2"), _ini.hertz(f_ref, "f_ref"),
            _ini.hertz(f_min, "f_min", allow_none=True), _ini.hertz(f_max, "f_max", allow_none=True))


def frequencies(m1, m2, f_ref, f_min, f_max):
    """(G M/c³ in s, X₁, v at f_ref, at f_min (or None), at f_max (or 1)), checking the mass ratio, the order of
    the frequencies, V_MIN ≤ v < 1 at f_min and f_ref and v ≤ 1 at f_max (of :func:`masses_and_frequencies`' values; also the
    check of a population's rows that :func:`population_settings` does not pass)."""
    if not max(m1, m2) <= MAX_MASS_RATIO * min(m1, m2):
        raise ValueError(f"m1/m2 = {m1 / m2:.4g}: the mass ratio must be at most {MAX_MASS_RATIO:g} either way")
    M_sec = _ini.total_mass_seconds(m1, m2)
    X1 = m1 / (m1 + m2)
    v0 = _ini.v_from_frequency(f_ref, M_sec)
    if v0 >= 1.0:
        raise ValueError(f"f_ref = {f_ref} Hz gives v = {v0:.4g} >= 1; f_ref must be below "
                         f"{1.0 / (math.pi * M_sec):.6g} Hz")
    if v0 < V_MIN:
        raise ValueError(f"f_ref = {f_ref} Hz gives v = {v0:.4g} < {V_MIN:g}; for these masses f_ref must be at "
                         f"least {_ini.frequency_from_v(V_MIN, M_sec):.6g} Hz")
    v_min = None if f_min is None else target_v(f_min, "f_min", False, f_ref, v0, M_sec)
    v_max = 1.0 if f_max is None else target_v(f_max, "f_max", True, f_ref, v0, M_sec)
    return M_sec, X1, v0, v_min, v_max


def target_v(f, name, forward, f_ref, v0, M_sec):
    """v at the GW frequency f where a run from f_ref (v = v0) ends: forward (f_max) above v0 and at most 1,
    backward (f_min) below v0 and at least V_MIN; else a ValueError naming ``name``.  The checks are on v, so a
    frequency an ulp from f_ref that gives v0 is refused too (``evolve_many`` applies them to each listed
    target)."""
    v = _ini.v_from_frequency(f, M_sec)
    if forward and v > 1.0:
        raise ValueError(f"{name} = {f} Hz gives v = {v:.4g} > 1; for these masses {name} must be at most "
                         f"{1.0 / (math.pi * M_sec):.6g} Hz")
    if not forward and v < V_MIN:
        raise ValueError(f"{name} = {f} Hz gives v = {v:.4g} < {V_MIN:g}; for these masses {name} must be at "
                         f"least {_ini.frequency_from_v(V_MIN, M_sec):.6g} Hz")
    if not (v > v0 if forward else v < v0):
        side = "above" if forward else "below"
        if f > f_ref if forward else f < f_ref:
            raise ValueError(f"{name} = {f!r} Hz is too close to f_ref = {f_ref!r} Hz: both give v = {v0!r} in "
                             f"float64; {name} must be far enough {side} f_ref to give a v {side} it")
        raise ValueError(f"{name} = {f} Hz must be {side} f_ref = {f_ref} Hz")
    return v


def _spin_content(c1, c2, ell):
    """('nonspinning' | 'aligned' | 'precessing', χ₁, χ₂); aligned spins (in-plane parts ≤ 1e-14) are made
    exactly parallel to ℓ̂."""
    lx, ly, lz = ell.tolist()     # Python floats: numpy costs ~0.5 µs per operation on three numbers
    x1, y1, z1 = c1.tolist()
    x2, y2, z2 = c2.tolist()
    a1 = x1 * lx + y1 * ly + z1 * lz
    a2 = x2 * lx + y2 * ly + z2 * lz
    if x1 or y1 or z1 or x2 or y2 or z2:
        # squares as products: Python's x ** 2 is libm's pow, numpy's (population_settings) is x * x, and the two
        # differ in the last bit for ~0.1% of numbers, which could classify a spin on the bound differently
        dx1, dy1, dz1 = x1 - a1 * lx, y1 - a1 * ly, z1 - a1 * lz
        dx2, dy2, dz2 = x2 - a2 * lx, y2 - a2 * ly, z2 - a2 * lz
        if dx1 * dx1 + dy1 * dy1 + dz1 * dz1 > 1e-28 or dx2 * dx2 + dy2 * dy2 + dz2 * dz2 > 1e-28:
            return "precessing", c1, c2
        content = "aligned"
    else:
        content = "nonspinning"   # (zero spins have no in-plane part)
    return content, a1 * ell, a2 * ell


MAX_PER_ORBIT = 2 ** 53
"""The largest number of samples per orbit taken (exact as a float; the memory check refuses far fewer)."""


SAMPLING_FORMS = ("'steps', 'final', a time step in seconds (a number, an astropy time, ('dt', seconds), "
                  "{'dt': seconds}, or text such as '1/4096' or '0.000244'), or n samples per orbit (('per_orbit', n), "
                  "{'per_orbit': n} or 'per_orbit:n', n an integer from 1 to 2^53)")
"""Every form `pnrotor.evolve`'s ``sampling`` takes (the command line's spellings among them), as its errors list
them."""


def parse_sampling(sampling):
    """→ ('steps', None) | ('final', None) | ('dt', seconds) | ('per_orbit', n), from any of
    :data:`SAMPLING_FORMS`; a ValueError listing them."""
    if isinstance(sampling, str):
        s = sampling.strip().lower()
        if s in ("steps", "step", "accepted"):
            return "steps", None
        if s == "final":
            return "final", None
        numerator, slash, denominator = s.partition("/")
        if s.startswith("per_orbit:"):
            count = s.partition(":")[2].strip()
            sampling = ("per_orbit", int(count) if count.isascii() and count.isdigit() else count)
        else:
            try:
                sampling = float(numerator) / float(denominator) if slash else float(s)
            except (ValueError, ZeroDivisionError):
                raise ValueError(f"sampling must be {SAMPLING_FORMS}; got {sampling!r}") from None
    if isinstance(sampling, dict):
        if len(sampling) != 1:
            raise ValueError(f"a sampling dict must have exactly one key, 'dt' or 'per_orbit': sampling must be "
                             f"{SAMPLING_FORMS}; got {sampling!r}")
        (key, val), = sampling.items()
        sampling = (key, val)
    if isinstance(sampling, tuple):
        if len(sampling) != 2:
            raise ValueError(f"sampling must be {SAMPLING_FORMS}; got {sampling!r}")
        key, val = sampling
        if key == "dt":
            return "dt", _ini.seconds(val, "sampling dt")
        if key == "per_orbit":
            if not (values.real(val) and 1 <= val <= MAX_PER_ORBIT and val == int(val)):   # no NaN, inf, 10**400
                raise ValueError(f"sampling per_orbit must be an integer from 1 to 2^53, got {val!r}")
            return "per_orbit", int(val)
        raise ValueError(f"unknown sampling key {key!r}: sampling must be {SAMPLING_FORMS}; got {sampling!r}")
    # a bare number or Quantity: Δt in seconds
    if not (values.real(sampling) or hasattr(sampling, "unit")):
        raise ValueError(f"sampling must be {SAMPLING_FORMS}; got {sampling!r}")
    return "dt", _ini.seconds(sampling, "sampling dt")
