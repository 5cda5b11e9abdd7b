"""Wigner D matrices straight from rotors, and rotating modes from one frame to another.

A waveform given in a frame rotated by the rotor R (its modes H_ℓm, e.g. the co-orbital frame with
ẑ = ℓ̂, x̂ = n̂, where R is pnrotor's orbital-frame rotor) has, in the fixed frame, the modes

    h_ℓm = Σ_m' 𝔇^ℓ_{m m'}(R) H_ℓm',     𝔇^ℓ_{m m'}(R) = e^{−imα} d^ℓ_{m m'}(β) e^{−im'γ},

the standard Wigner matrices of R = exp(α ẑ/2) exp(β ŷ/2) exp(γ ẑ/2) (Wigner's d; e.g. Boyle et al.
2013, arXiv:1302.2919, Sec. II and Boyle 2016, arXiv:1604.08139; Goldberg et al. 1967).  For R = exp(Φ ẑ/2),
h_ℓm = H_ℓm e^{−imΦ}: a nonprecessing binary's inertial modes are its co-orbital amplitudes times
e^{−imΦ}.

No Euler angles are formed: with the unit rotor R = (w, x, y, z),

    R_a = w + i z = cos(β/2) e^{i(α+γ)/2},     R_b = y − i x = sin(β/2) e^{i(α−γ)/2},

so cos(β/2) = |R_a|, sin(β/2) = |R_b|, e^{−iα} = conj(R̂_a R̂_b) and e^{−iγ} = conj(R̂_a) R̂_b with
R̂ = R/|R|.  Where |R_a| or |R_b| vanishes (ℓ̂ = −ẑ or ℓ̂ = ẑ) its phase is multiplied only by terms
that vanish there or by a zero power, so any unit value serves and the matrices stay exact through the
poles.  The small-d matrix is Wigner's finite sum

    d^ℓ_{m m'}(β) = Σ_s (−1)^{m−m'+s} √[(ℓ+m)!(ℓ−m)!(ℓ+m')!(ℓ−m')!] / [(ℓ+m'−s)! s! (m−m'+s)! (ℓ−m−s)!]
                    × cos(β/2)^{2ℓ+m'−m−2s} sin(β/2)^{m−m'+2s},

whose coefficients are tabulated once per ℓ_max (:func:`d_table`), for the elements with m ≥ |m'| only:
the others follow from d^ℓ_{m m'} = d^ℓ_{−m',−m} = (−1)^{m−m'} d^ℓ_{m' m}, which cuts the work per sample
about fourfold (ℓ ≤ 4: 99 terms instead of 284).  The powers of |R_a|, |R_b| are formed once per sample.
Rotors need not be normalized (v' = R v R⁻¹ does not see |R|).
"""

from functools import lru_cache
from math import factorial, sqrt

import numpy as np
from numba import njit

from pnrotor.waveform.layout import mode_index, n_modes

__all__ = ["d_table", "wigner_D", "rotate_modes", "rotate_about_z"]

_TINY = 1e-300


def _symmetric_partner(m, mp):
    """(m₀, m₀', sign) with m₀ ≥ |m₀'| and d^ℓ_{m m'} = sign · d^ℓ_{m₀ m₀'}."""
    if m >= abs(mp):
        return m, mp, 1
    if -mp >= abs(m):
        return -mp, -m, 1
    if mp >= abs(m):
        return mp, m, (-1) ** (m - mp)
    return -m, -mp, (-1) ** (m - mp)


@lru_cache(maxsize=None)
def d_table(ell_max):
    """Wigner's sum, tabulated for ℓ = 2 … ell_max (module docstring).

    Returns ``(start, coef, pa, pb, index, sign)``: the distinct elements (ℓ, m, m') with m ≥ |m'| are
    numbered p = 0, 1, …, and the terms of element p are ``start[p] : start[p+1]``, term j being
    coef[j] |R_a|^pa[j] |R_b|^pb[j]; element k of the full matrices, in the order ℓ, then m, then m'
    (each from −ℓ to ℓ), is ``sign[k] * d[index[k]]``.
    """
    start, coef, pa, pb, distinct = [0], [], [], [], {}
    for ell in range(2, ell_max + 1):
        for m in range(-ell, ell + 1):
            for mp in range(-m, m + 1):
                distinct[ell, m, mp] = len(start) - 1
                norm = sqrt(factorial(ell + m) * factorial(ell - m) * factorial(ell + mp) * factorial(ell - mp))
                for s in range(max(0, mp - m), min(ell + mp, ell - m) + 1):
                    coef.append((-1) ** (m - mp + s) * norm / (factorial(ell + mp - s) * factorial(s)
                                                               * factorial(m - mp + s) * factorial(ell - m - s)))
                    pa.append(2 * ell + mp - m - 2 * s)
                    pb.append(m - mp + 2 * s)
                start.append(len(coef))
    index, sign = [], []
    for ell in range(2, ell_max + 1):
        for m in range(-ell, ell + 1):
            for mp in range(-ell, ell + 1):
                m0, mp0, sg = _symmetric_partner(m, mp)
                index.append(distinct[ell, m0, mp0])
                sign.append(sg)
    return (np.array(start, dtype=np.int64), np.array(coef), np.array(pa, dtype=np.int64),
            np.array(pb, dtype=np.int64), np.array(index, dtype=np.int64), np.array(sign, dtype=np.float64))


@njit(cache=True)
def _setup(R, ell_max, start, coef, pa, pb, apow, bpow, d):
    """The distinct d elements of the unit R into d; returns e^{−iα}, e^{−iγ}."""
    w, x, y, z = R[0], R[1], R[2], R[3]
    n = np.sqrt(w * w + x * x + y * y + z * z)
    ra = complex(w / n, z / n)
    rb = complex(y / n, -x / n)
    a, b = abs(ra), abs(rb)
    ua = ra / a if a > _TINY else 1.0 + 0.0j
    ub = rb / b if b > _TINY else 1.0 + 0.0j
    apow[0] = 1.0
    bpow[0] = 1.0
    for k in range(1, 2 * ell_max + 1):
        apow[k] = apow[k - 1] * a
        bpow[k] = bpow[k - 1] * b
    for p in range(start.size - 1):
        s = 0.0
        for j in range(start[p], start[p + 1]):
            s += coef[j] * apow[pa[j]] * bpow[pb[j]]
        d[p] = s
    return (ua * ub).conjugate(), ua.conjugate() * ub


@njit(cache=True)
def _unit_powers(u, ell, out):
    """out[ℓ + m] = u^m for m = −ℓ … ℓ (|u| = 1)."""
    out[ell] = 1.0
    for m in range(1, ell + 1):
        out[ell + m] = out[ell + m - 1] * u
        out[ell - m] = out[ell - m + 1] * u.conjugate()


@njit(cache=True)
def _rotate(H, R, ell_max, start, coef, pa, pb, index, sign, h, D):
    """h[i] = 𝔇(R[i]) H[i] (arrays (N, n_modes): a sample's modes contiguous) if H has rows, else
    (H.shape[0] == 0) the matrices into D[i]."""
    apow = np.empty(2 * ell_max + 1)
    bpow = np.empty(2 * ell_max + 1)
    ealpha = np.empty(2 * ell_max + 1, dtype=np.complex128)
    egamma = np.empty(2 * ell_max + 1, dtype=np.complex128)
    G = np.empty(2 * ell_max + 1, dtype=np.complex128)
    d = np.empty(start.size - 1)
    matrices = H.shape[0] == 0
    for i in range(R.shape[0]):
        e_a, e_g = _setup(R[i], ell_max, start, coef, pa, pb, apow, bpow, d)
        k = 0
        for ell in range(2, ell_max + 1):
            _unit_powers(e_a, ell, ealpha)
            _unit_powers(e_g, ell, egamma)
            first = mode_index(ell, -ell)
            if matrices:
                for m in range(2 * ell + 1):
                    for mp in range(2 * ell + 1):
                        D[i, first + m, first + mp] = ealpha[m] * (sign[k] * d[index[k]]) * egamma[mp]
                        k += 1
                continue
            for mp in range(2 * ell + 1):
                G[mp] = egamma[mp] * H[i, first + mp]
            for m in range(2 * ell + 1):
                re = 0.0
                im = 0.0
                for mp in range(2 * ell + 1):
                    dk = sign[k] * d[index[k]]
                    re += dk * G[mp].real
                    im += dk * G[mp].imag
                    k += 1
                h[i, first + m] = ealpha[m] * complex(re, im)


def wigner_D(R, ell_max):
    """𝔇^ℓ_{m m'}(R) for rotors R (..., 4): array (..., n, n), n = (ell_max+1)² − 4, zero between
    different ℓ; rows m and columns m' in :func:`pnrotor.waveform.layout.mode_index` order."""
    R = np.asarray(R, dtype=np.float64)
    flat = np.ascontiguousarray(R.reshape(-1, 4))
    n = n_modes(ell_max)
    D = np.zeros((flat.shape[0], n, n), dtype=np.complex128)
    empty = np.empty((0, 0), dtype=np.complex128)
    _rotate(empty, flat, int(ell_max), *d_table(int(ell_max)), empty, D)
    return D.reshape(R.shape[:-1] + (n, n))


def rotate_modes(H, R, ell_max):
    """Modes h_ℓm = Σ_m' 𝔇^ℓ_{m m'}(R) H_ℓm' (n_modes, N) of modes H (n_modes, N) given in the frame of
    the rotors R (N, 4), for ℓ = 2 … ell_max in :func:`pnrotor.waveform.layout.mode_index` order.  The
    result is the transpose of an (N, n_modes) array, each sample's modes contiguous (measured ~0.74 µs
    per sample for ℓ ≤ 4 against 0.84 writing the rows; 3.2 µs for ℓ ≤ 8)."""
    H = np.asarray(H)
    R = np.ascontiguousarray(R, dtype=np.float64)
    if H.ndim != 2 or R.shape != (H.shape[1], 4) or H.shape[0] != n_modes(ell_max):
        raise ValueError(f"rotate_modes: H must be ((ell_max+1)^2 - 4, N) = ({n_modes(ell_max)}, N) and "
                         f"R (N, 4); got H {H.shape}, R {R.shape}")
    HT = np.ascontiguousarray(H.T, dtype=np.complex128)   # no copy for the transposed views we return
    hT = np.empty_like(HT)
    _rotate(HT, R, int(ell_max), *d_table(int(ell_max)), hT, np.empty((0, 0, 0), dtype=np.complex128))
    return hT.T


@njit(cache=True)
def _about_z(H, Phi, ell_max, h):
    powers = np.empty(ell_max + 1, dtype=np.complex128)
    for i in range(H.shape[0]):
        u = complex(np.cos(Phi[i]), -np.sin(Phi[i]))
        powers[0] = 1.0
        for m in range(1, ell_max + 1):
            powers[m] = powers[m - 1] * u
        for ell in range(2, ell_max + 1):
            for m in range(-ell, ell + 1):
                k = mode_index(ell, m)
                h[i, k] = H[i, k] * (powers[m] if m >= 0 else powers[-m].conjugate())


def rotate_about_z(H, Phi, ell_max):
    """rotate_modes for the rotors exp(Φ ẑ/2): h_ℓm = H_ℓm e^{−imΦ} (n_modes, N), Φ (N,) — the whole
    rotation of a nonprecessing binary in its own frame, at a fraction of the general cost.  Like
    rotate_modes it returns the transpose of an (N, n_modes) array: each sample's modes contiguous."""
    HT = np.ascontiguousarray(np.asarray(H).T, dtype=np.complex128)
    hT = np.empty_like(HT)
    _about_z(HT, np.ascontiguousarray(Phi, dtype=np.float64), int(ell_max), hT)
    return hT.T
