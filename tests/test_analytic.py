"""pnrotor.analytic against an independent mpmath evaluation of the paper's binary at 40 digits.

The reference multiplies the eight factors of eq:BinaryRotor literally, and differentiates them with the
product rule of eq:derivatives_of_rotors and eq:differentiate-unit-condition, then ω = 2 Ṙ R⁻¹
(eq:angular-velocity) — the paper's recipe, unlike the closed form used in pnrotor.analytic.
"""

import math

import mpmath as mp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pnrotor import quaternion as quat
from pnrotor.analytic import PrecessingNutatingBinary, cos_sin

DIGITS = mp.workdps(40)
"""Working precision of the reference (a decorator, so other test modules keep mpmath's default)."""

# times up to the paper's T = 10⁶, including whole numbers of orbits and precession cycles
TIMES = [0.0, 1.0, 999.9, 1e5 + 0.3, 3.3e5, 7.6e5, 7.77e5, 999_999.99, 1e6, -2.5e5]


def _mul(a, b):
    return [a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]]


def _conj(a):
    return [a[0], -a[1], -a[2], -a[3]]


def _exp_axis(half_angle, axis):
    q = [mp.cos(half_angle), mp.mpf(0), mp.mpf(0), mp.mpf(0)]
    q[axis] = mp.sin(half_angle)
    return q


def mp_factors(binary, t):
    """The eight factors of eq:BinaryRotor and their time derivatives, in mpmath at the working
    precision, from the float64 parameter values taken exactly."""
    t = mp.mpf(t)
    Oo, Op, a, ad, nu = (mp.mpf(x) for x in (binary.Omega_orb, binary.Omega_prec, binary.alpha,
                                             binary.alpha_dot, binary.nu))
    R0 = [mp.mpf(x) for x in binary.R0]
    R1, R2 = _exp_axis(Oo * t / 2, 3), _exp_axis((a + ad * t) / 2, 1)
    R3, R4 = _exp_axis(Op * t / 2, 3), _exp_axis(nu / 2, 1)
    zero = [mp.mpf(0)] * 4
    z, x = [0, 0, 0, 1], [0, 1, 0, 0]
    dR1 = _mul(R1, [c * Oo / 2 for c in z])  # eq:derivatives_of_rotors
    dR2 = _mul(R2, [c * ad / 2 for c in x])
    dR3 = _mul(R3, [c * Op / 2 for c in z])
    R1i, R3i = _conj(R1), _conj(R3)
    dR1i = [-c for c in _mul(_mul(R1i, dR1), R1i)]  # eq:differentiate-unit-condition
    dR3i = [-c for c in _mul(_mul(R3i, dR3), R3i)]
    return [(R0, zero), (R1, dR1), (R4, zero), (R1i, dR1i), (R3, dR3), (R2, dR2), (R3i, dR3i), (R1, dR1)]


def _product(factors):
    R = [mp.mpf(1), 0, 0, 0]
    for f, _ in factors:
        R = _mul(R, f)
    return R


@DIGITS
def mp_rotor_and_omega(binary, t):
    factors = mp_factors(binary, t)
    R = _product(factors)
    Rdot = [mp.mpf(0)] * 4
    for k in range(len(factors)):  # eq:product-rule
        term = [mp.mpf(1), 0, 0, 0]
        for j, (f, df) in enumerate(factors):
            term = _mul(term, df if j == k else f)
        Rdot = [u + v for u, v in zip(Rdot, term)]
    omega = _mul([2 * c for c in Rdot], _conj(R))  # eq:angular-velocity, |R| = 1
    return np.array([float(c) for c in R]), np.array([float(c) for c in omega[1:]]), float(omega[0])


def test_defaults_are_the_papers_constants():
    b = PrecessingNutatingBinary()
    alpha = math.pi / 8
    assert b.Omega_orb == 2 * math.pi / 1000 and b.Omega_prec == 2 * math.pi / 10000
    assert b.alpha == alpha and b.alpha_dot == 2 * alpha / 1e5 and b.nu == math.pi / 80 and b.T == 1e6
    # R0 = e^{−3α x/10}: a rotation by −3α/5 about x̂ (half-angle −3α/10), as R₂ = e^{α x/2} tilts by α
    assert np.allclose(b.R0, [math.cos(3 * alpha / 10), -math.sin(3 * alpha / 10), 0, 0], atol=1e-16)


def test_alpha_dot_and_R0_follow_an_overridden_alpha_and_R0_is_normalized():
    b = PrecessingNutatingBinary(alpha=0.2, R0=[0.0, 0.0, 3.0, 4.0])
    assert b.alpha_dot == 0.4e-5
    assert np.array_equal(b.R0, [0.0, 0.0, 0.6, 0.8])


@pytest.mark.parametrize("t", TIMES)
def test_rotor_and_omega_match_mpmath_at_the_paper_parameters(t):
    b = PrecessingNutatingBinary()
    R_ref, w_ref, scalar = mp_rotor_and_omega(b, t)
    assert abs(scalar) < 1e-35  # 2 Ṙ R⁻¹ is a pure vector: the reference is self-consistent
    assert np.max(np.abs(b.rotor(t) - R_ref)) <= 1e-15
    assert np.max(np.abs(b.angular_velocity(t) - w_ref)) <= 1e-17  # |ω| ≈ 6e-3: ~2e-15 relative


@DIGITS
def test_reference_is_accurate_where_plain_float64_phases_are_not():
    # at t ≈ 10⁶ the float64 product Ω_orb·t alone is off by up to 4.5e-13 rad; the reference is not
    b = PrecessingNutatingBinary()
    t = 999_999.99
    R_ref, _, _ = mp_rotor_and_omega(b, t)
    naive = np.array([math.cos(b.Omega_orb * t / 2), 0, 0, math.sin(b.Omega_orb * t / 2)])
    exact = np.array([float(mp.cos(mp.mpf(b.Omega_orb) * mp.mpf(t) / 2)), 0, 0,
                      float(mp.sin(mp.mpf(b.Omega_orb) * mp.mpf(t) / 2))])
    assert np.max(np.abs(naive - exact)) > 1e-14
    assert quat.frame_error(b.rotor(t), R_ref) < 5e-15


@settings(max_examples=25, deadline=None)
@given(
    Omega_orb=st.floats(1e-4, 0.1), Omega_prec=st.floats(-1e-2, 1e-2), alpha=st.floats(-3.0, 3.0),
    alpha_dot=st.floats(-1e-4, 1e-4), nu=st.floats(-1.0, 1.0),
    R0=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
    t=st.floats(-2e6, 2e6),
)
def test_rotor_and_omega_match_mpmath_for_any_parameters(Omega_orb, Omega_prec, alpha, alpha_dot, nu, R0, t):
    b = PrecessingNutatingBinary(Omega_orb=Omega_orb, Omega_prec=Omega_prec, alpha=alpha,
                                 alpha_dot=alpha_dot, nu=nu, R0=R0)
    R_ref, w_ref, _ = mp_rotor_and_omega(b, t)
    assert np.max(np.abs(b.rotor(t) - R_ref)) <= 1.5e-15
    scale = abs(Omega_orb) + abs(Omega_prec) + abs(alpha_dot)
    assert np.max(np.abs(b.angular_velocity(t) - w_ref)) <= 2e-15 * scale


@DIGITS
def test_mpmath_reference_derivative_agrees_with_numerical_differentiation():
    # guards the reference itself: its product-rule Ṙ equals mpmath's numerical derivative of R
    b = PrecessingNutatingBinary()

    def component(i):
        return lambda s: _product(mp_factors(b, s))[i]

    t = mp.mpf("123456.789")
    R = _product(mp_factors(b, t))
    Rdot = [mp.diff(component(i), t) for i in range(4)]
    omega = _mul([2 * c for c in Rdot], _conj(R))
    _, w_ref, _ = mp_rotor_and_omega(b, t)
    assert np.max(np.abs(np.array([float(c) for c in omega[1:]]) - w_ref)) < 1e-25


@pytest.mark.parametrize("t", [0.5, 1e6 + 0.25, 2.5e8, 3e8, 1e9 + 0.5, -7e9])  # both reductions (k < 2^20, ≥ 2^20)
@DIGITS
def test_cos_sin_is_exactly_reduced_for_large_arguments(t):
    c0, rate = 0.3, 2 * math.pi / 1000
    theta = mp.mpf(c0) + mp.mpf(rate) * mp.mpf(t)
    c, s = cos_sin(c0, rate, t)
    assert abs(c - float(mp.cos(theta))) <= 2.3e-16 and abs(s - float(mp.sin(theta))) <= 2.3e-16


def test_vectorized_shapes_and_frame_error():
    b = PrecessingNutatingBinary()
    t = np.linspace(0, 1e4, 6).reshape(2, 3)
    assert b.rotor(1.0).shape == (4,) and b.angular_velocity(1.0).shape == (3,)
    assert b.rotor(t).shape == (2, 3, 4) and b.angular_velocity(t).shape == (2, 3, 3)
    assert np.array_equal(b.rotor(t)[1, 2], b.rotor(t[1, 2]))
    R = b.rotor(t)
    assert np.all(b.frame_error(t, R) == 0.0) and np.all(b.frame_error(t, -3 * R) < 1e-15)
    tilted = quat.multiply(quat.exp([1e-6, 0, 0]), R)  # rotated by 2e-6 rad: δ = 2e-6 · √2
    assert np.allclose(b.frame_error(t, tilted), 2e-6 * math.sqrt(2), rtol=1e-6)


@pytest.mark.parametrize("kwargs", [{"R0": [0, 0, 0, 0]}, {"R0": [1, 0, 0]}, {"alpha": math.nan},
                                    {"Omega_orb": math.inf}, {"alpha_dot": math.nan}])
def test_invalid_parameters_are_rejected(kwargs):
    with pytest.raises(ValueError):
        PrecessingNutatingBinary(**kwargs)


def test_from_inputs_rebuilds_the_binary_bitwise_after_a_file(tmp_path):
    from pnrotor import hdf5, integrate_angular_velocity

    R0 = quat.normalize(np.array([1.0, 2.0, 3.0, 4.0]))
    assert not np.array_equal(quat.normalize(R0), R0)  # normalizing again changes it: a rebuild must not
    binary = PrecessingNutatingBinary(Omega_orb=0.011, Omega_prec=-0.0013, alpha=0.7, alpha_dot=3e-5, nu=0.2,
                                      R0=(1, 2, 3, 4), T=5e3)
    history = integrate_angular_velocity(binary, (0.0, 2e3), binary.rotor(0.0))
    hdf5.write(tmp_path / "run.h5", history)
    rebuilt = PrecessingNutatingBinary.from_inputs(hdf5.read(tmp_path / "run.h5").inputs)
    t = np.linspace(-1e6, 1e6, 1001)
    assert np.array_equal(rebuilt.params, binary.params) and rebuilt.T == binary.T
    assert np.array_equal(rebuilt.rotor(t), binary.rotor(t))
    assert np.array_equal(rebuilt.angular_velocity(t), binary.angular_velocity(t))


def test_from_inputs_is_none_unless_the_inputs_describe_the_binary():
    inputs = PrecessingNutatingBinary().describe()
    assert np.array_equal(PrecessingNutatingBinary.from_inputs(inputs).params, PrecessingNutatingBinary().params)
    assert PrecessingNutatingBinary.from_inputs({"omega": "numba function omega", "t_end": 1.0}) is None
    assert PrecessingNutatingBinary.from_inputs({}) is None
    for name in inputs:
        assert PrecessingNutatingBinary.from_inputs({k: v for k, v in inputs.items() if k != name}) is None
