r"""Truncated post-Newtonian series with spin-dependent coefficients.

This module owns the representation shared by :mod:`pnrotor.pn.energy`, :mod:`pnrotor.pn.flux` and the
right-hand sides in :mod:`pnrotor.pn.rhs`:

* a PN series is an array ``C[k, b, l]`` of shape ``(NK, NB, NL)`` meaning

      Σ_k v^k Σ_b B_b (C[k, b, 0] + C[k, b, 1] ln v),

  a relative expansion in v (k = 0 … 12: the point-particle and spin terms through 4.5PN, k ≤ 9, and the
  tidal terms of neutron stars at 5PN and 6PN, k = 10 and 12) whose coefficients are linear combinations
  of the spin invariants ``B`` below and may carry one power of ln v;
* the assembly of one quantity's series (Ê, F̂) from its coefficient functions (:func:`assemble`), the
  spin-orbit terms converted from Bohé et al.'s s_ℓ, σ_ℓ and the spin-spin terms from Sᵢ = Xᵢ²χᵢ;
* products of such series (with spin products reduced to the invariant basis), the truncated series
  ratio used by TaylorT4/T5, and truncation by PN order *separately* for each power of the spins;
* the numba evaluator :func:`eval_series` used inside the right-hand sides and events (the series stored
  in their parameter vector by :func:`fold_and_store`, each behind a header of the powers of v that hold
  spin and logarithmic terms, so that the evaluation skips the rest), which gives v dS/dv with S.

Spin-invariant basis (χᵢ the dimensionless spins, ℓ̂ the orbital angular momentum direction)::

    b:  0    1        2        3        4              5        6          7        8
        1    ℓ̂·χ₁     ℓ̂·χ₂     χ₁·χ₂    (ℓ̂·χ₁)(ℓ̂·χ₂)   χ₁·χ₁    (ℓ̂·χ₁)²    χ₂·χ₂    (ℓ̂·χ₂)²

Index 0 is spin-independent, 1–2 are linear in spin (spin-orbit), 3–8 quadratic (spin-spin,
self-spin and quadrupole-monopole, orbit averaged so that only these scalars occur).  Products of two
linear invariants map onto 4, 6, 8; anything of total spin power ≥ 3 is dropped, because the
cubic-in-spin terms of the energy and flux (Marsat 2015, arXiv:1411.4118) are not implemented and
keeping only their product pieces would be inconsistent.

Truncation rule: a term v^k B_b is kept iff ``k <= kmax[power(b)]`` where ``kmax = 2 × order`` for
the nonspinning (power 0), spin-orbit (power 1) and spin-spin (power 2) orders chosen by the user;
an order < 0 removes that spin power entirely.  Applying the rule to the inputs *and* to the result
of a product or ratio is the same as truncating the exact series, because every product raises both
k and the spin power.

Tidal terms (linear in the deformabilities Λᵢ, spin-independent, b = 0) are the terms with k ≥ TIDAL_K = 10:
no point-particle term reaches that power, so the rule above (k ≤ kmax[0] ≤ 9) drops them, and a fourth entry
``kmax[3]`` (the tidal order × 2, or −1) keeps them separately: :func:`pnrotor.pn.vdot.add_tides` carries them
through the approximants' ratios to first order in Λ.

The logarithm ln v is treated as an O(1) number (its coefficient is part of the v^k coefficient), the
convention of LALSuite's TaylorT4 and of PostNewtonian.jl's ``truncated_series_ratio``.  Products of
two logarithms first occur at v¹² and are outside this representation (checked).
"""

import functools
import math

import numpy as np
from numba import njit

NK = 13  # powers v^0 … v^12 (point particles through 4.5PN, k ≤ 9; tides at 5PN and 6PN, k = 10, 12)
TIDAL_K = 10  # the first power of the tidal terms (Vines, Flanagan & Hinderer 2011): b = 0 terms with k ≥ 10
NB = 9   # spin-invariant basis, see module docstring
NL = 2   # powers of ln v: 0 and 1
SERIES_HEADER = 5  # (n, s₀, s₁, l₀, l₁) before a series stored in p, see fold_and_store
SERIES_SLOTS = SERIES_HEADER + NK * NB * NL

B_ONE, B_A1, B_A2, B_S12, B_A1A2, B_S11, B_A1A1, B_S22, B_A2A2 = range(NB)
BASIS_NAMES = ("1", "l.chi1", "l.chi2", "chi1.chi2", "(l.chi1)(l.chi2)", "chi1.chi1", "(l.chi1)^2",
               "chi2.chi2", "(l.chi2)^2")
SPIN_POWER = np.array([0, 1, 1, 2, 2, 2, 2, 2, 2], dtype=np.int64)

# PROD[b1, b2] = basis index of B_b1 · B_b2, or -1 if the product has spin power > 2 (dropped)
PROD = -np.ones((NB, NB), dtype=np.int64)
for _b in range(NB):
    PROD[0, _b] = _b
    PROD[_b, 0] = _b
PROD[B_A1, B_A1] = B_A1A1
PROD[B_A1, B_A2] = B_A1A2
PROD[B_A2, B_A1] = B_A1A2
PROD[B_A2, B_A2] = B_A2A2
del _b

def shape_of(x):
    """np.shape(x), without making an array of a float or int (np.shape: ~1.4 µs, seven times in one binary's
    set-up)."""
    if isinstance(x, np.ndarray):
        return x.shape
    return () if isinstance(x, (float, int, np.generic)) else np.shape(x)


def new_series(shape=()):
    """A zero series C[k, b, l], or one per binary, C[k, b, l, i] for the trailing ``shape`` (n,)."""
    return np.zeros((NK, NB, NL) + tuple(shape))


def assemble(X1, kappa1, kappa2, nonspinning, spin_orbit, spin_spin_per_body, spin1_spin2):
    """The untruncated series C of one PN quantity (Ê or F̂) in the χ basis, from its coefficient functions
    (:mod:`pnrotor.pn.energy`, :mod:`pnrotor.pn.flux`): ``nonspinning(ν)`` → (c, c_log) over k;
    ``spin_orbit(ν)`` → {k: (c_s, c_σ)} of s_ℓ and δσ_ℓ; ``spin_spin_per_body(Xᵢ, κᵢ)`` → {k: (c_SS, c_LL)}
    of Sᵢ·Sᵢ and (ℓ̂·Sᵢ)²; ``spin1_spin2(ν)`` → {k: (c_S12, c_L12)} of S₁·S₂ and (ℓ̂·S₁)(ℓ̂·S₂).
    For arrays X1, κ₁, κ₂ (one binary each) the series of every binary, C[k, b, l, i]: the coefficient
    functions are elementwise, so each binary's numbers are those of a scalar call."""
    X2 = 1.0 - X1
    nu = X1 * X2
    C = new_series(shape_of(X1))
    c, clog = nonspinning(nu)
    C[:, B_ONE, 0] = c
    C[:, B_ONE, 1] = clog
    for k, (cs, csig) in spin_orbit(nu).items():
        c1, c2 = sl_sigma_to_basis(X1, X2, cs, csig)
        C[k, B_A1, 0] += c1
        C[k, B_A2, 0] += c2
    add_spin_spin(C, X1, X2, spin_spin_per_body(X1, kappa1), spin_spin_per_body(X2, kappa2), spin1_spin2(nu))
    return C


def sl_sigma_to_basis(X1, X2, c_s, c_sigma):
    """Coefficients of ℓ̂·χ₁ and ℓ̂·χ₂ of c_s s_ℓ + c_σ δ σ_ℓ, with s_ℓ = X₁²a₁ + X₂²a₂ and
    σ_ℓ = X₂a₂ − X₁a₁ (Bohé+ 2013, definitions above their Eq. (3.1), with M = 1)."""
    delta = X1 - X2
    return (c_s * X1 * X1 - c_sigma * delta * X1,
            c_s * X2 * X2 + c_sigma * delta * X2)


def add_spin_spin(C, X1, X2, per_body_1, per_body_2, s1s2):
    """Add orbit-averaged quadratic-in-spin terms, given in Sᵢ = Xᵢ²χᵢ units, to C in the χ basis."""
    for k, (c_ss, c_ll) in per_body_1.items():
        C[k, B_S11, 0] += c_ss * (X1 * X1 * X1 * X1)
        C[k, B_A1A1, 0] += c_ll * (X1 * X1 * X1 * X1)
    for k, (c_ss, c_ll) in per_body_2.items():
        C[k, B_S22, 0] += c_ss * (X2 * X2 * X2 * X2)
        C[k, B_A2A2, 0] += c_ll * (X2 * X2 * X2 * X2)
    for k, (c_s12, c_l12) in s1s2.items():
        C[k, B_S12, 0] += c_s12 * (X1 * X1) * (X2 * X2)
        C[k, B_A1A2, 0] += c_l12 * (X1 * X1) * (X2 * X2)
    return C


def add_tidal(C, X1, X2, lambda1, lambda2, per_body):
    """Add the tidal terms Σᵢ Λᵢ c_k(Xᵢ) v^k to C (b = 0; arrays X1, Λ: one binary each, elementwise), from
    ``per_body(X)`` → {k: c_k} per unit dimensionless deformability Λ of the body of mass fraction X
    (:func:`pnrotor.pn.energy.tidal_energy`, :func:`pnrotor.pn.flux.tidal_flux`); one binary without tides
    skips them (its ~10 µs; adding the zeros would give the same numbers)."""
    if not (shape_of(X1) or lambda1 or lambda2):
        return C
    for k, c in per_body(X1).items():
        C[k, B_ONE, 0] += lambda1 * c
    for k, c in per_body(X2).items():
        C[k, B_ONE, 0] += lambda2 * c
    return C


def kmax_from_orders(pn_order, so_order, ss_order, tidal_order=0.0):
    """Largest kept power of v for spin power 0, 1, 2 and of the tidal terms (−1: none of them), a new int64 array
    of 4: the tidal terms start at 5PN (k = 10), so a tidal order below 5 keeps none."""
    return np.array(_kmax(pn_order, so_order, ss_order, tidal_order), dtype=np.int64)


@functools.lru_cache(maxsize=32)
def _kmax(pn_order, so_order, ss_order, tidal_order):
    """:func:`kmax_from_orders` as a tuple, cached: every run of a population asks for the same orders, and the
    checks cost ~1.5 µs (equal keys give equal results: −0.0 and 0.0 are both kept orders)."""
    out = []
    for j, order in enumerate((pn_order, so_order, ss_order, tidal_order)):
        if order is None or order < 0:
            out.append(-1)
        else:
            twice = 2.0 * float(order)
            if abs(twice - round(twice)) > 1e-12:
                raise ValueError(f"PN orders must be multiples of 0.5, got {order!r}")
            out.append(min(int(round(twice)), NK - 1 if j == 3 else TIDAL_K - 1))
    if out[3] < TIDAL_K:
        out[3] = -1
    return tuple(out)


@njit(cache=True)
def truncate(C, kmax):
    """Zero every term v^k B_b with k > kmax[SPIN_POWER[b]] (in place) and return C."""
    for k in range(C.shape[0]):
        for b in range(C.shape[1]):
            if k > kmax[SPIN_POWER[b]]:
                for l in range(C.shape[2]):
                    C[k, b, l] = 0.0
    return C


@njit(cache=True)
def _accumulate_product(out, A, B, ka, kb, sign):
    """out[ka+kb] += sign · A[ka] ⊗ B[kb] (spin products reduced with PROD, ln-powers added)."""
    k = ka + kb
    for b1 in range(NB):
        for l1 in range(NL):
            a = A[ka, b1, l1]
            if a == 0.0:
                continue
            for b2 in range(NB):
                b3 = PROD[b1, b2]
                if b3 < 0:
                    continue
                for l2 in range(NL):
                    c = B[kb, b2, l2]
                    if c == 0.0:
                        continue
                    if l1 + l2 >= NL:
                        raise ValueError("series product produced ln(v)^2 inside the kept orders")
                    out[k, b3, l1 + l2] += sign * a * c


@njit(cache=True)
def _top(kmax):
    """The highest power of v that ``kmax`` keeps of any spin power (what :func:`truncate` reads; a series' higher
    powers are not computed: products of two logarithms first occur at v¹², past the point-particle orders)."""
    return min(max(kmax[0], kmax[1], kmax[2]), NK - 1)


@njit(cache=True)
def multiply(A, B, kmax):
    """Truncated product A·B."""
    out = np.zeros((NK, NB, NL))
    top = _top(kmax)
    for ka in range(top + 1):
        for kb in range(top + 1 - ka):
            _accumulate_product(out, A, B, ka, kb, 1.0)
    return truncate(out, kmax)


@njit(cache=True)
def divide(N, D, kmax):
    """Truncated series ratio Q = N / D (the TaylorT4/T5 re-expansion).

    D must start with a pure number: D[0] = d₀ · B_0 with d₀ ≠ 0 and no logarithm.  Then
    Q_k = (N_k − Σ_{i=1..k} D_i Q_{k−i}) / d₀, order by order.
    """
    d0 = D[0, 0, 0]
    for b in range(NB):
        for l in range(NL):
            if (b != 0 or l != 0) and D[0, b, l] != 0.0:
                raise ValueError("divide: the leading coefficient of the denominator must be a pure number")
    if d0 == 0.0:
        raise ValueError("divide: the denominator has a vanishing leading coefficient")
    Q = np.zeros((NK, NB, NL))
    for k in range(_top(kmax) + 1):
        for b in range(NB):
            for l in range(NL):
                Q[k, b, l] = N[k, b, l]
        for i in range(1, k + 1):
            _accumulate_product(Q, D, Q, i, k - i, -1.0)
        for b in range(NB):
            for l in range(NL):
                Q[k, b, l] /= d0
        # truncating as we go keeps dropped terms out of the higher orders
        for b in range(NB):
            if k > kmax[SPIN_POWER[b]]:
                for l in range(NL):
                    Q[k, b, l] = 0.0
    return Q


@njit(cache=True)
def copy_into(src, dst):
    """dst[...] = src for C-contiguous arrays of one shape, element by element: numba compiles an array assignment
    with its shape-mismatch error message, whose string formatting took 5.4-5.7 s of a cold evolve_many (numba's
    compile events; README, "Populations")."""
    s, d = src.reshape(src.size), dst.reshape(dst.size)
    for k in range(s.size):
        d[k] = s[k]


@njit(cache=True)
def v_derivative(C):
    """The series of v dC/dv: v d/dv[v^k(c + c_L ln v)] = v^k[(k c + c_L) + k c_L ln v] (same truncation)."""
    D = np.empty_like(C)
    for k in range(C.shape[0]):
        for b in range(C.shape[1]):
            D[k, b, 0] = k * C[k, b, 0] + C[k, b, 1]
            D[k, b, 1] = k * C[k, b, 1]
    return D


@njit(cache=True)
def eval_at(C, v, basis):
    """Σ_k v^k Σ_b B_b (C[k,b,0] + C[k,b,1] ln v) at one v (numba; see :func:`evaluate`)."""
    lnv = math.log(v)
    acc = 0.0
    for k in range(C.shape[0] - 1, -1, -1):
        ck = 0.0
        for b in range(C.shape[1]):
            ck += basis[b] * (C[k, b, 0] + C[k, b, 1] * lnv)
        acc = acc * v + ck
    return acc


@njit(cache=True)
def fold_and_store(C, basis, fold, p, off):
    """Write C (optionally contracted with the fixed invariants ``basis`` into column b = 0, see
    :func:`fold_basis`) into p[off:] as :func:`eval_series` reads it: the header (n, s₀, s₁, l₀, l₁),
    then C flat.  n = 1 + the highest nonzero power of v; the powers with a nonzero spin term (b ≥ 1)
    are s₀ ≤ k < s₁ without ln v and l₀ ≤ k < l₁ with it (0, 0 if none)."""
    n = 0
    s0 = s1 = l0 = l1 = 0
    for k in range(C.shape[0]):
        for b in range(C.shape[1]):
            for l in range(C.shape[2]):
                if fold:
                    val = 0.0
                    if b == 0:
                        for bb in range(C.shape[1]):
                            val += basis[bb] * C[k, bb, l]
                else:
                    val = C[k, b, l]
                p[off + SERIES_HEADER + (k * C.shape[1] + b) * C.shape[2] + l] = val
                if val != 0.0:
                    n = k + 1
                    if b > 0 and l == 0:
                        s0, s1 = (s0 if s1 else k), k + 1
                    elif b > 0:
                        l0, l1 = (l0 if l1 else k), k + 1
    p[off] = n
    p[off + 1] = s0
    p[off + 2] = s1
    p[off + 3] = l0
    p[off + 4] = l1


def fold_basis(C, basis_values):
    """Contract the spin basis with fixed invariant values: returns C' with only b = 0 nonzero.

    Used for aligned-spin and nonspinning runs, where the invariants are constants of the motion.
    """
    out = new_series()
    b = np.asarray(basis_values, dtype=np.float64)
    out[:, 0, 0] = C[:, :, 0] @ b
    out[:, 0, 1] = C[:, :, 1] @ b
    return out


def basis_values(a1, a2, s12, s11, s22):
    """The nine invariants from ℓ̂·χ₁, ℓ̂·χ₂, χ₁·χ₂, χ₁·χ₁, χ₂·χ₂: floats → (9,), or arrays (n,) → (9, n)."""
    one = 1.0 if isinstance(a1, float) else np.ones_like(a1)
    return np.array([one, a1, a2, s12, a1 * a2, s11, a1 * a1, s22, a2 * a2])


def evaluate(C, v, basis):
    """Evaluate a series at v (numpy reference, vectorized over v) with fixed basis values."""
    b = np.asarray(basis, dtype=np.float64)
    c0 = C[:, :, 0] @ b
    c1 = C[:, :, 1] @ b
    if np.ndim(v) == 0:
        v = float(v)
        lnv = math.log(v)
        acc = 0.0
        for k in range(NK - 1, -1, -1):
            acc = acc * v + float(c0[k]) + float(c1[k]) * lnv
        return acc
    v = np.asarray(v, dtype=np.float64)
    lnv = np.log(v)
    out = np.zeros_like(v)
    for k in range(NK - 1, -1, -1):
        out = out * v + c0[k] + c1[k] * lnv
    return out


@njit(cache=True, inline="always")
def eval_series(p, off, v, lnv, spins, b1, b2, b3, b4, b5, b6, b7, b8):
    """(S, v dS/dv) at v for S = Σ_k v^k Σ_b B_b (C[k,b,0] + C[k,b,1] ln v) stored at p[off:] by
    :func:`fold_and_store`; ``lnv`` = ln v, B_0 = 1 and b1…b8 the other eight invariants (module docstring).

    Each power k < n is contracted with the basis once into c_k + c_L,k ln v, its spin terms only where
    the header has them (s₀ ≤ k < s₁, and l₀ ≤ k < l₁ for those with ln v); ``spins=False``, for a series
    folded into b = 0 at setup, compiles them away.  Both sums are Horner's: S ← S v + c_k + c_L,k ln v
    and, for v dS/dv = Σ_k v^k [k (c_k + c_L,k ln v) + c_L,k], e ← (e + S) v + c_L,k (S before its update).
    A caller that uses only S leaves e to the compiler to drop.
    """
    n, s0, s1, l0, l1 = int(p[off]), int(p[off + 1]), int(p[off + 2]), int(p[off + 3]), int(p[off + 4])
    acc = 0.0
    dacc = 0.0
    for k in range(n - 1, -1, -1):
        o = off + SERIES_HEADER + k * (NB * NL)
        c = p[o]
        cl = p[o + 1]
        if spins and k < s1 and k >= s0:
            c += (b1 * p[o + 2] + b2 * p[o + 4] + b3 * p[o + 6] + b4 * p[o + 8] + b5 * p[o + 10]
                  + b6 * p[o + 12] + b7 * p[o + 14] + b8 * p[o + 16])
        if spins and k < l1 and k >= l0:
            cl += (b1 * p[o + 3] + b2 * p[o + 5] + b3 * p[o + 7] + b4 * p[o + 9] + b5 * p[o + 11]
                   + b6 * p[o + 13] + b7 * p[o + 15] + b8 * p[o + 17])
        dacc = (dacc + acc) * v + cl
        acc = acc * v + (c + cl * lnv)
    return acc, dacc
