"""pnrotor.quaternion against independent constructions: scipy's Rotation and explicit matrices."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from pnrotor import quaternion as q

finite = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
vec3 = arrays(np.float64, 3, elements=st.floats(-10.0, 10.0, allow_nan=False))


@st.composite
def rotors(draw, max_exponent=100):
    """Nonzero quaternions of norm in [10^-max_exponent, 10^max_exponent], incl. near-identity and near-π ones."""
    kind = draw(st.sampled_from(["random", "tiny_angle", "near_pi"]))
    axis = draw(arrays(np.float64, 3, elements=finite).filter(lambda a: np.linalg.norm(a) > 1e-3))
    axis = axis / np.linalg.norm(axis)
    if kind == "random":
        R = draw(arrays(np.float64, 4, elements=finite).filter(lambda a: np.linalg.norm(a) > 1e-3))
    else:
        eps = 10.0 ** draw(st.floats(-15, -2))
        half = eps if kind == "tiny_angle" else np.pi / 2 - eps
        R = np.concatenate([[np.cos(half)], np.sin(half) * axis])
    sign = draw(st.sampled_from([1.0, -1.0]))
    return sign * R * 10.0 ** draw(st.floats(-max_exponent, max_exponent))


def scipy_rotation(R):
    return Rotation.from_quat(np.asarray(R)[..., [1, 2, 3, 0]])  # scipy is scalar-last


@settings(max_examples=300, deadline=None)
@given(rotors(), vec3)
def test_rotate_matches_scipy_for_unnormalized_rotors(R, v):
    expected = scipy_rotation(R).apply(v)
    assert np.allclose(q.rotate(R, v), expected, rtol=0, atol=4e-15 * (1 + np.linalg.norm(v)))
    assert np.allclose(q.to_matrix(R) @ v, expected, rtol=0, atol=4e-15 * (1 + np.linalg.norm(v)))


@settings(max_examples=200, deadline=None)
@given(rotors(60), rotors(60), vec3)  # |a b| = |a| |b| must stay inside the range of qrotate
def test_product_composes_rotations(a, b, v):
    ab = q.multiply(a, b)
    assert np.allclose(q.rotate(ab, v), q.rotate(a, q.rotate(b, v)), atol=1e-14 * (1 + np.linalg.norm(v)))
    assert np.allclose(q.to_matrix(ab), (scipy_rotation(a) * scipy_rotation(b)).as_matrix(), atol=1e-14)


@settings(max_examples=200, deadline=None)
@given(rotors())
def test_inverse_conjugate_norm(R):
    one = q.multiply(R, q.inverse(R))
    assert np.allclose(one, [1, 0, 0, 0], atol=1e-15)
    n = np.sqrt(np.sum((R / np.abs(R).max()) ** 2)) * np.abs(R).max()
    assert q.norm(R) == pytest.approx(n, rel=1e-15)
    assert np.array_equal(q.conjugate(R), R * [1, -1, -1, -1])
    assert q.norm(q.normalize(R)) == pytest.approx(1.0, abs=4.5e-16)


@settings(max_examples=300, deadline=None)
@given(rotors())
def test_matrix_round_trip_and_scipy(R):
    M = q.to_matrix(R)
    assert np.allclose(M, scipy_rotation(R).as_matrix(), atol=1e-15 * 4)
    Rb = q.from_matrix(M)
    assert Rb[0] >= 0
    # two unit rotors each within ~2 ulp of norm 1, and the dot's own rounding: a few ulp of 1
    assert abs(abs(np.dot(Rb, q.normalize(R))) - 1) < 1e-15
    assert q.frame_error(Rb, R) < 4e-15


@settings(max_examples=300, deadline=None)
@given(rotors())
def test_exp_matches_scipy_rotvec_and_log_inverts_it(R):
    r = q.log(R)
    assert 0 <= np.linalg.norm(r) <= np.pi
    # scipy's rotation vector is the full angle: θ n̂ = 2 r
    assert np.allclose(q.to_matrix(q.exp(r)), Rotation.from_rotvec(2 * r).as_matrix(), atol=1e-15 * 4)
    # exp(log R) is R/|R| itself, sign included (|r| ≤ π covers both hemispheres); near |r| = π the
    # vector part sin|r| carries the absolute rounding of |r|, ulp(π) = 4.4e-16
    assert np.allclose(q.exp(r), q.normalize(R), rtol=0, atol=1e-15)


@pytest.mark.parametrize("theta", [0.0, 1e-300, 1e-12, 1e-8, 1e-4, 1.0, np.pi / 2, np.pi - 1e-8, np.pi - 1e-12, np.pi])
def test_log_exp_accurate_near_zero_and_pi(theta):
    axis = np.array([0.3, -0.4, 0.5]) / np.linalg.norm([0.3, -0.4, 0.5])
    r = theta * axis
    back = q.log(q.exp(r))
    if theta == np.pi:  # exp(π n̂) = −1: the axis is lost; any |r| = π is right
        assert np.linalg.norm(back) == pytest.approx(np.pi, rel=1e-15)
    else:
        assert np.allclose(back, r, rtol=0, atol=4e-16 * max(theta, 1e-300) + 1e-300)
    # the exact value of exp near 0 keeps its relative accuracy
    if 0 < theta < 1e-4:
        assert q.exp(r)[1:] == pytest.approx(np.sin(theta) * axis, rel=1e-15)


def test_log_of_minus_one_and_one():
    assert np.array_equal(q.log(np.array([1.0, 0, 0, 0])), [0, 0, 0])
    assert np.array_equal(q.log(np.array([-2.0, 0, 0, 0])), [np.pi, 0, 0])


@settings(max_examples=200, deadline=None)
@given(rotors(), rotors())
def test_frame_error_equals_closed_form(Ra, Re):
    # Σ|eᵢ − aᵢ|² = 6 − 2 tr(Mₑᵀ Mₐ) = 8 sin²(θ/2), θ the angle of the relative rotation
    theta = (scipy_rotation(Re).inv() * scipy_rotation(Ra)).magnitude()
    assert q.frame_error(Ra, Re) == pytest.approx(2 * np.sqrt(2) * abs(np.sin(theta / 2)), abs=2e-15)


def test_frame_error_of_small_rotation_is_sqrt2_angle():
    for eps in [1e-6, 1e-10, 1e-14]:
        Re = q.exp(np.array([0.3, 1.0, -0.2]))
        Ra = q.multiply(Re, q.exp(np.array([0, 0, eps / 2])))  # rotation by eps about z
        assert q.frame_error(Ra, Re) == pytest.approx(np.sqrt(2) * eps, rel=1e-6, abs=1e-16)


def test_from_frame_builds_the_rotor_of_the_frame():
    R = scipy_rotation(np.array([0.4, -0.2, 0.7, 0.1]))
    M = R.as_matrix()
    Rq = q.from_frame(M[:, 0], M[:, 1], M[:, 2])
    for i in range(3):
        assert np.allclose(q.rotate(Rq, np.eye(3)[i]), M[:, i], atol=1e-15)
    # arrays of frames
    Ms = Rotation.random(7, random_state=3).as_matrix()
    Rs = q.from_frame(Ms[:, :, 0], Ms[:, :, 1], Ms[:, :, 2])
    assert np.allclose(q.to_matrix(Rs), Ms, atol=1e-15 * 4)


@pytest.mark.parametrize(
    "frame",
    [
        ([1, 0, 0], [0, 1, 0], [0, 0, -1]),  # left-handed
        ([1, 0, 0], [0.1, 1, 0], [0, 0, 1]),  # not orthogonal
        ([2, 0, 0], [0, 1, 0], [0, 0, 1]),  # not unit
        ([np.nan, 0, 0], [0, 1, 0], [0, 0, 1]),
    ],
)
def test_from_frame_rejects_bad_frames(frame):
    with pytest.raises(ValueError, match="orthonormal"):
        q.from_frame(*frame)


def test_unflip_restores_sign_continuity():
    t = np.linspace(0, 20, 2001)
    smooth = q.exp(np.stack([0.3 * t, np.sin(t), 0.1 * t**1.5], axis=-1))  # crosses |r| = π/2 often
    smooth = q.unflip(smooth)
    assert np.all(np.sum(smooth[1:] * smooth[:-1], axis=-1) > 0)
    signs = np.random.default_rng(0).choice([-1.0, 1.0], size=(t.size, 1))
    signs[0] = 1.0
    assert np.array_equal(q.unflip(smooth * signs), smooth)
    with pytest.raises(ValueError, match=r"\(N, 4\)"):
        q.unflip(np.zeros((3, 3)))


def test_kernels_broadcast_over_arrays():
    R = np.random.default_rng(5).normal(size=(6, 4))
    v = np.random.default_rng(6).normal(size=3)
    rotated = q.rotate(R, v)
    assert rotated.shape == (6, 3)
    assert np.allclose(rotated, scipy_rotation(R).apply(v), atol=1e-14)
    assert q.frame_error(R, R[0]).shape == (6,)
    assert q.log(R).shape == (6, 3) and q.exp(q.log(R)).shape == (6, 4)


def test_the_array_functions_compile_no_shape_mismatch_error_path(cold_python):
    """In a fresh process with an empty numba cache, the gufuncs compile without numba's shape-mismatch error path
    (an out[:] = result assignment compiled it, with its string formatting: 2.7 s of the first cold modes call),
    and still give the kernels' values."""
    out = cold_python("import numpy as np\n"
                      "from pnrotor import quaternion as q\n"
                      "R = np.array([[0.9, 0.1, -0.3, 0.2], [0.5, 0.5, 0.5, -0.5]])\n"
                      "same = [np.array_equal(q.multiply(R, R[::-1])[0], q.qmul(R[0], R[1])),\n"
                      "        np.array_equal(q.to_matrix(R)[1], q.qto_matrix(R[1])),\n"
                      "        np.array_equal(q.rotate(R, np.eye(3)[:2])[0], q.qrotate(R[0], np.eye(3)[0]))]\n"
                      "for f in (q.conjugate, q.inverse, q.normalize, q.log):\n"
                      "    f(R)\n"
                      "q.from_matrix(q.to_matrix(R)), q.exp(np.ones((2, 3)))\n"
                      "print(all(same), [n for n in compiled if 'raise_with_shape' in n])\n")
    assert out.strip() == "True []", out


@pytest.mark.parametrize("call", [
    lambda: q.multiply(np.arange(1.0, 6.0), np.arange(1.0, 6.0)),   # 5 components
    lambda: q.multiply(np.ones((2, 3)), np.ones((2, 3))),             # 3
    lambda: q.normalize(np.ones(3)),
    lambda: q.conjugate(np.ones((4, 5))),
    lambda: q.inverse(np.ones(6)),
    lambda: q.rotate([1.0, 0.0, 0.0, 0.0], np.ones(4)),              # a vector of 4
    lambda: q.rotate(np.ones(3), np.ones(3)),                         # a rotor of 3
    lambda: q.rotate(np.ones(5), np.ones(3)),
    lambda: q.norm(np.ones(3)),
    lambda: q.norm(np.ones((2, 5))),
    lambda: q.exp(np.ones(4)),
    lambda: q.log(np.ones(3)),
    lambda: q.to_matrix(np.ones(5)),
    lambda: q.from_matrix(np.eye(4)),
    lambda: q.from_matrix(np.ones((3, 4))),                           # numpy refuses a non-square core
    lambda: q.frame_error(np.ones(5), np.ones(5)),
])
def test_the_array_functions_refuse_a_wrong_last_axis(call):
    """A quaternion axis that is not 4 (3 for vectors and matrices) raises, as numba's out[:] = result did for some,
    instead of reading past the arrays (a review found a segfault for 10**6 components, and other numbers)."""
    with pytest.raises(ValueError, match="4 components|mismatch in its core dimension"):
        call()


def test_the_array_functions_take_empty_broadcast_and_strided_arrays():
    """What the checks must let through: no quaternion at all, broadcasting rotors over vectors, strided inputs and
    outputs."""
    R = np.array([[0.9, 0.1, -0.3, 0.2], [0.5, 0.5, 0.5, -0.5], [0.0, 0.6, 0.0, 0.8]])
    v = np.eye(3)
    assert q.multiply(np.zeros((0, 4)), np.zeros((0, 4))).shape == (0, 4) and q.norm(np.zeros((0, 4))).shape == (0,)
    np.testing.assert_array_equal(q.rotate(R[:, None, :], v)[1, 2], q.qrotate(R[1], v[2]))
    out = np.empty((4, 3)).T
    q.multiply(R[:, ::-1].copy()[:, ::-1], R[::-1], out=out)
    np.testing.assert_array_equal(out[0], q.qmul(R[0], R[2]))
    np.testing.assert_array_equal(q.norm(R[:, ::1]), [q.qnorm(r) for r in R])
