"""The results of waveforms: `Modes` (h_ℓm of one run in one frame, `pnrotor.modes`) and `Polarizations` (h₊, h×
seen from one direction, `pnrotor.polarizations`), each registered with the arrays its file holds
(`pnrotor.results.schema`), and the checks of their arguments that `pnrotor.waveform` shares with them.

Their methods compute (rotations, polarizations) with the kernels of `pnrotor.waveform` and `pnrotor.quaternion`,
imported when first called: importing a result type loads neither numba nor h5py.
"""

import math
import sys
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from pnrotor import processes
from pnrotor.results.schema import M_UNIT, ROTOR, Array, check, register, short_repr
from pnrotor.values import integer, positive, real

FRAMES = ("inertial", "coprecessing", "coorbital")
"""The frames of `Modes`: inertial, co-precessing (ẑ = ℓ̂, no orbital phase), co-orbital (ẑ = ℓ̂, x̂ = n̂)."""


def megaparsecs(distance):
    """Mpc from a float (Mpc) or an astropy Quantity of length; ValueError naming ``distance``."""
    return positive(distance, "Mpc", "distance", "distance in Mpc")


def angle(value, name):
    """Radians from a finite real number in [−2π, 2π] (radians) or an astropy angle (any value); ValueError naming
    ``name``: a number beyond 2π is most likely in degrees."""
    u = sys.modules.get("astropy.units")   # a Quantity exists only if its module was imported
    if u is not None and isinstance(value, u.Quantity):
        if value.unit.physical_type != "angle":
            raise ValueError(f"{name} must be an angle (radians, or an astropy angle); got {value!r}")
        value = value.to_value(u.rad)
    elif real(value) and math.isfinite(value) and not -2.0 * math.pi <= value <= 2.0 * math.pi:
        raise ValueError(f"{name} = {value!r} is outside [-2 pi, 2 pi]: angles are in radians ({value!r} degrees is "
                         f"{math.radians(value):.6g} rad; or pass an astropy angle, such as {value!r} * u.deg)")
    if not (real(value) and math.isfinite(value)):
        raise ValueError(f"{name} must be a finite angle in radians (a number, or an astropy angle); got {value!r}")
    return float(value)


class CoarseSamplingWarning(UserWarning):
    """Modes (or polarizations) of samples too far apart in orbital phase to be a waveform: the run's
    ``sampling`` (its integrator's steps, by default) is too coarse."""


def warn_if_coarse(Phi, inputs, what):
    """A :class:`CoarseSamplingWarning` naming ``sampling`` if the orbital phase Φ advances by π/2 or more between
    two samples somewhere: h₂₂ ∝ e^{−2iΦ} then has at most two samples per cycle (Nyquist's limit, where a
    sinusoid is no longer determined by its samples), so ``what`` cannot be interpolated or Fourier transformed
    as a waveform.  A warning rather than an error: the values at the samples are right (and 'steps' is the
    default sampling, of runs whose modes are asked for their amplitudes' evolution too)."""
    if np.size(Phi) < 2:
        return
    step = float(np.abs(np.diff(Phi)).max())
    if step >= 0.5 * math.pi:
        given = inputs.get("sampling", "?")
        given = {"dt": f"{inputs.get('sampling_value', math.nan):g} s", "per_orbit":
                 f"'per_orbit:{inputs.get('sampling_value', math.nan):g}'"}.get(given, repr(given))
        warnings.warn(f"{what} of a run sampled at sampling={given} are coarse: the orbital phase advances by up to "
                      f"{step:.3g} rad between samples (pi/2 or more: at most two samples per cycle of h22); "
                      f"for a waveform evolve with a finer sampling, such as sampling=1/4096 or 'per_orbit:16'",
                      CoarseSamplingWarning, stacklevel=3)


def check_memory(count, samples, what, streamed=False):
    """A ValueError naming ell_max and sampling (and with ``streamed``, the streaming write) if ``count`` modes of
    ``samples`` samples (complex128) would not fit in the memory available
    (:func:`pnrotor.processes.available_memory`), before they are allocated."""
    need, free = 16 * count * samples, processes.available_memory()
    if not need < free:
        stream = (", or write them to a file block by block from the binary's parameters: pnrotor.hdf5.write(path, "
                  "pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=...).modes(...)) (pnrotor evolve --modes "
                  "--sampling DT writes that way)") if streamed else ""
        raise ValueError(f"{what}: {count} modes of {samples} samples would need {need / 2 ** 30:.3g} GiB, more than the "
                         f"{free / 2 ** 30:.3g} GiB of memory available now; choose a smaller ell_max or a coarser "
                         f"sampling{stream}")


@register(arrays={
    "t": Array(("N",), M_UNIT),
    "t_seconds": Array(("N",), "s"),
    "data": Array(("modes", "N"), "strain at distance_Mpc, or r h / M if distance_Mpc is absent; row k is mode "
                  "(l, m) with k = l (l + 1) + m - 4, l = 2 ... ell_max (LALSuite's convention)", "complex128"),
    "R": ROTOR,
    "Phi": Array(("N",), "rad; orbital phase"),
}, required_keys={"inputs": ("M_seconds", "ell_max")},
    dimensions={"modes": lambda values: (values["ell_max"] + 1) ** 2 - 4})
@dataclass(eq=False)
class Modes:
    """Modes h_ℓm(t) of one run in one frame.

    Attributes
    ----------
    t, t_seconds : (N,) times in M and in s (those of the evolution)
    ell_max : the modes are ℓ = 2 … ell_max, m = −ℓ … ℓ (their list: :attr:`ell_m`)
    data : (n_modes, N) complex, row k is the mode ell_m[k]
    frame : "inertial", "coprecessing" (ẑ = ℓ̂, no orbital phase) or "coorbital" (ẑ = ℓ̂, x̂ = n̂)
    R : (N, 4) the orbital-frame rotor, Phi : (N,) the orbital phase (to change frames)
    distance_Mpc : the distance of ``data`` as strain, or None for r h / M
    inputs : every input of the evolution and of :func:`pnrotor.modes`

    ``pnrotor.hdf5.write(path, modes)`` stores them (kind ``Modes``, docs/hdf5-schema.md), e.g. beside their
    run as another group of a batch file.
    """

    t: np.ndarray
    t_seconds: np.ndarray
    ell_max: int
    data: np.ndarray
    frame: str
    R: np.ndarray
    Phi: np.ndarray
    distance_Mpc: float = None
    inputs: dict = field(default_factory=dict)

    __repr__ = short_repr

    @property
    def ell_m(self):
        """[(ℓ, m), …] of the rows of ``data``."""
        from pnrotor.waveform.layout import ell_m

        return ell_m(self.ell_max)

    def mode(self, ell, m):
        """h_ℓm, (N,) complex."""
        from pnrotor.waveform.layout import mode_index

        if not (integer(ell) and integer(m) and 2 <= ell <= self.ell_max and abs(m) <= ell):
            raise ValueError(f"mode (ell, m) = ({ell!r}, {m!r}) not in these modes: need integers "
                             f"2 <= ell <= {self.ell_max}, |m| <= ell")
        return self.data[mode_index(ell, m)]

    def _frame_rotor(self, frame):
        """The rotor taking the inertial frame to ``frame``'s axes."""
        from pnrotor import quaternion as q

        if frame == "inertial":
            return np.broadcast_to(np.array([1.0, 0.0, 0.0, 0.0]), self.R.shape)
        if frame == "coorbital":
            return self.R
        half = -0.5 * self.Phi
        return q.multiply(self.R, np.column_stack((np.cos(half), np.zeros_like(half), np.zeros_like(half),
                                                   np.sin(half))))

    def _check(self, doing):
        """A ValueError naming ``doing`` unless these modes are well formed (:func:`pnrotor.results.check`: what
        ``hdf5.write`` checks, but for NaN in ``data``: harmless to the kernels, and a search through the largest
        array) and in one of :data:`FRAMES`, before a compiled kernel reads them."""
        check(self, doing, scan=False)
        if self.frame not in FRAMES:
            raise ValueError(f"{doing} this Modes: frame {self.frame!r} is not one of {', '.join(FRAMES)}")

    def in_frame(self, frame):
        """These modes in another frame (one of :data:`FRAMES`): h' = 𝔇(R'⁻¹ R) h (in their own frame, these
        modes themselves, not a copy)."""
        if frame not in FRAMES:
            raise ValueError(f"frame must be one of {', '.join(FRAMES)}; got {frame!r}")
        self._check("cannot rotate")
        return self._rotated(frame)

    def _rotated(self, frame):
        """:meth:`in_frame` of modes already checked."""
        if frame == self.frame:
            return self
        from pnrotor import quaternion as q
        from pnrotor.waveform.wigner import rotate_modes

        check_memory(self.data.shape[0], self.data.shape[1], "rotating them")
        rotor = q.multiply(q.conjugate(self._frame_rotor(frame)), self._frame_rotor(self.frame))
        return replace(self, data=rotate_modes(self.data, rotor, self.ell_max), frame=frame)

    def to_lal(self):
        """These modes, taken to the inertial frame, as LALSuite's ``SphHarmTimeSeries`` (strain;
        :func:`pnrotor.interop.lal.sph_harm_time_series`, needs lalsuite)."""
        from pnrotor.interop.lal import sph_harm_time_series

        return sph_harm_time_series(self)

    def to_sxs(self):
        """These modes, taken to the inertial frame, as ``sxs.WaveformModes`` (r h / M against t/M;
        :func:`pnrotor.interop.sxs.waveform_modes`, needs sxs)."""
        from pnrotor.interop.sxs import waveform_modes

        return waveform_modes(self)

    def polarizations(self, inclination, phi_ref=0.0, distance=None, psi=0.0):
        """h₊, h× (N,) seen from the direction (θ, φ) = (ι, π/2 − φ_ref) of the inertial frame — the direction
        LALSuite gives a line of sight with inclination ι and reference phase φ_ref when it builds
        polarizations from modes (``azimuthal = LAL_PI_2 - phiRef`` in LALSimInspiral.c) — with LALSuite's
        polarization angle ψ (:mod:`pnrotor.waveform.polarizations`), as strain at ``distance`` (Mpc or an
        astropy length; default the modes' own), or r h / M when neither gives a distance.  The angles are
        finite numbers in radians or astropy angles."""
        from pnrotor.waveform.distance import scale as distance_scale
        from pnrotor.waveform.polarizations import polarizations

        inclination, phi_ref, psi = (angle(x, name) for x, name in ((inclination, "inclination"),
                                                                      (phi_ref, "phi_ref"), (psi, "psi")))
        self._check("cannot compute the polarizations of")
        warn_if_coarse(self.Phi, self.inputs, "polarizations")
        to_Mpc = self.distance_Mpc if distance is None else megaparsecs(distance)
        scale = 1.0 if to_Mpc is None else distance_scale(self.distance_Mpc, to_Mpc, self.inputs["M_seconds"])
        data = self._rotated("inertial").data
        hp, hc = polarizations(data, self.ell_m, inclination, 0.5 * np.pi - phi_ref, psi)
        return scale * hp, scale * hc


@register(arrays={
    "t_seconds": Array(("N",), "s; t = 0 at f_ref"),
    "h_plus": Array(("N",), "strain at distance_Mpc; h+ - i hx = sum of h_lm -2Y_lm(inclination, pi/2 - phi_ref) "
                    "(LALSuite's convention)"),
    "h_cross": Array(("N",), "strain at distance_Mpc"),
})
@dataclass(eq=False)
class Polarizations:
    """h₊, h× of one run seen from one direction, as strain (``pnrotor.stream(…).polarizations(…)``; the arrays of
    ``pnrotor.polarizations``).

    Attributes
    ----------
    t_seconds : (N,) times in s (t = 0 at f_ref)
    h_plus, h_cross : (N,) strain at ``distance_Mpc``
    inclination, phi_ref : the direction (ι, π/2 − φ_ref) of the inertial frame they are seen from (radians)
    distance_Mpc : the distance
    inputs : every input of the evolution and of the modes summed (ell_max, amplitude_order)

    ``pnrotor.hdf5.write(path, polarizations)`` stores them (kind ``Polarizations``, docs/hdf5-schema.md).
    """

    t_seconds: np.ndarray
    h_plus: np.ndarray
    h_cross: np.ndarray
    inclination: float
    phi_ref: float
    distance_Mpc: float
    inputs: dict = field(default_factory=dict)
