r"""Spin-weighted spherical harmonics and the polarizations h₊, h× of a set of modes.

Convention (LALSuite's, ``XLALSpinWeightedSphericalHarmonic``; checked against it in the tests):

    ₛY_ℓm(θ, φ) = (−1)^m √[(ℓ+m)!(ℓ−m)!(2ℓ+1) / (4π (ℓ+s)!(ℓ−s)!)]
                  × Σ_r C(ℓ−s, r) C(ℓ+s, r+s−m) (−1)^(ℓ−r−s) sin^(2ℓ−k)(θ/2) cos^k(θ/2) e^{imφ},
    k = 2r + s − m, the sum over the r with both binomials nonzero

(Goldberg et al., J. Math. Phys. 8, 2155 (1967), Eq. (3.1), with sin^{2ℓ}(θ/2) cot^k(θ/2) written as a
product of powers so that it is finite at θ = 0 and π); ₋₂Y₂₂ = √(5/(64π)) (1 + cos θ)² e^{2iφ}.

The polarizations seen from the direction (θ, φ) = (ι, φ) of the modes' frame are

    h₊ − i h× = Σ_ℓm h_ℓm ₋₂Y_ℓm(ι, φ)

(the relation of ``XLALSimInspiralPolarizationsFromSphHarmTimeSeries``), and a polarization angle ψ
rotates them as h₊ + i h× → e^{2iψ}(h₊ + i h×) (h₊ → h₊ cos 2ψ − h× sin 2ψ, h× → h× cos 2ψ + h₊ sin 2ψ): ψ is
LALSuite's, F₊(0) h₊(ψ) + F×(0) h×(ψ) = F₊(ψ) h₊ + F×(ψ) h× for the antenna patterns F of
``XLALComputeDetAMResponse`` at polarization angle ψ (tests/test_waveform_polarizations.py).
"""

import math

import numpy as np


def swsh(s, ell, m, theta, phi):
    """ₛY_ℓm(θ, φ) (complex, broadcasting over θ and φ) in LALSuite's convention (module docstring)."""
    if not (abs(s) <= ell and abs(m) <= ell):
        raise ValueError(f"need |s| <= ell and |m| <= ell, got s = {s}, ell = {ell}, m = {m}")
    theta = np.asarray(theta, dtype=np.float64)
    half_sin, half_cos = np.sin(0.5 * theta), np.cos(0.5 * theta)
    norm = (-1) ** m * math.sqrt(math.factorial(ell + m) * math.factorial(ell - m) * (2 * ell + 1)
                                 / (4.0 * math.pi * math.factorial(ell + s) * math.factorial(ell - s)))
    total = np.zeros(np.shape(theta))
    for r in range(max(0, m - s), min(ell - s, ell + m) + 1):
        k = 2 * r + s - m
        total = total + (math.comb(ell - s, r) * math.comb(ell + s, r + s - m) * (-1) ** (ell - r - s)
                         * half_sin ** (2 * ell - k) * half_cos ** k)
    return norm * total * np.exp(1j * m * np.asarray(phi, dtype=np.float64))


def polarizations(data, ell_m, inclination, phi, psi=0.0):
    """(h₊, h×) from modes ``data`` (n_modes, N) with their (ℓ, m) in ``ell_m``, seen from (ι, φ) of the
    modes' frame, rotated by the polarization angle ψ (module docstring)."""
    h = np.zeros(np.shape(data)[1], dtype=np.complex128)
    for row, (ell, m) in zip(data, ell_m):
        h += row * swsh(-2, ell, m, inclination, phi)
    hp, hc = h.real, -h.imag
    if psi:
        c, s = math.cos(2.0 * psi), math.sin(2.0 * psi)
        hp, hc = hp * c - hc * s, hc * c + hp * s
    return hp, hc
