"""Waveform modes h_ℓm of a PN evolution: the co-orbital amplitudes rotated by the evolved frame.

For every sample of an :class:`pnrotor.pn.evolve.Evolution` (v, Φ, χ₁, χ₂ and the orbital-frame rotor R
with n̂ = R x̂ R⁻¹, ℓ̂ = R ẑ R⁻¹):

1. the spins in the co-orbital frame, χᵢ' = R⁻¹ χᵢ R (components along n̂, λ̂, ℓ̂);
2. the co-orbital amplitudes H_ℓm(v, ν, δ, χ₁', χ₂') up to ``amplitude_order`` and ``ell_max``:
   :mod:`pnrotor.waveform.nonspinning` and :mod:`pnrotor.waveform.spin`, each term with its source;
3. the inertial modes h_ℓm = Σ_m' 𝔇^ℓ_{m m'}(R) H_ℓm' (:mod:`pnrotor.waveform.wigner`; Boyle et al. 2013,
   arXiv:1302.2919): the frame history is exactly what turns amplitudes into a waveform.

All three in one compiled pass over blocks of samples (:func:`pnrotor.waveform.amplitudes.modes_in_frame`):
no array of spins or of H is formed, only h.  A nonprecessing run's spins are constant along ℓ̂ and go into
the coefficients, and in its own frame (R = exp(Φẑ/2)) the rotation is h_ℓm = H_ℓm e^{−imΦ}.

Convention: LALSuite's (its mode signs; h₊ − i h× = Σ h_ℓm ₋₂Y_ℓm(ι, φ) with its ₋₂Y_ℓm, see
:mod:`pnrotor.waveform.polarizations`); for a nonspinning binary h₂₂ = +|h₂₂| e^{−2iΦ}.  Kidder 2008
(arXiv:0710.0614) and Blanchet et al. 2008 (arXiv:0802.1249) write every mode with the opposite sign,
h_ℓm(LAL) = −h_ℓm(Kidder, Blanchet), as LALSuite's own conversion
(``XLALCreateSimInspiralPNModeCOMPLEX16TimeSeriesLALConvention``) does.  Units: r h/M (dimensionless)
unless a ``distance`` is given, then strain at that distance.

Checked: against LALSuite's SpinTaylorT4 modes (ℓ ≤ 4, 1.5PN; tests/test_waveform_lal.py), the PN flux
(tests/test_waveform_amplitudes.py), the rotation of a whole binary by a fixed rotor and the
quadrupole formula (tests/test_waveform_modes.py).
"""

import math
import sys
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from pnrotor import quaternion as q
from pnrotor.history import short_repr
from pnrotor.pn import sampling as _sampling
from pnrotor.pn.evolve import Evolution
from pnrotor.pn.initial import integer, real
from pnrotor.waveform import polarizations as _pol
from pnrotor.waveform.amplitudes import modes_in_frame
from pnrotor.waveform.distance import scale as _scale
from pnrotor.waveform.layout import ell_m as _ell_m
from pnrotor.waveform.layout import mode_index, n_modes
from pnrotor.waveform.wigner import rotate_modes

__all__ = ["Modes", "modes", "check_arguments", "FRAMES", "CoarseSamplingWarning"]

FRAMES = ("inertial", "coprecessing", "coorbital")
ELL_MAX = 8


def _megaparsecs(distance):
    """Mpc from a float (Mpc) or an astropy Quantity of length; ValueError naming ``distance``."""
    from pnrotor.pn.initial import positive

    return positive(distance, "Mpc", "distance", "distance in Mpc")


def _angle(value, name):
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


def _warn_if_coarse(Phi, inputs, what):
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
    inputs : every input of the evolution and of :func:`modes`

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
        return _ell_m(self.ell_max)

    def mode(self, ell, m):
        """h_ℓm, (N,) complex."""
        if not (integer(ell) and integer(m) and 2 <= ell <= self.ell_max and abs(m) <= ell):
            raise ValueError(f"mode (ell, m) = ({ell!r}, {m!r}) not in these modes: need integers "
                             f"2 <= ell <= {self.ell_max}, |m| <= ell")
        return self.data[mode_index(ell, m)]

    def _frame_rotor(self, frame):
        """The rotor taking the inertial frame to ``frame``'s axes."""
        if frame == "inertial":
            return np.broadcast_to(np.array([1.0, 0.0, 0.0, 0.0]), self.R.shape)
        if frame == "coorbital":
            return self.R
        half = -0.5 * self.Phi
        return q.multiply(self.R, np.column_stack((np.cos(half), np.zeros_like(half), np.zeros_like(half),
                                                   np.sin(half))))

    def _check(self, doing):
        """A ValueError naming ``doing`` unless these modes are well formed (:func:`pnrotor.hdf5.check`: what
        ``hdf5.write`` checks, but for NaN in ``data``: harmless to the kernels, and a search through the largest
        array) and in one of :data:`FRAMES`, before a compiled kernel reads them."""
        from pnrotor import hdf5

        hdf5.check(self, doing, scan=False)
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
        _check_memory(self.data.shape[0], self.data.shape[1], "rotating them")
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
        inclination, phi_ref, psi = (_angle(x, name) for x, name in ((inclination, "inclination"),
                                                                      (phi_ref, "phi_ref"), (psi, "psi")))
        self._check("cannot compute the polarizations of")
        _warn_if_coarse(self.Phi, self.inputs, "polarizations")
        to_Mpc = self.distance_Mpc if distance is None else _megaparsecs(distance)
        scale = 1.0 if to_Mpc is None else _scale(self.distance_Mpc, to_Mpc, self.inputs["M_seconds"])
        data = self._rotated("inertial").data
        hp, hc = _pol.polarizations(data, self.ell_m, inclination, 0.5 * np.pi - phi_ref, psi)
        return scale * hp, scale * hc


def check_arguments(ell_max, amplitude_order, distance=None):
    """:func:`modes`' options checked → (ell_max, 2 × amplitude_order, distance in Mpc or None); a ValueError
    naming the first bad one (callers check before computing a run)."""
    if not (integer(ell_max) and 2 <= ell_max <= ELL_MAX):
        raise ValueError(f"ell_max must be an integer from 2 to {ELL_MAX}; got {ell_max!r}")
    try:
        order2 = 2.0 * float(amplitude_order) if real(amplitude_order) else math.nan   # no str, bytes or bools
    except OverflowError:   # an int beyond any float (10**400)
        order2 = math.nan
    if not order2 in range(9):
        raise ValueError(f"amplitude_order must be one of 0, 0.5, ..., 4; got {amplitude_order!r}")
    return int(ell_max), int(order2), None if distance is None else _megaparsecs(distance)


def _check_memory(count, samples, what, streamed=False):
    """A ValueError naming ell_max and sampling (and with ``streamed``, the streaming write) if ``count`` modes of
    ``samples`` samples (complex128) would not fit in the memory available
    (:func:`pnrotor.pn.sampling.available_memory`), before they are allocated."""
    need, free = 16 * count * samples, _sampling.available_memory()
    if not need < free:
        stream = (", or write them to a file block by block from the binary's parameters: pnrotor.hdf5.write(path, "
                  "pnrotor.stream(m1, m2, chi1, chi2, f_ref, delta_t=...).modes(...)) (pnrotor evolve --modes "
                  "--sampling DT writes that way)") if streamed else ""
        raise ValueError(f"{what}: {count} modes of {samples} samples would need {need / 2 ** 30:.3g} GiB, more than the "
                         f"{free / 2 ** 30:.3g} GiB of memory available now; choose a smaller ell_max or a coarser "
                         f"sampling{stream}")


def tides_of(inputs, tidal_order):
    """``tides`` of :func:`pnrotor.waveform.amplitudes.modes_in_frame` for a run's inputs: (Λ₁, Λ₂, the largest
    power of v of a tidal term), to ``tidal_order`` (None: the run's own; 0, 5 or 6), none without deformabilities
    (or in a file written before them)."""
    from pnrotor.pn.settings import check_tidal_order

    order = inputs.get("tidal_order", 0.0) if tidal_order is None else check_tidal_order(tidal_order)
    lambdas = (float(inputs.get("lambda1", 0.0)), float(inputs.get("lambda2", 0.0)))
    return (*lambdas, int(2 * order)) if order and any(lambdas) else (0.0, 0.0, -1)


def check_memory_flag(memory):
    """``memory`` of :func:`modes` as a bool, or a ValueError naming it."""
    if not isinstance(memory, (bool, np.bool_)):
        raise ValueError(f"memory must be True or False, got {memory!r}")
    return bool(memory)


def wave_inputs(tides, memory):
    """The entries a Modes' inputs gain for ``tides`` (:func:`tides_of`) and ``memory``."""
    return {**({"tidal_amplitude_order": tides[2] / 2} if tides[2] > 0 else {}), **({"memory": True} if memory else {})}


def _inertial(evolution, ell_max, order2, scale, tides, memory):
    """h = 𝔇(R) H times ``scale``, in one pass of the amplitude kernel (spins and frame: :func:`spins_and_frame`;
    ``tides``, ``memory``: :func:`~pnrotor.waveform.amplitudes.modes_in_frame`'s)."""
    inputs = evolution.inputs
    if inputs["state"] == "precessing":   # spins taken into the orbital frame inside the kernel
        chi1, chi2, frame = evolution.chi1, evolution.chi2, "rotors"
    else:
        chi1, chi2, frame = spins_and_frame(inputs, evolution.chi1[0], evolution.chi2[0], evolution.ell_hat[0])
    return modes_in_frame(evolution.v, chi1, chi2, inputs["m1_Msun"], inputs["m2_Msun"], ell_max, order2,
                          inputs["kappa1"], inputs["kappa2"], R=evolution.R, frame=frame, scale=scale, tides=tides,
                          memory=memory)


def spins_and_frame(inputs, chi1, chi2, ell_hat):
    """(χ₁, χ₂, frame) of the amplitude kernel for a run on the aligned state (``inputs['state']``), whose spins chi1,
    chi2 and ℓ̂ are constant: the spins are None (nonspinning) or their components along ℓ̂, (0, 0, χᵢ·ℓ̂), folded into
    the coefficients, and R = R₀ exp(Φẑ/2) with R₀ the initial frame, so in the default frame (R₀ = 1) h = H e^{−imΦ}
    (frame "z"), else "rotors"."""
    from pnrotor.pn.initial import frame_rotor

    if inputs["spin_content"] == "aligned":
        chi1, chi2 = (np.array([0.0, 0.0, np.dot(chi, ell_hat)]) for chi in (chi1, chi2))
    else:
        chi1 = chi2 = None
    R0 = frame_rotor(np.asarray(inputs["ell_hat"]), np.asarray(inputs["n_hat"]))
    return chi1, chi2, "z" if np.array_equal(R0, [1.0, 0.0, 0.0, 0.0]) else "rotors"


def modes(evolution, ell_max=ELL_MAX, amplitude_order=3.5, distance=None, tidal_order=None, memory=False):
    """Inertial-frame modes h_ℓm (module docstring) of the samples of ``evolution`` (an
    :class:`~pnrotor.pn.evolve.Evolution`) as :class:`Modes`, for ℓ ≤ ``ell_max`` (2 … 8) with amplitude terms
    through ``amplitude_order`` (0 … 4 in steps of 0.5; the 4PN term is (2,2)'s), as strain at ``distance`` (Mpc or
    an astropy length) or, without one, as r h / M.  For a run with tidal deformabilities, the tidal amplitude terms
    (:mod:`pnrotor.waveform.tidal`) to ``tidal_order`` (0: none, 5 or 6; None: the run's tidal order).
    ``memory=True`` adds the nonlinear memory to the m = 0 modes (Favata 2009's closed form to the amplitude order, at
    most 3PN: :mod:`pnrotor.waveform.memory`, which states its convention for the start of the run: the memory
    accumulated since t → −∞).  ``pnrotor.modes`` (:func:`pnrotor.waveform.stream.modes`) takes a binary's
    parameters too."""
    if not isinstance(evolution, Evolution):
        raise TypeError(f"modes() takes an Evolution (what pnrotor.evolve returns, or pnrotor.hdf5.read reads), got "
                        f"{type(evolution).__name__}")
    ell_max, order2, distance_Mpc = check_arguments(ell_max, amplitude_order, distance)
    memory = check_memory_flag(memory)
    from pnrotor import hdf5

    hdf5.check(evolution, "cannot compute the modes of")   # a malformed run would be read out of bounds
    _warn_if_coarse(evolution.Phi, evolution.inputs, "modes")
    _check_memory(n_modes(ell_max), len(evolution), "modes()", streamed=True)
    inputs = evolution.inputs
    tides = tides_of(inputs, tidal_order)
    scale = 1.0 if distance_Mpc is None else _scale(None, distance_Mpc, inputs["M_seconds"])
    h = _inertial(evolution, ell_max, order2, scale, tides, memory)
    return Modes(t=evolution.t, t_seconds=evolution.t_seconds, ell_max=ell_max, data=h, frame="inertial",
                 R=evolution.R, Phi=evolution.Phi, distance_Mpc=distance_Mpc,
                 inputs=dict(inputs, ell_max=ell_max, amplitude_order=order2 / 2,
                             distance_Mpc=np.nan if distance_Mpc is None else distance_Mpc,
                             **wave_inputs(tides, memory)))
