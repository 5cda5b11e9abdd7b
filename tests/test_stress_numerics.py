"""Guards on the numerical corners measured by benchmarks/stress_numerics.py (Boyle 2016,
arXiv:1604.08139, Secs. II–V), each against an independent reference: the exact fixed-axis rotor
exp(½ F(t) ê) R₀ (eq:integrate-spinor with commuting ω's), the exact binary (eq:BinaryRotor), the
conservation of |R| by dR/dt = ½ ω R, the expected count of generator resets (eq:generator_reset),
the exact ṙ = ω/2 of eq:log_deriv_omega along the axis, or a measured growth exponent of δ
(eq:error_norm). Integrations run in the benchmark's cached right-hand sides, so nothing compiles
per process.

Not guarded here, because the tolerance does not control it (measured in the benchmark table):
Bulirsch–Stoer on a ω with a jump or a kink accepts a step straddling it with an error of up to
0.3 (jump) or 3e-4 (kink) at atol 1e-10: when the jump lies within the first or last substep
H/n of every column, no Gragg evaluation sees it and the extrapolation error estimate is blind.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from pnrotor import integrate_angular_velocity
from pnrotor import quaternion as quat
from pnrotor.analytic import PrecessingNutatingBinary

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import stress_numerics as S  # noqa: E402  (the benchmark's ω's, exact rotors and runner)

FORMS = list(S.FORMS)
METHODS = list(S.METHODS)
ATOL = S.ATOL_AXIS
R0 = S.R0_GENERIC


def axis_run(name, formulation, method, atol=ATOL, R0=R0, T=S.T_AXIS):
    omega = dict(S.AXIS_CASES)[name] if isinstance(name, str) else name
    return S.run(omega, (0.0, T), R0, formulation, method, atol, exact=lambda t: omega.rotor(t, R0))


ZERO, CONSTANT, COSINE, JUMP, KINK, PULSE, RAMP = (label for label, _ in S.AXIS_CASES)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("formulation", FORMS)
def test_zero_omega_keeps_R0_to_roundoff(formulation, method):
    r = axis_run(ZERO, formulation, method)
    h = r["h"]
    assert h.status == 0 and not r["crash"]
    assert np.max(np.abs(h.R - R0)) < 1e-15 and r["delta"] < 1e-15


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("formulation", FORMS)
def test_constant_and_reversing_omega_follow_the_exact_rotor(formulation, method):
    # measured: at most 12 atol (constant ω) and 38 atol (3 cos t) over atol 1e-8..1e-12
    for name in (CONSTANT, COSINE):
        r = axis_run(name, formulation, method)
        assert r["h"].status == 0 and not r["crash"], name
        assert r["delta"] < 100 * ATOL and r["flips"] == 0, (name, r["delta"], r["flips"])


@pytest.mark.parametrize("atol", [1e-8, 1e-11])
@pytest.mark.parametrize("formulation", FORMS)
def test_dop853_steps_across_a_jump_and_a_kink_within_the_tolerance(formulation, atol):
    # measured: at most 110 atol (jump) and 62 atol (kink) over atol 1e-8..1e-12
    for name in (JUMP, KINK):
        r = axis_run(name, formulation, "DOP853", atol=atol)
        assert r["h"].status == 0 and not r["crash"], name
        assert r["delta"] < 300 * atol and r["flips"] == 0, (name, r["delta"] / atol)


@pytest.mark.parametrize("formulation", ["rotor", "generator", "vectors2"])
def test_omega_varying_by_a_million_is_followed(formulation):
    # a 10⁶ pulse (1.8e4 rad in 0.04 time units) and a 10⁶ exponential ramp (1.4e3 rad); measured with
    # DOP853 at atol 1e-10: max δ 3.2e-7 (pulse), 2.7e-8 (ramp)
    for name, bound in ((PULSE, 1e-6), (RAMP, 1e-7)):
        r = axis_run(name, formulation, "DOP853")
        assert r["h"].status == 0 and not r["crash"], name
        assert r["delta"] < bound and r["flips"] == 0, (name, r["delta"])


def test_generator_reset_from_exactly_and_near_half_pi():
    # R₀ = (0, ê): |r₀| = π/2 exactly; ω at 60° to r. One reset per sign change of the exact rotor's scalar
    # part (6 forward, 5 backward over [0, 10π + 1]), signs continuous, δ at the tolerance level
    for r in S.generator_half_pi_runs():
        assert r["h"].status == 0 and not r["crash"]
        assert r["resets"] == r["expected"] and r["expected"] in (5, 6), (r["resets"], r["expected"])
        assert r["flips"] == 0 and r["delta"] < 100 * ATOL, r["delta"]


def test_rotor_through_minus_one_is_sign_continuous_in_every_formulation():
    # R(t) = exp(t ê/2): R(2π) = −1 exactly on the path; the unreset generator then has |r| = π with ω ∥ r
    runs = S.through_minus_one(0.0)
    for r in runs:
        assert r["h"].status == 0 and not r["crash"], r["label"]
        assert r["flips"] == 0 and r["delta"] < 100 * ATOL, (r["label"], r["delta"])
        exact = np.array([np.cos(0.5 * r["h"].t), *(np.sin(0.5 * r["h"].t)[None, :] * S.AXIS[:, None])]).T
        assert np.max(np.abs(r["h"].R - exact)) < 1e-6, r["label"]


@pytest.mark.parametrize("tilt", [1e-12, 1e-8])
def test_passing_near_minus_one_is_accurate_or_reported(tilt):
    # the unreset generator is singular next to R = −1 (measured: DOP853 stops with a step-size underflow
    # at 1e-12 rad); no formulation may return a wrong answer with status 0
    for r in S.through_minus_one(tilt):
        assert not r["crash"], r["label"]
        if r["h"].status == 0:
            assert r["h"].t[-1] == S.T_MINUS_ONE, r["label"]
            assert r["delta"] < 100 * ATOL and r["flips"] == 0, (r["label"], r["delta"])
        else:
            assert r["label"].startswith("noreset") and "step size" in r["h"].message, r["h"].message


def test_generator_derivative_along_its_axis_near_pi_is_half_omega():
    # along the axis ṙ = ω/2 exactly; θ cot θ and (1 − θ cot θ)/θ² cancel, losing at most ~eps/d
    for d in (1e-12, 1e-8, 1e-4, 1e-2):
        along, across = S.generator_derivative_along_axis(d)
        assert along < 2.2e-16 / d, (d, along)
        assert across > 0.4 / d  # the true singularity across the axis, ~1/(2d)


def test_exp_log_round_trip_across_the_branch():
    along_q, delta, along_r, n = S.round_trips(50)
    assert along_q < 4e-15 and delta < 1e-14 and along_r < 2e-15, (along_q, delta, along_r)


@pytest.mark.parametrize("formulation", ["rotor", "generator"])
def test_binary_error_grows_sublinearly_not_quadratically(formulation):
    # log-log slope of max δ over [0, t] on t ∈ [10⁴, 10⁶]: measured 0.30 (rotor), 0.42 (generator) (over
    # [10⁵, 10⁷] in the benchmark: 0.73–1.07); a relative error of 1e-11 in Ω_prec gives 1.2–1.3, a
    # systematic error growing with t would give 2
    T = 1e6
    b = PrecessingNutatingBinary()
    h = integrate_angular_velocity(b, (0.0, T), b.rotor(0.0), formulation, atol=1e-12)
    assert h.status == 0
    delta = b.frame_error(h.t, h.R)
    assert S.slope(h.t, delta, T) < 1.0
    assert np.max(delta) < 1e-9


def test_unnormalized_rotor_norm_is_conserved_to_the_tolerance():
    # dR/dt = ½ ω R conserves |R| for pure ω; the raw state is the dense output at the step ends
    T = 1e6
    b = PrecessingNutatingBinary()
    h = integrate_angular_velocity(b, (0.0, T), b.rotor(0.0), "rotor", atol=1e-12, dense=True)
    raw = h.dense(h.t)
    assert np.allclose(raw / np.linalg.norm(raw, axis=1)[:, None], h.R, rtol=0, atol=1e-15)
    drift = np.abs(np.linalg.norm(raw, axis=1) - 1.0)
    assert np.max(drift) < 200 * 1e-12  # measured: 6.7e-11


@pytest.mark.parametrize("formulation", ["rotor", "generator", "vectors-damped"])
def test_forward_then_backward_over_1e6_recovers_R0(formulation):
    # backward, the generator resets as forward and the damping rates change sign (else constraint
    # violations would grow as e^{λ|t|})
    T = 1e6
    b = PrecessingNutatingBinary()
    R0b = b.rotor(0.0)
    fwd = integrate_angular_velocity(b, (0.0, T), R0b, formulation, atol=1e-12)
    back = integrate_angular_velocity(b, (T, 0.0), fwd.R[-1], formulation, atol=1e-12)
    assert fwd.status == 0 and back.status == 0 and back.t[-1] == 0.0
    # measured: 7.7e-11 (rotor), 9.9e-11 (generator), 5.1e-12 (vectors-damped); forward max δ 1.1e-10, 2.0e-10, 8.1e-11
    assert quat.frame_error(back.R[-1], R0b) < 3 * np.max(b.frame_error(fwd.t, fwd.R)) + 1e-11


@pytest.mark.parametrize("method", METHODS)
def test_unreset_generator_on_the_binary_stops_with_a_reason(method):
    # backward from 0 the binary passes R = −1 (to 5e-15) at t = −75000, where the unreset generator is singular
    # (measured: step-size underflow in both methods, max δ 3.7e-11 and 9.0e-11 before it); the run must say so,
    # and be right up to where it stopped
    b = PrecessingNutatingBinary()
    h = integrate_angular_velocity(b, (0.0, -1e6), b.rotor(0.0), "generator-noreset", method, atol=1e-12)
    assert np.all(np.isfinite(h.R))
    assert h.status != 0 and "step size" in h.message and h.t[-1] == pytest.approx(-75000.0, abs=1e-3), h.message
    assert np.max(b.frame_error(h.t, h.R)) < 1e-9
