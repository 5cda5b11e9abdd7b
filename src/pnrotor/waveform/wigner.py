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
about fourfold (ℓ ≤ 4: 99 terms instead of 284).  Rotors need not be normalized (v' = R v R⁻¹ does not see
|R|).

Layout of the computation: the modes are (n_modes, N) arrays, each mode's samples contiguous, and the
samples are taken in blocks of ``_CHUNK``; within a block every loop runs over the samples innermost, each in
a small function of its own (LLVM vectorizes them there, not inline), so each is plain contiguous real
arithmetic.  Per block :func:`_rotor_block` forms |R̂_a|^k, |R̂_b|^k and e^{−imα}, e^{−imγ} by recurrences
in k and m; then per ℓ :func:`_rotate_ell` forms the monomials |R̂_a|^{2ℓ−j} |R̂_b|^j, the d elements (two
terms of their Wigner sums a pass) and the sums over m' of G_m' = e^{−im'γ} H_ℓm', rows m and −m together
from the same two elements d_{m,±m'}, since d^ℓ_{−m,∓m'} = (−1)^{m+m'} d^ℓ_{m,±m'}:

    h_m  ∝ Σ_{m'≥1} d_{m,m'} G_m' + d_{m,−m'} G_−m',    h_−m ∝ Σ_{m'≥1} (−1)^{m+m'} (d_{m,−m'} G_m' + d_{m,m'} G_−m')

(plus the m' = 0 column), which halves the loads of d; the caller applies e^{−im'γ} before and e^{−imα} as it
stores h (:func:`_store`).  Columns m' whose H_ℓm' vanish identically can be skipped, with the elements only
they use.  :func:`rotate_modes` (:func:`_rotate`) reads H from an array, and :func:`wigner_D` is it applied
to the columns of the identity; :func:`pnrotor.waveform.amplitudes.modes_in_frame` forms H block by block
in the same pass instead, with its phases e^{−im'γ} (no H array, no pass of its own for either phase).
Measured for 25,220 samples of a precessing run (one shared core): :func:`rotate_modes` ~0.18 µs per sample
for ℓ ≤ 4 and ~0.8 µs for ℓ ≤ 8, against 0.6 and 3.0 µs for the former per-sample version; at ℓ ≤ 8 much of
what remains is memory traffic of the d elements, G and h.
"""

from functools import lru_cache
from math import factorial, sqrt

import numpy as np
from numba import njit

from pnrotor.waveform.layout import mode_index, n_modes

__all__ = ["d_table", "wigner_D", "rotate_modes"]

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


_CHUNK = 256
"""Samples per block of :func:`_rotate` and of :func:`pnrotor.waveform.amplitudes._sum` (measured 64 … 1024:
256 the fastest, the d elements being formed one ℓ at a time)."""


# The kernels' innermost loops, one per function over the samples s of a block (row views of the
# block arrays).  Written inline they measured no faster (LLVM left most of them scalar there).

@njit(cache=True, fastmath={"contract"})
def _two_terms(d, c1, x1, c2, x2, add, nb):
    """d = c1 x1 + c2 x2, or d += it if ``add``."""
    if add:
        for s in range(nb):
            d[s] += c1 * x1[s] + c2 * x2[s]
    else:
        for s in range(nb):
            d[s] = c1 * x1[s] + c2 * x2[s]


@njit(cache=True, fastmath={"contract"})
def _times_phase(x_re, x_im, e_re, e_im, conj, out_re, out_im, nb):
    """out = e x (e* x if conj), complex numbers as (re, im) rows; out may be x."""
    sg = -1.0 if conj else 1.0
    for s in range(nb):
        er, ei, xr, xi = e_re[s], sg * e_im[s], x_re[s], x_im[s]
        out_re[s] = er * xr - ei * xi
        out_im[s] = er * xi + ei * xr


@njit(cache=True, fastmath={"contract"})
def _store(x_re, x_im, e_re, e_im, conj, out, nb):
    """out[2s], out[2s + 1] = the real and imaginary parts of e x (e* x if conj): complex numbers as (re, im)
    rows into a float view of a complex row."""
    sg = -1.0 if conj else 1.0
    for s in range(nb):
        er, ei, xr, xi = e_re[s], sg * e_im[s], x_re[s], x_im[s]
        out[2 * s] = er * xr - ei * xi
        out[2 * s + 1] = er * xi + ei * xr


@njit(cache=True)
def _phase_powers(e_re, e_im, nb):
    """Rows m = 2, 3, … of e^m from rows 0 (= 1) and 1 (= e)."""
    for m in range(2, e_re.shape[0]):
        _times_phase(e_re[m - 1], e_im[m - 1], e_re[1], e_im[1], False, e_re[m], e_im[m], nb)


@njit(cache=True, fastmath={"contract"})
def _add_quad(d1, d2, s1, s2, sig, g_re, g_im, gn_re, gn_im, h_re, h_im, hn_re, hn_im, nb):
    """h += s1 d1 g + s2 d2 gn and hn += sig (s2 d2 g + s1 d1 gn): rows m, −m from columns m', −m'."""
    for s in range(nb):
        a, b = s1 * d1[s], s2 * d2[s]
        h_re[s] += a * g_re[s] + b * gn_re[s]
        h_im[s] += a * g_im[s] + b * gn_im[s]
        hn_re[s] += sig * (b * g_re[s] + a * gn_re[s])
        hn_im[s] += sig * (b * g_im[s] + a * gn_im[s])


@njit(cache=True, fastmath={"contract"})
def _rotor_block(R, i0, nb, apow, bpow, ea_re, ea_im, eg_re, eg_im):
    """Of the rotors R[i0 : i0 + nb]: |R̂_a|^k, |R̂_b|^k (rows k) and e^{−imα}, e^{−imγ} (rows m)."""
    for s in range(nb):
        w, x, y, z = R[i0 + s, 0], R[i0 + s, 1], R[i0 + s, 2], R[i0 + s, 3]
        a2, b2 = w * w + z * z, x * x + y * y
        n = np.sqrt(a2 + b2)
        a, b = np.sqrt(a2), np.sqrt(b2)
        apow[0, s], bpow[0, s] = 1.0, 1.0
        apow[1, s], bpow[1, s] = a / n, b / n
        aw, az = (w / a, z / a) if a > _TINY else (1.0, 0.0)   # R̂_a = aw + i az
        by, bx = (y / b, -x / b) if b > _TINY else (1.0, 0.0)  # R̂_b = by + i bx
        ea_re[0, s], ea_im[0, s] = 1.0, 0.0
        eg_re[0, s], eg_im[0, s] = 1.0, 0.0
        ea_re[1, s], ea_im[1, s] = aw * by - az * bx, -(aw * bx + az * by)
        eg_re[1, s], eg_im[1, s] = aw * by + az * bx, aw * bx - az * by
    for k in range(2, apow.shape[0]):
        for s in range(nb):
            apow[k, s] = apow[k - 1, s] * apow[1, s]
            bpow[k, s] = bpow[k - 1, s] * bpow[1, s]
    _phase_powers(ea_re, ea_im, nb)
    _phase_powers(eg_re, eg_im, nb)


@njit(cache=True, fastmath={"contract"})
def _rotate_ell(ell, p0, k0, columns, needed, start, coef, pb, index, sign, apow, bpow, mono, d, G_re, G_im, h_re,
                h_im, nb):
    """Rows ℓ + m of (h_re, h_im) = Σ_m' d^ℓ_{m m'} G_m' for G_m' = e^{−im'γ} H_ℓm' in rows ℓ + m' of (G_re, G_im):
    h_ℓm before its factor e^{−imα} (:func:`_store`), for a block whose |R̂_a|^k, |R̂_b|^k :func:`_rotor_block`
    gave.  p0, k0: ℓ's first distinct element and first element of the full matrices in :func:`d_table`'s
    numbering; columns[m'] false for the |m'| where H_ℓm' vanishes (their terms are skipped), needed[p] false
    for the elements no other column uses."""
    width = 2 * ell + 1
    for j in range(width):   # the monomials |R_a|^{2ℓ−j} |R_b|^j of ℓ's terms
        for s in range(nb):
            mono[j, s] = apow[2 * ell - j, s] * bpow[j, s]
    # ℓ's distinct d elements (m ≥ |m'|): Wigner's sum, two terms a pass
    for p in range(p0, p0 + (ell + 1) ** 2):
        if needed[p]:
            lo, hi = start[p], start[p + 1]
            for j in range(lo, hi, 2):
                j2 = min(j + 1, hi - 1)
                _two_terms(d[p - p0], coef[j], mono[pb[j]], coef[j2] if j2 > j else 0.0, mono[pb[j2]], j > lo, nb)
    # rows m, −m together from d_{m,±m'} (d_{−m,∓m'} = (−1)^{m+m'} d_{m,±m'}); for m' = 0 the second element
    # is the first with weight 0, and for m = 0 row −m is the spare row 2ℓ_max + 1
    for m in range(ell + 1):
        r, rn = ell + m, ell - m if m > 0 else h_re.shape[0] - 1
        for s in range(nb):
            h_re[r, s] = h_im[r, s] = 0.0
            h_re[rn, s] = h_im[rn, s] = 0.0
        row = k0 + r * width
        for mp in range(ell + 1):
            if columns[mp]:
                c, cn = ell + mp, ell - mp
                _add_quad(d[index[row + c] - p0], d[index[row + cn] - p0], sign[row + c],
                          sign[row + cn] if mp > 0 else 0.0, 1.0 - 2.0 * ((m + mp) % 2), G_re[c], G_im[c], G_re[cn],
                          G_im[cn], h_re[r], h_im[r], h_re[rn], h_im[rn], nb)


@njit(cache=True)
def _rotation_scratch(ell_max, B):
    """The block arrays of :func:`_rotor_block` and :func:`_rotate_ell`: apow, bpow, mono, ea_re, ea_im, eg_re,
    eg_im, d, h_re, h_im (h with a spare row)."""
    n_pow, n_m = 2 * ell_max + 1, ell_max + 1
    return (np.empty((n_pow, B)), np.empty((n_pow, B)), np.empty((n_pow, B)), np.empty((n_m, B)), np.empty((n_m, B)),
            np.empty((n_m, B)), np.empty((n_m, B)), np.empty((n_m * n_m, B)), np.empty((n_pow + 1, B)),
            np.empty((n_pow + 1, B)))


@njit(cache=True)
def _rotate(H, R, ell_max, columns, needed, start, coef, pb, index, sign, h):
    """h[:, i] = 𝔇(R[i]) H[:, i] for (n_modes, N) arrays (h as a float view, (n_modes, 2N)), a block of _CHUNK
    samples at a time; every inner loop runs over the samples of the block (module docstring)."""
    B = _CHUNK
    apow, bpow, mono, ea_re, ea_im, eg_re, eg_im, d, h_re, h_im = _rotation_scratch(ell_max, B)
    G_re, G_im = np.empty((2 * ell_max + 1, B)), np.empty((2 * ell_max + 1, B))
    for i0 in range(0, R.shape[0], B):
        nb = min(B, R.shape[0] - i0)
        _rotor_block(R, i0, nb, apow, bpow, ea_re, ea_im, eg_re, eg_im)
        p0 = k0 = 0
        for ell in range(2, ell_max + 1):
            first = mode_index(ell, -ell)
            for r in range(2 * ell + 1):
                for s in range(nb):
                    G_re[r, s] = H[first + r, i0 + s].real
                    G_im[r, s] = H[first + r, i0 + s].imag
                u = abs(r - ell)
                _times_phase(G_re[r], G_im[r], eg_re[u], eg_im[u], r < ell, G_re[r], G_im[r], nb)
            _rotate_ell(ell, p0, k0, columns[ell], needed, start, coef, pb, index, sign, apow, bpow, mono, d, G_re,
                        G_im, h_re, h_im, nb)
            for r in range(2 * ell + 1):
                _store(h_re[r], h_im[r], ea_re[abs(r - ell)], ea_im[abs(r - ell)], r < ell, h[first + r, 2 * i0:], nb)
            p0 += (ell + 1) ** 2
            k0 += (2 * ell + 1) ** 2


def _needed_elements(columns, ell_max):
    """needed[p] of :func:`_rotate_ell`: the distinct elements some column m' with columns[ℓ, |m'|] uses."""
    index = d_table(ell_max)[4]
    return np.bincount(index, weights=columns[_element_columns(ell_max)], minlength=index.max() + 1) > 0


@lru_cache(maxsize=None)
def _element_columns(ell_max):
    """(ℓ, |m'|) of the full matrices' elements, in the order of :func:`d_table`'s index."""
    return tuple(np.array([(ell, abs(mp)) for ell in range(2, ell_max + 1) for _ in range(2 * ell + 1)
                           for mp in range(-ell, ell + 1)]).T)


def wigner_D(R, ell_max):
    """𝔇^ℓ_{m m'}(R) for rotors R (..., 4): array (..., n, n), n = (ell_max+1)² − 4, zero between
    different ℓ; rows m and columns m' in :func:`pnrotor.waveform.layout.mode_index` order.  Column m' is
    the rotation of the unit mode m' (:func:`rotate_modes` of the identity's columns, one kernel for both)."""
    R = np.asarray(R, dtype=np.float64)
    flat = R.reshape(-1, 4)
    n = n_modes(ell_max)
    columns = rotate_modes(np.tile(np.eye(n, dtype=np.complex128), flat.shape[0]), np.repeat(flat, n, axis=0),
                           ell_max)                                  # [j, i n + k] = 𝔇(R_i)_{jk}
    D = columns.reshape(n, flat.shape[0], n).transpose(1, 0, 2)
    return np.ascontiguousarray(D).reshape(R.shape[:-1] + (n, n))


def rotate_modes(H, R, ell_max):
    """Modes h_ℓm = Σ_m' 𝔇^ℓ_{m m'}(R) H_ℓm' (n_modes, N) of modes H (n_modes, N) given in the frame of
    the rotors R (N, 4), for ℓ = 2 … ell_max in :func:`pnrotor.waveform.layout.mode_index` order; a
    C-contiguous (n_modes, N) array (each mode's samples contiguous).  Measured ~0.18 µs per sample for
    ℓ ≤ 4, ~0.8 µs for ℓ ≤ 8 (module docstring)."""
    H = np.asarray(H)
    R = np.ascontiguousarray(R, dtype=np.float64)
    if H.ndim != 2 or R.shape != (H.shape[1], 4) or H.shape[0] != n_modes(ell_max):
        raise ValueError(f"rotate_modes: H must be ((ell_max+1)^2 - 4, N) = ({n_modes(ell_max)}, N) and "
                         f"R (N, 4); got H {H.shape}, R {R.shape}")
    H = np.ascontiguousarray(H, dtype=np.complex128)
    h = np.empty_like(H)
    columns = np.ones((ell_max + 1, ell_max + 1), dtype=np.bool_)
    start, coef, _, pb, index, sign = d_table(int(ell_max))
    _rotate(H, R, int(ell_max), columns, np.ones(start.size - 1, dtype=np.bool_), start, coef, pb, index, sign,
            h.view(np.float64))
    return h
