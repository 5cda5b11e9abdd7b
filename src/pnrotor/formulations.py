r"""Formulations of the angular-velocity integration problem (Boyle 2016, arXiv:1604.08139, Secs. II–IV).

Given an angular velocity ω(t), the orientation of a rotating frame can be found by integrating
different state variables. This module owns, for each formulation, the evolved state, its time
derivative given ω, the hook applied after each accepted step, and the conversions between the
state and unit rotors:

=====================  =====  ===================================================================
name                   state  equations
=====================  =====  ===================================================================
``rotor``              4      dR/dt = ½ ω R, R unnormalized (eq:integrate-spinor)
``generator``          3      ṙ of R = exp(r) (eq:log_deriv_omega), with the reset
                              r → r − π r/|r| after each accepted step with |r| ≥ π/2
                              (eq:generator_reset; the nearest multiple of π if |r| ≥ 3π/2)
``generator-noreset``  3      the same equation without the reset
``vectors3``           9      dfᵢ/dt = ω × fᵢ for the three frame vectors (eq:integr-frame-vectors)
``vectors2``           6      the same for f₀, f₁; f₂ = f₀ × f₁
``vectors-damped``     6      f₀ with norm damping λ (eq:vector-norm-damping), f₁ with
                              orthogonality damping μ (eq:vector-orthogonality-damping)
=====================  =====  ===================================================================

Derivative kernels have the form ``derivative(w, y, p, dydt)``, where ``w`` is ω(t) (any indexable of
three floats: an array or a tuple) and ``p`` is the parameter array of the right-hand side; the
damped formulation reads λ = p[-2], μ = p[-1], so the parameters of ω come first in ``p``.

A right-hand side for :mod:`pnrotor.ode` composes an ω kernel with a derivative kernel. For the
analytic binary these compositions are top-level, cached functions in :mod:`pnrotor.analytic`.
For a user's ω, :func:`rhs_for_numba_omega` builds the composition as a closure, which numba compiles
in every process (it cannot be cached across processes: once per process, before the first
integration with a given formulation and ω), and :func:`numba_omega_from_python` wraps a plain Python
callable in a numba object-mode call so that the same integrator can drive it, at the price of a
Python call per evaluation.

Rotors returned by every formulation are unit and sign-continuous (:meth:`Formulation.rotors`).
The rotor and unreset generator states are continuous, so their rotors are. The generator reset
may flip the sign of exp(r) (exp(r − nπ r/|r|) = (−1)ⁿ exp(r), eq:rotation_equivalence), and a frame defines
its rotor only up to sign; for those formulations each sample's sign is chosen closest to the
previous sample advanced by the midpoint rule, exp(½ ω(t_mid) Δt) R_prev (first-order Magnus). Plain
nearest-sign alignment fails once the frame turns by more than a half turn between samples, which
Bulirsch–Stoer steps on the paper's binary do (up to ~660 time units, 2/3 of an orbit); the midpoint
prediction stays within 50° of the truth for gaps up to 3 orbits there, so it holds for
every integrator output and for t_eval samples that resolve the rotation to that extent.
"""

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import njit, objmode

from pnrotor import quaternion as quat
from pnrotor.ode import AFTER_STEP_SIG, RHS_SIG

# --------------------------------------------------------------------------------------------------
# derivative kernels
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def rotor_derivative(w, y, p, dydt):
    """dR/dt = ½ ω R (eq:integrate-spinor), ω the pure quaternion (0, w), R = y of any nonzero norm.

    With R = (s, v): ω R = (−w·v, s w + w × v).
    """
    s, vx, vy, vz = y[0], y[1], y[2], y[3]
    wx, wy, wz = w[0], w[1], w[2]
    dydt[0] = -0.5 * (wx * vx + wy * vy + wz * vz)
    dydt[1] = 0.5 * (s * wx + wy * vz - wz * vy)
    dydt[2] = 0.5 * (s * wy + wz * vx - wx * vz)
    dydt[3] = 0.5 * (s * wz + wx * vy - wy * vx)


# Below this |r|, r cot r and (1 − r cot r)/r² are evaluated from their Taylor series; the first
# omitted terms, r⁸/4725 and 2r⁸/93555, are below 1e-19. Above it the closed forms lose at most
# eps/|r|² ≤ 2e-12 relative in (1 − r cot r)/r², a term multiplied by |r|², so ≤ 2e-16 |ω| in ṙ.
_GEN_SERIES_BELOW = 1e-2


@njit(cache=True)
def generator_derivative(w, y, p, dydt):
    """ṙ of the generator r of R = exp(r) (eq:log_deriv_omega), with θ = |r|:

        ṙ = ½ ω × r + ω (θ cot θ)/2 + r (r·ω) (1 − θ cot θ)/(2θ²).

    Singular where θ → π (R → −1); the reset (eq:generator_reset) keeps θ ≤ π/2.
    """
    rx, ry, rz = y[0], y[1], y[2]
    wx, wy, wz = w[0], w[1], w[2]
    th2 = rx * rx + ry * ry + rz * rz
    if th2 < _GEN_SERIES_BELOW * _GEN_SERIES_BELOW:
        # θ cot θ = 1 − θ²/3 − θ⁴/45 − 2θ⁶/945 − …;  (1 − θ cot θ)/θ² = 1/3 + θ²/45 + 2θ⁴/945 + θ⁶/4725 + …
        c = 1.0 - th2 * (1.0 / 3.0 + th2 * (1.0 / 45.0 + th2 * (2.0 / 945.0)))
        g = 1.0 / 3.0 + th2 * (1.0 / 45.0 + th2 * (2.0 / 945.0 + th2 * (1.0 / 4725.0)))
    else:
        th = np.sqrt(th2)
        c = th * np.cos(th) / np.sin(th)
        g = (1.0 - c) / th2
    rw = rx * wx + ry * wy + rz * wz
    dydt[0] = 0.5 * ((wy * rz - wz * ry) + c * wx + g * rw * rx)
    dydt[1] = 0.5 * ((wz * rx - wx * rz) + c * wy + g * rw * ry)
    dydt[2] = 0.5 * ((wx * ry - wy * rx) + c * wz + g * rw * rz)


@njit(cache=True)
def vectors_derivative(w, y, p, dydt):
    """dfᵢ/dt = ω × fᵢ (eq:integr-frame-vectors) for the y.size // 3 vectors stored one after another."""
    wx, wy, wz = w[0], w[1], w[2]
    for k in range(0, y.size, 3):
        fx, fy, fz = y[k], y[k + 1], y[k + 2]
        dydt[k] = wy * fz - wz * fy
        dydt[k + 1] = wz * fx - wx * fz
        dydt[k + 2] = wx * fy - wy * fx


@njit(cache=True)
def damped_vectors_derivative(w, y, p, dydt):
    """f₀, f₁ with constraint damping; λ = p[-2], μ = p[-1]:

        df₀/dt = ω × f₀ + λ (1 − f₀·f₀) f₀                                    (eq:vector-norm-damping)
        df₁/dt = ω × f₁ + μ (f₀ × (f₁ × f₀) / |f₀ × (f₁ × f₀)| − f₁)      (eq:vector-orthogonality-damping)

    with f₀ × (f₁ × f₀) = f₁ (f₀·f₀) − f₀ (f₀·f₁).
    """
    vectors_derivative(w, y, p, dydt)
    lam = p[p.size - 2]
    mu = p[p.size - 1]
    ax, ay, az = y[0], y[1], y[2]
    bx, by, bz = y[3], y[4], y[5]
    aa = ax * ax + ay * ay + az * az
    ab = ax * bx + ay * by + az * bz
    k = lam * (1.0 - aa)
    dydt[0] += k * ax
    dydt[1] += k * ay
    dydt[2] += k * az
    ux = bx * aa - ax * ab
    uy = by * aa - ay * ab
    uz = bz * aa - az * ab
    un = np.sqrt(ux * ux + uy * uy + uz * uz)
    dydt[3] += mu * (ux / un - bx)
    dydt[4] += mu * (uy / un - by)
    dydt[5] += mu * (uz / un - bz)


@njit(AFTER_STEP_SIG, cache=True)
def generator_reset(t, y, p):
    """r → r − nπ r/|r| with n = round(|r|/π) when |r| ≥ π/2: the same rotation, exp of it is (−1)ⁿ exp(r).

    The paper's reset (eq:generator_reset) is n = 1, which is enough for |r| < 3π/2 at the end of a step.
    A step can end beyond that where ṙ stays bounded through |r| = π (ω ∥ r: ṙ = ω/2), and one
    subtraction of π then left |r| = 5.2 (benchmarks/stress_numerics.py); the nearest multiple
    brings every step back to |r| ≤ π/2."""
    th = np.sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2])
    if th < 0.5 * np.pi:
        return False
    k = 1.0 - np.pi * np.floor(th / np.pi + 0.5) / th
    y[0] *= k
    y[1] *= k
    y[2] *= k
    return True


# --------------------------------------------------------------------------------------------------
# conversions between states and rotors (NumPy, over arrays of states)
# --------------------------------------------------------------------------------------------------


def _frame_rotors(f0, f1, f2):
    """Unit rotors of the rotations nearest (Frobenius norm, by the polar decomposition) to the matrices
    with columns f0, f1, f2, each of shape (N, 3); integrated frames are only approximately orthonormal."""
    M = np.stack([f0, f1, f2], axis=-1)
    U, _, Vt = np.linalg.svd(M)
    # a reflection (det < 0) can only come from a frame far from any rotation; flip to the nearest rotation
    U[..., :, 2] *= np.sign(np.linalg.det(U @ Vt))[..., None]
    return quat.from_matrix(U @ Vt)


def _rotor_state(R0):
    return quat.normalize(R0)


def _rotor_rotors(Y):
    return quat.normalize(Y)


def _generator_state(R0):
    # start from the representative with scalar part ≥ 0, whose generator has |r| ≤ π/2
    return quat.log(R0 if R0[0] >= 0.0 else -R0)


def _generator_rotors(Y):
    return quat.exp(Y)


def _vectors3_state(R0):
    return quat.rotate(R0, np.eye(3)).reshape(9)


def _vectors3_rotors(Y):
    return _frame_rotors(Y[:, 0:3], Y[:, 3:6], Y[:, 6:9])


def _vectors2_state(R0):
    return quat.rotate(R0, np.eye(3)[:2]).reshape(6)


def _vectors2_rotors(Y):
    return _frame_rotors(Y[:, 0:3], Y[:, 3:6], np.cross(Y[:, 0:3], Y[:, 3:6]))


@dataclass(frozen=True)
class Formulation:
    """One way of integrating ω: its state, derivative kernel, after-step hook and rotor conversions.

    ``derivative`` is the numba kernel ``(w, y, p, dydt)``; ``after_step`` an ``AFTER_STEP_SIG`` hook or
    None; ``n_params`` the number of trailing entries of ``p`` the derivative reads (λ, μ);
    ``initial_state(R0)`` the state (size,) of the unit rotor R0; ``to_rotors(Y)`` unit rotors (N, 4)
    of states (N, size), without regard to sign; ``continuous`` whether those rotors inherit the
    continuity of the states.
    """

    name: str
    size: int
    derivative: object
    after_step: object
    n_params: int
    initial_state: Callable
    to_rotors: Callable
    continuous: bool

    def rotors(self, Y, R_ref, t, omega_at, t_ref=None):
        """Unit rotors (N, 4) of states Y (N, size) at times t (N,), sign-continuous from the rotor R_ref at
        t_ref (default t[0]), the start of the integration.

        A continuous formulation's rotors keep the sign they have at the start against R_ref (that of its
        initial state's rotor), whatever the samples.  For the others each sample's sign follows its
        predecessor's, the first's R_ref's, by the midpoint prediction of the module docstring:
        ``omega_at(ts)`` returns ω at an array of times, shape (len(ts), 3).
        """
        R = self.to_rotors(np.asarray(Y, dtype=np.float64))
        if not len(R):
            return R
        if self.continuous:
            start = self.to_rotors(self.initial_state(np.asarray(R_ref, dtype=np.float64))[None, :])[0]
            return R if np.dot(start, R_ref) >= 0.0 else -R
        t = np.concatenate(([t[0] if t_ref is None else t_ref], t))
        R = np.concatenate((np.asarray(R_ref, dtype=np.float64)[None, :], R))
        dt = np.diff(t)
        predicted = quat.multiply(quat.exp(0.5 * dt[:, None] * omega_at(t[:-1] + 0.5 * dt)), R[:-1])
        # flipping sample i flips its agreement with sample i + 1: the signs are a running product
        agree = np.einsum("ij,ij->i", R[1:], predicted) >= 0.0
        return R[1:] * np.cumprod(np.where(agree, 1.0, -1.0))[:, None]


FORMULATIONS = {
    f.name: f
    for f in (
        Formulation("rotor", 4, rotor_derivative, None, 0, _rotor_state, _rotor_rotors, True),
        Formulation("generator", 3, generator_derivative, generator_reset, 0,
                    _generator_state, _generator_rotors, False),
        Formulation("generator-noreset", 3, generator_derivative, None, 0,
                    _generator_state, _generator_rotors, True),
        Formulation("vectors3", 9, vectors_derivative, None, 0, _vectors3_state, _vectors3_rotors, False),
        Formulation("vectors2", 6, vectors_derivative, None, 0, _vectors2_state, _vectors2_rotors, False),
        Formulation("vectors-damped", 6, damped_vectors_derivative, None, 2,
                    _vectors2_state, _vectors2_rotors, False),
    )
}
"""The formulations by name: the rotor (the paper's recommendation), the generators, the frame vectors."""


def get(name):
    """The :class:`Formulation` called ``name`` (ValueError listing the choices otherwise)."""
    try:
        return FORMULATIONS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown formulation {name!r}; choose one of {', '.join(FORMULATIONS)}") from None


# --------------------------------------------------------------------------------------------------
# right-hand sides for a user's ω
# --------------------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=64)
def rhs_for_numba_omega(derivative, omega):
    """The right-hand side ``rhs(t, y, p, dydt) = derivative(omega(t), y, p, dydt)`` (``RHS_SIG``) for a
    numba function ``omega(t)`` returning three floats.

    A closure over ``omega``, so it is compiled once per process (numba cannot cache it across
    processes); memoized within the process.
    """

    @njit(RHS_SIG)
    def rhs(t, y, p, dydt):
        derivative(omega(t), y, p, dydt)

    return rhs


@functools.lru_cache(maxsize=64)
def numba_omega_from_python(omega):
    """A numba function ``w(t)`` (float64[3]) that calls the Python callable ``omega(t)`` in object mode.

    Lets the numba integrators drive a plain Python ω, at the cost of a Python call per evaluation.
    Exceptions raised by ``omega`` propagate out of the integrator.
    """

    @njit
    def w(t):
        with objmode(out="float64[::1]"):
            out = np.ascontiguousarray(omega(t), dtype=np.float64).reshape(3)
        return out

    return w
