r"""Co-orbital mode amplitudes H_ℓm at every sample: the terms of the sources, as one table, in numba.

Every term of :mod:`~pnrotor.waveform.nonspinning` and :mod:`~pnrotor.waveform.spin` has the form
h₀ v^k c q with h₀ = 8 √(π/5) ν v², a complex coefficient c fixed by the masses and q a real quantity
of the sample (1, ln v, or one of the spin quantities of :data:`pnrotor.waveform.spin.BASIS`).  For a
run, :func:`table` keeps the terms of the modes ℓ ≤ ell_max up to the amplitude order (k ≤ 2 × order),
adds the m < 0 partners (H_ℓ,−m = ±(−1)^ℓ H*_ℓm, + for nonspinning and symmetric spin terms, − for
the antisymmetric ones), and :func:`coorbital_modes` sums them per sample in one compiled pass: no
term is evaluated for a mode or an order nobody asked for, and no spin quantity for a nonspinning run.
For a precessing run the kernel also takes the spins from the inertial frame into the orbital frame of
each sample's rotor R (χ' = R⁻¹ χ R) and writes H with each mode's samples contiguous, the layout
:func:`pnrotor.waveform.wigner.rotate_modes` reads (else each sample's modes, for rotate_about_z).
"""

import numpy as np
from numba import njit

from pnrotor.quaternion import qrotate_into
from pnrotor.waveform import nonspinning, spin
from pnrotor.waveform.layout import mode_index, n_modes

__all__ = ["table", "coorbital_modes", "H0"]

H0 = 8.0 * np.sqrt(np.pi / 5.0)
"""h₀ / (ν v²)."""

_Q_ONE, _Q_LOG = 0, 1
_Q_SPIN = {name: 2 + j for j, name in enumerate(spin.BASIS)}
N_Q = 2 + len(spin.BASIS)


def table(nu, delta, ell_max, order2, spins):
    """(mode row, power k, quantity index, coefficient) arrays of every term kept (module docstring);
    ``spins`` False leaves the spin terms out."""
    rows = []

    def add(ell, m, k, q, c, parity):
        if ell <= ell_max and k <= order2 and c != 0:
            rows.append((mode_index(ell, m), k, q, complex(c)))
            if m:
                rows.append((mode_index(ell, -m), k, q, parity * (-1) ** ell * complex(c).conjugate()))

    for (ell, m), series in nonspinning.terms(nu, delta).items():
        for k, a, b in series:
            add(ell, m, k, _Q_ONE, a, 1)
            add(ell, m, k, _Q_LOG, b, 1)
    if spins:
        symmetric, antisymmetric = spin.terms(nu, delta)
        for parity, group in ((1, symmetric), (-1, antisymmetric)):
            for ell, m, k, name, c in group:
                add(ell, m, k, _Q_SPIN[name], c, parity)
    row, k, q, c = zip(*rows) if rows else ((), (), (), ())
    return (np.array(row, dtype=np.int64), np.array(k, dtype=np.int64), np.array(q, dtype=np.int64),
            np.array(c, dtype=np.complex128))


@njit(cache=True)
def _quantities(v, chi1, chi2, i, X1, X2, kappa1, kappa2, spins, out):
    """The quantities q of sample i (1, ln v and the spin basis of :mod:`pnrotor.waveform.spin`) into out."""
    out[0] = 1.0
    out[1] = np.log(v[i])
    if not spins:
        return
    c1, c2 = chi1[i], chi2[i]
    for a in range(3):
        out[2 + a] = X1 * X1 * c1[a] + X2 * X2 * c2[a]
        out[5 + a] = X2 * c2[a] - X1 * c1[a]
        out[8 + a] = kappa1 * X1 * X1 * c1[a] * c1[a] + 2.0 * X1 * X2 * c1[a] * c2[a] + kappa2 * X2 * X2 * c2[a] * c2[a]
    j = 11
    for a in range(3):
        for b in range(a + 1, 3):   # (n, λ), (n, ℓ), (λ, ℓ)
            out[j] = 2.0 * (kappa1 * X1 * X1 * c1[a] * c1[b] + X1 * X2 * (c1[a] * c2[b] + c1[b] * c2[a])
                            + kappa2 * X2 * X2 * c2[a] * c2[b])
            j += 1


@njit(cache=True)
def _sum_terms(v, chi1, chi2, nu, X1, X2, kappa1, kappa2, spins, row, k, q, c, H):
    quantities = np.empty(N_Q)
    powers = np.empty(8)
    for i in range(v.size):
        _quantities(v, chi1, chi2, i, X1, X2, kappa1, kappa2, spins, quantities)
        _add_terms(v[i], nu, quantities, powers, row, k, q, c, H, i)


@njit(cache=True, inline="always")
def _add_terms(vi, nu, quantities, powers, row, k, q, c, H, i):
    """H[i, row[j]] += c[j] h₀ v^k[j] quantities[q[j]] for every term j of the table (powers: scratch)."""
    powers[0] = H0 * nu * vi * vi
    for p in range(1, 8):
        powers[p] = powers[p - 1] * vi
    for j in range(row.size):
        H[i, row[j]] += c[j] * (powers[k[j]] * quantities[q[j]])


@njit(cache=True)
def _sum_terms_rotated(v, chi1, chi2, R, nu, X1, X2, kappa1, kappa2, row, k, q, c, H):
    """_sum_terms for inertial spins and rotors R, into H (n_modes, N): per sample the spins are taken into
    the frame of R[i]; a block of samples is summed [sample, row] and copied out row by row (contiguous
    writes of H)."""
    quantities = np.empty(N_Q)
    powers = np.empty(8)
    c1, c2 = np.empty((1, 3)), np.empty((1, 3))
    B = 256
    block = np.zeros((B, H.shape[0]), dtype=np.complex128)
    for i0 in range(0, v.size, B):
        nb = min(B, v.size - i0)
        for s in range(nb):
            i = i0 + s
            w, x, y, z = R[i, 0], R[i, 1], R[i, 2], R[i, 3]
            qrotate_into(w, -x, -y, -z, chi1[i], c1[0])   # χ' = R⁻¹ χ R
            qrotate_into(w, -x, -y, -z, chi2[i], c2[0])
            _quantities(v[i:i + 1], c1, c2, 0, X1, X2, kappa1, kappa2, True, quantities)
            _add_terms(v[i], nu, quantities, powers, row, k, q, c, block, s)
        for r in range(H.shape[0]):
            for s in range(nb):
                H[r, i0 + s] = block[s, r]
                block[s, r] = 0.0


def coorbital_modes(v, chi1, chi2, m1, m2, ell_max, order2, kappa1=1.0, kappa2=1.0, R=None):
    """H_ℓm (n_modes, N) complex, rows in :func:`~pnrotor.waveform.layout.mode_index` order, of
    samples v (N,) with spins chi1, chi2 (N, 3) along (n̂, λ̂, ℓ̂) (None for a nonspinning run) — or, given the
    orbital-frame rotors R (N, 4), in the inertial frame, projected per sample in the kernel (no temporary
    arrays) — masses m1, m2 (any unit), ℓ ≤ ell_max and amplitude order order2/2.  With R the array is
    C-contiguous (each mode's samples contiguous), else the transpose of an (N, n_modes) one."""
    M = m1 + m2
    X1, X2 = m1 / M, m2 / M
    nu, delta = X1 * X2, X1 - X2
    spins = chi1 is not None
    if not spins:
        chi1 = chi2 = np.zeros((0, 3))   # not read
    v = np.ascontiguousarray(v, dtype=np.float64)
    chi1, chi2 = np.ascontiguousarray(chi1, dtype=np.float64), np.ascontiguousarray(chi2, dtype=np.float64)
    terms = table(nu, delta, ell_max, order2, spins)
    if R is not None and spins:   # each mode's samples contiguous (what rotate_modes reads)
        H = np.zeros((n_modes(ell_max), v.size), dtype=np.complex128)
        _sum_terms_rotated(v, chi1, chi2, np.ascontiguousarray(R, dtype=np.float64), nu, X1, X2, float(kappa1),
                           float(kappa2), *terms, H)
        return H
    H = np.zeros((v.size, n_modes(ell_max)), dtype=np.complex128)   # each sample's modes contiguous
    _sum_terms(v, chi1, chi2, nu, X1, X2, float(kappa1), float(kappa2), spins, *terms, H)
    return H.T
