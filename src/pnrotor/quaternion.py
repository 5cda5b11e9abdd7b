r"""Quaternion kernels on float64 arrays, scalar first: q = (w, x, y, z).

This module owns quaternion arithmetic for the whole package. It has two layers:

* **kernels** (``q*`` names) — ``@njit(cache=True)`` functions on single quaternions (float64[4]) and
  vectors (float64[3]), for use inside other numba code (right-hand sides, step loops);
* **array functions** (plain names) — numba gufuncs over the last axis that broadcast like numpy, e.g.
  ``rotate(R, v)`` with R of shape (N, 4) and v of shape (3,) or (N, 3).

Rotors follow Boyle, *The integration of angular velocity* (arXiv:1604.08139):

* Rotation of a vector by a rotor that need **not** be normalized, eq:rotor-rotation,
  v' = R v R⁻¹, evaluated with the faster form given in the footnote to that equation,
  v' = v + 2 r × (s v + r × v) / m, with s, r the scalar and vector parts of R and m = s² + |r|².
  Only R ≠ 0 is required; the norm of R cancels.
* exp and log of a pure-vector quaternion r (the generator, Sec. IV): exp(r) = cos|r| + sin|r| r/|r|,
  a rotation by the angle 2|r| about r/|r|. ``qlog`` returns the generator of the *normalized* rotor
  with |r| ∈ [0, π], computed with atan2 so that it is accurate near 0 and near π.
* The frame error norm of eq:error_norm, δ = √Σᵢ |eᵢ − aᵢ|², with eᵢ = Rₑ fᵢ Rₑ⁻¹, aᵢ = Rₐ fᵢ Rₐ⁻¹
  over the inertial basis fᵢ = x̂, ŷ, ẑ.

Rotation matrices act on column vectors, v' = M v, so the columns of M are the rotated basis vectors;
``from_frame(ex, ey, ez)`` builds the rotor that takes x̂, ŷ, ẑ to the given orthonormal frame.
"""

import functools

import numpy as np
from numba import guvectorize, njit

# --------------------------------------------------------------------------------------------------
# kernels on single quaternions and vectors
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def qmul(a, b):
    """Hamilton product a b (i² = j² = k² = ijk = −1)."""
    out = np.empty(4)
    out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]
    out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2]
    out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1]
    out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]
    return out


@njit(cache=True)
def qconj(q):
    """Conjugate: (w, −x, −y, −z)."""
    out = np.empty(4)
    out[0] = q[0]
    out[1] = -q[1]
    out[2] = -q[2]
    out[3] = -q[3]
    return out


@njit(cache=True)
def qnorm2(q):
    """Sum of the squares of the four components (the paper's m)."""
    return q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]


@njit(cache=True)
def qnorm(q):
    """Euclidean norm |q| = √m, without overflow or underflow for extreme components."""
    return np.hypot(np.hypot(q[0], q[1]), np.hypot(q[2], q[3]))


@njit(cache=True)
def qinv(q):
    """Inverse q⁻¹ = q̄ / m (q ≠ 0)."""
    m = qnorm2(q)
    out = np.empty(4)
    out[0] = q[0] / m
    out[1] = -q[1] / m
    out[2] = -q[2] / m
    out[3] = -q[3] / m
    return out


@njit(cache=True)
def qnormalize(q):
    """q / |q| (q ≠ 0)."""
    n = qnorm(q)
    out = np.empty(4)
    for i in range(4):
        out[i] = q[i] / n
    return out


@njit(cache=True)
def qrotate(R, v):
    """v' = R v R⁻¹ for any nonzero R (eq:rotor-rotation), as v + 2 r × (s v + r × v)/m.

    m = |R|² must be a normal float64: 1e-150 < |R| < 1e150.
    """
    out = np.empty(3)
    qrotate_into(R[0], R[1], R[2], R[3], v, out)
    return out


@njit(cache=True, inline="always")
def qrotate_into(s, rx, ry, rz, v, out):
    """out = R v R⁻¹ for R = (s, rx, ry, rz), as :func:`qrotate`, without allocating (for numba loops;
    R⁻¹ v R is (s, −rx, −ry, −rz))."""
    m = s * s + rx * rx + ry * ry + rz * rz
    # u = s v + r × v
    ux = s * v[0] + ry * v[2] - rz * v[1]
    uy = s * v[1] + rz * v[0] - rx * v[2]
    uz = s * v[2] + rx * v[1] - ry * v[0]
    c = 2.0 / m
    out[0] = v[0] + c * (ry * uz - rz * uy)
    out[1] = v[1] + c * (rz * ux - rx * uz)
    out[2] = v[2] + c * (rx * uy - ry * ux)


@njit(cache=True)
def qexp(r):
    """exp of the pure-vector quaternion r (float64[3]): cos|r| + sin|r| r/|r| (a unit rotor)."""
    theta = np.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    out = np.empty(4)
    out[0] = np.cos(theta)
    # sin(θ)/θ has no cancellation for θ > 0; below 1e-8 its Taylor series is 1 to double precision
    k = np.sin(theta) / theta if theta > 1e-8 else 1.0 - theta * theta / 6.0
    out[1] = k * r[0]
    out[2] = k * r[1]
    out[3] = k * r[2]
    return out


@njit(cache=True)
def qlog(q):
    """Generator r (float64[3]) of the normalized rotor q/|q|: q/|q| = exp(r), |r| ∈ [0, π].

    |r| = atan2(|vector part|, scalar part), accurate near 0 and π. For a vector part exactly zero and
    a negative scalar part (the rotor −1), the axis is arbitrary and (π, 0, 0) is returned.  The vector
    part's squared norm must be a normal float: |vector part| in (1e-150, 1e150) (beyond, it overflows or
    underflows and the result is wrong).
    """
    vn = np.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    out = np.zeros(3)
    if vn == 0.0:
        if q[0] < 0.0:
            out[0] = np.pi
        return out
    k = np.arctan2(vn, q[0]) / vn
    out[0] = k * q[1]
    out[1] = k * q[2]
    out[2] = k * q[3]
    return out


@njit(cache=True)
def qto_matrix(R):
    """3×3 rotation matrix M of the (possibly unnormalized) rotor R, so that M v = R v R⁻¹."""
    w, x, y, z = R[0], R[1], R[2], R[3]
    m = w * w + x * x + y * y + z * z
    c = 2.0 / m
    M = np.empty((3, 3))
    M[0, 0] = 1.0 - c * (y * y + z * z)
    M[0, 1] = c * (x * y - w * z)
    M[0, 2] = c * (x * z + w * y)
    M[1, 0] = c * (x * y + w * z)
    M[1, 1] = 1.0 - c * (x * x + z * z)
    M[1, 2] = c * (y * z - w * x)
    M[2, 0] = c * (x * z - w * y)
    M[2, 1] = c * (y * z + w * x)
    M[2, 2] = 1.0 - c * (x * x + y * y)
    return M


@njit(cache=True)
def qfrom_matrix(M):
    """Unit rotor of the rotation matrix M (w ≥ 0).

    Shepperd's method: of 4w², 4x², 4y², 4z² (each a combination of the diagonal), the largest is
    taken by a square root and the other components from off-diagonal sums, so no component is
    found by a square root of a small, cancelling number.
    """
    t = M[0, 0] + M[1, 1] + M[2, 2]
    q = np.empty(4)
    if t >= M[0, 0] and t >= M[1, 1] and t >= M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + t)
        q[0] = 0.25 * s
        q[1] = (M[2, 1] - M[1, 2]) / s
        q[2] = (M[0, 2] - M[2, 0]) / s
        q[3] = (M[1, 0] - M[0, 1]) / s
    elif M[0, 0] >= M[1, 1] and M[0, 0] >= M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + M[0, 0] - M[1, 1] - M[2, 2])
        q[0] = (M[2, 1] - M[1, 2]) / s
        q[1] = 0.25 * s
        q[2] = (M[0, 1] + M[1, 0]) / s
        q[3] = (M[0, 2] + M[2, 0]) / s
    elif M[1, 1] >= M[2, 2]:
        s = 2.0 * np.sqrt(1.0 + M[1, 1] - M[0, 0] - M[2, 2])
        q[0] = (M[0, 2] - M[2, 0]) / s
        q[1] = (M[0, 1] + M[1, 0]) / s
        q[2] = 0.25 * s
        q[3] = (M[1, 2] + M[2, 1]) / s
    else:
        s = 2.0 * np.sqrt(1.0 + M[2, 2] - M[0, 0] - M[1, 1])
        q[0] = (M[1, 0] - M[0, 1]) / s
        q[1] = (M[0, 2] + M[2, 0]) / s
        q[2] = (M[1, 2] + M[2, 1]) / s
        q[3] = 0.25 * s
    if q[0] < 0.0:
        for i in range(4):
            q[i] = -q[i]
    n = qnorm(q)
    for i in range(4):
        q[i] /= n
    return q


@njit(cache=True)
def qframe_error(Ra, Re):
    """Frame error norm δ = √Σᵢ |eᵢ − aᵢ|² (eq:error_norm) between rotors Ra and Re of any norm in (1e-150, 1e150)
    (:func:`qrotate`'s range: beyond it the squared norm is not a normal float and the result is not finite)."""
    total = 0.0
    f = np.zeros(3)
    for i in range(3):
        f[:] = 0.0
        f[i] = 1.0
        a = qrotate(Ra, f)
        e = qrotate(Re, f)
        for j in range(3):
            d = e[j] - a[j]
            total += d * d
    return np.sqrt(total)


# --------------------------------------------------------------------------------------------------
# array functions: gufuncs over the last axis, broadcasting like numpy
# --------------------------------------------------------------------------------------------------

_Q2 = ["void(float64[:], float64[:], float64[:])"]


@njit(cache=True)
def _check(x, n):
    """A ValueError unless x, a gufunc's quaternion or vector, has n components (its kernel would read past it)."""
    if x.shape[0] != n:
        raise ValueError("quaternion arrays need 4 components on their last axis, vectors and matrices 3")


@njit(cache=True)
def _put(r, out):
    """out[:] = r, element by element (the inputs checked, numpy checks the lengths of ``out``): ``out[:] = r`` would
    compile numba's shape-mismatch error path with its string formatting, 2.7 s of the first cold ``modes()``
    (numba's compile events; README, "Fresh machine")."""
    for k in range(out.shape[0]):
        out[k] = r[k]


def _gufunc(signatures, layout):
    """``guvectorize(signatures, layout, cache=True)``, built on the first call rather than at import: numba
    compiles (or loads from its cache) a gufunc with explicit signatures when it is decorated, and the
    twelve here would be compiled or loaded by every process that imports this module, where the PN runs need
    only the kernels above."""
    def wrap(kernel):
        built = None

        @functools.wraps(kernel)
        def call(*args, **kwargs):
            nonlocal built
            if built is None:
                built = guvectorize(signatures, layout, cache=True)(kernel)
            return built(*args, **kwargs)
        return call
    return wrap


@_gufunc(_Q2, "(n),(n)->(n)")
def multiply(a, b, out):
    """Hamilton product a b of quaternion arrays (..., 4)."""
    _check(a, 4)
    _check(b, 4)
    _put(qmul(a, b), out)


@_gufunc(["void(float64[:], float64[:])"], "(n)->(n)")
def conjugate(q, out):
    """Conjugate of quaternion arrays (..., 4)."""
    _check(q, 4)
    _put(qconj(q), out)


@_gufunc(["void(float64[:], float64[:])"], "(n)->(n)")
def inverse(q, out):
    """Inverse q̄/|q|² of quaternion arrays (..., 4)."""
    _check(q, 4)
    _put(qinv(q), out)


@_gufunc(["void(float64[:], float64[:])"], "(n)->()")
def norm(q, out):
    """Euclidean norm of quaternion arrays (..., 4) → (...)."""
    _check(q, 4)
    out[0] = qnorm(q)


@_gufunc(["void(float64[:], float64[:])"], "(n)->(n)")
def normalize(q, out):
    """q/|q| for quaternion arrays (..., 4)."""
    _check(q, 4)
    _put(qnormalize(q), out)


@_gufunc(["void(float64[:], float64[:], float64[:])"], "(n),(m)->(m)")
def rotate(R, v, out):
    """R v R⁻¹ for rotors (..., 4) of any norm in (1e-150, 1e150) (:func:`qrotate`) and vectors (..., 3)
    (eq:rotor-rotation)."""
    _check(R, 4)
    _check(v, 3)
    _put(qrotate(R, v), out)


@_gufunc(["void(float64[:], float64[:], float64[:])"], "(m),(n)->(n)")
def _exp(r, dummy, out):
    _check(r, 3)
    _put(qexp(r), out)


def exp(r):
    """exp of pure-vector quaternions given as vectors (..., 3) → unit rotors (..., 4)."""
    return _exp(np.asarray(r, dtype=np.float64), np.empty(4))


@_gufunc(["void(float64[:], float64[:], float64[:])"], "(n),(m)->(m)")
def _log(q, dummy, out):
    _check(q, 4)
    _put(qlog(q), out)


def log(q):
    """Generators (..., 3) of the normalized rotors q/|q| (..., 4), with |r| ∈ [0, π], for norms in (1e-150, 1e150)
    (:func:`qlog`)."""
    return _log(np.asarray(q, dtype=np.float64), np.empty(3))


@_gufunc(["void(float64[:], float64[:,:], float64[:,:])"], "(n),(m,m)->(m,m)")
def _to_matrix(R, dummy, out):
    _check(R, 4)
    m = qto_matrix(R)
    for i in range(3):
        _put(m[i], out[i])


def to_matrix(R):
    """Rotation matrices (..., 3, 3) of rotors (..., 4) of any norm in (1e-150, 1e150) (the squared norm must be a
    normal float)."""
    return _to_matrix(np.asarray(R, dtype=np.float64), np.empty((3, 3)))


@_gufunc(["void(float64[:,:], float64[:], float64[:])"], "(m,m),(n)->(n)")
def _from_matrix(M, dummy, out):
    _check(M, 3)
    _check(M[0], 3)
    _put(qfrom_matrix(M), out)


def from_matrix(M):
    """Unit rotors (..., 4), scalar part ≥ 0, of rotation matrices (..., 3, 3)."""
    return _from_matrix(np.asarray(M, dtype=np.float64), np.empty(4))


def from_frame(ex, ey, ez):
    """Unit rotor R with R x̂ R⁻¹ = ex, R ŷ R⁻¹ = ey, R ẑ R⁻¹ = ez, for a right-handed orthonormal frame.

    The frame vectors may be arrays (..., 3). They are checked to be orthonormal and right-handed to
    1e-8; for a frame with small errors the nearest rotation is found through the polar decomposition
    (an SVD), so the result is the best rotation in the Frobenius norm.
    """
    M = np.stack(np.broadcast_arrays(*(np.asarray(e, dtype=np.float64) for e in (ex, ey, ez))), axis=-1)
    err = np.abs(np.swapaxes(M, -1, -2) @ M - np.eye(3)).max(initial=0.0)
    if not np.isfinite(err) or err > 1e-8 or np.any(np.linalg.det(M) <= 0):
        raise ValueError(
            "from_frame: ex, ey, ez must be orthonormal to 1e-8 and right-handed (ex × ey = ez); "
            f"largest deviation of the Gram matrix from the identity is {err:.3g}"
        )
    U, _, Vt = np.linalg.svd(M)
    return from_matrix(U @ Vt)


@njit(cache=True)
def _unflip(R):
    out = R.copy()
    for i in range(1, out.shape[0]):
        d = 0.0
        for j in range(4):
            d += out[i, j] * out[i - 1, j]
        if d < 0.0:
            for j in range(4):
                out[i, j] = -out[i, j]
    return out


def unflip(R):
    """Sign-continuous copy of a time series of rotors (N, 4): R[i] → −R[i] where R[i]·R[i−1] < 0.

    R and −R are the same rotation; this picks, step by step, the sign closer to the previous rotor.
    """
    R = np.ascontiguousarray(R, dtype=np.float64)
    if R.ndim != 2 or R.shape[1] != 4:
        raise ValueError(f"unflip: R must have shape (N, 4), got {R.shape}")
    return _unflip(R)


@_gufunc(["void(float64[:], float64[:], float64[:])"], "(n),(n)->()")
def frame_error(Ra, Re, out):
    """δ of eq:error_norm between rotor arrays (..., 4) and (..., 4) → (...)."""
    _check(Ra, 4)
    _check(Re, 4)
    out[0] = qframe_error(Ra, Re)
