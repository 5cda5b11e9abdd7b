r"""Binding energy E(v) of a quasi-circular compact binary and its derivative E′(v) = dE/dv.

Units G = c = M = m₁ + m₂ = 1; v = (M Ω_orb)^{1/3}; X₁ = m₁/M, X₂ = m₂/M, ν = X₁X₂, δ = X₁ − X₂;
χᵢ the dimensionless spins (Sᵢ = mᵢ² χᵢ); κᵢ the spin-induced quadrupole constants (1 for black
holes).  We write

    E(v) = −(ν v²/2) Ê(v),     Ê = Σ_k v^k Σ_b B_b (e[k,b,0] + e[k,b,1] ln v),
    E′(v) = −ν v Ê′(v),

with the spin-invariant basis B of :mod:`pnrotor.pn.series`.  :func:`energy_series` returns Ê with
every term we know (truncation by PN order is applied later, in :mod:`pnrotor.pn.vdot`).

Sources, term by term (every coefficient below carries its own citation):

* nonspinning, 1PN–4PN: Blanchet, Living Rev. Rel. 17, 2 (2014), arXiv:1310.1528, Eq. (233)
  (the 4PN term, with ln(16x) = 4 ln 2 + 2 ln v, is the Jaranowski–Schäfer / Bini–Damour result).
  There is no 0.5PN, 1.5PN, 2.5PN, 3.5PN or 4.5PN nonspinning term.
* spin-orbit, 1.5PN, 2.5PN, 3.5PN: Bohé, Marsat, Faye & Blanchet, CQG 30, 075017 (2013),
  arXiv:1212.5520, Eq. (4.6) (also Blanchet 2014, Eq. (415)), in terms of
  s_ℓ = S_ℓ/M² = X₁²(ℓ̂·χ₁) + X₂²(ℓ̂·χ₂) and σ_ℓ = Σ_ℓ/M² = X₂(ℓ̂·χ₂) − X₁(ℓ̂·χ₁).  (The 4PN
  spin-orbit energy term vanishes.)
* quadratic in spin, 2PN and 3PN: Bohé, Faye, Marsat & Porter, CQG 32, 195010 (2015),
  arXiv:1501.01529 (3PN; Eq. (3.30) in the n̂, λ̂, ℓ̂ decomposition as cited by LALSuite), with the
  2PN S₁S₂ term of Kidder, PRD 52, 821 (1995), gr-qc/9506022, and the 2PN quadrupole-monopole term
  of Poisson, PRD 57, 5287 (1998), gr-qc/9709032.  Precessing orbits need the *orbit-averaged*
  form, obtained with ⟨nⁱnʲ⟩ = ⟨λⁱλʲ⟩ = ½(δⁱʲ − ℓⁱℓʲ) (e.g. Racine, Buonanno & Kidder, PRD 80,
  044010 (2009), arXiv:0812.4413, App. B).  Averaged coefficients as used by LALSuite's
  SpinTaylor (``XLALSimInspiralPNEnergy_*Avg``); we verified them independently (tests) against the
  aligned-spin form, Eq. (3.33) of arXiv:1501.01529 in the s_ℓ, σ_ℓ, κ± variables.

* tidal (adiabatic electric-quadrupole deformation of neutron stars), 5PN and 6PN: Vines, Flanagan &
  Hinderer, PRD 83, 084051 (2011), arXiv:1101.1673, Eq. (2.11) (:func:`tidal_energy`), in the
  dimensionless deformabilities Λᵢ = λᵢ/mᵢ⁵ = (2/3) k₂ (Rᵢ/mᵢ)⁵ of LALSuite's ``lambda1``/``lambda2``.

Orbit averaging a 2PN spin-spin term leaves an O(v³) relative error (Racine et al. 2009, App. B);
this is the standard SpinTaylor model and the one LALSuite integrates.

The spin-induced quadrupole κᵢ (Qᵢ = −κᵢ χᵢ² mᵢ³) and the tidal deformability Λᵢ of a neutron star are both set
by its equation of state; quasi-universal relations connect them (Yagi & Yunes 2013, arXiv:1303.1528, the
"I-Love-Q" relations), but pnrotor takes each as given: which relation, if any, is the user's choice.
"""

import math

import numpy as np
from numba import njit

from .series import NK, add_tidal, assemble, shape_of

EULER_GAMMA = 0.57721566490153286061
LN2 = math.log(2.0)
PI2 = math.pi ** 2


# --------------------------------------------------------------------------------------------------
# nonspinning
# --------------------------------------------------------------------------------------------------

def nonspinning_energy_coefficients(nu):
    """(e, elog): Ê coefficients e[k] of v^k and elog[k] of v^k ln v, nonspinning, through 4PN (for an array
    of ν, e[k] is an array like it).

    Blanchet, Living Rev. Rel. 17, 2 (2014), Eq. (233); x = v².
    """
    e = np.zeros((NK,) + shape_of(nu))
    elog = np.zeros((NK,) + shape_of(nu))
    e[0] = 1.0
    # 1PN: −3/4 − ν/12                                          [Blanchet 2014, Eq. (233)]
    e[2] = -0.75 - nu / 12.0
    # 2PN: −27/8 + 19ν/8 − ν²/24                                [Blanchet 2014, Eq. (233)]
    e[4] = -27.0 / 8.0 + 19.0 / 8.0 * nu - (nu * nu) / 24.0
    # 3PN: −675/64 + (34445/576 − 205π²/96)ν − 155ν²/96 − 35ν³/5184   [Blanchet 2014, Eq. (233)]
    e[6] = (-675.0 / 64.0 + (34445.0 / 576.0 - 205.0 * PI2 / 96.0) * nu - 155.0 / 96.0 * (nu * nu)
            - 35.0 / 5184.0 * (nu * nu * nu))
    # 4PN: −3969/128 + (−123671/5760 + 9037π²/1536 + 896γ_E/15 + 448/15 ln(16x))ν
    #      + (−498449/3456 + 3157π²/576)ν² + 301ν³/1728 + 77ν⁴/31104   [Blanchet 2014, Eq. (233)]
    #      with 448/15 ln(16 v²) = 1792 ln2/15 + 896/15 ln v
    e[8] = (-3969.0 / 128.0
            + (-123671.0 / 5760.0 + 9037.0 * PI2 / 1536.0 + 896.0 * EULER_GAMMA / 15.0
               + 1792.0 * LN2 / 15.0) * nu
            + (-498449.0 / 3456.0 + 3157.0 * PI2 / 576.0) * (nu * nu)
            + 301.0 / 1728.0 * (nu * nu * nu) + 77.0 / 31104.0 * (nu * nu * nu * nu))
    elog[8] = 896.0 / 15.0 * nu
    return e, elog


# --------------------------------------------------------------------------------------------------
# spin-orbit
# --------------------------------------------------------------------------------------------------

def spin_orbit_energy_sl_sigma(nu):
    """{k: (c_s, c_σ)} with Ê ∋ v^k (c_s s_ℓ + c_σ δ σ_ℓ).

    Bohé, Marsat, Faye & Blanchet (2013), arXiv:1212.5520, Eq. (4.6).
    """
    return {
        # 1.5PN: 14/3 s_ℓ + 2 δσ_ℓ                                  [Bohé+ 2013, Eq. (4.6)]
        3: (14.0 / 3.0, 2.0),
        # 2.5PN: (11 − 61ν/9) s_ℓ + (3 − 10ν/3) δσ_ℓ               [Bohé+ 2013, Eq. (4.6)]
        5: (11.0 - 61.0 * nu / 9.0, 3.0 - 10.0 * nu / 3.0),
        # 3.5PN: (135/4 − 367ν/4 + 29ν²/12) s_ℓ + (27/4 − 39ν + 5ν²/4) δσ_ℓ   [Bohé+ 2013, Eq. (4.6)]
        7: (135.0 / 4.0 - 367.0 * nu / 4.0 + 29.0 * (nu * nu) / 12.0,
            27.0 / 4.0 - 39.0 * nu + 5.0 * (nu * nu) / 4.0),
    }


# --------------------------------------------------------------------------------------------------
# quadratic in spin (orbit averaged)
# --------------------------------------------------------------------------------------------------

def spin_spin_energy_per_body(X, kappa):
    """Orbit-averaged self-spin + quadrupole-monopole coefficients of body i (X = mᵢ/M).

    Returns {k: (c_SS, c_LL)} with Ê ∋ v^k [c_SS Sᵢ·Sᵢ + c_LL (ℓ̂·Sᵢ)²], Sᵢ = X² χᵢ (units M²).
    """
    return {
        # 2PN quadrupole-monopole, averaged: κ/(2X²) Sᵢ² − 3κ/(2X²)(ℓ̂·Sᵢ)²
        #   [Poisson 1998, gr-qc/9709032; Mikóczi+ 2005, astro-ph/0504538, Eq. (6); averaged as in
        #    Racine+ 2009 App. B]
        4: (0.5 * kappa / (X * X), -1.5 * kappa / (X * X)),
        # 3PN self-spin + quadrupole-monopole, averaged          [Bohé+ 2015, arXiv:1501.01529, Eq. (3.30)]
        #   self:   (−1/X² − 1/(6X) − 1/2) Sᵢ² + (6/X² − 3/(2X) − 11/18)(ℓ̂·Sᵢ)²
        #   QM (κ): (5/(4X²) + 5/(4X) + 5/12) Sᵢ² + (−15/(4X²) − 15/(4X) − 5/4)(ℓ̂·Sᵢ)²
        6: ((-1.0 / (X * X) - 1.0 / (6.0 * X) - 0.5)
            + kappa * (1.25 / (X * X) + 1.25 / X + 5.0 / 12.0),
            (6.0 / (X * X) - 1.5 / X - 11.0 / 18.0)
            + kappa * (-3.75 / (X * X) - 3.75 / X - 1.25)),
    }


def spin1_spin2_energy(nu):
    """Orbit-averaged S₁S₂ coefficients {k: (c_S12, c_L12)}: Ê ∋ v^k [c_S12 S₁·S₂ + c_L12 (ℓ̂·S₁)(ℓ̂·S₂)]."""
    return {
        # 2PN: instantaneous −(2/ν)[S₁·S₂ − 3(n̂·S₁)(n̂·S₂)], averaged → (1/ν) S₁·S₂ − (3/ν)(ℓ̂·S₁)(ℓ̂·S₂)
        #   [Kidder 1995, gr-qc/9506022; Mikóczi, Vasúth & Gergely 2005, astro-ph/0504538, Eq. (6)
        #    (the equation LALSuite cites); averaged as in Racine+ 2009 App. B]
        4: (1.0 / nu, -3.0 / nu),
        # 3PN, averaged: (2/ν − 11/6) S₁·S₂ + (−11/(3ν) + 23/18)(ℓ̂·S₁)(ℓ̂·S₂)   [Bohé+ 2015, Eq. (3.30)]
        6: (2.0 / nu - 11.0 / 6.0, -11.0 / (3.0 * nu) + 23.0 / 18.0),
    }


# --------------------------------------------------------------------------------------------------
# tidal
# --------------------------------------------------------------------------------------------------

def tidal_energy(X):
    """{k: c_k} with Ê ∋ Λ c_k v^k for the body of mass fraction X = m/M and dimensionless deformability Λ.

    Vines, Flanagan & Hinderer 2011, arXiv:1101.1673, Eq. (2.11), for their body 2: Ê ∋ −9 (χ₁/χ₂) λ̂
    − (11/2)(χ₁/χ₂)(3 + 2χ₂ + 3χ₂²) λ̂ x with their χᵢ = mᵢ/M (mass fractions, not spins), λ̂ = λ₂ x⁵/M⁵ and
    x = v².  With λ₂ = Λ₂ m₂⁵, λ̂ = Λ₂ χ₂⁵ v¹⁰; for the body X (the other's fraction 1 − X):
    """
    Y = 1.0 - X
    X4 = (X * X) * (X * X)
    return {
        # 5PN: −9 (1 − X) X⁴                                     [Vines+ 2011, Eq. (2.11)]
        10: -9.0 * Y * X4,
        # 6PN: −(11/2)(1 − X)(3 + 2X + 3X²) X⁴                   [Vines+ 2011, Eq. (2.11)]
        12: -5.5 * Y * (3.0 + 2.0 * X + 3.0 * (X * X)) * X4,
    }


# --------------------------------------------------------------------------------------------------
# assembled series
# --------------------------------------------------------------------------------------------------

def energy_series(X1, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """Ê(v): every known term (nonspinning to 4PN, spin-orbit to 3.5PN, spin² to 3PN, tidal at 5PN and 6PN),
    untruncated."""
    E = assemble(X1, kappa1, kappa2, nonspinning_energy_coefficients, spin_orbit_energy_sl_sigma,
                 spin_spin_energy_per_body, spin1_spin2_energy)
    return add_tidal(E, X1, 1.0 - X1, lambda1, lambda2, tidal_energy)


@njit(cache=True)
def energy_derivative_series(E):
    """Ê′ with E′ = dE/dv = −ν v Ê′, from Ê: d/dv[v^{k+2}(e + e_L ln v)] = v^{k+1}[(k+2)(e + e_L ln v) + e_L]."""
    D = np.empty_like(E)
    for k in range(E.shape[0]):
        for b in range(E.shape[1]):
            D[k, b, 0] = 0.5 * ((k + 2) * E[k, b, 0] + E[k, b, 1])
            D[k, b, 1] = 0.5 * (k + 2) * E[k, b, 1]
    return D
