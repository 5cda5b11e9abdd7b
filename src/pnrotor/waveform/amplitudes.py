r"""Co-orbital mode amplitudes H_ℓm: the terms of the sources as one table, and the numba kernel that sums
them and, in the same pass, takes them to the inertial frame.

Every term of :mod:`~pnrotor.waveform.nonspinning` and :mod:`~pnrotor.waveform.spin` has the form
h₀ v^k c q with h₀ = 8 √(π/5) ν v², a complex coefficient c fixed by the masses and q a real quantity
of the sample (1, ln v, or one of the spin quantities of :data:`pnrotor.waveform.spin.BASIS`).  For a
run, :func:`table` keeps the terms of the modes ℓ ≤ ell_max, m ≥ 0 up to the amplitude order
(k ≤ 2 × order), each with its parity: H_ℓm = S_ℓm + A_ℓm, the sums of its symmetric and antisymmetric
terms, and H_ℓ,−m = (−1)^ℓ (S_ℓm − A_ℓm)* (:mod:`~pnrotor.waveform.spin`; every nonspinning term is
symmetric).  So only m ≥ 0 is summed, into separate real and imaginary rows (a coefficient's zero part is no
term), S_ℓm in row ℓ + m and A_ℓm in row ℓ − m, which then become H_ℓm and H_ℓ,−m in place: no term is
evaluated for a mode, an order or a spin quantity nobody asked for (none for a nonspinning run), and spins
that are the same at every sample (aligned ones) are folded into the coefficients.

:func:`_sum` runs over blocks of samples (``wigner.CHUNK``) with the samples innermost (the block functions
:func:`block_start` and :func:`block_ell`, which :mod:`pnrotor.waveform.stream` calls too): per block v^k, ln v
(only if a term needs it) and the spin quantities — for a precessing run of spins taken from the inertial
frame into each sample's orbital frame, χ' = R⁻¹ χ R — then per ℓ the amplitudes and, without writing them
out, the rotation to the inertial frame: H itself (co-orbital), H_ℓm e^{−imΦ} (a nonprecessing run in its
own frame) or 𝔇(R) H (:func:`pnrotor.waveform.wigner.rotate_ell`, only the columns m' with terms).
For a precessing run the sums and differences H_ℓm' ± H_ℓ,−m' that the rotation's first product takes are formed
as H_ℓ,±m' are (:func:`_mirror`).  Only the powers of v and the spin quantities some term needs are formed.
Measured (benchmarks/bench_modes.py, shared two-core machine), modes() per sample: precessing runs ~100–140 ns
for ℓ ≤ 4 at 1.5PN and ~340–460 ns for ℓ ≤ 8 at 3.5PN (~130–160 and ~430–500 before the rotors were copied to
rows and the sums folded into :func:`_mirror`; ~500–600 with d's elements formed per sample, ~400 and ~1,500 ns
for amplitudes and rotation as two passes over an H array); nonprecessing runs ~60–120 and ~190–240 ns, against
~140–280 and ~500–700 ns.  Runs of at least 2 × :data:`pnrotor.waveform.wigner.MIN_PART` samples are computed
in parts at the same time on the machine's threads (:mod:`pnrotor.threads`; the kernel is ``nogil`` and takes the
range of samples, each part's blocks starting at a multiple of the block; bitwise the same output): the 30+10 M☉
precessing run at 1/4096 s (9,926 samples) ℓ ≤ 4 at 1.5PN 1.67 → 0.98 ms, ℓ ≤ 8 at 3.5PN 4.75 → 3.3 ms, equal
masses precessing (25,220) 4.13 → 2.29 ms, on two cores (tight loops).  The kernel is one compiled function for
every frame (~6.5–7 s to compile on a cold cache).  It holds the block functions of :mod:`~pnrotor.waveform.wigner`
and :func:`pnrotor.quaternion.qrotate_into` (numba caches it per source file): after editing those, remove this
module's ``__pycache__/amplitudes.*.nb*``.
"""

from functools import lru_cache

import numpy as np
from numba import njit

from pnrotor import threads
from pnrotor.quaternion import qrotate_into
from pnrotor.waveform import nonspinning, spin, tidal, wigner
from pnrotor.waveform.layout import mode_index, n_modes
from pnrotor.waveform.memory import terms as memory_terms
from pnrotor.waveform.wigner import (CHUNK, phase_powers, rotate_ell, rotation_scratch, rotor_block,
                                     rotor_rows, store, rotation_plan)

__all__ = ["table", "coorbital_modes", "modes_in_frame", "H0"]

H0 = 8.0 * np.sqrt(np.pi / 5.0)
"""h₀ / (ν v²)."""

_Q_ONE, Q_LOG = 0, 1
_Q_SPIN = {name: 2 + j for j, name in enumerate(spin.BASIS)}
Q_P = _Q_SPIN["P_nn"]
"""The first quadratic quantity: those from here on only if a term needs them."""
N_Q = 2 + len(spin.BASIS)
FRAME_CODES = {"coorbital": 0, "z": 1, "rotors": 2}
"""The frames :func:`_sum` gives the modes in: H, H_ℓm e^{−imΦ} for R = exp(Φẑ/2), 𝔇(R) H."""


NO_TIDES = (0.0, 0.0, -1)
"""``tides`` of a run without them: (Λ₁, Λ₂, the largest power k of a tidal term kept, −1 none)."""
TIDAL_K = 10
"""The tidal terms (:mod:`~pnrotor.waveform.tidal`) are those of k ≥ 10: no other term reaches that power."""


def table(nu, delta, ell_max, order2, spins, tides=NO_TIDES, memory=False):
    """(mode row, power k, quantity index, coefficient, parity) arrays of every term kept, m ≥ 0 (module
    docstring); ``spins`` False leaves the spin terms out; ``tides`` = (Λ₁, Λ₂, k_max) the tidal terms up to v^k_max
    (:data:`NO_TIDES`: none); ``memory`` adds the m = 0 memory terms (:mod:`~pnrotor.waveform.memory`)."""
    row_of = mode_index.py_func   # the plain Python function (a compiled call per term would cost ~1 µs)
    rows = [(row_of(ell, m), k, q, c, parity)
            for ell, m, k, q, c, parity in _terms(nu, delta, ell_max, order2, spins, tides, memory)]
    row, k, q, c, parity = zip(*rows) if rows else ((), (), (), (), ())
    return (np.array(row, dtype=np.int64), np.array(k, dtype=np.int64), np.array(q, dtype=np.int64),
            np.array(c, dtype=np.complex128), np.array(parity, dtype=np.int64))


def _terms(nu, delta, ell_max, order2, spins, tides=NO_TIDES, memory=False):
    """The terms of :func:`table` as a list of Python tuples (ℓ, m, k, q, complex coefficient, parity)."""
    return [(ell, m, k, q, complex(c), parity)
            for ell, m, k, q, c, parity in _source_terms(nu, delta, ell_max, spins, tides, memory)
            if _kept(ell, k, ell_max, order2, tides[2]) and c != 0]


def _kept(ell, k, ell_max, order2, tidal_k):
    """Whether a term of ℓ and v^k is kept: ℓ ≤ ell_max, k ≤ order2, or for a tidal term (k ≥ TIDAL_K) k ≤ tidal_k."""
    return ell <= ell_max and k <= (tidal_k if k >= TIDAL_K else order2)


def _source_terms(nu, delta, ell_max, spins, tides=NO_TIDES, memory=False):
    """(ℓ, m, k, q, coefficient, parity) of every coefficient the sources give for ``ell_max`` (zeros and terms of
    higher ℓ or order too), in their order: per nonspinning (ℓ, m) and k its a_k (q = 1) and b_k (q = ln v), then
    with ``spins`` the symmetric and the antisymmetric spin terms, with tides (k_max ≥ TIDAL_K) the tidal terms,
    with ``memory`` the memory terms.  Which terms these are does not depend on ν, δ or the Λᵢ."""
    out = [(ell, m, k, q, c, 1) for (ell, m), series in nonspinning.terms(nu, delta, ell_max).items()
           for k, a, b in series for q, c in ((_Q_ONE, a), (Q_LOG, b))]
    if spins:
        for parity, group in zip((1, -1), spin.terms(nu, delta)):
            out += [(ell, m, k, _Q_SPIN[name], c, parity) for ell, m, k, name, c in group]
    if tides[2] >= TIDAL_K:
        out += [(ell, m, k, _Q_ONE, c, 1) for ell, m, k, c in tidal.terms(0.5 * (1.0 + delta), *tides[:2])]
    if memory:
        out += [(ell, m, k, _Q_ONE, c, 1) for (ell, m), series in memory_terms(nu).items() for k, c in series]
    return out


def _source_values(nu, delta, ell_max, spins, tides=NO_TIDES, memory=False):
    """The coefficients of :func:`_source_terms` alone, in its order, without its bookkeeping."""
    values = [x for series in nonspinning.terms(nu, delta, ell_max).values() for _, a, b in series for x in (a, b)]
    if spins:
        for group in spin.terms(nu, delta):
            values += [term[4] for term in group]
    if tides[2] >= TIDAL_K:
        values += [term[3] for term in tidal.terms(0.5 * (1.0 + delta), *tides[:2])]
    if memory:
        values += [c for series in memory_terms(nu).values() for _, c in series]
    return values


@lru_cache(maxsize=None)
def _layout(ell_max, order2, spins, folded, tidal_k, memory):
    """What of :func:`_real_terms` depends only on its options (``folded``: spin quantities folded into the
    coefficients): the source coefficients kept (:func:`_source_terms` positions: ℓ ≤ ell_max, k ≤ order2, tidal
    terms to tidal_k); for their real parts, then their imaginary parts, the sum each adds to; the sums' (ℓ,
    target, k, q), sorted; and the spin quantity q ≥ 2 of each kept coefficient (else 0)."""
    n_pow = 2 * ell_max + 1
    kept = [(j, ell, m, k, q, parity) for j, (ell, m, k, q, _, parity) in
            enumerate(_source_terms(0.2, 0.3, ell_max, spins, (1.0, 1.0, tidal_k), memory))
            if _kept(ell, k, ell_max, order2, tidal_k)]
    keys = [(ell, (ell + m if parity > 0 else ell - m) + part * n_pow, k, _Q_ONE if folded and q >= 2 else q)
            for part in (0, 1) for _, ell, m, k, q, parity in kept]
    sums = sorted(set(keys))
    where = {key: i for i, key in enumerate(sums)}
    columns = np.array(sums, dtype=np.int64).reshape(-1, 4).T
    return (np.array([j for j, *_ in kept], dtype=np.int64), np.array([where[key] for key in keys], dtype=np.int64),
            tuple(np.ascontiguousarray(x) for x in columns),
            np.array([q if q >= 2 else 0 for *_, q, _ in kept], dtype=np.int64))


@lru_cache(maxsize=64)
def _real_terms(nu, delta, ell_max, order2, spins, constants, tides=NO_TIDES, memory=False):
    """:func:`table`'s terms as the kernel adds them: (ell_start, target, k, q, c, plan), real terms
    sorted by ℓ (those of ℓ are ell_start[ℓ] : ell_start[ℓ+1]), target the row of the block array (ℓ ± m for
    the real part, 2 ell_max + 1 more for the imaginary part); the spin quantities q ≥ 2 folded into c if
    ``constants`` gives their values (terms with equal target, k and q summed, in the sources' order); plan the
    passes of the rotation, which skip the columns m' where H_ℓ,±m' has no term
    (:func:`pnrotor.waveform.wigner.rotation_plan`).  Sums that vanish (e.g. the odd-m terms of equal masses)
    are no terms.  Cached: a run's modes computed again (another ℓ_max, frame or distance) skip these;
    what depends only on the options is :func:`_layout`'s."""
    n_pow = 2 * ell_max + 1
    kept, into, (ell, target, k, q), spin_q = _layout(ell_max, order2, spins, constants is not None, tides[2], memory)
    c = np.array(_source_values(nu, delta, ell_max, spins, tides, memory), dtype=np.complex128)[kept]
    parts = np.concatenate((c.real, c.imag))
    if constants is not None:
        factor = np.array((1.0,) + constants[1:])[spin_q]   # constants[q] for q ≥ 2, else 1
        parts *= np.concatenate((factor, factor))
    summed = np.bincount(into, weights=parts, minlength=ell.size)   # in order: as a sum term after term
    nonzero = summed != 0.0
    ell, target, k, q, summed = ell[nonzero], target[nonzero], k[nonzero], q[nonzero], summed[nonzero]
    columns = np.zeros((ell_max + 1, ell_max + 1), dtype=np.bool_)
    columns[ell, np.abs(target % n_pow - ell)] = True
    return np.searchsorted(ell, np.arange(ell_max + 2)), target, k, q, summed, rotation_plan(columns)


@njit(cache=True, fastmath={"contract"})
def _add_term(X, t, c, p, k, Q, q, nb):
    """Row t of X += c (row k of p) (row q of Q) (a loop of its own, as the block loops of
    :mod:`pnrotor.waveform.wigner`, on whole arrays and row indices as they are)."""
    for s in range(nb):
        X[t, s] += c * p[k, s] * Q[q, s]


@njit(cache=True, fastmath={"contract"})
def _spin_block(chi, nb, X1, X2, kappa1, kappa2, quadratic, Q):
    """Rows 2 … of Q: the spin basis of :mod:`pnrotor.waveform.spin` from the rows χ₁ₙ, χ₁λ, χ₁ℓ, χ₂ₙ, χ₂λ, χ₂ℓ
    of chi, for nb samples (P and Q, rows 8 …, only if ``quadratic``)."""
    for a in range(3):
        for s in range(nb):
            c1, c2 = chi[a, s], chi[3 + a, s]
            Q[2 + a, s] = X1 * X1 * c1 + X2 * X2 * c2
            Q[5 + a, s] = X2 * c2 - X1 * c1
    if not quadratic:
        return
    for a in range(3):
        for s in range(nb):
            c1, c2 = chi[a, s], chi[3 + a, s]
            Q[8 + a, s] = kappa1 * X1 * X1 * c1 * c1 + 2.0 * X1 * X2 * c1 * c2 + kappa2 * X2 * X2 * c2 * c2
    j = 11
    for a in range(3):
        for b in range(a + 1, 3):   # (n, λ), (n, ℓ), (λ, ℓ)
            for s in range(nb):
                Q[j, s] = 2.0 * (kappa1 * X1 * X1 * chi[a, s] * chi[b, s]
                                 + X1 * X2 * (chi[a, s] * chi[3 + b, s] + chi[b, s] * chi[3 + a, s])
                                 + kappa2 * X2 * X2 * chi[3 + a, s] * chi[3 + b, s])
            j += 1


@njit(cache=True, fastmath={"contract"})
def _sample_block(v, chi1, chi2, R, spins, i0, nb, h0, logs, quadratic, X1, X2, kappa1, kappa2, p, Q, chi, x, c):
    """Of samples i0 … i0+nb−1: p[k] = h₀ v^k (the rows p has), Q[1] = ln v if ``logs``, and with ``spins`` (1:
    co-orbital components given, 2: inertial ones, taken into the frame of R) the spin basis, its quadratic part
    if ``quadratic`` (chi: block scratch; x, c: (3,), a spin and its rotation)."""
    v = v[i0:i0 + nb]   # indexed by the loop's own s (an index i0 + s keeps LLVM from vectorizing a loop)
    for s in range(nb):
        p[0, s] = h0 * v[s] * v[s]
    for k in range(1, p.shape[0]):
        for s in range(nb):
            p[k, s] = p[k - 1, s] * v[s]
    if logs:
        for s in range(nb):
            Q[1, s] = np.log(v[s])
    if not spins:
        return
    for s in range(nb):
        i = i0 + s
        for body in range(2):
            spin = chi1 if body == 0 else chi2
            x[0], x[1], x[2] = spin[i, 0], spin[i, 1], spin[i, 2]
            if spins == 2:
                qrotate_into(R[i, 0], -R[i, 1], -R[i, 2], -R[i, 3], x, c)   # χ' = R⁻¹ χ R
                x[0], x[1], x[2] = c[0], c[1], c[2]
            chi[3 * body, s], chi[3 * body + 1, s], chi[3 * body + 2, s] = x[0], x[1], x[2]
    _spin_block(chi, nb, X1, X2, kappa1, kappa2, quadratic, Q)


@njit(cache=True, fastmath={"contract"})
def _ell_amplitudes(ell, lo, hi, target, k, q, c, p, Q, e_re, e_im, fold, X, nb):
    """Rows ℓ + m of X (real parts; imaginary parts 2 ell_max + 1 rows further) = e^{−imφ} H_ℓm of the block for
    the phase factors e^{−iφ}, e^{−2iφ}, … in rows 1, 2, … of (e_re, e_im), from the real terms lo … hi−1: S_ℓm
    and A_ℓm summed into rows ℓ + m and ℓ − m, then (:func:`_mirror`) H_ℓm = S + A, H_ℓ,−m = (−1)^ℓ (S − A)*
    with their phases in place (with ``fold``, their sums and differences)."""
    n = X.shape[0] // 2
    for r in range(2 * ell + 1):
        for s in range(nb):
            X[r, s] = X[n + r, s] = 0.0
    for j in range(lo, hi):
        _add_term(X, target[j], c[j], p, k[j], Q, q[j], nb)
    sig = 1.0 - 2.0 * (ell % 2)
    for m in range(1, ell + 1):
        _mirror(X, ell + m, ell - m, n, e_re, e_im, m, sig, fold, nb)


@njit(cache=True, fastmath={"contract"})
def _mirror(X, rp, rn, n, e_re, e_im, m, sig, fold, nb):
    """(h, hn) = (e (S + A), e* sig (S − A)*) = (U + V, sig (U − V)*) with U = e S, V = e A, from (S, A) = (h, hn):
    h, hn the rows rp, rn of X (real parts; imaginary parts n rows further), e row m of (e_re, e_im) (a loop of
    its own: LLVM vectorizes it here, not inline); with ``fold``, their sum and difference h ± hn instead, as the
    rotation's first product takes them (:func:`pnrotor.waveform.wigner.rotate_ell`)."""
    for s in range(nb):
        er, ei, sr, si, ar, ai = e_re[m, s], e_im[m, s], X[rp, s], X[n + rp, s], X[rn, s], X[n + rn, s]
        ur, ui, vr, vi = er * sr - ei * si, er * si + ei * sr, er * ar - ei * ai, er * ai + ei * ar
        hr, hi, nr, ni = ur + vr, ui + vi, sig * (ur - vr), sig * (vi - ui)
        if fold:
            X[rp, s], X[n + rp, s], X[rn, s], X[n + rn, s] = hr + nr, hi + ni, hr - nr, hi - ni
        else:
            X[rp, s], X[n + rp, s], X[rn, s], X[n + rn, s] = hr, hi, nr, ni


@njit(cache=True)
def workspace(ell_max, k, B):
    """The block arrays of :func:`block_start` and :func:`block_ell` for ℓ ≤ ell_max and blocks of B samples, as
    one tuple: p (the powers of v up to the highest k of a term), Q (its row 0 and, for the spins of a constant
    run, every row = 1), chi, X, the rotation's (:func:`pnrotor.waveform.wigner.rotation_scratch`) and the unit
    phases one_re, one_im."""
    p = np.empty((1 + (k.max() if k.size else 0), B))
    rq, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im, y_re, y_im, h_re, h_im = rotation_scratch(ell_max, B)
    return (p, np.ones((N_Q, B)), np.empty((6, B)), np.empty((2 * (2 * ell_max + 1), B)), rq, eb_re, eb_im, ea_re,
            ea_im, eg_re, eg_im, y_re, y_im, h_re, h_im, np.ones((ell_max + 1, B)), np.zeros((ell_max + 1, B)))


@njit(cache=True)
def block_start(w, xs, cs, v, chi1, chi2, R, F, spins, frame, h0, logs, quadratic, X1, X2, kappa1, kappa2, i0, nb):
    """What the ℓ of the samples i0 … i0+nb−1 share, into workspace ``w`` (:func:`workspace`): the powers of v and
    the spin quantities (:func:`_sample_block`, the spins taken into the frames of the rotors R; xs, cs its (3,)
    scratch) and the phases of ``frame`` for the rotors F (R, or R seen from another fixed frame): for "rotors" (2)
    those of 𝔇(F) (:func:`pnrotor.waveform.wigner.rotor_block`), for "z" (1) e^{−imΦ}."""
    p, Q, chi, X, rq, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im, y_re, y_im, h_re, h_im, one_re, one_im = w
    _sample_block(v, chi1, chi2, R, spins, i0, nb, h0, logs, quadratic, X1, X2, kappa1, kappa2, p, Q, chi, xs, cs)
    if frame == 2:
        rotor_block(F, i0, nb, rq, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im)
    elif frame == 1:   # e^{−imΦ}: e^{−iΦ} = (w − iz)² / (w² + z²) for R = exp(Φẑ/2) = (w, 0, 0, z)
        rotor_rows(F, i0, nb, rq)
        for s in range(nb):
            a, z = rq[0, s], rq[3, s]
            n2 = a * a + z * z
            eg_re[1, s], eg_im[1, s] = (a * a - z * z) / n2, -2.0 * a * z / n2
        phase_powers(eg_re, eg_im, nb)


@njit(cache=True)
def block_ell(w, ell, frame, ell_start, target, k, q, c, first, rows, coefs, nb):
    """The modes ℓ of the block :func:`block_start` prepared, but their last phases: (o_re, o_im, e_re, e_im) with
    h_ℓm = e_{|m|} o_{ℓ+m} for m ≥ 0 and e*_{|m|} o_{ℓ+m} for m < 0 (what :func:`pnrotor.waveform.wigner.store`
    applies): the amplitudes with the phases of ``frame`` (:func:`_ell_amplitudes`) and, for "rotors", rotated
    (:func:`pnrotor.waveform.wigner.rotate_ell`)."""
    p, Q, chi, X, rq, eb_re, eb_im, ea_re, ea_im, eg_re, eg_im, y_re, y_im, h_re, h_im, one_re, one_im = w
    n = X.shape[0] // 2
    H_re, H_im = X[:n], X[n:]
    # the phases of the amplitudes ((i e^{−iγ})^m', e^{−imΦ} or 1) and of the stored modes ((−i e^{−iα})^m or 1)
    in_re, in_im, out_re, out_im = (eg_re, eg_im, ea_re, ea_im) if frame == 2 else (
        (eg_re, eg_im, one_re, one_im) if frame == 1 else (one_re, one_im, one_re, one_im))
    _ell_amplitudes(ell, ell_start[ell], ell_start[ell + 1], target, k, q, c, p, Q, in_re, in_im, frame == 2, X, nb)
    if frame == 2:
        rotate_ell(ell, first, rows, coefs, eb_re, eb_im, H_re, H_im, y_re, y_im, h_re, h_im, nb)
        return h_re, h_im, out_re, out_im
    return H_re, H_im, out_re, out_im


@njit(cache=True, nogil=True)
def _sum(v, chi1, chi2, R, spins, frame, scale, h0, logs, X1, X2, kappa1, kappa2, ell_max, ell_start, target, k, q,
         c, first, rows, coefs, out, lo, hi):
    """out, a float view (n_modes, 2N) of complex (n_modes, N), = the modes of the samples lo … hi−1 in frame
    ``frame`` (:data:`FRAME_CODES`), a block of samples at a time (lo a multiple of CHUNK gives the blocks of the
    whole range: the same vector and remainder loops, so the same bits), times ``scale`` as they are stored (module
    docstring; the other arguments are :func:`_sample_block`'s, :func:`_real_terms`' and
    :func:`pnrotor.waveform.wigner.rotation_plan`'s)."""
    B = CHUNK
    w = workspace(ell_max, k, B)
    xs, cs = np.empty(3), np.empty(3)
    quadratic = np.any(q >= Q_P)
    for i0 in range(lo, hi, B):
        nb = min(B, hi - i0)
        block_start(w, xs, cs, v, chi1, chi2, R, R, spins, frame, h0, logs, quadratic, X1, X2, kappa1, kappa2, i0,
                     nb)
        for ell in range(2, ell_max + 1):
            o_re, o_im, e_re, e_im = block_ell(w, ell, frame, ell_start, target, k, q, c, first, rows, coefs, nb)
            first_row = mode_index(ell, -ell)
            for r in range(2 * ell + 1):
                store(o_re, o_im, r, e_re, e_im, abs(r - ell), r < ell, scale, out, first_row + r, i0, nb)


def modes_in_frame(v, chi1, chi2, m1, m2, ell_max, order2, kappa1=1.0, kappa2=1.0, R=None, frame="coorbital",
                   scale=1.0, tides=NO_TIDES, memory=False):
    """The modes (n_modes, N) complex, C-contiguous, rows in :func:`~pnrotor.waveform.layout.mode_index` order,
    of samples v (N,) for masses m1, m2 (any unit), ℓ ≤ ell_max and amplitude order order2/2, times ``scale``,
    in ``frame``: "coorbital" (H_ℓm), "rotors" (𝔇(R) H for the orbital-frame rotors R (N, 4)) or "z" (the
    same for rotors about ẑ, R = exp(Φẑ/2): H_ℓm e^{−imΦ}).  Spins chi1, chi2: None (nonspinning), (3,) the
    same at every sample along (n̂, λ̂, ℓ̂), or (N, 3) per sample, along (n̂, λ̂, ℓ̂) or, given R, in the
    inertial frame (projected per sample in the kernel).  ``tides`` = (Λ₁, Λ₂, k_max): the tidal terms of
    :mod:`~pnrotor.waveform.tidal` up to v^k_max (:data:`NO_TIDES`: none); ``memory``: the m = 0 memory terms of
    :mod:`~pnrotor.waveform.memory` (a function of v alone: any block of samples on its own)."""
    if not getattr(_sum, "overloads", True):   # the CLI may be compiling them aside: load them, not compile twice
        from pnrotor import numba_cache

        numba_cache.wait_for_aside("modes")
    v = np.ascontiguousarray(v, dtype=np.float64)
    empty = np.zeros((0, 3))
    constant = chi1 is not None and np.ndim(chi1) == 1
    spins = 0 if chi1 is None or constant else (2 if R is not None else 1)
    terms = kernel_terms(m1, m2, ell_max, order2, kappa1, kappa2, chi1 is not None, (chi1, chi2) if constant else None,
                         tides, memory)
    chi1, chi2 = (empty, empty) if not spins else (np.ascontiguousarray(x, dtype=np.float64) for x in (chi1, chi2))
    R = np.zeros((0, 4)) if R is None else np.ascontiguousarray(R, dtype=np.float64)
    out = np.empty((n_modes(ell_max), v.size), dtype=np.complex128)
    args = (v, chi1, chi2, R, spins, FRAME_CODES[frame], float(scale), *terms, out.view(np.float64))
    threads.run(lambda lo, hi: _sum(*args, lo, hi), threads.parts(v.size, wigner.MIN_PART, CHUNK))
    return out


def kernel_terms(m1, m2, ell_max, order2, kappa1, kappa2, spinning, constant=None, tides=NO_TIDES, memory=False):
    """What the amplitude kernels take of a run besides its samples, frame and scale: (h₀/v², whether a term needs
    ln v, X₁, X₂, κ₁, κ₂, ell_max, then :func:`_real_terms`' ell_start, target, k, q, c and its rotation plan) for
    masses m1, m2 (any unit), ℓ ≤ ell_max, amplitude order order2/2, with spin terms if ``spinning``; ``constant``:
    the spins (χ₁, χ₂) along (n̂, λ̂, ℓ̂) if they are the same at every sample (folded into the coefficients), else
    None (given per sample)."""
    M = m1 + m2
    X1, X2 = m1 / M, m2 / M
    nu, delta = X1 * X2, X1 - X2
    constants = None
    if constant is not None:
        Q = np.ones((N_Q, 1))
        _spin_block(np.concatenate(constant).astype(np.float64).reshape(6, 1), 1, X1, X2, float(kappa1),
                    float(kappa2), True, Q)
        constants = tuple(Q[:, 0].tolist())
    ell_start, target, k, q, c, plan = _real_terms(nu, delta, int(ell_max), int(order2), bool(spinning), constants,
                                                   tuple(tides), bool(memory))
    return (H0 * nu, bool(np.any(q == Q_LOG)), X1, X2, float(kappa1), float(kappa2), int(ell_max), ell_start, target,
            k, q, c, *plan)


def compile_kernels():
    """Compile the kernels of :func:`modes_in_frame` (or load them from numba's cache) with a one-sample call: every
    run gives them the same types (spins, frames and orders are values, the arrays C-contiguous float64).  What
    :func:`pnrotor.numba_cache.compile_aside` runs in another process for a CLI run whose modes it writes, on a cold
    cache, so that they compile beside the run, not after it."""
    modes_in_frame(np.full(1, 0.3), np.zeros(3), np.zeros(3), 1.0, 1.0, 2, 0, R=np.array([[1.0, 0.0, 0.0, 0.0]]),
                   frame="rotors")


def coorbital_modes(v, chi1, chi2, m1, m2, ell_max, order2, kappa1=1.0, kappa2=1.0, R=None, tides=NO_TIDES,
                    memory=False):
    """H_ℓm (n_modes, N) complex, C-contiguous, rows in :func:`~pnrotor.waveform.layout.mode_index` order, of
    samples v (N,) with spins chi1, chi2 (N, 3) along (n̂, λ̂, ℓ̂) (None for a nonspinning run) — or, given the
    orbital-frame rotors R (N, 4), in the inertial frame, projected per sample in the kernel (no temporary
    arrays) — masses m1, m2 (any unit), ℓ ≤ ell_max, amplitude order order2/2, ``tides`` and ``memory`` as
    :func:`modes_in_frame`'s."""
    return modes_in_frame(v, chi1, chi2, m1, m2, ell_max, order2, kappa1, kappa2, R=R, tides=tides, memory=memory)
