r"""Boundary between physical units and the geometric units of the PN system; frames and validation.

* Masses in solar masses (floats) or astropy mass Quantities; frequencies in Hz (floats) or astropy
  frequency Quantities; times returned in seconds and in units of M.
* G M☉/c³ in seconds: astropy's IAU 2015 nominal GM☉ over c³, written out (importing astropy to compute it
  took 0.3 s of every process); tests check it equals astropy's value, and LALSuite's ``LAL_MTSUN_SI`` to
  its last bit (LAL rounds it 1 ulp lower).
* f is the *gravitational-wave* frequency, twice the orbital one: v = (π M f)^{1/3}.
* The initial frame: ℓ̂ (orbital angular momentum direction) and n̂ (separation direction, from body
  2 to body 1 as in LALSuite's E1); the rotor R₀ takes (x̂, ŷ, ẑ) to (n̂, λ̂ = ℓ̂ × n̂, ℓ̂).

Astropy Quantities are recognized only when the caller has imported astropy; pnrotor never imports it
on this path, and never in the numba code.
"""

import math

import numpy as np

from pnrotor.values import BOOLS as _BOOLS, positive as _positive
MTSUN_SI = 4.9254909476412675e-06
"""G M☉ / c³ in seconds (IAU 2015 nominal GM☉ = 1.3271244e20 m³/s², c = 299792458 m/s)."""


def solar_masses(m, name="mass"):
    """A mass in M☉ from a float (already M☉) or an astropy Quantity; must be finite and > 0."""
    return _positive(m, "M_sun", name, "mass")


def hertz(f, name="frequency", allow_none=False):
    """A frequency in Hz from a float or an astropy Quantity; must be finite and > 0."""
    if f is None:
        if allow_none:
            return None
        raise ValueError(f"{name} is required")
    return _positive(f, "Hz", name, "frequency in Hz")


def seconds(dt, name="time step"):
    """A time in seconds from a float or an astropy Quantity; must be finite and > 0."""
    return _positive(dt, "s", name, "time in seconds")


def total_mass_seconds(m1, m2):
    """G(m₁ + m₂)/c³ in seconds, masses in M☉."""
    return (m1 + m2) * MTSUN_SI


def v_from_frequency(f_gw, M_sec):
    """v = (π M f_GW)^{1/3} (f_GW = 2 f_orb)."""
    return (math.pi * M_sec * f_gw) ** (1.0 / 3.0)


def frequency_from_v(v, M_sec):
    """f_GW = v³/(π M)."""
    return np.asarray(v) ** 3 / (math.pi * M_sec)


def newtonian_time_to_coalescence(v, nu):
    """τ(v) = 5/(256 ν v⁸) in units of M: the leading-order time from v to coalescence."""
    return 5.0 / (256.0 * nu * v ** 8)


def elementwise(f, *arrays):
    """f of Python floats applied to the elements of equal-length 1-d arrays → float64 array: for a population, the
    numbers of one binary's call bitwise (numpy's ``**`` is not libm's pow on every CPU: SIMD versions on some)."""
    return np.array([f(*x) for x in zip(*(a.tolist() for a in arrays))], dtype=np.float64)


def _vec3(a, name):
    """Three finite floats from a 3-vector (plain Python floats: cheaper than numpy for three numbers)."""
    try:
        x, y, z = a
        if isinstance(x, _BOOLS) or isinstance(y, _BOOLS) or isinstance(z, _BOOLS):
            raise TypeError
        x, y, z = float(x), float(y), float(z)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a 3-vector of finite numbers, got {a!r}") from None
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        raise ValueError(f"{name} must be finite, got {a!r}")
    return x, y, z


def _one_dimensional(a):
    """Whether a is a tuple, a list (their items are checked by float()) or any 1-D array_like; np.ndim alone
    costs ~1 µs on a tuple, a twentieth of the input checks of a run."""
    return isinstance(a, (tuple, list)) or np.ndim(a) == 1


def spin_vector(chi, name):
    """A dimensionless spin 3-vector, finite with |χ| ≤ 1."""
    if not _one_dimensional(chi):
        raise ValueError(f"{name} must be a 3-vector, got shape {np.shape(chi)}")
    x, y, z = _vec3(chi, name)
    m2 = x * x + y * y + z * z
    if m2 > 1.0 + 1e-14:
        raise ValueError(f"|{name}| = {math.sqrt(m2)!r} exceeds 1")
    return np.array([x, y, z])


FRAME_TOL = 1e-8
"""How far from unit length and from orthogonal ℓ̂ and n̂ may be (:func:`orthonormal_frame`)."""


def orthonormal_frame(ell_hat, n_hat, tol=FRAME_TOL):
    """(ℓ̂, n̂) checked to be unit and orthogonal within ``tol`` and then made exactly so."""
    vecs = []
    for name, a in (("ell_hat", ell_hat), ("n_hat", n_hat)):
        if not _one_dimensional(a):
            raise ValueError(f"{name} must be a finite 3-vector, got {a!r}")
        x, y, z = _vec3(a, name)
        norm = math.sqrt(x * x + y * y + z * z)
        if abs(norm - 1.0) > tol:
            raise ValueError(f"{name} must be a unit vector (|{name}| = {norm!r})")
        vecs.append((x / norm, y / norm, z / norm))
    (lx, ly, lz), (nx, ny, nz) = vecs
    dot = lx * nx + ly * ny + lz * nz
    if abs(dot) > tol:
        raise ValueError(f"n_hat must be orthogonal to ell_hat (n̂·ℓ̂ = {dot!r})")
    nx, ny, nz = nx - dot * lx, ny - dot * ly, nz - dot * lz
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    return np.array([lx, ly, lz]), np.array([nx / norm, ny / norm, nz / norm])


def frame_rotor(ell, n):
    """Unit rotor R₀ with R₀ x̂ R₀⁻¹ = n̂, R₀ ẑ R₀⁻¹ = ℓ̂ (and ŷ → λ̂ = ℓ̂ × n̂)."""
    from ..quaternion import qfrom_matrix
    lam = (ell[1] * n[2] - ell[2] * n[1], ell[2] * n[0] - ell[0] * n[2], ell[0] * n[1] - ell[1] * n[0])
    M = np.array([[n[0], lam[0], ell[0]], [n[1], lam[1], ell[1]], [n[2], lam[2], ell[2]]])
    # the kernel's own Python: once per frame (settings caches it), and no 0.5 s compile on a cold cache
    return qfrom_matrix.py_func(M)
