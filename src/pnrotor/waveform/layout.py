"""How modes are stored: one row per (ℓ, m), ℓ = 2 … ℓ_max and, within each ℓ, m = −ℓ … ℓ.

Row k of a (n_modes, N) array holds h_ℓm with k = ℓ(ℓ+1) + m − 4 (:func:`mode_index`), so ℓ's rows start
at ℓ² − 4 and there are (ℓ_max+1)² − 4 rows in all (21 for ℓ_max = 4, 77 for ℓ_max = 8): the order of
LALSuite's and the SXS mode arrays from ℓ = 2.
"""

from numba import njit

__all__ = ["mode_index", "n_modes", "ell_m"]


@njit(cache=True)
def mode_index(ell, m):
    """Row of (ℓ, m): ℓ(ℓ+1) + m − 4."""
    return ell * (ell + 1) + m - 4


def n_modes(ell_max):
    """Rows for ℓ = 2 … ell_max: (ell_max+1)² − 4."""
    return (ell_max + 1) ** 2 - 4


def ell_m(ell_max):
    """The (ℓ, m) of every row, in order."""
    return [(ell, m) for ell in range(2, ell_max + 1) for m in range(-ell, ell + 1)]
