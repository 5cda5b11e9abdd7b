r"""Tidal terms of the co-orbital mode amplitudes H_ℓm: neutron stars deformed by their companion's tidal field.

Each body A with dimensionless deformability Λ_A (LALSuite's lambda1/lambda2, :mod:`pnrotor.pn.energy`) gains the
adiabatic quadrupole Q_A = −λ_A E_A, λ_A = Λ_A m_A⁵, in the companion's tidal field E_A; the binary's radiative
multipoles gain Q_A and its moments about the centre of mass, and the orbit at given frequency widens by
r = (M/x)(1 + 3 Λ_A X_A⁴ X_B x⁵).  With X = X_A, Y = X_B = 1 − X the mass fractions and H_ℓm = h₀ Σ_k c_k v^k
(h₀ = 8 √(π/5) ν v², as :mod:`pnrotor.waveform.nonspinning`; LALSuite's signs), body A adds

* (2,2): v¹⁰ 3 Λ X⁴ (3 − 2X) and v¹² Λ X⁴ (−202 + 560X − 340X² + 45X³)/14: Vines, Flanagan & Hinderer 2011
  (arXiv:1101.1673, Sec. V, h₂₂ through the first post-Newtonian tidal order), as Damour, Nagar & Villain 2012
  (arXiv:1203.4352) factor it: ĥ₂₂ = 2 k̂_A (X/Y + 3)(1 + β₁ x) x⁵, k̂_A = (3/2) Λ Y X⁴,
  β₁ = (−202 + 560X − 340X² + 45X³)/(42(3 − 2X));
* (2,1), (3,3), (3,1): v¹¹ (3i/2) Λ X⁴ Y (4X − 3), v¹¹ 54i √(15/224) Λ X⁴ Y² and v¹¹ −(3i/(2√14)) Λ X⁴ Y²: the
  leading tidal parts of the current quadrupole (J_ij ∋ ε^{ab⟨i}Q_A^{j⟩a}v_A^b + ½ε^{ab⟨i}x_A^a Q̇_A^{j⟩b}) and the
  mass octupole (I_ijk ∋ 3 x_A^⟨i Q_A^{jk⟩}) with the widened orbit, the modes Damour, Nagar & Villain 2012
  give in factored form (App. A; LALSuite's TEOBResumS ``eob_wav_hlmTidal``: relative corrections −3k̂_A(3 − 4X)
  and −12k̂_A Y);  here they are absolute: relative to the Newtonian mode without its factor δ = X₁ − X₂, so that
  they stay for equal masses (the mode δ-normalized, as in TEOBResumS, misses the 6PN flux; see below);
* (3,2): v¹² 4 √(5/7) Λ X⁴ Y (1 − 2Y + 3Y²): Damour, Nagar & Villain 2012 (ibid.; 8 k̂_A (1 − 2Y + 3Y²)/(1 − 3ν)
  relative to the Newtonian (3,2) mode, whose factor 1 − 3ν it carries), the current octupole's tidal part.

Body B adds the same with X ↔ Y and Λ_B, times (−1)^m (exchanging the bodies turns n̂ into −n̂).  Checked
(tests/test_pn_tides.py): the modes carry the tidal energy flux of :mod:`pnrotor.pn.flux` (Vines et al. 2011)
coefficient by coefficient, the 5PN term from (2,2) and the 6PN term from (2,2) with the odd-m modes.  Not
included: the v¹² tidal parts of (4,4) and (4,2) (mass hexadecapole), for which we have no published source
to check against, and tidal terms of m = 0 modes.
"""

import math

__all__ = ["terms"]

_SQ = math.sqrt


def terms(X1, lambda1, lambda2):
    """[(ℓ, m, k, c), …]: H_ℓm ∋ h₀ c v^k for the bodies of mass fractions X1, 1 − X1 and deformabilities
    Λ₁, Λ₂ (module docstring), m > 0, the terms of both bodies summed per (ℓ, m, k): always the same six, in the
    same order (zero without tides)."""
    X2 = 1.0 - X1
    out = {}
    for X, Y, lam, sign in ((X1, X2, lambda1, 1.0), (X2, X1, lambda2, -1.0)):
        X4 = (X * X) * (X * X)
        for ell, m, k, c in (
                (2, 2, 10, 3.0 * lam * X4 * (3.0 - 2.0 * X)),
                (2, 2, 12, lam * X4 * (-202.0 + 560.0 * X - 340.0 * X * X + 45.0 * X * X * X) / 14.0),
                (2, 1, 11, 1.5j * lam * X4 * Y * (4.0 * X - 3.0)),
                (3, 3, 11, 54j * _SQ(15.0 / 224.0) * lam * X4 * Y * Y),
                (3, 1, 11, -1.5j / _SQ(14.0) * lam * X4 * Y * Y),
                (3, 2, 12, 4.0 * _SQ(5.0 / 7.0) * lam * X4 * Y * (1.0 - 2.0 * Y + 3.0 * Y * Y))):
            out[ell, m, k] = out.get((ell, m, k), 0.0) + (sign if m % 2 else 1.0) * c
    return [(ell, m, k, c) for (ell, m, k), c in out.items()]
