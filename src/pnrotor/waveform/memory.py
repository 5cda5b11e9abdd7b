r"""The nonlinear (displacement) memory of the m = 0 modes: Favata's closed form through 3PN.

The gravitational-wave memory is sourced by the waves' own energy flux,

    h^mem_ℓm(t) = −r √((ℓ−2)!/(ℓ+2)!) ∫_{−∞}^{t} dt' ∮ dΩ |ḣ(t', Ω)|² Y*_ℓm(Ω),   ḣ = Σ ḣ_ℓ'm' ₋₂Y_ℓ'm'

(Favata 2009, arXiv:0812.0069, Sec. II, with h = h₊ − ih× = Σ h_ℓm ₋₂Y_ℓm; the minus sign is LALSuite's
mode convention, the negative of Favata's and Blanchet's, as in :mod:`~pnrotor.waveform.nonspinning`).  For a
quasi-circular, nonprecessing inspiral it grows monotonically with the radiated energy and lives in the m = 0
modes; Favata integrates it in closed form as a function of v (his Eq. (4.3), through 3PN), which is what this
module gives, as co-orbital amplitude terms (ν v² h₀-normalized like every other term, h₀ = 8 √(π/5) ν v²):

    H₂₀ = −5/(14√6) h₀ [1 + v²(−4075/4032 + 67ν/48) + …],    H₄₀ = −1/(504√2) h₀ [1 + …],
    H₆₀ = 4195/(1419264√273) h₀ [v²(1 − 3612ν/839) + …],     H₈₀ = −75601/(213497856√119) h₀ [v⁴(…) + …],

the coefficients as PostNewtonian.jl's mode weights transcribe Favata's Eqs. (4.3a)–(4.3d).

Convention for the start of the run: the closed form is the memory accumulated since t → −∞ (infinite
separation), not since the run's first sample, so the m = 0 modes start at H_ℓ0(v₀) ≠ 0.  The memory of the
run's own span is h_ℓ0(t) − h_ℓ0(t₀) (subtract the first sample).  Being a function of v alone, the memory needs
no integral over the run: every sample (and every block of a streamed run) is computed on its own.  For a
precessing run the co-orbital terms are rotated with the current frame, which assumes the memory grew along the
current ℓ̂: exact for nonprecessing binaries, an approximation of the order of the precession's angle otherwise.

Checked (tests/test_waveform_memory.py): its rate along a T4 run equals the integrand above evaluated numerically
from pnrotor's own oscillatory modes (ℓ ≤ 8, amplitude order 3; the angular integral by quadrature), their relative
difference vanishing as v⁷, beyond the 3PN of both.
"""

import math

__all__ = ["terms"]

_PI = math.pi
_SQ = math.sqrt


def terms(nu):
    """{(ℓ, 0): [(k, a_k), …]}: the memory's H_ℓ0 = h₀ Σ_k a_k v^k, ℓ = 2, 4, 6, 8 (module docstring)."""
    n, pi = nu, _PI
    c20, c40 = -5.0 / (14.0 * _SQ(6.0)), -1.0 / (504.0 * _SQ(2.0))
    c60, c80 = 4195.0 / (1419264.0 * _SQ(273.0)), -75601.0 / (213497856.0 * _SQ(119.0))
    return {
        # Favata 2009, Eq. (4.3a)
        (2, 0): [(k, c20 * a) for k, a in (
            (0, 1.0), (2, -4075 / 4032 + 67 * n / 48),
            (4, -151877213 / 67060224 - 123815 * n / 44352 + 205 * n * n / 352),
            (5, (-253 / 336 + 253 * n / 84) * pi),
            (6, -4397711103307 / 532580106240 + (700464542023 / 13948526592 - 205 * pi * pi / 96) * n
             + 69527951 * n * n / 166053888 + 1321981 * n * n * n / 5930496))],
        # Favata 2009, Eq. (4.3b)
        (4, 0): [(k, c40 * a) for k, a in (
            (0, 1.0), (2, -180101 / 29568 + 27227 * n / 1056),
            (4, 2201411267 / 158505984 - 34829479 * n / 432432 + 844951 * n * n / 27456),
            (5, (-13565 / 1232 + 13565 * n / 308) * pi),
            (6, 15240463356751 / 781117489152 + (-1029744557245 / 27897053184 - 205 * pi * pi / 96) * n
             - 4174614175 * n * n / 36900864 + 221405645 * n * n * n / 11860992))],
        # Favata 2009, Eq. (4.3c)
        (6, 0): [(k, c60 * a) for k, a in (
            (2, 1 - 3612 * n / 839),
            (4, -45661561 / 6342840 + 101414 * n / 2517 - 48118 * n * n / 839),
            (5, (1248 / 839 - 4992 * n / 839) * pi),
            (6, 3012132889099 / 144921208320 - 27653500031 * n / 191694720 + 1317967427 * n * n / 4107744
             - 24793657 * n * n * n / 342312))],
        # Favata 2009, Eq. (4.3d)
        (8, 0): [(k, c80 * a) for k, a in (
            (4, 1 - 452070 * n / 75601 + 733320 * n * n / 75601),
            (6, -265361599 / 33869248 + 18177898147 * n / 321757856 - 722521125 * n * n / 5745676
             + 261283995 * n * n * n / 2872838))],
    }
