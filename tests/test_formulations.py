"""pnrotor.formulations: each derivative against an independent form of its equation and against the
derivative of the exact state along the analytic binary; the generator reset; state ⇄ rotor conversions."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pnrotor import formulations as F
from pnrotor import quaternion as quat
from pnrotor.analytic import PrecessingNutatingBinary

vec3 = arrays(np.float64, 3, elements=st.floats(-1.0, 1.0))
quat4 = arrays(np.float64, 4, elements=st.floats(-2.0, 2.0)).filter(lambda q: np.linalg.norm(q) > 0.1)
BINARY = PrecessingNutatingBinary()


def derivative(kernel, w, y, p=np.zeros(0)):
    out = np.full(y.size, np.nan)
    kernel(np.asarray(w, dtype=np.float64), np.asarray(y, dtype=np.float64), p, out)
    return out


def pure(v):
    return np.concatenate([[0.0], v])


# --------------------------------------------------------------------------------------------------
# each derivative against an independent expression of its equation
# --------------------------------------------------------------------------------------------------


@settings(max_examples=200, deadline=None)
@given(vec3, quat4)
def test_rotor_derivative_is_half_omega_times_R(w, R):
    expected = 0.5 * quat.multiply(pure(w), R)  # eq:integrate-spinor with the Hamilton product
    assert np.allclose(derivative(F.rotor_derivative, w, R), expected, rtol=0, atol=1e-15)


@st.composite
def generators(draw):
    """Generators with |r| from 1e-8 to π − 0.05, concentrated around the series/closed-form switch."""
    axis = draw(vec3.filter(lambda a: np.linalg.norm(a) > 1e-2))
    kind = draw(st.sampled_from(["any", "switch", "tiny"]))
    if kind == "any":
        theta = draw(st.floats(1e-3, math.pi - 0.05))
    elif kind == "switch":
        theta = draw(st.floats(0.5e-2, 2e-2))
    else:
        theta = draw(st.floats(1e-8, 1e-3))
    return theta * axis / np.linalg.norm(axis)


@settings(max_examples=300, deadline=None)
@given(generators(), vec3)
def test_generator_derivative_inverts_the_omega_of_logarithms(r, w):
    # eq:omega_logarithms, with [a, b] = 2 a × b: ω = 2ṙ + (sin²θ/θ²) 2 r×ṙ + ((θ − sinθ cosθ)/(2θ³)) 4 r×(r×ṙ)
    rdot = derivative(F.generator_derivative, w, r)
    th = np.linalg.norm(r)
    a = math.sin(th) ** 2 / th**2
    b = (th - math.sin(th) * math.cos(th)) / (2 * th**3) if th > 1e-4 else 1 / 3 - th**2 / 15
    omega = 2 * rdot + a * 2 * np.cross(r, rdot) + b * 4 * np.cross(r, np.cross(r, rdot))
    # ṙ grows like 1/(π − θ) towards θ = π; rounding errors in ω grow with it
    assert np.allclose(omega, w, rtol=0, atol=2e-15 * (1 + np.linalg.norm(rdot)) * (1 + th**2))


@settings(max_examples=100, deadline=None)
@given(generators(), vec3)
def test_generator_derivative_moves_exp_r_as_half_omega_R(r, w):
    # d/dt exp(r(t)) = ½ ω exp(r) (eq:integrate-spinor), by a 4th-order central difference along ṙ
    rdot = derivative(F.generator_derivative, w, r)
    h = 1e-3 * min(1.0, math.pi - np.linalg.norm(r))
    d = (8 * (quat.exp(r + h * rdot) - quat.exp(r - h * rdot))
         - (quat.exp(r + 2 * h * rdot) - quat.exp(r - 2 * h * rdot))) / (12 * h)
    assert np.allclose(d, 0.5 * quat.multiply(pure(w), quat.exp(r)), rtol=0, atol=1e-9)


@settings(max_examples=100, deadline=None)
@given(arrays(np.float64, 9, elements=st.floats(-2.0, 2.0)), vec3)
def test_vectors_derivative_is_omega_cross_each_vector(y, w):
    expected = np.cross(w, y.reshape(3, 3)).reshape(9)  # eq:integr-frame-vectors
    assert np.allclose(derivative(F.vectors_derivative, w, y), expected, rtol=0, atol=1e-15)
    assert np.allclose(derivative(F.vectors_derivative, w, y[:6]), expected[:6], rtol=0, atol=1e-15)


@settings(max_examples=100, deadline=None)
@given(arrays(np.float64, 6, elements=st.floats(-2.0, 2.0)).filter(
    lambda y: np.linalg.norm(np.cross(y[:3], y[3:])) > 1e-3), vec3, st.floats(0, 10), st.floats(0, 10))
def test_damped_vectors_derivative_adds_the_papers_damping_terms(y, w, lam, mu):
    f0, f1 = y[:3], y[3:]
    u = np.cross(f0, np.cross(f1, f0))
    expected = np.concatenate([
        np.cross(w, f0) + lam * (1 - f0 @ f0) * f0,  # eq:vector-norm-damping
        np.cross(w, f1) + mu * (u / np.linalg.norm(u) - f1),  # eq:vector-orthogonality-damping
    ])
    p = np.array([7.0, 7.0, lam, mu])  # ω's own parameters come first; λ, μ are the last two
    # u/|u| carries the rounding of u, ~ε |f0|²|f1|, divided by |u|: near-parallel f0, f1 amplify it
    condition = 1.0 + mu * (f0 @ f0) * np.linalg.norm(f1) / np.linalg.norm(u)
    assert np.allclose(derivative(F.damped_vectors_derivative, w, y, p), expected, rtol=1e-13,
                       atol=1e-14 * condition)


def test_damping_vanishes_on_an_orthonormal_frame():
    f = quat.rotate(BINARY.rotor(123.0), np.eye(3)[:2]).reshape(6)
    w = BINARY.angular_velocity(123.0)
    p = np.array([5.0, 3.0])
    assert np.allclose(derivative(F.damped_vectors_derivative, w, f, p),
                       derivative(F.vectors_derivative, w, f), rtol=0, atol=1e-15)


# --------------------------------------------------------------------------------------------------
# derivatives along the exact trajectory of the binary
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(F.FORMULATIONS))
@pytest.mark.parametrize("t", [50.0, 3210.5, 777_777.0])
def test_derivative_along_the_binary_equals_the_rate_of_the_exact_state(name, t):
    # the state of the exact rotor, differentiated by a 4th-order central difference (h = 2: error ~1e-12)
    form = F.get(name)
    p = np.array([1.0, 1.0]) if form.n_params else np.zeros(0)
    state = form.initial_state
    if name.startswith("generator"):
        # the generator of the exact rotor on a continuous branch around t (log picks |r| ≤ π/2 at t)
        s = 1.0 if BINARY.rotor(t)[0] >= 0 else -1.0

        def state(R):  # noqa: F811 (the branch of exp⁻¹ continuous through t)
            return quat.log(s * R)
    h = 2.0
    ys = [state(BINARY.rotor(t + k * h)) for k in (-2, -1, 1, 2)]
    rate = (ys[0] - 8 * ys[1] + 8 * ys[2] - ys[3]) / (12 * h)
    y = state(BINARY.rotor(t))
    w = BINARY.angular_velocity(t)
    assert np.allclose(derivative(form.derivative, w, y, p), rate, rtol=0, atol=2e-11)


# --------------------------------------------------------------------------------------------------
# generator reset, eq:generator_reset
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("theta", [*np.linspace(0.0, math.pi - 1e-6, 29), math.pi / 2 - 1e-12, math.pi / 2 + 1e-12])
def test_generator_reset(theta):
    axis = np.array([0.3, -0.8, 0.52])
    r = theta * axis / np.linalg.norm(axis)
    y = r.copy()
    changed = F.generator_reset(0.0, y, np.zeros(0))
    assert changed == (theta >= math.pi / 2)
    if changed:
        assert np.allclose(y, r - math.pi * r / theta, rtol=0, atol=1e-15)
        assert np.linalg.norm(y) <= math.pi / 2 + 1e-15
        assert np.allclose(quat.exp(y), -quat.exp(r), rtol=0, atol=1e-15)  # same rotation, other sign
    else:
        assert np.array_equal(y, r)


@pytest.mark.parametrize("theta", [3 * math.pi / 2 - 1e-9, 3 * math.pi / 2, 5.0, 8.35, 10 * math.pi + 0.3, 40.0])
def test_generator_reset_beyond_three_half_pi(theta):
    """A step that ends past 3π/2 (possible where ṙ stays bounded through |r| = π, ω ∥ r) is brought back to
    |r| ≤ π/2 by subtracting the nearest multiple nπ: the same rotation, rotor (−1)ⁿ exp(r)."""
    axis = np.array([0.3, -0.8, 0.52])
    r = theta * axis / np.linalg.norm(axis)
    y = r.copy()
    assert F.generator_reset(0.0, y, np.zeros(0))
    assert np.linalg.norm(y) <= math.pi / 2 * (1 + 1e-15)
    n = round((theta - y @ axis / np.linalg.norm(axis)) / math.pi)   # y = r − nπ r/|r|
    assert n == round(theta / math.pi) or theta == 3 * math.pi / 2
    assert np.allclose(quat.exp(y), (-1) ** n * quat.exp(r), rtol=0, atol=4e-15 * theta)


def test_generator_reset_at_exactly_half_pi_reverses_r():
    r = np.array([0.0, math.pi / 2, 0.0])
    y = r.copy()
    assert F.generator_reset(0.0, y, np.zeros(0))
    assert np.allclose(y, -r, rtol=0, atol=1e-15)


# --------------------------------------------------------------------------------------------------
# conversions and sign continuity
# --------------------------------------------------------------------------------------------------


@settings(max_examples=50, deadline=None)
@given(quat4, st.sampled_from(list(F.FORMULATIONS)))
def test_initial_state_round_trips_to_the_rotor(R0, name):
    form = F.get(name)
    y0 = form.initial_state(R0)
    assert y0.shape == (form.size,)
    R = form.rotors(y0[None, :], R0, np.zeros(1), BINARY.angular_velocity)
    assert np.allclose(R[0], R0 / np.linalg.norm(R0), rtol=0, atol=2e-15)


def test_generator_initial_state_is_the_short_generator():
    R0 = np.array([-0.1, 0.3, 0.9, 0.2])
    assert np.linalg.norm(F.get("generator").initial_state(R0)) <= math.pi / 2


def test_vectors_rotors_are_the_nearest_rotation_of_a_perturbed_frame():
    # a symmetric perturbation of the rotation matrix, (I + εS) M, has M as its nearest rotation
    # (polar decomposition), so vectors3 must return the exact rotor; vectors2 sees f₀ × f₁ instead of
    # the perturbed third column, so its rotor is off by O(ε)
    R = BINARY.rotor(np.linspace(0, 5e3, 50))
    M = quat.to_matrix(R)
    S = np.array([[1.0, 0.3, -0.2], [0.3, -0.5, 0.1], [-0.2, 0.1, 0.7]])
    eps = 1e-5
    f = np.swapaxes((np.eye(3) + eps * S) @ M, -1, -2)  # rows f0, f1, f2
    exact = np.swapaxes(M, -1, -2)
    got3 = F.get("vectors3").to_rotors(f.reshape(-1, 9))
    assert np.max(quat.frame_error(got3, R)) < 1e-14
    assert np.max(quat.frame_error(F.get("vectors2").to_rotors(exact[:, :2].reshape(-1, 6)), R)) < 1e-14
    assert np.max(quat.frame_error(F.get("vectors2").to_rotors(f[:, :2].reshape(-1, 6)), R)) < 2 * eps
    assert np.allclose(quat.norm(got3), 1.0, rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", ["generator", "vectors3", "vectors2"])
def test_rotors_follow_the_continuous_rotor_across_sign_flips_and_large_gaps(name):
    # samples 600 time units apart (over half an orbit: plain nearest-sign alignment fails), with the
    # states' own rotor signs scrambled (as generator resets and frame→rotor conversions do)
    t = np.arange(0.0, 2e4, 600.0)
    R_exact = BINARY.rotor(t)
    form = F.get(name)
    rng = np.random.default_rng(0)
    scrambled = R_exact * rng.choice([-1.0, 1.0], size=(len(t), 1))
    Y = np.array([form.initial_state(R) for R in scrambled])
    got = form.rotors(Y, R_exact[0], t, BINARY.angular_velocity)
    assert np.allclose(got, R_exact, rtol=0, atol=1e-12)
    plain = quat.unflip(form.to_rotors(Y))
    assert not np.allclose(plain * np.sign(plain[:1] @ R_exact[0]), R_exact, atol=1e-3)


def test_unknown_formulation():
    with pytest.raises(ValueError, match="choose one of rotor, generator"):
        F.get("quaternion")
