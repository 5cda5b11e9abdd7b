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
poles.  The small-d matrix goes through the constant matrix Δ = d^ℓ(π/2) (the rotation by β about ŷ is the one
about ẑ seen from a frame turned by π/2; e.g. Risbo 1996, J. Geodesy 70, 383):

    d^ℓ_{m m'}(β) = i^{m'−m} Σ_μ Δ_{μm} e^{iμβ} Δ_{μm'},     so
    h_ℓm = (−i e^{−iα})^m Σ_μ Δ_{μm} e^{iμβ} Σ_m' Δ_{μm'} (i e^{−iγ})^m' H_ℓm',

two products with a constant real matrix around one phase per row, and no element of d is formed per sample;
e^{iβ} = (|R_a| + i|R_b|)²/|R|², and the factors i^{±m} ride on the phases.  Δ is Wigner's finite sum

    d^ℓ_{m m'}(β) = Σ_s (−1)^{m−m'+s} √[(ℓ+m)!(ℓ−m)!(ℓ+m')!(ℓ−m')!] / [(ℓ+m'−s)! s! (m−m'+s)! (ℓ−m−s)!]
                    × cos(β/2)^{2ℓ+m'−m−2s} sin(β/2)^{m−m'+2s}

at β = π/2, summed in rationals (:func:`d_half_pi`: each element the float nearest its value), and its rows
are orthonormal, so each product adds rounding of a few ulps and the matrices stay within ~1e-15 of exact
for every β, the poles included.  Of Δ only m, m' ≥ 0 is used: Δ_{μ,−m'} = (−1)^{ℓ+μ} Δ_{μm'} and
Δ_{−μ,m'} = (−1)^{ℓ+m'} Δ_{μm'}, so with P_m' = X_m' + X_−m', M_m' = X_m' − X_−m' of a product's input X,

    y_±μ = A ± B,     A = Σ_{ℓ+m' even} Δ_{μm'} S_m',     B = Σ_{ℓ+m' odd} Δ_{μm'} S_m',     S = P if ℓ+μ is even, else M,

(Δ_{0m'} = 0 for ℓ+m' odd), (ℓ+1)² terms a product instead of (2ℓ+1)²; the same holds for Δᵀ.  Rotors need not
be normalized (v' = R v R⁻¹ does not see |R|).

Layout of the computation: the modes are (n_modes, N) arrays, each mode's samples contiguous, and the
samples are taken in blocks of ``CHUNK``; within a block every loop runs over the samples innermost, each in
a small function of its own (LLVM vectorizes them there, not inline), so each is plain contiguous real
arithmetic.  Per block :func:`rotor_block` forms e^{iμβ}, (−i e^{−iα})^m and (i e^{−iγ})^m by recurrences in
μ and m (from the rotors copied to rows first: a loop that indexes R[i0 + s] or any array at i0 + s is left
scalar by LLVM); then per ℓ :func:`rotate_ell` takes the sums and differences G_m' ± G_−m' of
G_m' = (i e^{−iγ})^m' H_ℓm', does the first product (passes of :func:`rotation_plan`, each adding up to three terms
of A and three of B to the rows ±μ, :func:`_pass`), the phases e^{±iμβ} with the sums and differences of the
result, and the second product; the caller applies (i e^{−iγ})^m' and forms G_m' ± G_−m' before, and applies
(−i e^{−iα})^m as it stores h (:func:`store`).  Columns m' whose H_ℓm' vanish identically are left out of the
first product.  :func:`rotate_modes` (:func:`_rotate`) reads H from an array, and :func:`wigner_D` is it applied to
the columns of the identity; :func:`pnrotor.waveform.amplitudes.modes_in_frame` forms H block by block in the
same pass instead, with its phases (i e^{−iγ})^m' and the sums and differences (no H array, no pass of its own
for either).  Measured for 25,220 samples of a precessing run (one shared core): :func:`rotate_modes` ~0.12–0.15 µs
per sample for ℓ ≤ 4 and ~0.6 µs for ℓ ≤ 8, against ~0.15 and ~0.8 µs with d's elements formed per sample from
Wigner's sum (and 0.6 and 3.0 µs for the per-sample version before that); what remains is mostly loads and
stores of the blocks' rows.
"""

import math
from fractions import Fraction
from functools import lru_cache
from math import factorial, sqrt

import numpy as np
from numba import njit

from pnrotor import threads
from pnrotor.waveform.layout import mode_index, n_modes

__all__ = ["d_half_pi", "rotation_plan", "wigner_D", "rotate_modes"]

_TINY2 = 1e-280
"""|R_a|², |R_b|² at or below this fraction of |R|² count as zero: above it, with |R|² > 1e-8 (rotors farther from
unit norm are first scaled by a power of 2), they are normal numbers, so their square roots, and the unit phases
formed with them, are exact to rounding (at ~1e-160 of |R| the squares are subnormal, the phases were off by up to
4e-5: a review's finding)."""


@lru_cache(maxsize=None)
def d_half_pi(ell):
    """Δ_{m m'} = d^ℓ_{m m'}(π/2) for m, m' = 0 … ℓ, (ℓ+1, ℓ+1), each the float nearest its exact value (Wigner's
    sum in rationals: Δ² = (ℓ+m)!(ℓ−m)!(ℓ+m')!(ℓ−m')! S² / 4^ℓ, S the sum of the module docstring)."""
    out = np.zeros((ell + 1, ell + 1))
    for m in range(ell + 1):
        for mp in range(ell + 1):
            total = sum(Fraction((-1) ** (m - mp + s), factorial(ell + mp - s) * factorial(s) * factorial(m - mp + s)
                                 * factorial(ell - m - s))
                        for s in range(max(0, mp - m), min(ell + mp, ell - m) + 1))
            square = total * total * factorial(ell + m) * factorial(ell - m) * factorial(ell + mp) \
                * factorial(ell - mp) / 4 ** ell
            out[m, mp] = (1.0 if total >= 0 else -1.0) * sqrt(float(square))
    return out


def rotation_plan(columns):
    """The passes of :func:`rotate_ell` for columns[ℓ, |m'|] (ℓ = 0 … ℓ_max; false where H_ℓ,±m' vanish):
    ``(first, rows, coefs)``, the passes of ℓ's first product (over m') ``first[2ℓ] : first[2ℓ+1]`` and of its
    second (over m'') ``first[2ℓ+1] : first[2ℓ+2]``; pass k adds to the rows (rows[k, 0], rows[k, 1]) = (ℓ + μ,
    ℓ − μ) of its output (the spare row 2ℓ_max + 1 for μ = 0), from the rows rows[k, 2:8] of its input with the
    weights coefs[k] (:func:`_pass`; three terms of A and three of B: one pass per μ for ℓ ≤ 5, two for
    ℓ ≤ 8), and rows[k, 8] is 1 if it adds to what earlier passes wrote."""
    return _plan(columns.shape[0] - 1, columns.tobytes())


@lru_cache(maxsize=None)
def _plan(ell_max, columns):
    """:func:`rotation_plan` for columns as bytes (module docstring: the products and their symmetries)."""
    columns = np.frombuffer(columns, dtype=np.bool_).reshape(ell_max + 1, ell_max + 1)
    spare = 2 * ell_max + 1
    first, rows, coefs = [0] * (2 * ell_max + 3), [], []
    for ell in range(2, ell_max + 1):
        delta = d_half_pi(ell)
        for product, (weights, present) in enumerate(((delta, columns[ell]), (delta.T, np.ones(ell + 1, bool)))):
            for mu in range(ell + 1):
                # input row of column ν: ℓ + ν holds P_ν = X_ν + X_−ν, ℓ − ν holds M_ν = X_ν − X_−ν (row ℓ: X_0)
                odd_row = (ell + mu) % 2
                terms = ([], [])
                for nu in range(ell + 1):
                    if present[nu] and weights[mu, nu] != 0.0:
                        terms[(ell + nu) % 2].append((ell - nu if odd_row else ell + nu, weights[mu, nu]))
                for k in range(max(1, -(-len(terms[0]) // 3), -(-len(terms[1]) // 3))):
                    picked = [t[j] if j < len(t) else (ell, 0.0) for j in range(3 * k, 3 * k + 3) for t in terms]
                    rows.append([ell + mu, ell - mu if mu else spare] + [r for r, _ in picked] + [int(k > 0)])
                    coefs.append([c for _, c in picked])
            first[2 * ell + product + 1] = len(rows)
        first[2 * ell + 3:] = [len(rows)] * (2 * ell_max + 3 - (2 * ell + 3))
    return (np.array(first, dtype=np.int64), np.array(rows, dtype=np.int64).reshape(-1, 9),
            np.array(coefs, dtype=np.float64).reshape(-1, 6))


CHUNK = 256
"""Samples per block of :func:`_rotate` and of :func:`pnrotor.waveform.amplitudes._sum`."""

MIN_PART = 1024
"""Samples per thread at least for :func:`_rotate` and :func:`pnrotor.waveform.amplitudes._sum`, which compute runs
of 2 MIN_PART samples or more in parts on the machine's threads (:mod:`pnrotor.threads`)."""


# The kernels' innermost loops, one per function over the samples s of a block, on the block arrays and row
# indices.  Written inline they were no faster (LLVM left most of them scalar there).

@njit(cache=True, fastmath={"contract"})
def _times_phase(x_re, x_im, r, e_re, e_im, u, conj, out_re, out_im, ro, nb):
    """Row ro of out = e x (e* x if conj) for rows r of x and u of e, complex numbers as (re, im) arrays; out may
    be x."""
    sg = -1.0 if conj else 1.0
    for s in range(nb):
        er, ei, xr, xi = e_re[u, s], sg * e_im[u, s], x_re[r, s], x_im[r, s]
        out_re[ro, s] = er * xr - ei * xi
        out_im[ro, s] = er * xi + ei * xr


@njit(cache=True, fastmath={"contract"})
def store(x_re, x_im, r, e_re, e_im, u, conj, scale, out, row, i0, nb):
    """out[row, 2i], out[row, 2i + 1] (i = i0 + s) = the real and imaginary parts of scale e x (scale e* x if
    conj) for rows r of x and u of e: complex numbers as (re, im) arrays into a float view of a complex array."""
    sg = -scale if conj else scale
    o = out[row, 2 * i0:]   # indexed by the loop's own s (an index i0 + s keeps LLVM from vectorizing a loop)
    for s in range(nb):
        er, ei, xr, xi = scale * e_re[u, s], sg * e_im[u, s], x_re[r, s], x_im[r, s]
        o[2 * s] = er * xr - ei * xi
        o[2 * s + 1] = er * xi + ei * xr


@njit(cache=True)
def phase_powers(e_re, e_im, nb):
    """Rows m = 2, 3, … of e^m from rows 0 (= 1) and 1 (= e)."""
    for m in range(2, e_re.shape[0]):
        _times_phase(e_re, e_im, m - 1, e_re, e_im, 1, False, e_re, e_im, m, nb)


@njit(cache=True, fastmath={"contract"})
def _sum_difference(x_re, x_im, rp, rn, e_re, e_im, u, nb):
    """(p, n) = (e p + e* n, e p − e* n) for the rows p = rp, n = rn of x and e = u of e."""
    for s in range(nb):
        er, ei = e_re[u, s], e_im[u, s]
        ur, ui = er * x_re[rp, s] - ei * x_im[rp, s], er * x_im[rp, s] + ei * x_re[rp, s]
        vr, vi = er * x_re[rn, s] + ei * x_im[rn, s], er * x_im[rn, s] - ei * x_re[rn, s]
        x_re[rp, s], x_im[rp, s], x_re[rn, s], x_im[rn, s] = ur + vr, ui + vi, ur - vr, ui - vi


@njit(cache=True, fastmath={"contract"})
def _pass(y, x, rows, coefs, k, nb):
    """Pass k of :func:`rotation_plan` on real rows, x to y: (y_r, y_rn) = (A + B, A − B), added to them if it
    says so, for A = c0 x_j0 + c2 x_j2 + c4 x_j4, B = c1 x_j1 + c3 x_j3 + c5 x_j5 (r, rn, j = rows[k, :8],
    c = coefs[k]; the real and imaginary parts a call each: LLVM vectorizes these, not the complex pass)."""
    r, rn, j0, j1, j2, j3, j4, j5 = rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4], rows[k, 5], \
        rows[k, 6], rows[k, 7]
    c0, c1, c2, c3, c4, c5 = coefs[k, 0], coefs[k, 1], coefs[k, 2], coefs[k, 3], coefs[k, 4], coefs[k, 5]
    if rows[k, 8] == 1:
        for s in range(nb):
            a = c0 * x[j0, s] + c2 * x[j2, s] + c4 * x[j4, s]
            b = c1 * x[j1, s] + c3 * x[j3, s] + c5 * x[j5, s]
            y[r, s] += a + b
            y[rn, s] += a - b
    else:
        for s in range(nb):
            a = c0 * x[j0, s] + c2 * x[j2, s] + c4 * x[j4, s]
            b = c1 * x[j1, s] + c3 * x[j3, s] + c5 * x[j5, s]
            y[r, s], y[rn, s] = a + b, a - b


@njit(cache=True)
def rotor_rows(R, i0, nb, q):
    """Rows w, x, y, z of q (4, CHUNK) = the rotors R[i0 : i0 + nb]: LLVM vectorizes a loop over rows, not over
    R's strided columns (the loop of :func:`rotor_block`)."""
    for s in range(nb):
        for k in range(4):
            q[k, s] = R[i0 + s, k]


@njit(cache=True, fastmath={"contract"}, error_model="numpy")
def rotor_block(R, i0, nb, q, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im):
    """Of the rotors R[i0 : i0 + nb], rows m ≥ 1 of e^{imβ}, (−i e^{−iα})^m and (i e^{−iγ})^m (module docstring;
    rows 0, = 1, are :func:`rotation_scratch`'s); q (4, CHUNK) scratch (:func:`rotor_rows`)."""
    rotor_rows(R, i0, nb, q)
    for s in range(nb):
        w, x, y, z = q[0, s], q[1, s], q[2, s], q[3, s]
        a2, b2 = w * w + z * z, x * x + y * y
        if not 1e-8 < a2 + b2 < 1e8:   # far from unit norm: scaled by a power of 2 (exact) to |R| in [1/2, 2)
            e = math.frexp(max(abs(w), abs(x), abs(y), abs(z)))[1]
            w, x, y, z = math.ldexp(w, -e), math.ldexp(x, -e), math.ldexp(y, -e), math.ldexp(z, -e)
            a2, b2 = w * w + z * z, x * x + y * y
        a, b = np.sqrt(a2), np.sqrt(b2)
        n = 1.0 / (a2 + b2)   # e^{iβ} = (|R_a| + i |R_b|)² / |R|²
        eb_re[1, s], eb_im[1, s] = (a2 - b2) * n, 2.0 * a * b * n
        if not a2 > _TINY2 * (a2 + b2):   # R_a = w + i z → 1 where it vanishes: any unit phase serves (module
            w, z, a = 1.0, 0.0, 1.0       # docstring; its terms are O(|R_a|) ≤ 1e-140 of the others)
        if not b2 > _TINY2 * (a2 + b2):   # R_b = y − i x → 1
            y, x, b = 1.0, 0.0, 1.0
        n = 1.0 / (a * b)   # −i e^{−iα} = −i conj(R_a R_b) / (|R_a| |R_b|), i e^{−iγ} = i conj(R_a) R_b / (|R_a| |R_b|)
        ea_re[1, s], ea_im[1, s] = (w * x - z * y) * n, -(w * y + z * x) * n
        eg_re[1, s], eg_im[1, s] = (w * x + z * y) * n, (w * y - z * x) * n
    phase_powers(eb_re, eb_im, nb)
    phase_powers(ea_re, ea_im, nb)
    phase_powers(eg_re, eg_im, nb)


@njit(cache=True)
def _passes(lo, hi, rows, coefs, x_re, x_im, y_re, y_im, nb):
    """The passes lo … hi−1 of :func:`rotation_plan` from x to y."""
    for k in range(lo, hi):
        _pass(y_re, x_re, rows, coefs, k, nb)
        _pass(y_im, x_im, rows, coefs, k, nb)


@njit(cache=True)
def rotate_ell(ell, first, rows, coefs, eb_re, eb_im, G_re, G_im, y_re, y_im, h_re, h_im, nb):
    """Rows ℓ + m of (h_re, h_im) = Σ_μ Δ_{μm} e^{iμβ} Σ_m' Δ_{μm'} G_m' for G_m' = (i e^{−iγ})^m' H_ℓm', given as
    G_ℓ + G_−ℓ, …, G_0, …, G_ℓ − G_−ℓ in the rows of (G_re, G_im) (overwritten): h_ℓm before its factor
    (−i e^{−iα})^m (:func:`store`), for a block whose e^{iμβ} :func:`rotor_block` gave, by the passes of
    :func:`rotation_plan` (first, rows, coefs: the columns m' where H_ℓ,±m' vanish are skipped), y scratch.  The
    second product's input rows ℓ ± ν become their sums and differences with their phases e^{±iνβ}."""
    _passes(first[2 * ell], first[2 * ell + 1], rows, coefs, G_re, G_im, y_re, y_im, nb)
    for mu in range(1, ell + 1):
        _sum_difference(y_re, y_im, ell + mu, ell - mu, eb_re, eb_im, mu, nb)
    _passes(first[2 * ell + 1], first[2 * ell + 2], rows, coefs, y_re, y_im, h_re, h_im, nb)


@njit(cache=True)
def rotation_scratch(ell_max, B):
    """The block arrays of :func:`rotor_block` and :func:`rotate_ell`: q, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im
    (their rows 0 set here to 1, once), y_re, y_im, h_re, h_im (y and h with a spare row)."""
    n_m, n_rows = ell_max + 1, 2 * ell_max + 2
    e_re, e_im = np.empty((3, n_m, B)), np.empty((3, n_m, B))
    e_re[:, 0], e_im[:, 0] = 1.0, 0.0
    return (np.empty((4, B)), e_re[0], e_im[0], e_re[1], e_im[1], e_re[2], e_im[2], np.empty((n_rows, B)),
            np.empty((n_rows, B)), np.empty((n_rows, B)), np.empty((n_rows, B)))


@njit(cache=True, nogil=True)
def _rotate(H, R, ell_max, first, rows, coefs, h, lo, hi):
    """h[:, i] = 𝔇(R[i]) H[:, i] for i = lo … hi−1 of (n_modes, N) arrays (h as a float view, (n_modes, 2N)), a
    block of CHUNK samples at a time (lo a multiple of CHUNK: the blocks of the whole range); every inner loop
    runs over the samples of the block (module docstring)."""
    B = CHUNK
    q, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im, y_re, y_im, h_re, h_im = rotation_scratch(ell_max, B)
    G_re, G_im = np.empty((2 * ell_max + 1, B)), np.empty((2 * ell_max + 1, B))
    for i0 in range(lo, hi, B):
        nb = min(B, hi - i0)
        rotor_block(R, i0, nb, q, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im)
        for ell in range(2, ell_max + 1):
            first_row = mode_index(ell, -ell)
            for r in range(2 * ell + 1):
                for s in range(nb):
                    G_re[r, s] = H[first_row + r, i0 + s].real
                    G_im[r, s] = H[first_row + r, i0 + s].imag
                _times_phase(G_re, G_im, r, eg_re, eg_im, abs(r - ell), r < ell, G_re, G_im, r, nb)
            for nu in range(1, ell + 1):
                _sum_difference(G_re, G_im, ell + nu, ell - nu, eb_re, eb_im, 0, nb)
            rotate_ell(ell, first, rows, coefs, eb_re, eb_im, G_re, G_im, y_re, y_im, h_re, h_im, nb)
            for r in range(2 * ell + 1):
                store(h_re, h_im, r, ea_re, ea_im, abs(r - ell), r < ell, 1.0, h, first_row + r, i0, nb)


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
    C-contiguous (n_modes, N) array (each mode's samples contiguous).  Measured ~0.12–0.15 µs per sample for
    ℓ ≤ 4, ~0.6 µs for ℓ ≤ 8 on one thread (module docstring); N ≥ 2 :data:`MIN_PART` in parts on the machine's
    threads (``Modes.in_frame('coprecessing')``, 9,926 samples, ℓ ≤ 8: 11.5 → 8.1 ms on two cores)."""
    H = np.asarray(H)
    R = np.ascontiguousarray(R, dtype=np.float64)
    if H.ndim != 2 or R.shape != (H.shape[1], 4) or H.shape[0] != n_modes(ell_max):
        raise ValueError(f"rotate_modes: H must be ((ell_max+1)^2 - 4, N) = ({n_modes(ell_max)}, N) and "
                         f"R (N, 4); got H {H.shape}, R {R.shape}")
    H = np.ascontiguousarray(H, dtype=np.complex128)
    h = np.empty_like(H)
    every_column = np.ones((ell_max + 1, ell_max + 1), dtype=np.bool_)
    args = (H, R, int(ell_max), *rotation_plan(every_column), h.view(np.float64))
    threads.run(lambda lo, hi: _rotate(*args, lo, hi), threads.parts(R.shape[0], MIN_PART, CHUNK))
    return h
