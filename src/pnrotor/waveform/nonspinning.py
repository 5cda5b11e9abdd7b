r"""Nonspinning co-orbital mode amplitudes H_ℓm of a quasi-circular binary, through 3PN (4PN for (2,2)).

In the co-orbital frame (ẑ = ℓ̂, x̂ = n̂ pointing from body 2 to body 1) the modes are

    H_ℓm = h₀ Σ_k v^k (a_k + b_k ln v),     h₀ = 2ν v² √(16π/5) = 8 √(π/5) ν v²   (units r h / M),

and :func:`terms` gives the (k, a_k, b_k) of every (ℓ, m ≥ 0) for a mass ratio (ν, δ = (m₁ − m₂)/M);
m < 0 follows from H_ℓ,−m = (−1)^ℓ H*_ℓm.  Signs are LALSuite's (h₂₂ = +|h₂₂| e^{−2iΦ}; Kidder's and
Blanchet's modes are the negatives of these, as in LALSuite's
``XLALCreateSimInspiralPNModeCOMPLEX16TimeSeriesLALConvention``).

Sources: Blanchet, Faye, Iyer & Sinha 2008 (arXiv:0802.1249, the Ĥ_ℓm through 3PN for ℓ ≤ 8;
reviewed in Blanchet's Living Review 2014), for (2,2) at 3.5PN Faye, Marsat, Blanchet & Iyer 2012
(arXiv:1210.2339) and at 4PN Blanchet, Faye, Henry, Larrouturou & Trestini 2023 (arXiv:2304.11186,
Eq. (6.17), as transcribed by PostNewtonian.jl's mode weights, with ln(16x) = 4 ln 2 + 2 ln v); the
coefficients as collected in Boyle et al. 2014
(arXiv:1409.4431, Eqs. (A5)) and PostNewtonian.jl's mode weights, except (2,2) at 3.5PN, where that
collection has −2459/378 for the −2495/378 of Faye et al.  Checked (tests/test_waveform_amplitudes.py)
against the PN energy flux of :mod:`pnrotor.pn.flux`, coefficient by coefficient through 3.5PN (which
is how the −2459/378 showed; the 4PN (2,2) term at equal masses, where the odd-m modes vanish and every
other mode that reaches the 4PN flux is known), and against LALSuite's SpinTaylor modes through 1.5PN for ℓ ≤ 4
(tests/test_waveform_lal.py).  LALSuite's separate ``XLALSimInspiralPNMode{ℓ}{m}`` (Kidder 2008,
arXiv:0710.0614) agree term by term to ≤ 8e-15 for ℓ ≤ 6 but for these (tests/test_waveform_nonspinning.py,
which also shows ours right each time): no 3PN term in the odd-m modes and (3,2); the 1PN corrections of
(4,2), (4,3), (4,4) with the opposite sign; (3,3)'s 2PN ν² term with the opposite sign; an extra
8(1 − 3ν) ln 2 in (4,2)'s 1.5PN tail term; no factor i in (4,3); (5,3) −√(2/3) times ours;
(6,6)'s 1PN factor in (6,4); and the m = 0 memory constants (a placeholder 1.0 for (6,0)).

Left out, on purpose:

* the nonlinear memory: the slowly growing m = 0 parts of H₂₀, H₄₀, H₆₀, H₈₀ (Favata 2008,
  arXiv:0812.0069), which LALSuite's SpinTaylor modes also omit; H₃₀'s oscillatory-free 2.5PN term
  −(2/5) i √(6/7) ν v⁵ h₀ is kept;
* the tail phase: Blanchet writes the modes with ψ = Φ − 3 v³ (1 − ν v²/2) ln(v²/v₀²); pnrotor, like
  LALSuite's SpinTaylor modes and PostNewtonian.jl, uses the orbital phase Φ itself, so the 1.5PN
  ln-phase is not applied (the 3PN amplitude logarithms, b_k, are kept);
* the 3.5PN (v⁷) terms of the odd-m modes ((2,1): Henry, Faye & Blanchet 2022, arXiv:2210.15602; (3,1),
  (3,3): Faye, Blanchet & Iyer 2015, arXiv:1409.3546), which amplitude order 3.5 and 4 would take: not
  checked here (the 4PN flux of unequal masses needs the (2,1) term, which we have no transcription of).
"""

import math

__all__ = ["terms"]

_GAMMA_E = 0.5772156649015329
_LN2 = math.log(2.0)
_LN32 = math.log(1.5)
_LN52 = math.log(2.5)
_PI = math.pi
_SQ = math.sqrt


def terms(nu, delta, ell_max=8):
    """{(ℓ, m): [(k, a_k, b_k), …]} for m ≥ 0, ℓ ≤ 8 (those of ℓ ≥ 5 only if ell_max ≥ 5): H_ℓm = h₀ Σ_k v^k (a_k +
    b_k ln v) (module docstring)."""
    modes = _up_to_4(nu, delta)
    if ell_max >= 5:
        modes.update(_from_5(nu, delta))
    return modes


def _up_to_4(nu, delta):
    """:func:`terms` of ℓ ≤ 4."""
    n, d, pi, i = nu, delta, _PI, 1j
    return {
        (2, 1): [(1, i * d / 3, 0), (3, i * d * (-17 + 20 * n) / 84, 0), (4, d * (1 + 2 * i * pi + 4 * _LN2) / 6, 0),
                 (5, i * d * (-172 + n * (-2036 + 237 * n)) / 1512, 0),
                 (6, d * (-34 * i * pi - 17 * (1 + 4 * _LN2) + 2 * n * (353 + 6 * i * pi + 12 * _LN2)) / 168, 0)],
        (2, 2): [(0, 1, 0), (2, (-107 + 55 * n) / 42, 0), (3, 2 * pi, 0),
                 (4, (-2173 + n * (-7483 + 2047 * n)) / 1512, 0),
                 (5, -24 * i * n + (-107 + 34 * n) * pi / 21, 0),
                 (6, 27027409 / 646800 - 856 * _GAMMA_E / 105 + n * (-834555 + n * (-729396 + 114635 * n)) / 99792
                  + 41 * n * pi ** 2 / 96 + 2 * pi * (214 * i + 35 * pi) / 105 - 1712 * _LN2 / 105, -856 / 105),
                 # Faye et al. 2012 as quoted in Blanchet's Living Review 2014; PostNewtonian.jl's transcription
                 # has −2459/378 for −2495/378 (tests/test_waveform_amplitudes.py: the 3.5PN flux needs −2495)
                 (7, -2173 * pi / 756 + (-2495 * pi / 378 + 14333 * i / 162) * n + (40 * pi / 27 - 4066 * i / 945) * n ** 2,
                  0),
                 # 4PN: Blanchet et al. 2023, arXiv:2304.11186, Eq. (6.17) (PostNewtonian.jl's transcription); the
                 # ln(16x) = 4 ln 2 + 2 ln v of its 45796/2205 and 15284/441 ν terms taken apart
                 (8, -846557506853 / 12713500800 + 45796 * _GAMMA_E / 2205 - 22898 * i * pi / 2205 - 107 * pi ** 2 / 63
                  + 91592 * _LN2 / 2205
                  + (-336005827477 / 4237833600 + 15284 * _GAMMA_E / 441 - 219314 * i * pi / 2205
                     - 9755 * pi ** 2 / 32256 + 30568 * _LN2 / 441) * n
                  + (256450291 / 7413120 - 1025 * pi ** 2 / 1008) * n ** 2 - 81579187 * n ** 3 / 15567552
                  + 26251249 * n ** 4 / 31135104,
                  45796 / 2205 + 15284 * n / 441)],
        (3, 0): [(5, -2 * i * _SQ(6 / 7) * n / 5, 0)],
        (3, 1): [(1, i * d / (12 * _SQ(14)), 0), (3, -i * d * (4 + n) / (18 * _SQ(14)), 0),
                 (4, d * (7 + 5 * i * pi + 10 * _LN2) / (60 * _SQ(14)), 0),
                 (5, -i * d * (-607 + n * (272 + 247 * n)) / (2376 * _SQ(14)), 0),
                 (6, d * (-5 * i * (16 + 7 * n) * pi + 2 * (-56 + n - 5 * (16 + 7 * n) * _LN2)) / (360 * _SQ(14)), 0)],
        (3, 2): [(2, _SQ(5 / 7) * (1 - 3 * n) / 3, 0), (4, (-193 + (145 - 73 * n) * 5 * n) / (54 * _SQ(35)), 0),
                 (5, (-15 * i + 66 * i * n + 10 * pi - 30 * pi * n) / (3 * _SQ(35)), 0),
                 (6, (-1451 + (-17387 + 3 * (33342 - 5341 * n) * n) * n) / (2376 * _SQ(35)), 0)],
        (3, 3): [(1, -3 * i * _SQ(15 / 224) * d, 0), (3, -3 * i * _SQ(15 / 56) * d * (-2 + n), 0),
                 (4, _SQ(243 / 70) * d * (-7 - 5 * i * pi + 10 * _LN32) / 4, 0),
                 (5, -i * _SQ(3 / 542080) * d * (369 + (-3676 + 887 * n) * n), 0),
                 (6, d * (-3645 * i * (-8 + 3 * n) * pi + (40824 - 96206 * n + 7290 * (-8 + 3 * n) * _LN32))
                  / (216 * _SQ(210)), 0)],
        (4, 1): [(3, i * d * (1 - 2 * n) / (84 * _SQ(10)), 0),
                 (5, -i * d * (404 + (-1011 + 332 * n) * n) / (11088 * _SQ(10)), 0),
                 (6, d * (64 - 1661 * n - 30 * i * (-1 + 2 * n) * pi + 60 * (1 - 2 * n) * _LN2) / (2520 * _SQ(10)), 0)],
        (4, 2): [(2, _SQ(5) * (1 - 3 * n) / 63, 0), (4, (-1311 + 5 * (805 - 57 * n) * n) / (4158 * _SQ(5)), 0),
                 (5, (-21 * i + n * (84 * i - 30 * pi) + 10 * pi) / (63 * _SQ(5)), 0),
                 (6, (9342351 + 7 * n * (-5460759 + 115 * n * (34822 + 3363 * n))) / (22702680 * _SQ(5)), 0)],
        (4, 3): [(3, 9 * i * d * (-1 + 2 * n) / (4 * _SQ(70)), 0),
                 (5, 3 * i * d * (468 + (-1267 + 524 * n) * n) / (176 * _SQ(70)), 0),
                 (6, d * (-5184 + 16301 * n + 2430 * i * (-1 + 2 * n) * pi + 4860 * (1 - 2 * n) * _LN32)
                  / (360 * _SQ(70)), 0)],
        (4, 4): [(2, 8 * _SQ(5 / 7) * (-1 + 3 * n) / 9, 0),
                 (4, 4 * (1779 + 5 * n * (-1273 + 525 * n)) / (297 * _SQ(35)), 0),
                 (5, (160 * (-1 + 3 * n) * pi + i * (336 - 1193 * n + 320 * (-1 + 3 * n) * _LN2)) / (9 * _SQ(35)), 0),
                 (6, (-9618039 + 7 * n * (9793071 + 5 * n * (-3231338 + 678291 * n))) / (405405 * _SQ(35)), 0)],
    }


def _from_5(nu, delta):
    """:func:`terms` of ℓ = 5 … 8."""
    n, d, pi, i = nu, delta, _PI, 1j
    # factors shared by the modes of ℓ ≥ 5
    p5 = 1.0 + 5.0 * (-1.0 + n) * n
    p7 = -1.0 + (-1.0 + n) ** 2 * 7.0 * n
    q3 = d * (-1.0 + n) * (-1.0 + 3.0 * n)
    return {
        (5, 1): [(3, i * d * (1 - 2 * n) / (288 * _SQ(385)), 0),
                 (5, -i * d * (179 + 4 * (-88 + n) * n) / (11232 * _SQ(385)), 0),
                 (6, d * (181 - 70 * i * (-1 + 2 * n) * pi + 140 * _LN2 - 28 * n * (313 + 10 * _LN2))
                  / (20160 * _SQ(385)), 0)],
        (5, 2): [(4, 2 * p5 / (27 * _SQ(55)), 0),
                 (6, (-3911 + 7 * n * (3079 + 35 * n * (-118 + 33 * n))) / (12285 * _SQ(55)), 0)],
        (5, 3): [(3, 9 * i * _SQ(3 / 110) * d * (-1 + 2 * n) / 32, 0),
                 (5, 3 * i * _SQ(3 / 110) * d * (207 + 8 * n * (-58 + 11 * n)) / 416, 0),
                 (6, d * (-395847 + 1171828 * n + 153090 * i * (-1 + 2 * n) * pi - 306180 * (-1 + 2 * n) * _LN32)
                  / (60480 * _SQ(330)), 0)],
        (5, 4): [(4, -32 * p5 / (9 * _SQ(165)), 0),
                 (6, 16 * (4451 - 7 * n * (3619 + 5 * n * (-1042 + 339 * n))) / (4095 * _SQ(165)), 0)],
        (5, 5): [(3, -625 * i * d * (-1 + 2 * n) / (96 * _SQ(66)), 0),
                 (5, -625 * i * d * (263 + 16 * n * (-43 + 16 * n)) / (3744 * _SQ(66)), 0),
                 (6, d * (565625 - 1481676 * n - 218750 * i * (-1 + 2 * n) * pi + 437500 * (-1 + 2 * n) * _LN52)
                  / (6720 * _SQ(66)), 0)],
        (6, 1): [(5, i * q3 / (8316 * _SQ(26)), 0)],
        (6, 2): [(4, 2 * p5 / (297 * _SQ(65)), 0),
                 (6, (-81 + (59 + (-64 + 7 * n) * n) * 7 * n) / (2079 * _SQ(65)), 0)],
        (6, 3): [(5, -81 * i * q3 / (616 * _SQ(65)), 0)],
        (6, 4): [(4, -128 * _SQ(2 / 39) * p5 / 495, 0),
                 (6, -64 * _SQ(2 / 39) * (-93 + 7 * (71 + (-88 + 19 * n) * n) * n) / 3465, 0)],
        (6, 5): [(5, 3125 * i * q3 / (504 * _SQ(429)), 0)],
        (6, 6): [(4, 54 * p5 / (5 * _SQ(143)), 0),
                 (6, 27 * (-113 + 7 * (91 + (-128 + 39 * n) * n) * n) / (35 * _SQ(143)), 0)],
        (7, 1): [(5, i * q3 / (864864 * _SQ(2)), 0)],
        (7, 2): [(6, -p7 / (3003 * _SQ(3)), 0)],
        (7, 3): [(5, -243 * i * _SQ(3 / 2) * q3 / 160160, 0)],
        (7, 4): [(6, 128 * _SQ(2 / 33) * p7 / 1365, 0)],
        (7, 5): [(5, 15625 * i * q3 / (26208 * _SQ(66)), 0)],
        (7, 6): [(6, -81 * _SQ(3 / 143) * p7 / 35, 0)],
        (7, 7): [(5, -16807 * i * _SQ(7 / 858) * q3 / 1440, 0)],
        (8, 2): [(6, -p7 / (9009 * _SQ(85)), 0)],
        (8, 4): [(6, 128 * _SQ(2 / 187) * p7 / 4095, 0)],
        (8, 6): [(6, -243 * _SQ(3 / 17017) * p7 / 35, 0)],
        (8, 8): [(6, 16384 * _SQ(2 / 85085) * p7 / 63, 0)],
    }
