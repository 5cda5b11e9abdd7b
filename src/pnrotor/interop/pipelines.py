r"""What pnrotor's plugins for the analysis pipelines share (:mod:`pnrotor.interop.pycbc`,
:mod:`pnrotor.interop.gwsignal`, :mod:`pnrotor.interop.bilby`): one binary's h₊, h× or modes from the keywords of
LALSuite's SpinTaylor family, meaning what they mean there.

The conventions are those of ``XLALSimInspiralChooseTDWaveform`` for SpinTaylorT4 (LALSimInspiralGeneratorLegacy.c,
LALSimInspiralSpinTaylor.c; checked against it sample by sample in tests/test_pipelines.py):

* χ₁, χ₂ are given at f_ref in the frame of the orbit there, x̂ = n̂ (from body 2 to body 1), ẑ = L̂_N (LAL's default
  frame axis, ORBITAL_L): pnrotor's ``ell_hat = ẑ, n_hat = x̂``;
* the line of sight is at polar angle ``inclination`` from L̂_N and azimuth π/2 − φ_ref in that frame
  (``XLALSimInspiralInitialConditionsPrecessingApproxs``: N·n̂ = sin ι sin φ_ref, N·λ̂ = sin ι cos φ_ref), and h₊, h×
  are :meth:`pnrotor.waveform.modes.Modes.polarizations` there; the longitude of the ascending nodes Ω rotates them
  as LAL does (h₊ → h₊ cos 2Ω + h× sin 2Ω, h× → h× cos 2Ω − h₊ sin 2Ω);
* f_ref = 0 means f_lower (LAL's ``FIX_REFERENCE_FREQUENCY`` for the SpinTaylors); an f_ref below f_lower is refused;
* the samples are at f_ref's time + kΔt from f_lower to the end of the inspiral, the last at t = 0: the epoch is
  −(N − 1)Δt, LAL SpinTaylor's (``XLALSimInspiralSpinTaylorPNEvolveOrbit``: "Adjust tStart so last sample is at
  time=0", which ``appendTSandFree`` keeps when it joins the halves before and after f_ref); LAL's series have one
  sample more at the start (its backward half keeps the first sample below f_lower);
* the PN orders are LAL's integers, twice the PN order, −1 meaning pnrotor's default: ``amplitude_order`` k → the
  modes' amplitude order k/2 (−1: 3.5PN, all pnrotor has), ``phase_order`` k → ``pn_order`` k/2 (−1: 3.5PN),
  ``spin_order`` k → ``spin_orbit_order`` and ``spin_spin_order`` min(k/2, their maxima) (−1: pnrotor's defaults,
  which keep the 3.5PN and 4PN spin-orbit terms of v̇ that LAL's SpinTaylorT4 leaves out: ``spin_order=6`` is LAL's
  truncation, :func:`pnrotor.pn.lalsuite_orders`);
* ``dquad_mon1``, ``dquad_mon2`` give κᵢ = 1 + dquad_monᵢ (LAL's quadparam);
* tides: ``lambda1``, ``lambda2`` are the dimensionless deformabilities Λᵢ (pnrotor's and LAL's, None meaning 0), and
  ``tidal_order`` is LAL's tideO: −1 all (5PN and 6PN), 12 (6PN), 10 (5PN only) or 0 none
  (:data:`pnrotor.pn.evolve.LAL_TIDAL_ORDERS`; LAL's SpinTaylor refuses the others); they enter the orbit.  The tidal
  terms of the amplitude (5PN to 6PN, :mod:`pnrotor.waveform.tidal`) come with ``amplitude_order=-1`` (all pnrotor
  has) and not with an amplitude order k ≥ 0, which keeps the terms through v^k (k ≤ 7): as LAL's SpinTaylor
  polarizations and modes, which have none;
* the modes are ℓ ≤ ``ell_max``, by default all those the amplitude order has: ℓ enters at (ℓ − 2)/2 PN, so
  ℓ ≤ 2 + k, at most :data:`pnrotor.waveform.modes.ELL_MAX`.

Every pnrotor option of :func:`pnrotor.evolve` but those the hosts set (sampling, f_min, ell_hat, n_hat,
approximant) and ``tidal_order`` (LAL's meaning here) passes through by name, with ``ell_max``.  Bad input is a ``ValueError`` naming the parameter; each
host turns it into its own exception.
"""

import functools
import math
from typing import NamedTuple

__all__ = ["polarizations", "modes", "spintaylor_polarizations", "spintaylor_modes", "end_frequency"]

APPROXIMANTS = ("T1", "T4", "T5")
HOST_SET = ("sampling", "f_min", "ell_hat", "n_hat", "approximant")
"""Options of :func:`pnrotor.evolve` that the hosts' own keywords set."""


def polarizations(m1, m2, chi1, chi2, f_ref, *, inclination, distance, delta_t, phi_ref=0.0, f_min=None, f_max=None,
                  ell_max=8, amplitude_order=3.5, amplitude_tides=None, **options):
    """(t, h₊, h×) of a binary: float64 arrays, t in s (t = 0 at f_ref, samples at kΔt from f_min, or f_ref, to f_max
    or the end of the inspiral), strain at ``distance`` Mpc seen from (ι, π/2 − φ_ref) of the frame (n̂, λ̂, ℓ̂) at
    f_ref; ``options`` go to :func:`pnrotor.evolve`, ``amplitude_tides`` is the modes' ``tidal_order`` (None: the
    run's; 0: no tidal amplitude terms).

    The one call the plugins make for polarizations: ``pnrotor.polarizations``' streamed route (h₊, h× computed from
    the integrator's dense output, :mod:`pnrotor.waveform.stream`), with the modes' tidal order of its own."""
    from pnrotor import stream

    p = stream(m1, m2, chi1, chi2, f_ref, delta_t=delta_t, f_min=f_min, f_max=f_max, **options).polarizations(
        inclination=inclination, distance=distance, phi_ref=phi_ref, ell_max=ell_max, amplitude_order=amplitude_order,
        tidal_order=amplitude_tides).compute()
    return p.t_seconds, p.h_plus, p.h_cross


def modes(m1, m2, chi1, chi2, f_ref, *, distance, delta_t, f_min=None, f_max=None, ell_max=8, amplitude_order=3.5,
          amplitude_tides=None, **options):
    """:class:`pnrotor.waveform.modes.Modes` (inertial frame ẑ = ℓ̂, x̂ = n̂ at f_ref, strain at ``distance`` Mpc)
    on the samples of :func:`polarizations`: ``pnrotor.modes``' streamed route."""
    from pnrotor import stream

    return stream(m1, m2, chi1, chi2, f_ref, delta_t=delta_t, f_min=f_min, f_max=f_max, **options).modes(
        ell_max, amplitude_order, distance, tidal_order=amplitude_tides).compute()


class Arguments(NamedTuple):
    """A host's SpinTaylor keywords as pnrotor's: f_ref and f_min in Hz (f_min None when the waveform starts at
    f_ref), ℓ_max, the amplitude order (PN), the modes' tidal order (None: the run's; 0: none), and the options of
    :func:`pnrotor.evolve`."""

    f_ref: float
    f_min: float
    ell_max: int
    amplitude_order: float
    amplitude_tides: float
    options: dict


@functools.cache
def evolve_options():
    """The keyword options of :func:`pnrotor.evolve` a host may pass through: its named keywords and the fields of
    :class:`pnrotor.Options` (each by name, not ``options`` itself), but those the host sets."""
    from pnrotor.options import OPTION_DEFAULTS
    from pnrotor.pn.evolve import OPTIONS

    return frozenset(name for name in (*OPTIONS, *OPTION_DEFAULTS) if name not in HOST_SET + ("tidal_order", "options"))


def _lal_order(value, name, highest):
    """The PN order of a LAL order ``value`` (−1, or an integer 0 … ``highest``: twice the PN order), None for −1."""
    from pnrotor.values import real

    k = float(value) if real(value) else math.nan
    if not (k == -1 or k in range(highest + 1)):
        raise ValueError(f"{name} must be -1 (pnrotor's default) or an integer from 0 to {highest} (twice the PN "
                         f"order); got {value!r}")
    return None if k == -1 else k / 2


def arguments(approximant, f_lower, f_ref, amplitude_order=-1, phase_order=-1, spin_order=-1, tidal_order=-1,
              dquad_mon1=None, dquad_mon2=None, lambda1=None, lambda2=None, **options):
    """:class:`Arguments` from the SpinTaylor keywords (module docstring); a ValueError naming the first bad one."""
    from pnrotor.pn.evolve import LAL_TIDAL_ORDERS
    from pnrotor.values import real
    from pnrotor.options import MAX_SO_ORDER, MAX_SS_ORDER
    from pnrotor.waveform.modes import ELL_MAX

    unknown = sorted(set(options) - evolve_options() - {"ell_max"})
    if unknown:
        host_set = [name for name in unknown if name in HOST_SET]
        if host_set:
            raise ValueError(f"{', '.join(host_set)}: set by the host's own keywords (approximant, delta_t, f_lower; "
                             f"the frame is L_N's at f_ref), not a pnrotor option here")
        raise ValueError(f"unknown option(s) {', '.join(map(repr, unknown))}: pnrotor's options here are "
                         f"{', '.join(sorted(evolve_options() | {'ell_max'}))}")
    if approximant not in APPROXIMANTS:
        raise ValueError(f"approximant must be one of {', '.join(APPROXIMANTS)}; got {approximant!r}")
    for name, value in (("f_lower", f_lower), ("f_ref", f_ref)):
        if not (real(value) and math.isfinite(value)):
            raise ValueError(f"{name} must be a finite frequency in Hz; got {value!r}")
    f_lower, f_ref = float(f_lower), float(f_ref)
    if f_ref == 0.0:
        f_ref = f_lower
    if f_ref < f_lower:
        raise ValueError(f"f_ref = {f_ref!r} Hz must not be below f_lower = {f_lower!r} Hz (or 0, meaning f_lower)")
    order = _lal_order(amplitude_order, "amplitude_order", 7)
    amplitude_tides = None if order is None else 0.0
    order = 3.5 if order is None else order
    ell_max = options.pop("ell_max", None)
    if ell_max is None:
        ell_max = min(ELL_MAX, 2 + int(2 * order))
    pn_order = _lal_order(phase_order, "phase_order", 9)
    spin = _lal_order(spin_order, "spin_order", 8)
    tides = LAL_TIDAL_ORDERS.get(float(tidal_order) if real(tidal_order) else None)
    if tides is None:
        raise ValueError(f"tidal_order must be -1 (all: 5PN and 6PN), 12 (6PN), 10 (5PN) or 0 (none), LAL's tideO; "
                         f"got {tidal_order!r}")
    options["tidal_order"] = tides
    given = (("phase_order", "pn_order", pn_order),
             ("spin_order", "spin_orbit_order", None if spin is None else min(spin, MAX_SO_ORDER)),
             ("spin_order", "spin_spin_order", None if spin is None else min(spin, MAX_SS_ORDER)),
             ("dquad_mon1", "kappa1", None if dquad_mon1 is None else 1.0 + dquad_mon1),
             ("dquad_mon2", "kappa2", None if dquad_mon2 is None else 1.0 + dquad_mon2),
             ("lambda1", "lambda1", lambda1), ("lambda2", "lambda2", lambda2))
    for keyword, name, value in given:
        if value is None:
            continue
        if name in options:
            raise ValueError(f"give either {keyword} or pnrotor's {name}, not both")
        options[name] = value
    return Arguments(f_ref, None if f_ref == f_lower else f_lower, ell_max, order,
                     amplitude_tides, dict(options, approximant=approximant))


def _check_masses(m1, m2):
    """pnrotor's check of the masses, first: a host may derive f_lower from them (NaN from a negative mass)."""
    from pnrotor.pn.initial import solar_masses

    solar_masses(m1, "m1")
    solar_masses(m2, "m2")


def _epoch(t, delta_t):
    """LAL SpinTaylor's epoch of samples ``t``: −(N − 1)Δt, the last sample at t = 0."""
    if t.size < 2:
        raise ValueError(f"delta_t = {delta_t!r} s leaves fewer than 2 samples of this inspiral")
    return -(t.size - 1) * delta_t


def spintaylor_polarizations(approximant, m1, m2, chi1, chi2, *, distance, inclination, phi_ref, delta_t, f_lower,
                             f_ref=0.0, long_asc_nodes=0.0, **keywords):
    """(epoch in s, h₊, h×) with the meaning of LAL's ChooseTDWaveform(SpinTaylor``approximant``) (module docstring):
    masses in M☉, χᵢ (3,), distance in Mpc, angles in rad, frequencies in Hz, ``keywords`` those of
    :func:`arguments` and pnrotor's options."""
    from pnrotor.values import real

    if not (real(long_asc_nodes) and math.isfinite(long_asc_nodes)):
        raise ValueError(f"long_asc_nodes must be a finite angle in radians; got {long_asc_nodes!r}")
    _check_masses(m1, m2)
    a = arguments(approximant, f_lower, f_ref, **keywords)
    t, hp, hc = polarizations(m1, m2, chi1, chi2, a.f_ref, inclination=inclination, distance=distance,
                              delta_t=delta_t, phi_ref=phi_ref, f_min=a.f_min, ell_max=a.ell_max,
                              amplitude_order=a.amplitude_order, amplitude_tides=a.amplitude_tides, **a.options)
    if long_asc_nodes:
        c, s = math.cos(2.0 * long_asc_nodes), math.sin(2.0 * long_asc_nodes)
        hp, hc = c * hp + s * hc, c * hc - s * hp
    return _epoch(t, delta_t), hp, hc


def spintaylor_modes(approximant, m1, m2, chi1, chi2, *, distance, delta_t, f_lower, f_ref=0.0, **keywords):
    """(epoch in s, :class:`~pnrotor.waveform.modes.Modes`) on the samples of :func:`spintaylor_polarizations`, in
    the frame of LAL's ChooseTDModes(SpinTaylor…): ẑ = L̂_N, x̂ = n̂ at f_ref; seen from (ι, π/2 − φ_ref) they give
    its h₊, h× (at Ω = 0)."""
    _check_masses(m1, m2)
    a = arguments(approximant, f_lower, f_ref, **keywords)
    m = modes(m1, m2, chi1, chi2, a.f_ref, distance=distance, delta_t=delta_t, f_min=a.f_min, ell_max=a.ell_max,
              amplitude_order=a.amplitude_order, amplitude_tides=a.amplitude_tides, **a.options)
    return _epoch(m.t_seconds, delta_t), m


def end_frequency(approximant, m1, m2, chi1, chi2, *, f_lower, f_ref=0.0, **keywords):
    """The highest frequency in Hz of the waveform of :func:`spintaylor_polarizations`: that of the highest
    harmonic, m = ℓ_max, at the end of the inspiral, (ℓ_max / 2) f_GW(v_end), from one run to the end without
    output."""
    from pnrotor import evolve

    a = arguments(approximant, f_lower, f_ref, **keywords)
    run = evolve(m1, m2, chi1, chi2, a.f_ref, sampling="final", **a.options)
    return 0.5 * a.ell_max * float(run.f_gw[-1])
