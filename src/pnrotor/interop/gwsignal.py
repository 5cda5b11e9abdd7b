"""LAL gwsignal generator: pnrotor's T1, T4 or T5 waveform for ``lalsimulation.gwsignal``.

::

    from lalsimulation.gwsignal import GenerateTDWaveform, GenerateFDWaveform, GenerateTDModes
    from pnrotor.interop.gwsignal import PNRotorGenerator

    params = dict(mass1=30 * u.solMass, mass2=10 * u.solMass, spin1x=0.5 * u.dimensionless_unscaled, …,
                  deltaT=1 / 4096 * u.s, f22_start=20 * u.Hz, f22_ref=25 * u.Hz, phi_ref=0.4 * u.rad,
                  distance=100 * u.Mpc, inclination=0.7 * u.rad, condition=0)
    hpc = GenerateTDWaveform(params, PNRotorGenerator("T4", amplitude_order=0))
    hpc.hp, hpc.hc                       # gwpy TimeSeries (unit strain), epoch −(N − 1)Δt
    hpc.strain("H1", ra, dec, psi, tgps)

The parameters mean what they mean for LAL's SpinTaylorT4 generator (:mod:`pnrotor.interop.pipelines`): masses,
Cartesian spins at f22_ref in the frame of L̂_N there, f22_ref = 0 meaning f22_start, φ_ref, inclination,
longAscNodes, and the tidal deformabilities lambda1, lambda2; numbers without units are SI, as gwsignal reads them.
pnrotor's own options and LAL's PN orders (``amplitude_order``, ``phase_order``, ``spin_order``, ``tidal_order``:
LAL's integers, −1 pnrotor's default and all tidal terms) are given to the generator or, per call, in the parameters
(bilby passes its extra waveform arguments that way); ``lmax`` > 0 sets ℓ_max.  With ``condition=1``, gwsignal's own conditioning (``conditioning_routines='gwsignal'``) tapers and
high-passes the time domain and makes ``GenerateFDWaveform`` possible; it knows f22_ref = 0 only for its NRSurr,
so give a nonzero f22_ref there.  Bad input raises the ``ValueError`` that gwsignal maps LAL's input domain errors
to, ``"Input domain error: "`` with pnrotor's message (bilby's ``catch_waveform_errors`` recognizes it).
"""

import astropy.units as u
import lal
import numpy as np
from gwpy.timeseries import TimeSeries
from lalsimulation.gwsignal.core import parameter_conventions
from lalsimulation.gwsignal.core.waveform import CompactBinaryCoalescenceGenerator

from pnrotor.interop import pipelines

__all__ = ["PNRotorGenerator"]

UNITS = {"mass1": u.kg, "mass2": u.kg, "deltaT": u.s, "f22_start": u.Hz, "f22_ref": u.Hz, "distance": u.m,
         "phi_ref": u.rad, "inclination": u.rad, "longAscNodes": u.rad, "meanPerAno": u.rad,
         "eccentricity": u.dimensionless_unscaled, "lambda1": u.dimensionless_unscaled,
         "lambda2": u.dimensionless_unscaled,
         **{f"spin{i}{c}": u.dimensionless_unscaled for i in (1, 2) for c in "xyz"}}
"""The gwsignal parameters read here, with the SI unit of a number given without one."""
UNMODELLED = {"eccentricity": 0.0, "meanPerAno": 0.0, "ModeArray": None}
"""gwsignal parameters of physics pnrotor does not model, with the values that leave it out."""
IGNORED = ("condition", "deltaF", "f_max")
"""gwsignal parameters of the conditioning and the frequency domain, which the time domain does not use (nor does
LAL's SpinTaylor)."""


def _value(params, key, default=None):
    """``params[key]`` in the SI unit of :data:`UNITS`; if absent ``default``, or gwsignal's default, or 0."""
    value = params.get(key, parameter_conventions.default_dict.get(key, 0.0) if default is None else default)
    if isinstance(value, u.Quantity):
        return value.to_value(UNITS[key])
    return value


def _domain_error(error):
    return ValueError(f"Input domain error: {error}")


class PNRotorGenerator(CompactBinaryCoalescenceGenerator):
    """gwsignal generator of pnrotor's ``approximant`` ('T1', 'T4', 'T5', or 'PNRotorT4' …) in the time domain,
    with default ``options`` (pnrotor's, and LAL's ``amplitude_order``, ``phase_order``, ``spin_order``) that each
    call's parameters may override (module docstring)."""

    def __init__(self, approximant="T4", **options):
        super().__init__()
        name = str(approximant).removeprefix("PNRotor")
        if name not in pipelines.APPROXIMANTS:
            raise ValueError(f"approximant must be one of {', '.join(pipelines.APPROXIMANTS)} (or PNRotorT1 …); "
                             f"got {approximant!r}")
        self.approximant = name
        self.options = options
        self._generation_domain = None
        self._implemented_domain = "time"

    def __repr__(self):
        return f"PNRotorGenerator({self.approximant!r}{''.join(f', {k}={v!r}' for k, v in self.options.items())})"

    @property
    def metadata(self):
        return {"type": "cbc_pnrotor", "f_ref_spin": True, "modes": True, "polarizations": True,
                "implemented_domain": "time", "generation_domain": self._generation_domain,
                "approximant": f"PNRotor{self.approximant}", "implementation": "pnrotor",
                "conditioning_routines": "gwsignal"}

    def _update_domains(self):
        self._implemented_domain = "time"

    def _binary(self, params):
        """(keywords of :func:`pnrotor.interop.pipelines.spintaylor_modes` but the angles, the angles (ι, φ_ref,
        Ω)) from gwsignal's ``params``; a ValueError for what pnrotor cannot take."""
        standard = set(parameter_conventions.full_parameter_list)
        options = dict(self.options, **{k: v for k, v in params.items() if k not in standard})
        for key, default in UNMODELLED.items():
            value = params.get(key, default) if key == "ModeArray" else _value(params, key, default)
            if not (value is default or value == default):
                raise ValueError(f"{key} = {value}: PNRotor{self.approximant} does not model it (leave it at "
                                 f"{default!r})")
        others = sorted(k for k in params if k in standard and k not in UNITS
                        and k not in IGNORED + ("lmax", "ModeArray"))
        if others:
            raise ValueError(f"PNRotorGenerator takes mass1, mass2, spin1x … spin2z, deltaT, f22_start, f22_ref, "
                             f"phi_ref, distance, inclination, longAscNodes; not {', '.join(others)}")
        lmax = params.get("lmax", 0)
        if lmax:
            options.setdefault("ell_max", lmax)
        options.update({key: _value(params, key) for key in ("lambda1", "lambda2") if key in params})
        for key in ("mass1", "mass2"):
            if key not in params:
                raise ValueError(f"PNRotorGenerator needs {key}")
        binary = dict(m1=_value(params, "mass1") / lal.MSUN_SI, m2=_value(params, "mass2") / lal.MSUN_SI,
                      chi1=[_value(params, f"spin1{c}") for c in "xyz"], chi2=[_value(params, f"spin2{c}") for c in "xyz"],
                      distance=_value(params, "distance") / (1e6 * lal.PC_SI),
                      delta_t=_value(params, "deltaT"), f_lower=_value(params, "f22_start"),
                      f_ref=_value(params, "f22_ref"), **options)
        angles = tuple(_value(params, key) for key in ("inclination", "phi_ref", "longAscNodes"))
        return binary, angles

    def generate_td_waveform(self, **params):
        """(h₊, h×) as gwpy ``TimeSeries`` (unit strain, epoch −(N − 1)Δt: LAL SpinTaylor's)."""
        try:
            binary, (inclination, phi_ref, long_asc_nodes) = self._binary(params)
            epoch, hp, hc = pipelines.spintaylor_polarizations(
                self.approximant, binary.pop("m1"), binary.pop("m2"), binary.pop("chi1"), binary.pop("chi2"),
                inclination=inclination, phi_ref=phi_ref, long_asc_nodes=long_asc_nodes, **binary)
        except (ValueError, TypeError) as error:
            raise _domain_error(error) from None
        dt = binary["delta_t"]
        return (TimeSeries(hp, t0=epoch, dt=dt, unit="strain", name="hplus"),
                TimeSeries(hc, t0=epoch, dt=dt, unit="strain", name="hcross"))

    def generate_td_modes(self, **params):
        """{'time_array': t, (ℓ, m): gwpy ``TimeSeries`` of h_ℓm (complex, strain)} in the frame of LAL's SpinTaylor
        modes, ẑ = L̂_N, x̂ = n̂ at f22_ref (φ_ref and longAscNodes unused, as LAL's): ``GenerateTDModes`` of them,
        called at (ι, π/2 − φ_ref), gives :meth:`generate_td_waveform`'s h₊, h× for longAscNodes = 0."""
        try:
            binary, _ = self._binary(params)
            epoch, m = pipelines.spintaylor_modes(self.approximant, binary.pop("m1"), binary.pop("m2"),
                                                  binary.pop("chi1"), binary.pop("chi2"), **binary)
        except (ValueError, TypeError) as error:
            raise _domain_error(error) from None
        dt = binary["delta_t"]
        out = {"time_array": epoch + dt * np.arange(m.data.shape[1])}
        for (ell, mm), h in zip(m.ell_m, m.data):
            out[ell, mm] = TimeSeries(h, t0=epoch, dt=dt, unit="strain", name=f"h_{ell}_{mm}")
        return out
