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

import numpy as np

from pnrotor.pn.evolve import Evolution
from pnrotor.results.schema import check
from pnrotor.results.waves import FRAMES, CoarseSamplingWarning, Modes, check_memory, megaparsecs, warn_if_coarse
from pnrotor.values import integer, real
from pnrotor.waveform.amplitudes import modes_in_frame
from pnrotor.waveform.distance import scale as _scale
from pnrotor.waveform.layout import n_modes

__all__ = ["Modes", "modes", "check_arguments", "FRAMES", "CoarseSamplingWarning"]

ELL_MAX = 8


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
    return int(ell_max), int(order2), None if distance is None else megaparsecs(distance)


def tides_of(inputs, tidal_order):
    """``tides`` of :func:`pnrotor.waveform.amplitudes.modes_in_frame` for a run's inputs: (Λ₁, Λ₂, the largest
    power of v of a tidal term), to ``tidal_order`` (None: the run's own; 0, 5 or 6), none without deformabilities
    (or in a file written before them)."""
    from pnrotor.options import check_tidal_order

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
    check(evolution, "cannot compute the modes of")   # a malformed run would be read out of bounds
    warn_if_coarse(evolution.Phi, evolution.inputs, "modes")
    check_memory(n_modes(ell_max), len(evolution), "modes()", streamed=True)
    inputs = evolution.inputs
    tides = tides_of(inputs, tidal_order)
    scale = 1.0 if distance_Mpc is None else _scale(None, distance_Mpc, inputs["M_seconds"])
    h = _inertial(evolution, ell_max, order2, scale, tides, memory)
    return Modes(t=evolution.t, t_seconds=evolution.t_seconds, ell_max=ell_max, data=h, frame="inertial",
                 R=evolution.R, Phi=evolution.Phi, distance_Mpc=distance_Mpc,
                 inputs=dict(inputs, ell_max=ell_max, amplitude_order=order2 / 2,
                             distance_Mpc=np.nan if distance_Mpc is None else distance_Mpc,
                             **wave_inputs(tides, memory)))
