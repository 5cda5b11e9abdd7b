"""Wigner D matrices from rotors (pnrotor.waveform.wigner) against two independent evaluations.

* LAL's ``WignerDMatrix(ℓ, m', m, α, β, γ)`` (Jacobi-polynomial form of d, from Euler angles), for
  rotors built as exp(α ẑ/2) exp(β ŷ/2) exp(γ ẑ/2) by quaternion products;
* the ``spherical`` package (its own recursion, from quaternions), through ℓ = 8, including rotors within
  1e-9 … 1e-15 of ℓ̂ = ±ẑ, where Euler angles are degenerate;

and the properties the mode rotation rests on: unitarity, the group law 𝔇(R₁R₂) = 𝔇(R₁)𝔇(R₂), and
h_ℓm = H_ℓm e^{−imΦ} for R = exp(Φ ẑ/2).
"""

import numpy as np
import pytest

from pnrotor import quaternion as q
from pnrotor.waveform.layout import mode_index
from pnrotor.waveform.wigner import rotate_modes, wigner_D

ELL_MAX = 8
rng = np.random.default_rng(20261125)


def axis_rotor(angle, axis):
    return np.concatenate(([np.cos(angle / 2)], np.sin(angle / 2) * np.asarray(axis, dtype=float)))


def euler_rotor(alpha, beta, gamma):
    z, y = (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)
    return q.multiply(q.multiply(axis_rotor(alpha, z), axis_rotor(beta, y)), axis_rotor(gamma, z))


def random_rotors(n):
    R = rng.normal(size=(n, 4))
    return R / np.linalg.norm(R, axis=1)[:, None]


def near_poles():
    """Rotors taking ẑ to within ε of ±ẑ, with generic twists (and exactly onto them)."""
    out = []
    for eps in (0.0, 1e-15, 1e-12, 1e-9, 1e-6):
        for twist in (0.3, 2.9, -1.7):
            out.append(euler_rotor(twist, eps, 1.1 - twist))
            out.append(euler_rotor(twist, np.pi - eps, 0.4 + twist))
    return np.array(out)


def test_against_lal_wigner_from_euler_angles():
    lal = pytest.importorskip("lal")
    for alpha, beta, gamma in rng.uniform([-np.pi, 0.0, -np.pi], [np.pi, np.pi, np.pi], size=(6, 3)):
        D = wigner_D(euler_rotor(alpha, beta, gamma), ELL_MAX)
        for ell in range(2, ELL_MAX + 1):
            for m in range(-ell, ell + 1):
                for mp in range(-ell, ell + 1):
                    ref = lal.WignerDMatrix(ell, m, mp, alpha, beta, gamma)
                    assert abs(D[mode_index(ell, m), mode_index(ell, mp)] - ref) < 1e-13, (ell, m, mp)


@pytest.mark.parametrize("eps", [1e-20, 1e-100, 1e-150, 1e-155, 1e-158, 1e-160, 1e-162, 1e-200, 1e-300, 5e-324])
def test_rotors_within_a_tiny_angle_of_the_poles_give_the_poles_matrices(eps):
    """D is continuous at the poles: rotors a tiny ε from ℓ̂ = ±ẑ (components down to subnormal) give the matrices
    of the exact pole to rounding (at ε ~ 1e-160 the squared components are subnormal: a review found errors of
    4e-5 there)."""
    for sign in (1.0, -1.0):
        for twist in (0.0, 0.7):
            exact = q.multiply(axis_rotor(twist, (0.0, 0.0, 1.0)), np.array([0.0, 1.0, 0.0, 0.0]) if sign < 0
                               else np.array([1.0, 0.0, 0.0, 0.0]))
            tilted = exact + eps * np.array([0.3, -0.2, 0.5, 0.1])
            np.testing.assert_allclose(wigner_D(tilted, ELL_MAX), wigner_D(exact, ELL_MAX), rtol=0, atol=1e-14)


@pytest.mark.parametrize("scale", [1e-300, 1e-153, 1e-100, 1e-30, 1e-12, 3.0, 1e30, 1e100, 1.3e154, 1e300])
def test_rotors_need_not_be_normalized(scale):
    """D(s R) = D(R) for any scale s whose products do not overflow, near the poles too (a review found 5e-6 errors at
    s = 1e-30 and NaN at 1e-153 and 1.3e154 before rotors far from unit norm were first scaled by a power of 2)."""
    R = np.concatenate((random_rotors(10), near_poles(), [[np.cos(0.7), -1e-129 * np.sin(2.1), 1e-129 * np.cos(2.1),
                                                           np.sin(0.7)]]))
    np.testing.assert_allclose(wigner_D(scale * R, ELL_MAX), wigner_D(R, ELL_MAX), rtol=0, atol=1e-13)


def test_against_spherical_package_including_poles():
    spherical = pytest.importorskip("spherical")
    quaternionic = pytest.importorskip("quaternionic")
    R = np.concatenate((random_rotors(40), near_poles()))
    ours = wigner_D(R, ELL_MAX)
    wig = spherical.Wigner(ELL_MAX)
    ref = wig.D(quaternionic.array(R))
    worst = 0.0
    for ell in range(2, ELL_MAX + 1):
        for m in range(-ell, ell + 1):
            for mp in range(-ell, ell + 1):
                # spherical's 𝔇^ℓ_{m',m} is the conjugate of the standard matrix element 𝔇^ℓ_{m m'} (its
                # convention, Boyle et al. 2016 arXiv:1604.05140), measured here for every element
                theirs = np.conj(ref[:, wig.Dindex(ell, m, mp)])
                worst = max(worst, np.max(np.abs(ours[:, mode_index(ell, m), mode_index(ell, mp)] - theirs)))
    assert worst < 1e-13


def test_unitary_and_group_law():
    R1, R2 = random_rotors(5), random_rotors(5)
    D1, D2 = wigner_D(R1, ELL_MAX), wigner_D(R2, ELL_MAX)
    D12 = wigner_D(q.multiply(R1, R2), ELL_MAX)
    eye = np.eye(D1.shape[1])
    for k in range(5):
        assert np.max(np.abs(D1[k] @ D1[k].conj().T - eye)) < 1e-13
        assert np.max(np.abs(D12[k] - D1[k] @ D2[k])) < 1e-13


def test_unnormalized_rotor_gives_the_same_matrix():
    R = random_rotors(4)
    assert np.max(np.abs(wigner_D(3.7 * R, ELL_MAX) - wigner_D(R, ELL_MAX))) < 1e-14


def test_rotation_about_z_multiplies_by_exp_minus_i_m_phi():
    n = 50
    phi = np.linspace(-20.0, 20.0, n)
    R = np.array([axis_rotor(p, (0, 0, 1)) for p in phi])
    H = rng.normal(size=((ELL_MAX + 1) ** 2 - 4, n)) + 1j * rng.normal(size=((ELL_MAX + 1) ** 2 - 4, n))
    h = rotate_modes(H, R, ELL_MAX)
    for ell in range(2, ELL_MAX + 1):
        for m in range(-ell, ell + 1):
            k = mode_index(ell, m)
            assert np.max(np.abs(h[k] - H[k] * np.exp(-1j * m * phi))) < 1e-13 * np.max(np.abs(H[k]))


def test_rotate_modes_equals_matrix_product():
    n = 30
    R = np.concatenate((random_rotors(n - 30 + 20), near_poles()[:10]))
    H = rng.normal(size=((ELL_MAX + 1) ** 2 - 4, len(R))) + 1j * rng.normal(size=((ELL_MAX + 1) ** 2 - 4, len(R)))
    D = wigner_D(R, ELL_MAX)
    assert np.max(np.abs(rotate_modes(H, R, ELL_MAX) - np.einsum("imk,ki->mi", D, H))) < 1e-13


def test_rotate_modes_rejects_mismatched_shapes():
    with pytest.raises(ValueError, match="rotate_modes"):
        rotate_modes(np.zeros((5, 3)), np.zeros((3, 4)), 3)
