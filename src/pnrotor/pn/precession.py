r"""Precession of the spins and of the orbital plane (orbit averaged), and the orbital-phase shift.

Units G = c = M = 1; Xᵢ = mᵢ/M, ν = X₁X₂, δᵢ = Xᵢ − Xⱼ (j the other body); χᵢ dimensionless spins,
Sᵢ = Xᵢ²χᵢ; ℓ̂ the orbital angular momentum direction; a⊥ = a − (ℓ̂·a)ℓ̂.

Spins
-----
The magnitude of each spin is conserved and χ̇ᵢ = Ωᵢ × χᵢ with, orbit averaged,

    Ωᵢ = v⁵ (σ₀ + σ₂ v² + σ₄ v⁴) ℓ̂                                  spin-orbit, LO/NLO/NNLO
       + v⁶ [ −Xⱼ² χⱼ + (3/2) Xⱼ² χⱼ⊥ + (3/2) ν κᵢ χᵢ⊥ ]               spin-spin + quadrupole-monopole, 2PN
       + v⁸ [ c₃ⱼ χⱼ + c₃ⱼ⊥ χⱼ⊥ + c₃ᵢ⊥ χᵢ⊥ ]                          spin-spin + QM, 3PN

* spin-orbit: Bohé, Marsat, Faye & Blanchet, CQG 30, 075017 (2013), arXiv:1212.5520, Eq. (4.5)
  (LO: Barker & O'Connell; NLO: Faye, Blanchet & Buonanno 2006, gr-qc/0605139);
* 2PN spin-spin: Kidder, PRD 52, 821 (1995), gr-qc/9506022, Eq. (2.4) instantaneous
  Ωᵢ ∋ v⁶ Xⱼ²(−χⱼ + 3(n̂·χⱼ)n̂); quadrupole-monopole: Racine, PRD 78, 044021 (2008), Eq. (2.7),
  Ωᵢ ∋ 3ν κᵢ v⁶ (n̂·χᵢ) n̂ (κᵢ the quadrupole constant, Poisson 1998);
* 3PN spin-spin and QM: Bohé, Faye, Marsat & Porter (2015), arXiv:1501.01529, Eq. (A.2) (as cited
  by LALSuite, whose n̂/λ̂ coefficients we average; no second independent transcription available);
* orbit averaging with ⟨(a·n̂)n̂⟩ = ⟨(a·λ̂)λ̂⟩ = ½ a⊥ (Racine, Buonanno & Kidder 2009, App. B).

Orbital plane: Ω_ℓ and the relation to ϖ
-----------------------------------------
Bohé et al. (2013), Eq. (4.1), write the orbital frame (n̂, λ̂, ℓ̂) as rotating with angular velocity
Ω = ω ℓ̂ + ϖ n̂: ϖ, the precession of the orbital plane, is *along n̂* and oscillates at the orbital
frequency because it is ∝ S·n̂ (their Eq. (4.4), a_ℓ = rωϖ).  An orbit-averaged spin model cannot
carry that oscillation; its consistent counterpart is the orbit average Ω_ℓ = ⟨ϖ n̂⟩, which lies
in the orbital plane.  We compute it, as LALSuite's SpinTaylor does, from conservation of the total
angular momentum under precession, L̇ = −Ṡ₁ − Ṡ₂ with L = |L| ℓ̂:

    Ω_ℓ = ℓ̂ × ℓ̂̇ = −ℓ̂ × (Ṡ₁ + Ṡ₂) / |L|,    |L| = (ν/v)(1 + L₂ v² + L₄ v⁴),

L₂ = 3/2 + ν/6, L₄ = 27/8 − 19ν/8 + ν²/24 (Blanchet, Living Rev. Rel. 17, 2 (2014), Eq. (234);
Bohé+ 2013 Eq. (4.7)), spin contributions to L omitted (LALSuite's ``lscorr = 0``).  At leading
order this is exactly ⟨ϖ n̂⟩ with ϖ from Bohé+ 2013 Eq. (4.4):
⟨ϖ n̂⟩ = ½ v⁶ (7 S⊥ + 3δ Σ⊥) = v⁶ Σᵢ (2 + 3Xⱼ/(2Xᵢ)) Sᵢ⊥ (checked in the tests).  |L| is kept
to the same relative order as the spin-orbit precession: L₂ with NLO, L₄ with NNLO.

The frame rotor then obeys dR/dt = ½ (Φ̇ ℓ̂ + Ω_ℓ) R (see :mod:`pnrotor.pn.rhs`).

Why the torque form is the default: it is the model LALSuite integrates (the acceptance reference) and
it keeps J = L + S₁ + S₂ fixed except for radiation reaction along ℓ̂ (tested).  Beyond leading order
it is *not* identical to ⟨ϖ n̂⟩ with Bohé+ 2013's ϖ: the two differ at NLO because LALSuite's |L|
omits the spin-dependent part of L (``lscorr = 0``).  Both are available (``precession='averaged'``
and ``'averaged_varpi'`` in :func:`pnrotor.pn.evolve`), as is the instantaneous Ω = v³ℓ̂ + ϖn̂
(``'instantaneous'``), where ℓ̂ nutates about the averaged direction at twice the orbital frequency
with amplitude ϖ_max/(4ω) ~ v³|Σ wᵢχᵢ⊥|/4 (~0.003–0.03 rad for the test binaries, more at the end
of the inspiral).  Starting both from the same ℓ̂ puts the instantaneous one at an extreme of its
nutation, so the cones differ by that amplitude and the phasing drifts apart over the inspiral
(0.2–4 rad between the two conventions for q = 3–10 from 15 Hz): the meaning of "ℓ̂ at f_ref"
(instantaneous or orbit-averaged) is a convention that matters at this level.

Instantaneous ϖ (used only with ``precession='instantaneous'`` / ``'averaged_varpi'``)
-----------------------------------------------------------------------------------
ϖ = v⁶ Σᵢ (w₀ + w₂v² + w₄v⁴)ᵢ (n̂·χᵢ) from Bohé+ 2013 Eqs. (4.3)–(4.4) (:func:`varpi_coefficients`);
its orbit average is ⟨ϖ n̂⟩ = v⁶ Σᵢ ½(w₀ + w₂v² + w₄v⁴)ᵢ χᵢ⊥.

Orbital phase
-------------
Replacing ϖ n̂ by its average changes the phase of n̂ in the precessing frame at second order:
Φ̇ = ω − |Ω_ℓ|²/(4ω) with ω = v³ and Ω_ℓ at leading order (Bohé et al. / Blanchet et al.,
arXiv:1507.00406; LALSuite's ``omegashift``, applied for spin order ≥ 3PN), i.e.

    Φ̇ = v³ − |Σᵢ wᵢ χᵢ⊥|² v⁹ / 4,    wᵢ = Xᵢ² (1/2 + 3/(2Xᵢ)).
"""

import numpy as np


def spin_orbit_precession(X_i, X_j):
    """(σ₀, σ₂, σ₄) of Ωᵢ ∋ v⁵(σ₀ + σ₂v² + σ₄v⁴) ℓ̂.   Bohé+ 2013, arXiv:1212.5520, Eq. (4.5)."""
    nu = X_i * X_j
    d = X_i - X_j
    # LO:   3/4 + ν/2 − 3δ/4                                            [Bohé+ 2013, Eq. (4.5)]
    s0 = 0.75 + 0.5 * nu - 0.75 * d
    # NLO:  9/16 + 5ν/4 − ν²/24 + δ(−9/16 + 5ν/8)                       [Bohé+ 2013, Eq. (4.5)]
    s2 = 9.0 / 16.0 + 1.25 * nu - (nu * nu) / 24.0 + d * (-9.0 / 16.0 + 0.625 * nu)
    # NNLO: 27/32 + 3ν/16 − 105ν²/32 − ν³/48 + δ(−27/32 + 39ν/8 − 5ν²/32)   [Bohé+ 2013, Eq. (4.5)]
    s4 = (27.0 / 32.0 + 3.0 * nu / 16.0 - 105.0 * (nu * nu) / 32.0 - (nu * nu * nu) / 48.0
          + d * (-27.0 / 32.0 + 39.0 * nu / 8.0 - 5.0 * (nu * nu) / 32.0))
    return s0, s2, s4


def spin_spin_precession_2pn(X_i, X_j, kappa_i):
    """(c_j, c_j⊥, c_i⊥) of Ωᵢ ∋ v⁶ [c_j χⱼ + c_j⊥ χⱼ⊥ + c_i⊥ χᵢ⊥], orbit averaged.

    Instantaneous: v⁶ [Xⱼ²(−χⱼ + 3(n̂·χⱼ)n̂) + 3νκᵢ(n̂·χᵢ)n̂]   [Kidder 1995, Eq. (2.4); Racine 2008, Eq. (2.7)]
    """
    nu = X_i * X_j
    return -(X_j * X_j), 1.5 * (X_j * X_j), 1.5 * nu * kappa_i


def spin_spin_precession_3pn(X_i, X_j, kappa_i):
    """(c_j, c_j⊥, c_i⊥) of Ωᵢ ∋ v⁸ [c_j χⱼ + c_j⊥ χⱼ⊥ + c_i⊥ χᵢ⊥], orbit averaged.

    Bohé+ 2015, arXiv:1501.01529, Eq. (A.2), in LALSuite's n̂/λ̂ decomposition with spins Sₖ = Xₖ²χₖ
    and m = Xᵢ (coefficients of the instantaneous Ωᵢ):
      Sⱼ: −3/2 − m;  (n̂·Sⱼ)n̂: 3/2 + 2m + m²;  (λ̂·Sⱼ)λ̂: 3/2 + m;
      (n̂·Sᵢ)n̂: 7/2 − 3/m − m²/2;  (λ̂·Sᵢ)λ̂: 3 − 3m/2 − 3/(2m);
      QM (×κᵢ): (n̂·Sᵢ)n̂: 3(1/(2m) + 1 − m − m²/2);  (λ̂·Sᵢ)λ̂: 3(1/m − 1).
    Averaging replaces (a·n̂)n̂ and (a·λ̂)λ̂ by ½a⊥.
    """
    c_s, c_sn, c_sv, c_in, c_iv = spin_spin_precession_3pn_instantaneous(X_i, X_j, kappa_i)
    return c_s, 0.5 * (c_sn + c_sv), 0.5 * (c_in + c_iv)


def spin_spin_precession_3pn_instantaneous(X_i, X_j, kappa_i):
    """(c_j, c_jn, c_jλ, c_in, c_iλ) of the instantaneous
    Ωᵢ ∋ v⁸ [c_j χⱼ + c_jn (n̂·χⱼ)n̂ + c_jλ (λ̂·χⱼ)λ̂ + c_in (n̂·χᵢ)n̂ + c_iλ (λ̂·χᵢ)λ̂]
    (QM folded into c_in, c_iλ), from the coefficients listed in :func:`spin_spin_precession_3pn`."""
    m = X_i
    c_s = -1.5 - m
    c_sn = 1.5 + 2.0 * m + m * m
    c_sv = 1.5 + m
    c_in = 3.5 - 3.0 / m - 0.5 * m * m
    c_iv = 3.0 - 1.5 * m - 1.5 / m
    q_n = 3.0 * (0.5 / m + 1.0 - m - 0.5 * m * m)
    q_v = 3.0 * (1.0 / m - 1.0)
    xj2 = (X_j * X_j)
    xi2 = (X_i * X_i)
    return (c_s * xj2, c_sn * xj2, c_sv * xj2, (c_in + kappa_i * q_n) * xi2, (c_iv + kappa_i * q_v) * xi2)


def varpi_coefficients(X_i, X_j):
    """(w₀, w₂, w₄) of the instantaneous precession of the orbital plane,
    ϖ = v⁶ Σᵢ (w₀ + w₂v² + w₄v⁴)ᵢ (n̂·χᵢ)   (spin-orbit part; M = 1).

    Bohé, Marsat, Faye & Blanchet (2013), arXiv:1212.5520: frame rotation Ω = ωℓ̂ + ϖn̂ (Eq. (4.1)),
    a_ℓ = rωϖ (Eq. (4.4)) and γ = M/r (Eq. (4.3)) give ϖ = γ a_ℓ/v³ with
      a_ℓ = v⁷ [(7S_n + 3δΣ_n) + v²((−10 − 29ν/3)S_n + δ(−6 − 9ν/2)Σ_n)
                + v⁴((3/2 + 59ν/4 + 52ν²/9)S_n + δ(3/2 + 73ν/8 + 17ν²/6)Σ_n)]      [Eq. (4.4)]
      γ = v²[1 + (1 − ν/3)v² + (1 − 65ν/12)v⁴ + spin-orbit terms]                   [Eq. (4.3)]
    re-expanded and truncated at relative v⁴ (the spin-orbit terms of γ would give spin² terms and are
    dropped).  S_n = Σᵢ Xᵢ²(n̂·χᵢ), Σ_n = X₂(n̂·χ₂) − X₁(n̂·χ₁), δ = X₁ − X₂: for body i,
    (n̂·χᵢ) enters S_n with Xᵢ² and δΣ_n with ∓δXᵢ (− for body 1).
    """
    nu = X_i * X_j
    # coefficient of (n̂·χᵢ) in δΣ_n: δ·(−X₁) for body 1, δ·(+X₂) for body 2; δ = X₁ − X₂
    # For body i this is −(Xᵢ − Xⱼ)Xᵢ in both cases.
    dsig = -(X_i - X_j) * X_i
    a = (7.0 * (X_i * X_i) + 3.0 * dsig,
         (-10.0 - 29.0 * nu / 3.0) * (X_i * X_i) + (-6.0 - 4.5 * nu) * dsig,
         (1.5 + 59.0 * nu / 4.0 + 52.0 * (nu * nu) / 9.0) * (X_i * X_i) + (1.5 + 73.0 * nu / 8.0 + 17.0 * (nu * nu) / 6.0) * dsig)
    g2 = 1.0 - nu / 3.0
    g4 = 1.0 - 65.0 * nu / 12.0
    return a[0], a[1] + g2 * a[0], a[2] + g2 * a[1] + g4 * a[0]


def angular_momentum_coefficients(nu):
    """(L₂, L₄) of |L| = (ν/v)(1 + L₂v² + L₄v⁴) = (ν/v)(1 + v²(L₂ + L₄v²)).   Blanchet 2014, Eq. (234); Bohé+ 2013, Eq. (4.7)."""
    return 1.5 + nu / 6.0, 27.0 / 8.0 - 19.0 / 8.0 * nu + (nu * nu) / 24.0


def phase_shift_weights(X1, X2):
    """(w₁, w₂) of the leading-order Ω_ℓ = v⁶ Σ wᵢ χᵢ⊥ used in Φ̇ = v³ − |Σwᵢχᵢ⊥|² v⁹/4.

    wᵢ = Xᵢ²(1/2 + 3/(2Xᵢ)) (= Xᵢ² (2 + 3Xⱼ/(2Xᵢ))); arXiv:1507.00406 (LALSuite ``omegashift``).
    """
    return X1 * X1 * (0.5 + 1.5 / X1), X2 * X2 * (0.5 + 1.5 / X2)


# --------------------------------------------------------------------------------------------------
# the precession coefficients as truncated series (what the parameter vector holds, pnrotor.pn.system)
# --------------------------------------------------------------------------------------------------

SPIN_ORBIT_ORDERS = (1.5, 2.5, 3.5)
"""The PN orders of the phasing's spin-orbit terms (LALSuite: spin order 3/5/7) with which the terms of the series in
v² of the spin-orbit precession enter: σ₀, σ₂, σ₄ (:func:`spin_orbit_precession`), ϖ's w₀, w₂, w₄
(:func:`varpi_coefficients`), and of |L| = (ν/v)(1 + v²(L₂ + L₄v²)) the L₂, L₄ (:func:`angular_momentum_coefficients`)
with the second and third.  A new term: one more order here and one more coefficient in each of these functions."""

SPIN_SPIN = ((2.0, spin_spin_precession_2pn), (3.0, spin_spin_precession_3pn))
"""The orbit-averaged spin-spin precession as a truncated series, Ωᵢ ∋ Σₖ v⁶⁺²ᵏ [c_j χⱼ + c_j⊥ χⱼ⊥ + c_i⊥ χᵢ⊥]: for
each power of v, the PN order of the spin² terms of the phasing with which it enters and its coefficient function
(Xᵢ, Xⱼ, κᵢ) → (c_j, c_j⊥, c_i⊥).  A new term: one more entry."""


def truncated(coefficients, orders, order):
    """The coefficients of a series, those of the terms that enter at a PN order above ``order`` zeroed."""
    return [c if entry <= order else 0.0 for c, entry in zip(coefficients, orders)]


def precession_terms(so_order, ss_order):
    """Which precession terms a truncation includes: dict of booleans (the numpy reference below and the instantaneous
    model's spin-spin terms): spin-orbit LO/NLO/NNLO and 2PN/3PN spin-spin, by :data:`SPIN_ORBIT_ORDERS` and
    :data:`SPIN_SPIN`."""
    so = -1.0 if so_order is None else so_order
    ss = -1.0 if ss_order is None else ss_order
    (lo, nlo, nnlo), ((ss2, _), (ss3, _)) = SPIN_ORBIT_ORDERS, SPIN_SPIN
    return {"so_lo": so >= lo, "so_nlo": so >= nlo, "so_nnlo": so >= nnlo, "ss_2pn": ss >= ss2, "ss_3pn": ss >= ss3}


# --------------------------------------------------------------------------------------------------
# numpy reference (tests; the right-hand sides in rhs.py evaluate the same formulas in numba)
# --------------------------------------------------------------------------------------------------

def _perp(a, ell):
    return a - np.dot(a, ell) * ell


def spin_precession_vectors(v, chi1, chi2, ell, X1, kappa1=1.0, kappa2=1.0, so_order=3.5, ss_order=3.0):
    """(Ω₁, Ω₂), orbit averaged, at one point (numpy reference)."""
    X2 = 1.0 - X1
    inc = precession_terms(so_order, ss_order)
    out = []
    for (Xi, Xj, chii, chij, ki) in ((X1, X2, chi1, chi2, kappa1), (X2, X1, chi2, chi1, kappa2)):
        s0, s2, s4 = spin_orbit_precession(Xi, Xj)
        so = (s0 * inc["so_lo"] + s2 * v ** 2 * inc["so_nlo"] + s4 * v ** 4 * inc["so_nnlo"]) * v ** 5
        om = so * ell
        if inc["ss_2pn"]:
            cj, cjp, cip = spin_spin_precession_2pn(Xi, Xj, ki)
            om = om + v ** 6 * (cj * chij + cjp * _perp(chij, ell) + cip * _perp(chii, ell))
        if inc["ss_3pn"]:
            cj, cjp, cip = spin_spin_precession_3pn(Xi, Xj, ki)
            om = om + v ** 8 * (cj * chij + cjp * _perp(chij, ell) + cip * _perp(chii, ell))
        out.append(om)
    return out[0], out[1]


def orbital_precession_vector(v, chi1, chi2, ell, X1, kappa1=1.0, kappa2=1.0, so_order=3.5, ss_order=3.0):
    """Ω_ℓ = −ℓ̂ × (Ṡ₁ + Ṡ₂)/|L| (numpy reference)."""
    X2 = 1.0 - X1
    nu = X1 * X2
    inc = precession_terms(so_order, ss_order)
    om1, om2 = spin_precession_vectors(v, chi1, chi2, ell, X1, kappa1, kappa2, so_order, ss_order)
    sdot = X1 ** 2 * np.cross(om1, chi1) + X2 ** 2 * np.cross(om2, chi2)
    L2, L4 = angular_momentum_coefficients(nu)
    Lmag = nu / v * (1.0 + L2 * v ** 2 * inc["so_nlo"] + L4 * v ** 4 * inc["so_nnlo"])
    return -np.cross(ell, sdot) / Lmag
