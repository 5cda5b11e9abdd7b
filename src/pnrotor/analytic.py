r"""The precessing and nutating binary of Boyle 2016 (arXiv:1604.08139), Sec. V-B: an exact rotor R(t)
and its exact angular velocity, the reference against which integrations are verified.

This module owns

* :class:`PrecessingNutatingBinary` — the parameters (the paper's values by default,
  eq:precession_constants), ``rotor(t)`` and ``angular_velocity(t)`` over arrays of times,
  ``frame_error`` (δ of eq:error_norm against the exact frame), and the integrator's right-hand sides;
* the numba kernels :func:`binary_rotor` (eq:BinaryRotor) and :func:`binary_omega` (its ω), with the
  parameters in a float64 array (:attr:`PrecessingNutatingBinary.params`);
* one cached right-hand side per derivative kernel of :mod:`pnrotor.formulations`, composing it with
  :func:`binary_omega` (top-level functions, so numba caches them across processes).

**The rotor** (eq:BinaryRotor) is R = R₀ R₁ R₄ R₁⁻¹ R₃ R₂ R₃⁻¹ R₁ with R₁ = exp(Ω_orb t ẑ/2),
R₂ = exp((α + α̇ t) x̂/2), R₃ = exp(Ω_prec t ẑ/2), R₄ = exp(ν x̂/2), evaluated literally as that product.

**The angular velocity** ω = 2 Ṙ R⁻¹ (eq:angular-velocity) follows from the product rule
(eq:product-rule) with eq:derivatives_of_rotors and eq:differentiate-unit-condition: for R = A B,
2 Ṙ R⁻¹ = 2 Ȧ A⁻¹ + A (2 Ḃ B⁻¹) A⁻¹, and each factor exp(θ(t) v̂/2) contributes θ̇ v̂. Writing
N = R₁ R₄ R₁⁻¹ = exp(ν n̂/2) and Q = R₃ R₂ R₃⁻¹ = exp(β q̂/2), with φ = Ω_orb t, ψ = Ω_prec t,
β = α + α̇ t, n̂ = (cos φ, sin φ, 0), q̂ = (cos ψ, sin ψ, 0), the sum collapses to

    ω = R₀ [ Ω_orb ẑ + N ( Ω_prec ẑ + α̇ q̂ + (Ω_orb − Ω_prec) ℓ − Ω_orb ẑ ) N⁻¹ ] R₀⁻¹,
    ℓ = Q ẑ Q⁻¹ = (sin ψ sin β, −cos ψ sin β, cos β)   (the orbital axis before nutation),

with the rotation by N done by Rodrigues' formula and the one by R₀ by its matrix. No finite
differences; the tests compare it with an mpmath evaluation of the product rule and of 2 Ṙ R⁻¹.

**Precision at large t.** In float64, Ω_orb t at t = 10⁶ (≈ 6283) carries a rounding error of up to
4.5e-13 rad, which puts an error of ~1e-12 into δ: larger than the floor the integrations reach.
Every angle here is therefore formed as the exact real number c + r t for the float64 values
c, r, t (Dekker's error-free product and Knuth's error-free sum give it as an unevaluated sum of two
doubles) and reduced modulo π/2 (Cody–Waite with 33-bit parts of π/2 while the quadrant count is
below 2²⁰, else against a two-double π/2), so the remainder x ∈ [−π/4, π/4] has an absolute error of
about one rounding at any t; cos x and sin x then follow from fdlibm's minimax polynomials (checked
against mpmath, tests/test_analytic.py; and faster than libm on a plainly rounded angle, which matters
since ω is evaluated ~10⁶ times per run). The binary is thereby defined by its
float64 parameter values: Ω_orb is the double nearest 2π/1000, and the phase is that double times t,
exactly.
The integrated ω is evaluated the same way. It matters there too, though less: ω depends on the
orbital phase only through the nutation (a rotation by ν), but on the precession phase Ω_prec t
(≈ 628 rad at t = 10⁶, rounding ~6e-14) through the orbital axis, times Ω_orb. Measured on the
paper's case with the rotor formulation and DOP853 over [0, 10⁶] (max δ with exact phases / with
plainly rounded phases in ω, both against this exact reference): atol 1e-12: 1.08e-10 / 1.05e-10;
atol 1e-14: 3.8e-12 / 9.6e-12. A plain float64 reference rotor alone is off by up to 6e-13 in δ.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from pnrotor import formulations as _form
from pnrotor import quaternion as quat

# --------------------------------------------------------------------------------------------------
# exactly reduced angles
# --------------------------------------------------------------------------------------------------

_SPLIT = 134217729.0  # 2^27 + 1, Veltkamp's splitting constant for float64
_PIO2_HI = 1.5707963267948966  # the double nearest π/2
_PIO2_LO = 6.123233995736766e-17  # π/2 − _PIO2_HI, to double precision
_TWO_OVER_PI = 0.6366197723675814
_PIO2_1, _PIO2_2, _PIO2_2T = 1.5707963267341256, 6.077100506303966e-11, 2.0222662487959506e-21  # π/2 in 33-bit parts

# Minimax polynomials for sin and cos on [−π/4, π/4], errors below one ulp (the coefficients of
# fdlibm's __kernel_sin and __kernel_cos, Sun Microsystems 1993).
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11


@njit(cache=True)
def _two_prod(a, b):
    """(p, e) with p = fl(a b) and p + e = a b exactly (Dekker's product; |a b| < 1e300)."""
    p = a * b
    c = _SPLIT * a
    ahi = c - (c - a)
    alo = a - ahi
    c = _SPLIT * b
    bhi = c - (c - b)
    blo = b - bhi
    e = ((ahi * bhi - p) + ahi * blo + alo * bhi) + alo * blo
    return p, e


@njit(cache=True)
def _two_sum(a, b):
    """(s, e) with s = fl(a + b) and s + e = a + b exactly (Knuth's sum)."""
    s = a + b
    bb = s - a
    e = (a - (s - bb)) + (b - bb)
    return s, e


@njit(cache=True, fastmath={"contract"})
def _cos_sin_poly(x):
    """(cos x, sin x) for |x| ≤ π/4 (fdlibm's kernels; fused multiply-adds allowed, they only help)."""
    z = x * x
    sn = x + x * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    cs = w + (((1.0 - w) - hz) + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6))))))
    return cs, sn


@njit(cache=True)
def cos_sin(c, rate, t):
    """(cos θ, sin θ) of the real number θ = c + rate·t (for the float64 values given), to ~1e-16 for
    |θ| up to ~1e15 (beyond, the two-double π/2 runs out of digits): θ is formed exactly as a sum of
    two doubles, reduced modulo π/2, and the polynomials are evaluated on the remainder
    x ∈ [−π/4, π/4] (see the module docstring)."""
    p, e = _two_prod(rate, t)
    s, e2 = _two_sum(c, p)
    e += e2
    k = math.floor(s * _TWO_OVER_PI + 0.5)
    # s − k π/2, with s − a1 exact (Sterbenz: a1 is within a factor 2 of s when k ≠ 0)
    if abs(k) < 1048576.0:  # k < 2^20: k·_PIO2_1 and k·_PIO2_2 are exact (33-bit constants, Cody–Waite)
        x = ((s - k * _PIO2_1) - k * _PIO2_2) + (e - k * _PIO2_2T)
    else:
        a1, a2 = _two_prod(k, _PIO2_HI)
        x = (s - a1) + (e - a2 - k * _PIO2_LO)
    cs, sn = _cos_sin_poly(x)
    quadrant = int(k) & 3
    if quadrant == 0:
        return cs, sn
    if quadrant == 1:
        return -sn, cs
    if quadrant == 2:
        return -cs, -sn
    return sn, -cs


# --------------------------------------------------------------------------------------------------
# kernels; p = [Ω_orb, Ω_prec, α, α̇, ν, R₀ (4, unit), M₀ (9, rotation matrix of R₀, row-major),
#              cos ν, sin ν, 1 − cos ν]
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def _axis_rotor(cs, axis, sign):
    """exp(sign · θ/2 · ê_axis) for axis 1 = x̂, 3 = ẑ, from cs = (cos θ/2, sin θ/2)."""
    R = np.zeros(4)
    R[0] = cs[0]
    R[axis] = sign * cs[1]
    return R


@njit(cache=True)
def binary_rotor(t, p):
    """R(t) = R₀ R₁ R₄ R₁⁻¹ R₃ R₂ R₃⁻¹ R₁ (eq:BinaryRotor), unit, continuous in t."""
    h1 = cos_sin(0.0, 0.5 * p[0], t)
    h3 = cos_sin(0.0, 0.5 * p[1], t)
    R1 = _axis_rotor(h1, 3, 1.0)
    R1inv = _axis_rotor(h1, 3, -1.0)
    R2 = _axis_rotor(cos_sin(0.5 * p[2], 0.5 * p[3], t), 1, 1.0)
    R3 = _axis_rotor(h3, 3, 1.0)
    R3inv = _axis_rotor(h3, 3, -1.0)
    R4 = _axis_rotor(cos_sin(0.5 * p[4], 0.0, t), 1, 1.0)
    R = quat.qmul(p[5:9], R1)
    R = quat.qmul(R, R4)
    R = quat.qmul(R, R1inv)
    R = quat.qmul(R, R3)
    R = quat.qmul(R, R2)
    R = quat.qmul(R, R3inv)
    return quat.qmul(R, R1)


@njit(cache=True)
def binary_omega(t, p):
    """ω(t) = 2 Ṙ R⁻¹ of :func:`binary_rotor`, as a tuple (ωx, ωy, ωz) (closed form of the module
    docstring; allocation-free, for use inside right-hand sides)."""
    Oo, Op, adot = p[0], p[1], p[3]
    cphi, sphi = cos_sin(0.0, Oo, t)
    cpsi, spsi = cos_sin(0.0, Op, t)
    cb, sb = cos_sin(p[2], adot, t)
    # u = Ω_prec ẑ + α̇ q̂ + (Ω_orb − Ω_prec) ℓ − Ω_orb ẑ
    d = Oo - Op
    ux = adot * cpsi + d * spsi * sb
    uy = adot * spsi - d * cpsi * sb
    uz = Op + d * cb - Oo
    # N u N⁻¹ by Rodrigues: u cos ν + (n̂ × u) sin ν + n̂ (n̂·u)(1 − cos ν), n̂ = (cos φ, sin φ, 0)
    cn, sn = p[18], p[19]
    nu_dot = (cphi * ux + sphi * uy) * p[20]
    bx = ux * cn + sphi * uz * sn + cphi * nu_dot
    by = uy * cn - cphi * uz * sn + sphi * nu_dot
    bz = uz * cn + (cphi * uy - sphi * ux) * sn + Oo
    # rotate by R₀ (its matrix M₀)
    return (p[9] * bx + p[10] * by + p[11] * bz,
            p[12] * bx + p[13] * by + p[14] * bz,
            p[15] * bx + p[16] * by + p[17] * bz)


@njit(cache=True)
def _rotors(ts, p, out):
    for i in range(ts.size):
        out[i] = binary_rotor(ts[i], p)


@njit(cache=True)
def _omegas(ts, p, out):
    for i in range(ts.size):
        w = binary_omega(ts[i], p)
        out[i, 0] = w[0]
        out[i, 1] = w[1]
        out[i, 2] = w[2]


# --------------------------------------------------------------------------------------------------
# right-hand sides: each derivative kernel of pnrotor.formulations composed with binary_omega, compiled for
# pnrotor.ode.RHS_SIG by the integrator when a run first needs it (not at import: ~1-1.5 s each on a cold cache)
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def _rhs_rotor(t, y, p, dydt):
    _form.rotor_derivative(binary_omega(t, p), y, p, dydt)


@njit(cache=True)
def _rhs_generator(t, y, p, dydt):
    _form.generator_derivative(binary_omega(t, p), y, p, dydt)


@njit(cache=True)
def _rhs_vectors(t, y, p, dydt):
    _form.vectors_derivative(binary_omega(t, p), y, p, dydt)


@njit(cache=True)
def _rhs_damped_vectors(t, y, p, dydt):
    _form.damped_vectors_derivative(binary_omega(t, p), y, p, dydt)


_RHS = {
    _form.rotor_derivative: _rhs_rotor,
    _form.generator_derivative: _rhs_generator,
    _form.vectors_derivative: _rhs_vectors,
    _form.damped_vectors_derivative: _rhs_damped_vectors,
}


# --------------------------------------------------------------------------------------------------
# the binary
# --------------------------------------------------------------------------------------------------


def _finite(name, value):
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


@dataclass(frozen=True, eq=False)
class PrecessingNutatingBinary:
    """The paper's precessing and nutating binary (Sec. V-B, eq:BinaryRotor, eq:precession_constants).

    Parameters (defaults are the paper's, eq:precession_constants): ``Omega_orb`` = 2π/1000, ``Omega_prec`` =
    2π/10000, ``alpha`` = π/8, ``alpha_dot`` = 2α/10⁵, ``nu`` = π/80, ``R0`` = e^{−3α x̂/10} (in the paper's
    notation, where R₂ = e^{α x̂/2} tilts by α, a rotation by −3α/5 about x̂), ``T`` = 10⁶
    (the span of the paper's study: 1000 orbits, 100 precession cycles).  ``alpha_dot`` and ``R0`` default
    to these expressions in the given ``alpha``; ``R0`` may be any nonzero quaternion (w, x, y, z)
    and is normalized (one already unit to rounding is kept as given, since normalizing it again may
    change its last bits); all parameters must be finite and ``T`` > 0. :meth:`describe` gives the
    parameters as a run's ``inputs``, and :meth:`from_inputs` rebuilds the binary from them.

    Pass the binary itself as the ``omega`` of :func:`pnrotor.integrate_angular_velocity`: it
    supplies cached right-hand sides (:meth:`integrand`), so nothing is compiled per process.
    """

    Omega_orb: float = 2.0 * math.pi / 1000.0
    Omega_prec: float = 2.0 * math.pi / 10000.0
    alpha: float = math.pi / 8.0
    alpha_dot: float = None
    nu: float = math.pi / 80.0
    R0: np.ndarray = None
    T: float = 1.0e6
    params: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        def set_(name, value):  # fields of a frozen dataclass are set through object.__setattr__
            object.__setattr__(self, name, value)

        for name in ("Omega_orb", "Omega_prec", "alpha", "nu", "T"):
            set_(name, _finite(name, getattr(self, name)))
        if not self.T > 0.0:
            raise ValueError(f"T (the span of the study) must be finite and > 0, got {self.T!r}")
        set_("alpha_dot", 2.0 * self.alpha / 1.0e5 if self.alpha_dot is None
             else _finite("alpha_dot", self.alpha_dot))
        if self.R0 is None:
            R0 = quat.exp(np.array([-0.3 * self.alpha, 0.0, 0.0]))
        else:
            R0 = np.array(self.R0, dtype=np.float64)
            if R0.shape != (4,) or not np.all(np.isfinite(R0)) or not np.any(R0):
                raise ValueError(f"R0 must be a finite nonzero quaternion (w, x, y, z), got {self.R0!r}")
            if abs(R0 @ R0 - 1.0) > 4.0 * np.finfo(np.float64).eps:
                R0 = quat.normalize(R0)
        R0.setflags(write=False)
        set_("R0", R0)
        p = np.concatenate([[self.Omega_orb, self.Omega_prec, self.alpha, self.alpha_dot, self.nu],
                            R0, quat.to_matrix(R0).reshape(9),
                            [math.cos(self.nu), math.sin(self.nu), 2.0 * math.sin(0.5 * self.nu) ** 2]])
        p.setflags(write=False)
        set_("params", p)

    def rotor(self, t):
        """Exact unit rotors R(t) (eq:BinaryRotor): shape (4,) for a scalar t, (..., 4) for an array."""
        t = np.asarray(t, dtype=np.float64)
        ts = np.ascontiguousarray(t.reshape(-1))
        out = np.empty((ts.size, 4))
        _rotors(ts, self.params, out)
        return out.reshape(t.shape + (4,))

    def angular_velocity(self, t):
        """Exact ω(t) = 2 Ṙ R⁻¹ (eq:angular-velocity): shape (3,) for a scalar t, (..., 3) for an array."""
        t = np.asarray(t, dtype=np.float64)
        ts = np.ascontiguousarray(t.reshape(-1))
        out = np.empty((ts.size, 3))
        _omegas(ts, self.params, out)
        return out.reshape(t.shape + (3,))

    def frame_error(self, t, R):
        """δ(t) of eq:error_norm between rotors R (..., 4) at times t and the exact frame."""
        return quat.frame_error(np.asarray(R, dtype=np.float64), self.rotor(t))

    def integrand(self, formulation):
        """(rhs, p) for integrating this binary's ω in ``formulation`` (a :class:`Formulation`):
        the cached right-hand side and the leading parameters of its ``p``."""
        return _RHS[formulation.derivative], self.params

    def describe(self):
        """The parameters as a dict of plain numbers and arrays (for a run's ``inputs``)."""
        return {"omega": "PrecessingNutatingBinary", "Omega_orb": self.Omega_orb,
                "Omega_prec": self.Omega_prec, "alpha": self.alpha, "alpha_dot": self.alpha_dot,
                "nu": self.nu, "binary_R0": np.array(self.R0), "T": self.T}

    @classmethod
    def from_inputs(cls, inputs):
        """The binary a run's ``inputs`` describe (:meth:`describe`, which
        :func:`pnrotor.integrate_angular_velocity` puts there; e.g. a `FrameHistory` read from a file of
        ``pnrotor verify -o``), the same bitwise: its ``params`` and rotors. None when ``inputs`` do not
        describe one: another ω, or a parameter missing."""
        names = ("Omega_orb", "Omega_prec", "alpha", "alpha_dot", "nu", "T")
        if inputs.get("omega") != "PrecessingNutatingBinary" or not all(n in inputs for n in (*names, "binary_R0")):
            return None
        return cls(R0=inputs["binary_R0"], **{name: inputs[name] for name in names})

