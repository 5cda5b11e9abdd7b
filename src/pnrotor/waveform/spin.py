r"""Spin terms of the co-orbital mode amplitudes H_ℓm, for precessing spins, through 2PN.

With the spins' components along the co-orbital axes a ∈ (n̂, λ̂, ℓ̂) (n̂ from body 2 to body 1,
λ̂ = ℓ̂ × n̂) and X_i = m_i/M, the terms are written in

    S_a = X₁² χ₁ₐ + X₂² χ₂ₐ          (S/M², S = S₁ + S₂)
    Σ_a = X₂ χ₂ₐ − X₁ χ₁ₐ            (Σ/M², Σ = M (S₂/m₂ − S₁/m₁))
    P_aa = s⁺ₐ s⁻ₐ,  Q_ab = s⁺ₐ s⁻_b + s⁺_b s⁻ₐ

with s^± = S₀^±/M² of Buonanno, Faye & Hinderer 2013 (arXiv:1209.6349, Eq. (3.4)), whose products are,
for any spin-induced quadrupole parameters κᵢ (κ = 1 for black holes),

    P_aa = κ₁ X₁² χ₁ₐ² + 2 X₁ X₂ χ₁ₐ χ₂ₐ + κ₂ X₂² χ₂ₐ²,
    Q_ab = 2 [κ₁ X₁² χ₁ₐ χ₁_b + X₁ X₂ (χ₁ₐ χ₂_b + χ₁_b χ₂ₐ) + κ₂ X₂² χ₂ₐ χ₂_b].

H_ℓm += h₀ v^k c q with h₀ = 8 √(π/5) ν v² and q one of these basis quantities; :func:`terms` lists
(ℓ, m, k, q, c).  The terms come in two kinds under reflection through the orbital plane: ``symmetric``
ones, for which H_ℓ,−m = (−1)^ℓ H*_ℓm as for nonspinning binaries (they depend on S_ℓ, Σ_ℓ and the
quadratic P, Q_nλ), and ``antisymmetric`` ones (linear in the in-plane S_n, S_λ, Σ_n, Σ_λ, or Q_nℓ,
Q_λℓ), for which H_ℓ,−m = −(−1)^ℓ H*_ℓm; these exist only for precessing spins.

Sources, as collected in Boyle et al. 2014 (arXiv:1409.4431, Eqs. (A5)) and PostNewtonian.jl's mode
weights, which cite: 1PN spin-orbit, Kidder 1995 (Phys. Rev. D 52, 821) Eq. (3.22d); 1.5PN
spin-orbit, Kidder 1995 Eq. (3.22f) and Will & Wiseman 1996 (Phys. Rev. D 54, 4813) Eq. (F15b); 2PN
spin-orbit and spin-spin, Buonanno, Faye & Hinderer 2013, Eqs. (4.13) and (4.15).  Signs are
LALSuite's.  Checked against the PN flux for aligned spins through 2PN, κ included
(tests/test_waveform_amplitudes.py), and against LALSuite's SpinTaylor modes (Arun et al. 2009,
arXiv:0810.5336, App. B) through 1.5PN for precessing binaries (tests/test_waveform_lal.py), where
LALSuite's ℓ = 3 spin terms come out twice too large: ``XLALSimInspiralSpinPNMode3m`` sums the two
spins where its ℓ = 2 twin (and the formula) averages them.
"""

import math

__all__ = ["BASIS", "terms"]

BASIS = ("S_n", "S_lambda", "S_ell", "Sigma_n", "Sigma_lambda", "Sigma_ell",
         "P_nn", "P_lambdalambda", "P_ellell", "Q_nlambda", "Q_nell", "Q_lambdaell")
"""The per-sample spin quantities the terms multiply, in this order (module docstring)."""

_SQ = math.sqrt


def terms(nu, delta):
    """(symmetric, antisymmetric): lists of (ℓ, m, k, basis name, coefficient), m ≥ 0 (module docstring)."""
    n, d, i = nu, delta, 1j
    symmetric = [
        (2, 0, 4, "P_nn", 1 / _SQ(6)), (2, 0, 4, "P_lambdalambda", -1 / _SQ(6)),
        (2, 1, 2, "Sigma_ell", i / 2), (2, 1, 4, "S_ell", -86 * i * d / 42), (2, 1, 4, "Sigma_ell", i * (139 * n - 79) / 42),
        (2, 2, 3, "S_ell", -2.0), (2, 2, 3, "Sigma_ell", -2 * d / 3),
        (2, 2, 4, "P_ellell", 1.0), (2, 2, 4, "P_lambdalambda", 10 / 12), (2, 2, 4, "P_nn", -22 / 12),
        (2, 2, 4, "Q_nlambda", -15 * i / 12),
        (3, 1, 4, "S_ell", _SQ(14) * i * d / 336), (3, 1, 4, "Sigma_ell", -5 * _SQ(14) * i * (3 * n - 1) / 336),
        (3, 2, 3, "S_ell", 2 * _SQ(35) / 21), (3, 2, 3, "Sigma_ell", 2 * _SQ(35) * d / 21),
        (3, 3, 4, "S_ell", 21 * _SQ(210) * i * d / 112), (3, 3, 4, "Sigma_ell", -9 * _SQ(210) * i * (3 * n - 1) / 112),
        (4, 1, 4, "S_ell", _SQ(10) * i * d / 336), (4, 1, 4, "Sigma_ell", _SQ(10) * i * (1 - 3 * n) / 336),
        (4, 3, 4, "S_ell", -9 * _SQ(70) * i * d / 112), (4, 3, 4, "Sigma_ell", 9 * _SQ(70) * i * (3 * n - 1) / 112),
    ]
    antisymmetric = [
        (2, 0, 2, "Sigma_n", _SQ(6) * i / 6),
        (2, 0, 4, "S_n", 255 * _SQ(6) * i * d / 126), (2, 0, 4, "Sigma_n", -_SQ(6) * i * (506 * n - 45) / 126),
        (2, 1, 3, "S_lambda", 4 * i / 6), (2, 1, 3, "S_n", 25 / 6), (2, 1, 3, "Sigma_lambda", 4 * i * d / 6),
        (2, 1, 3, "Sigma_n", 13 * d / 6), (2, 1, 4, "Q_nell", -3 / 4),
        (2, 2, 2, "Sigma_lambda", -1 / 2), (2, 2, 2, "Sigma_n", -i / 2),
        (2, 2, 4, "S_lambda", 19 * d / 84), (2, 2, 4, "S_n", 182 * i * d / 84),
        (2, 2, 4, "Sigma_lambda", (5 - 43 * n) / 84), (2, 2, 4, "Sigma_n", i * (98 - 280 * n) / 84),
        (3, 0, 4, "S_lambda", -17 * _SQ(42) * d / 168), (3, 0, 4, "Sigma_lambda", _SQ(42) * (35 * n - 9) / 168),
        (3, 1, 3, "S_lambda", _SQ(14) * i / 21), (3, 1, 3, "S_n", _SQ(14) / 21),
        (3, 1, 3, "Sigma_lambda", _SQ(14) * i * d / 21), (3, 1, 3, "Sigma_n", _SQ(14) * d / 21),
        (3, 2, 4, "Sigma_lambda", -_SQ(35) * (83 * n - 17) / 168), (3, 2, 4, "Sigma_n", 4 * _SQ(35) * i * (55 * n - 13) / 168),
        (3, 2, 4, "S_lambda", 25 * _SQ(35) * d / 168), (3, 2, 4, "S_n", -100 * _SQ(35) * i * d / 168),
        (3, 3, 3, "S_lambda", _SQ(210) * i / 21), (3, 3, 3, "S_n", -_SQ(210) / 21),
        (3, 3, 3, "Sigma_lambda", _SQ(210) * i * d / 21), (3, 3, 3, "Sigma_n", -_SQ(210) * d / 21),
        (4, 0, 4, "S_n", _SQ(2) * i * d / 168), (4, 0, 4, "Sigma_n", _SQ(2) * i * (1 - 3 * n) / 168),
        (4, 2, 4, "Sigma_lambda", -13 * _SQ(5) * (3 * n - 1) / 168), (4, 2, 4, "Sigma_n", 14 * _SQ(5) * i * (3 * n - 1) / 168),
        (4, 2, 4, "S_lambda", 13 * _SQ(5) * d / 168), (4, 2, 4, "S_n", -14 * _SQ(5) * i * d / 168),
        (4, 4, 4, "Sigma_lambda", 9 * _SQ(35) * (1 - 3 * n) / 56), (4, 4, 4, "Sigma_n", -9 * _SQ(35) * i * (3 * n - 1) / 56),
        (4, 4, 4, "S_lambda", 9 * _SQ(35) * d / 56), (4, 4, 4, "S_n", 9 * _SQ(35) * i * d / 56),
    ]
    return symmetric, antisymmetric
