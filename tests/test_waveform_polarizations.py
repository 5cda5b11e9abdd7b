"""Spin-weighted harmonics and polarizations (pnrotor.waveform.polarizations) against LALSuite and the
quadrupole formula."""

import numpy as np
import pytest
from helpers import needs, reference

from pnrotor.waveform.polarizations import polarizations, swsh

lal, ls = reference("lal"), reference("lalsimulation")
needs_lal = needs("lal", "lalsimulation")

rng = np.random.default_rng(7)
ANGLES = [(0.0, 0.3), (np.pi, -1.2), (1e-9, 2.0), (np.pi - 1e-9, 0.1), (0.7, 0.0), (2.2, 4.0), (1.5707963, -0.4)]


@needs_lal
def test_swsh_equals_lal_for_spin_minus_two():
    worst = 0.0
    for ell in range(2, 9):
        for m in range(-ell, ell + 1):
            for theta, phi in ANGLES:
                ref = lal.SpinWeightedSphericalHarmonic(theta, phi, -2, ell, m)
                worst = max(worst, abs(swsh(-2, ell, m, theta, phi) - ref))
    assert worst < 1e-13


def test_spin_zero_is_the_ordinary_harmonic():
    """₀Y_ℓm = Y_ℓm with the Condon–Shortley phase (scipy's; LAL implements only s = −2)."""
    special = pytest.importorskip("scipy.special")
    theta = np.array([a for a, _ in ANGLES])
    phi = np.array([b for _, b in ANGLES])
    for ell in range(0, 9):
        for m in range(-ell, ell + 1):
            np.testing.assert_allclose(swsh(0, ell, m, theta, phi), special.sph_harm_y(ell, m, theta, phi),
                                       atol=1e-13)


def test_swsh_rejects_bad_indices():
    with pytest.raises(ValueError, match="ell"):
        swsh(-2, 2, 3, 0.1, 0.2)


@needs_lal
def test_polarizations_equal_lal_sum_over_modes():
    """LAL's own h₊, h× from a set of its modes (SpinTaylorT4, ℓ ≤ 4, a precessing binary: all m present)."""
    node = ls.SimInspiralChooseTDModes(0.0, 1.0 / 4096, 30 * lal.MSUN_SI, 10 * lal.MSUN_SI, 0.5, 0.1, 0.3, 0.0, 0.4,
                                       -0.2, 40.0, 40.0, 1e6 * lal.PC_SI, None, 4, ls.SpinTaylorT4)
    data, ell_m, walk = [], [], node
    while walk is not None:
        data.append(walk.mode.data.data.copy())
        ell_m.append((walk.l, walk.m))
        walk = walk.next
    data = np.array(data)
    assert len(ell_m) == 21
    scale = np.max(np.abs(data))
    for iota, phi in ANGLES:
        hp_ref, hc_ref = ls.SimInspiralPolarizationsFromSphHarmTimeSeries(node, iota, phi)
        hp, hc = polarizations(data, ell_m, iota, phi)
        assert np.max(np.abs(hp - hp_ref.data.data)) < 1e-13 * scale
        assert np.max(np.abs(hc - hc_ref.data.data)) < 1e-13 * scale


@needs_lal
def test_polarization_angle_is_lals():
    """A detector's strain from the polarizations at ψ through LAL's antenna patterns at 0 is the strain from
    those at 0 through LAL's patterns at ψ (``XLALComputeDetAMResponse``)."""
    ell_m = [(2, m) for m in range(-2, 3)]
    data = rng.normal(size=(5, 8)) + 1j * rng.normal(size=(5, 8))
    hp, hc = polarizations(data, ell_m, 0.9, 0.3)
    response = lal.CachedDetectors[lal.LHO_4K_DETECTOR].response
    ra, dec, gmst = 1.1, -0.4, 0.3
    f0 = lal.ComputeDetAMResponse(response, ra, dec, 0.0, gmst)
    for psi in (0.2, np.pi / 4, 2.0, -0.7):
        hp_psi, hc_psi = polarizations(data, ell_m, 0.9, 0.3, psi=psi)
        f = lal.ComputeDetAMResponse(response, ra, dec, psi, gmst)
        strain = f[0] * hp + f[1] * hc
        np.testing.assert_allclose(f0[0] * hp_psi + f0[1] * hc_psi, strain, atol=1e-13 * np.max(np.abs(strain)))
    hp_pi, hc_pi = polarizations(data, ell_m, 0.9, 0.3, psi=np.pi)  # ψ → ψ + π changes nothing
    np.testing.assert_allclose(hp_pi, hp, atol=1e-13)
    np.testing.assert_allclose(hc_pi, hc, atol=1e-13)


def test_quadrupole_formula_from_the_22_modes():
    """h₂₂ = A e^{−2iΦ}, h₂,₋₂ = h₂₂* with A = 8√(π/5) ν v² (r h/M, LAL's sign) seen from (ι, φ):
    A ₋₂Y₂₂ = ν v² (1 + cos ι)² e^{2iφ}, so h₊ − i h× = ν v² [(1+cos ι)² e^{−2i(Φ−φ)} + (1−cos ι)² e^{2i(Φ−φ)}],
    i.e. h₊ = 2ν v² (1 + cos²ι) cos 2(Φ−φ), h× = 4ν v² cos ι sin 2(Φ−φ): the quadrupole waveform of a
    circular binary (the textbook form has the opposite overall sign, Kidder's/Blanchet's mode sign)."""
    nu, v = 0.1875, 0.3
    Phi = np.linspace(0.0, 7.0, 50)
    A = 8.0 * np.sqrt(np.pi / 5.0) * nu * v * v
    data = np.zeros((5, Phi.size), dtype=complex)
    data[4] = A * np.exp(-2j * Phi)          # (2, 2)
    data[0] = A * np.exp(2j * Phi)           # (2, −2) = h₂₂*
    ell_m = [(2, m) for m in range(-2, 3)]
    for iota, phi in ANGLES:
        hp, hc = polarizations(data, ell_m, iota, phi)
        np.testing.assert_allclose(hp, 2 * nu * v * v * (1 + np.cos(iota) ** 2) * np.cos(2 * (Phi - phi)), atol=1e-14)
        np.testing.assert_allclose(hc, 4 * nu * v * v * np.cos(iota) * np.sin(2 * (Phi - phi)), atol=1e-14)
