r"""Gravitational-wave energy flux F(v) of a quasi-circular compact binary.

Units G = c = M = 1, notation as in :mod:`pnrotor.pn.energy`.  We write

    F(v) = (32/5) ν² v¹⁰ F̂(v),     F̂ = Σ_k v^k Σ_b B_b (f[k,b,0] + f[k,b,1] ln v).

Sources, term by term:

* nonspinning through 3.5PN: Blanchet, Living Rev. Rel. 17, 2 (2014), arXiv:1310.1528, Eq. (314);
  4PN and 4.5PN: Blanchet, Faye, Henry, Larrouturou & Trestini, PRD 108, 064041 (2023),
  arXiv:2304.11186 (the complete 4.5PN flux; Eq. (6.11) as cited by PostNewtonian.jl).  In all of
  them ln(16x) and ln x are rewritten with x = v²: ln(16x) = 4 ln 2 + 2 ln v.
* spin-orbit, 1.5PN, 2.5PN, 3PN (tail), 3.5PN, 4PN (tail): Marsat, Bohé, Blanchet & Buonanno,
  CQG 31, 025023 (2014), arXiv:1307.6793, Eq. (4.9), in s_ℓ, σ_ℓ.
* quadratic in spin, 2PN and 3PN: Bohé, Faye, Marsat & Porter (2015), arXiv:1501.01529
  (Eq. (4.12) in the n̂, λ̂, ℓ̂ decomposition as cited by LALSuite; 2PN S₁S₂ of Kidder 1995 and
  quadrupole-monopole of Poisson 1998 included there), orbit averaged with
  ⟨nⁱnʲ⟩ = ⟨λⁱλʲ⟩ = ½(δⁱʲ − ℓⁱℓʲ).  Checked in the tests against the aligned-spin form, Eq. (4.14)
  of arXiv:1501.01529.
* tidal, 5PN and 6PN: Vines, Flanagan & Hinderer 2011, arXiv:1101.1673, Eq. (3.6) ((3.7) on arXiv)
  (:func:`tidal_flux`), in LALSuite's dimensionless Λᵢ (:mod:`pnrotor.pn.energy`).
* the flux into black-hole horizons (``horizon_absorption``), at leading order in the tidal coupling, any spins,
  averaged over the orbit: Alvi 2001 (gr-qc/0107080) (:func:`horizon_rates`, with the spins' and masses' rates).

Note on LALSuite: its orbit-averaged 3PN quadrupole-monopole coefficient of (ℓ̂·Sᵢ)²,
``XLALSimInspiralPNFlux_6PNQMS1OS1OCoeffAvg``, has the constant 12.9/8 = 129/80 where the
average of its own instantaneous coefficients (and Eq. (4.14) of arXiv:1501.01529 for aligned spins)
give 129/8.  Only SpinTaylorT1 uses that function (T4/T5 use separately derived coefficients that
agree with 129/8); we use 129/8, so SpinTaylorT1 with spins differs from LALSuite by this term.
"""

import math

import numpy as np
from numba import njit

from .energy import EULER_GAMMA, LN2, PI2
from .series import NK, add_tidal, assemble, shape_of

PI = math.pi
LN3 = math.log(3.0)


def nonspinning_flux_coefficients(nu):
    """(f, flog): F̂ coefficients of v^k and of v^k ln v, nonspinning, through 4.5PN (for an array of ν, f[k]
    is an array like it)."""
    f = np.zeros((NK,) + shape_of(nu))
    flog = np.zeros((NK,) + shape_of(nu))
    f[0] = 1.0
    # 1PN: −1247/336 − 35ν/12                                    [Blanchet 2014, Eq. (314)]
    f[2] = -1247.0 / 336.0 - 35.0 / 12.0 * nu
    # 1.5PN: 4π (leading tail)                                    [Blanchet 2014, Eq. (314)]
    f[3] = 4.0 * PI
    # 2PN: −44711/9072 + 9271ν/504 + 65ν²/18                     [Blanchet 2014, Eq. (314)]
    f[4] = -44711.0 / 9072.0 + 9271.0 / 504.0 * nu + 65.0 / 18.0 * (nu * nu)
    # 2.5PN: (−8191/672 − 583ν/24)π                              [Blanchet 2014, Eq. (314)]
    f[5] = (-8191.0 / 672.0 - 583.0 / 24.0 * nu) * PI
    # 3PN: 6643739519/69854400 + 16π²/3 − 1712γ_E/105 − 856/105 ln(16x)
    #      + (−134543/7776 + 41π²/48)ν − 94403ν²/3024 − 775ν³/324   [Blanchet 2014, Eq. (314)]
    f[6] = (6643739519.0 / 69854400.0 + 16.0 * PI2 / 3.0 - 1712.0 / 105.0 * (EULER_GAMMA + 2.0 * LN2)
            + (-134543.0 / 7776.0 + 41.0 * PI2 / 48.0) * nu - 94403.0 / 3024.0 * (nu * nu)
            - 775.0 / 324.0 * (nu * nu * nu))
    flog[6] = -1712.0 / 105.0
    # 3.5PN: (−16285/504 + 214745ν/1728 + 193385ν²/3024)π          [Blanchet 2014, Eq. (314)]
    f[7] = (-16285.0 / 504.0 + 214745.0 / 1728.0 * nu + 193385.0 / 3024.0 * (nu * nu)) * PI
    # 4PN: −323105549467/3178375200 + 232597γ_E/4410 − 1369π²/126 + 39931 ln2/294 − 47385 ln3/1568
    #      + 232597/8820 ln x
    #      + ν(−1452202403629/1466942400 + 41478γ_E/245 − 267127π²/4608 + 479062 ln2/2205
    #          + 47385 ln3/392 + 20739/245 ln x)
    #      + ν²(1607125/6804 − 3157π²/384) + 6875ν³/504 + 5ν⁴/6          [Blanchet+ 2023, arXiv:2304.11186]
    f[8] = (-323105549467.0 / 3178375200.0 + 232597.0 / 4410.0 * EULER_GAMMA - 1369.0 * PI2 / 126.0
            + 39931.0 / 294.0 * LN2 - 47385.0 / 1568.0 * LN3
            + (-1452202403629.0 / 1466942400.0 + 41478.0 / 245.0 * EULER_GAMMA - 267127.0 * PI2 / 4608.0
               + 479062.0 / 2205.0 * LN2 + 47385.0 / 392.0 * LN3) * nu
            + (1607125.0 / 6804.0 - 3157.0 * PI2 / 384.0) * (nu * nu)
            + 6875.0 / 504.0 * (nu * nu * nu) + 5.0 / 6.0 * (nu * nu * nu * nu))
    flog[8] = 232597.0 / 4410.0 + 41478.0 / 245.0 * nu
    # 4.5PN: π[265978667519/745113600 − 6848γ_E/105 − 3424/105 ln(16x)
    #          + (2062241/22176 + 41π²/12)ν − 133112905ν²/290304 − 3719141ν³/38016]
    #                                                              [Blanchet+ 2023, arXiv:2304.11186]
    f[9] = PI * (265978667519.0 / 745113600.0 - 6848.0 / 105.0 * (EULER_GAMMA + 2.0 * LN2)
                 + (2062241.0 / 22176.0 + 41.0 * PI2 / 12.0) * nu - 133112905.0 / 290304.0 * (nu * nu)
                 - 3719141.0 / 38016.0 * (nu * nu * nu))
    flog[9] = -6848.0 / 105.0 * PI
    return f, flog


def spin_orbit_flux_sl_sigma(nu):
    """{k: (c_s, c_σ)} with F̂ ∋ v^k (c_s s_ℓ + c_σ δ σ_ℓ).   Marsat+ 2014, arXiv:1307.6793, Eq. (4.9)."""
    return {
        # 1.5PN: −4 s_ℓ − 5/4 δσ_ℓ                                   [Marsat+ 2014, Eq. (4.9)]
        3: (-4.0, -1.25),
        # 2.5PN: (−9/2 + 272ν/9) s_ℓ + (−13/16 + 43ν/4) δσ_ℓ           [Marsat+ 2014, Eq. (4.9)]
        5: (-4.5 + 272.0 * nu / 9.0, -13.0 / 16.0 + 43.0 * nu / 4.0),
        # 3PN (tail): −16π s_ℓ − 31π/6 δσ_ℓ                            [Marsat+ 2014, Eq. (4.9)]
        6: (-16.0 * PI, -31.0 * PI / 6.0),
        # 3.5PN: (476645/6804 + 6172ν/189 − 2810ν²/27) s_ℓ
        #        + (9535/336 + 1849ν/126 − 1501ν²/36) δσ_ℓ              [Marsat+ 2014, Eq. (4.9)]
        7: (476645.0 / 6804.0 + 6172.0 * nu / 189.0 - 2810.0 * (nu * nu) / 27.0,
            9535.0 / 336.0 + 1849.0 * nu / 126.0 - 1501.0 * (nu * nu) / 36.0),
        # 4PN (tail): (−3485/96 + 13879ν/72)π s_ℓ + (−7163/672 + 130583ν/2016)π δσ_ℓ
        #                                                              [Marsat+ 2014, Eq. (4.9)]
        8: ((-3485.0 / 96.0 + 13879.0 * nu / 72.0) * PI,
            (-7163.0 / 672.0 + 130583.0 * nu / 2016.0) * PI),
    }


def spin_spin_flux_per_body(X, kappa):
    """Orbit-averaged self-spin + QM flux coefficients of body i: {k: (c_SS, c_LL)},
    F̂ ∋ v^k [c_SS Sᵢ·Sᵢ + c_LL (ℓ̂·Sᵢ)²], Sᵢ = X²χᵢ."""
    return {
        # 2PN, averaged — self-spin: 7/(96X²) Sᵢ² − 1/(96X²)(ℓ̂·Sᵢ)²;
        #   quadrupole-monopole (κ): −1/X² Sᵢ² + 3/X² (ℓ̂·Sᵢ)²    [arXiv:1303.7412, Eq. (3.13) and
        #   Bohé+ 2015, Eq. (4.12) (as cited by LALSuite); Poisson 1998 for the QM part]
        4: (7.0 / (96.0 * (X * X)) - kappa / (X * X),
            -1.0 / (96.0 * (X * X)) + 3.0 * kappa / (X * X)),
        # 3PN, averaged — self-spin: (189/(16X²) − 35/(144X) + 47/144) Sᵢ²
        #                          + (−239/(16X²) + 293/(144X) + 299/144)(ℓ̂·Sᵢ)²;
        #   QM (κ): (279/(112X²) + 45/(16X) − 43/8) Sᵢ² + (−837/(112X²) − 135/(16X) + 129/8)(ℓ̂·Sᵢ)²
        #                                                         [Bohé+ 2015, arXiv:1501.01529, Eq. (4.12)]
        6: ((189.0 / (16.0 * (X * X)) - 35.0 / (144.0 * X) + 47.0 / 144.0)
            + kappa * (279.0 / (112.0 * (X * X)) + 45.0 / (16.0 * X) - 43.0 / 8.0),
            (-239.0 / (16.0 * (X * X)) + 293.0 / (144.0 * X) + 299.0 / 144.0)
            + kappa * (-837.0 / (112.0 * (X * X)) - 135.0 / (16.0 * X) + 129.0 / 8.0)),
    }


def spin1_spin2_flux(nu):
    """Orbit-averaged S₁S₂ flux coefficients {k: (c_S12, c_L12)}."""
    return {
        # 2PN, averaged: −103/(48ν) S₁·S₂ + 289/(48ν)(ℓ̂·S₁)(ℓ̂·S₂)   [Kidder 1995, gr-qc/9506022;
        #   in the n̂, λ̂ form of Bohé, Marsat & Blanchet 2013, arXiv:1303.7412, Eq. (3.13) (as cited by
        #   LALSuite) and Bohé+ 2015, Eq. (4.12); averaged as in Racine+ 2009 App. B]
        4: (-103.0 / (48.0 * nu), 289.0 / (48.0 * nu)),
        # 3PN, averaged: (2123/(84ν) + 821/72) S₁·S₂ + (−5647/(168ν) − 2023/72)(ℓ̂·S₁)(ℓ̂·S₂)
        #                                                           [Bohé+ 2015, arXiv:1501.01529, Eq. (4.12)]
        6: (2123.0 / (84.0 * nu) + 821.0 / 72.0, -5647.0 / (168.0 * nu) - 2023.0 / 72.0),
    }


def tidal_flux(X):
    """{k: c_k} with F̂ ∋ Λ c_k v^k for the body of mass fraction X and dimensionless deformability Λ.

    Vines, Flanagan & Hinderer 2011, arXiv:1101.1673, Eq. (3.6) ((3.7) on arXiv), for their body 2:
    F̂ ∋ [(18 − 12χ₂)/χ₂] λ̂ + [(−704 − 1803χ₂ + 4501χ₂² − 2170χ₂³)/(28χ₂)] λ̂ x with χᵢ = mᵢ/M,
    λ̂ = λ₂x⁵/M⁵ = Λ₂χ₂⁵v¹⁰ (their normalization as in :func:`pnrotor.pn.energy.tidal_energy`); for the body X:
    """
    X4 = (X * X) * (X * X)
    return {
        # 5PN: (18 − 12X) X⁴                                             [Vines+ 2011, Eq. (3.6)]
        10: (18.0 - 12.0 * X) * X4,
        # 6PN: (−704 − 1803X + 4501X² − 2170X³) X⁴/28                   [Vines+ 2011, Eq. (3.6)]
        12: (-704.0 - 1803.0 * X + 4501.0 * (X * X) - 2170.0 * (X * X * X)) * X4 / 28.0,
    }


@njit(cache=True)
def horizon_rates(X, nu, v, a, chi_sq):
    r"""(F̂_H, v ∂F̂_H/∂v, dS/dt, dm/dt) of the black hole of mass fraction X (G = c = M = 1) with spin χ⃗, a = ℓ̂·χ⃗
    and χ² = χ⃗·χ⃗, in a circular binary of symmetric mass ratio ν at v, averaged over the orbit, at leading order
    in the tidal coupling (exact in the spin): the energy flux into the horizon relative to the Newtonian flux
    (32/5)ν²v¹⁰ and its v-derivative at fixed spin (what the energy balance takes), the rate of the spin's magnitude
    S = X²|χ⃗| (the angular momentum absorbed along χ̂) and of the mass (dm/dt = (32/5)ν²v¹⁰ F̂_H).

    Alvi 2001 (gr-qc/0107080): the companion's quadrupolar tidal field, decomposed in harmonics m about the spin
    axis, each rotating at ω = mφ̇, gives dm/dt = φ̇ I₀ (φ̇ − Ω_H), dS/dt = I₀ (φ̇ − Ω_H) (his Eq. (21)), with
    I₀ = (16/5) ν² v¹² X⁴ (1 + κ) sin²θ (1 − ¾χ² + (15/4)χ² sin²θ) (his Eq. (10); M = 1; PostNewtonian.jl's
    ``tidal_heating`` writes them so), κ = √(1 − χ²), r_H = X(1 + κ), Ω_H = χ/(2 r_H), θ the angle between χ̂ and
    the companion.  That is the sum over m of C A_|m| |Y₂ₘ(θ)|² (mφ̇)(mφ̇ − mΩ_H) (and m(mφ̇ − mΩ_H) for dS/dt),
    C = (4π/15)(16/5)ν²v¹²X⁴(1 + κ), with A₁ = 1 − ¾χ², A₂ = 1 + 3χ²: the m-dependence of Teukolsky & Press
    1974's low-frequency horizon absorption, ∏ₙ₌₁² (n²κ² + m²χ²)/4, which also gives A₀ = κ⁴.  With the spin
    along ℓ̂ the field rotates rigidly (θ = π/2, φ̇ = Ω = v³).  With the spin tilted, cos ι = ℓ̂·χ̂ = c, it does not
    (θ changes along the orbit; Alvi's rigid rotation at φ̇ = Ω cos ι / sin²θ, which PostNewtonian.jl evaluates at
    each instant, leaves that out: for a hole of vanishing spin tilted by ι it averages to |cos ι| of the
    nonspinning hole's absorption, where that of a Schwarzschild hole, (16/45) m⁶ ⟨Ė_ab Ė^ab⟩, does not depend on
    any axis).  Here the field's harmonics about ℓ̂, m′ = 0 (static) and ±2 (ω = ±2Ω), are turned to the spin's
    axis with Wigner's d²ₘₘ′(ι), and each (m, ω) absorbs as above, ω(ω − mΩ_H) A_|m| and m(ω − mΩ_H) A_|m|; the
    average over the orbit sums them with weights |d²ₘ₂|²/8 (twice, for m′ = ±2) and |d²ₘ₀|²/12:

        dm/dt = C′[Ω² G − Ω Ω_H c H/2],   dS/dt = C′[Ω c H/2 − Ω_H L/8],   C′ = (16/5)ν²v¹²X⁴(1 + κ), Ω = v³,
        G = 1 − ¾χ² + (15/4)a² + ⅜(χ² − a²)²,   H = 2 + (9/4)χ² + (15/4)a²,
        L = 4(1 + c²) + χ²(33/4 + (9/2)c² + (45/4)c⁴);

    so F̂_H = ½X⁴(1 + κ) G v⁸ − ⅛ X³ a H v⁵.  Along ℓ̂ (a = ±χ) these are Alvi's I₀(1 + 3χ²) ν²v¹²… exactly:
    F̂_H = −¼X³a(1 + 3a²)v⁵ + ½X⁴(1 + κ)(1 + 3a²)v⁸, whose test-mass limit X → 1 is Tagoshi, Mano & Takasugi
    1997's −¼(q + 3q³)v⁵ (gr-qc/9711072) and, without spin, Poisson & Sasaki 1995's v⁸ (gr-qc/9412027); for
    χ → 0, G = H/2 = 1 at any tilt.  tests/test_pn_horizon.py checks the average against the orbit average of the
    unaveraged sum, computed from the spin-frame harmonics and their time derivatives.

    Terms of order ω² are Alvi's (complete for a nonrotating hole; for a rotating one the response's own frequency
    dependence adds a term of that order, Chatziioannou, Poisson & Yunes 2013, arXiv:1211.1686, not included).  A
    hole without spin (χ = 0) takes its axis along ℓ̂ (c = 1): it is spun up along ℓ̂ at dS/dt = C′Ω.
    """
    chi = math.sqrt(chi_sq)
    kappa = math.sqrt(max(0.0, 1.0 - chi_sq))
    c = a / chi if chi > 0.0 else 1.0
    a_sq = a * a
    d = chi_sq - a_sq
    c_sq = c * c
    G = 1.0 - 0.75 * chi_sq + 3.75 * a_sq + 0.375 * (d * d)
    H = 2.0 + 2.25 * chi_sq + 3.75 * a_sq
    L = 4.0 * (1.0 + c_sq) + chi_sq * (8.25 + c_sq * (4.5 + 11.25 * c_sq))
    v3 = v * v * v
    v5 = v3 * v * v
    v10 = v5 * v5
    X3 = X * X * X
    f8 = 0.5 * X3 * X * (1.0 + kappa) * G * (v5 * v3)   # v⁸: the orbit's                       [Alvi 2001, Eq. (21)]
    f5 = -0.125 * X3 * a * H * v5                       # v⁵: the horizon's rotation Ω_H          [Alvi 2001, Eq. (21)]
    fh = f8 + f5
    sdot = 3.2 * (nu * nu) * X3 * (v10 * v * v) * (0.5 * X * (1.0 + kappa) * v3 * c * H - 0.0625 * chi * L)
    return fh, 8.0 * f8 + 5.0 * f5, sdot, 6.4 * (nu * nu) * v10 * fh


def flux_series(X1, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """F̂(v): every known term (nonspinning to 4.5PN, spin-orbit to 4PN, spin² to 3PN, tidal at 5PN and 6PN),
    untruncated."""
    F = assemble(X1, kappa1, kappa2, nonspinning_flux_coefficients, spin_orbit_flux_sl_sigma,
                 spin_spin_flux_per_body, spin1_spin2_flux)
    return add_tidal(F, X1, 1.0 - X1, lambda1, lambda2, tidal_flux)
