r"""The numba right-hand sides and events of the post-Newtonian system (its layout: :mod:`pnrotor.pn.layout`).

Two specializations, each a top-level ``@njit(cache=True)`` function that :func:`pnrotor.ode.by_address`
compiles for ``RHS_SIG`` (or ``EVENTS_SIG``) when a run first needs it, so the DOP853 driver (which takes
first-class functions of that signature) is compiled once per machine and cached, and a run compiles
only the specialization it uses.  The
right-hand sides and event functions are compiled with ``error_model='numpy'``: they cannot raise (a
division by zero gives inf or nan, which the integrator reports as ``'nonfinite'``), so
:func:`~pnrotor.pn.evolve.evolve` passes them by address (:func:`pnrotor.ode.by_address`).  They are
also compiled with ``fastmath={'contract'}`` and nothing else of fastmath: a product and a sum may fuse
into one FMA (one rounding instead of two, where the CPU has FMA; faster), nothing is
reordered, and inf and nan propagate as without it.

* :func:`rhs_precessing` — state ``y = [v, χ₁(3), χ₂(3), R(4), Φ]`` (12 components; with horizon absorption 14,
  the masses m₁, m₂ in units of M at f_ref appended);
* :func:`rhs_aligned` — nonspinning and aligned spins, ``y = [v, Φ]``: ℓ̂ and the spins are constant,
  the spin equations and the precession are not integrated at all, and the frame is reconstructed
  exactly as R(t) = R₀ exp(Φ ẑ/2).

Approximant, PN orders and spin content are *data*: the parameter vector ``p`` (:mod:`pnrotor.pn.system`)
holds the series coefficients with every truncated term zeroed (see :mod:`pnrotor.pn.series`), so
one compiled function serves every approximant and order.  Each series is stored behind a header of
the powers of v that hold spin and logarithmic terms (:func:`~pnrotor.pn.series.fold_and_store`), so
an evaluation contracts the spin basis only where a term is, and :func:`~pnrotor.pn.series.eval_series`
gives v dS/dv with S (event 6).

Equations (units G = c = M = 1, t in units of M)
-------------------------------------------------
* Energy balance: v̇ = −F/E′ = (32ν/5) v⁹ N(v)/D(v), with E = −(νv²/2)Ê and F = (32/5)ν²v¹⁰F̂
  (:mod:`~pnrotor.pn.energy`, :mod:`~pnrotor.pn.flux`), N and D the approximant's
  (:mod:`~pnrotor.approximants`: TaylorT1 N = F̂, D = Ê′; TaylorT4 N = [F̂/Ê′], D = 1; TaylorT5 N = 1,
  D = [Ê′/F̂]), with neutron-star tides to first order in Λᵢ (:func:`pnrotor.pn.vdot.add_tides`).  With horizon
  absorption (p[P_HORIZON] ≠ 0, precessing state only) the flux into both horizons (a body with Λᵢ > 0, a neutron
  star, has none), averaged over the orbit (:func:`pnrotor.pn.flux.horizon_rates`), is computed at the current spins
  in the right-hand side and the events and added at first order: N + F̂_H (T1, T4), D − F̂_H (T5).

* Spins: χ̇ᵢ = Ωᵢ × χᵢ (:mod:`~pnrotor.pn.precession`); with horizon absorption also + (Ṡᵢ/Xᵢ²) χ̂ᵢ − 2(ṁᵢ/Xᵢ) χᵢ,
  the angular momentum and mass each horizon absorbs (Ṡᵢ, taken from the orbit, enters Ω_ℓ too), and the masses
  ṁᵢ are integrated as y[Y_M1], y[Y_M2].
* Frame: dR/dt = ½ Ω R with ℓ̂ = R ẑ R⁻¹, n̂ = R x̂ R⁻¹ (Boyle 2016, arXiv:1604.08139,
  eq:integrate-spinor; R unnormalized, its norm cancels in R v R⁻¹).  The orbital frame rotates with
  Ω = Φ̇ ℓ̂ + Ω_ℓ, Ω_ℓ = −ℓ̂ × (Ṡ₁ + Ṡ₂)/|L| the orbit-averaged precession of the orbital plane.
  Two equivalent ways of integrating it, selected by ``p[P_ROTOR]``:

      0 "coprecessing": the state holds R_p with dR_p/dt = ½ Ω_ℓ R_p, and R = R_p exp(Φ ẑ/2).
        Exact, because d/dt[R_p e^{Φẑ/2}] = ½Ω_ℓ R + ½Φ̇ R_p ẑ R_p⁻¹ R = ½(Ω_ℓ + Φ̇ ℓ̂) R and
        R_p ẑ R_p⁻¹ = R ẑ R⁻¹ = ℓ̂.  R_p varies on the precession time scale, so the integrator is
        not forced to resolve every orbit.
      1 "orbital": the state holds R itself, dR/dt = ½(Φ̇ ℓ̂ + Ω_ℓ) R, the orbital motion included
        (the paper's equation as written; needs steps that resolve the orbit).

* Phase: Φ̇ = v³ − |Ω_ℓ,LO|²/(4v³) (the shift only if ``p[P_SHIFT]`` = 1; arXiv:1507.00406).

A third right-hand side, :func:`rhs_precessing_instantaneous`, integrates the *instantaneous*
(not orbit-averaged) precession literally as Bohé et al. 2013 write it: the full orbital rotor R with
Ω = v³ ℓ̂ + ϖ n̂, ϖ from their Eqs. (4.3)–(4.4) (spin-orbit, LO–NNLO), and the spins with the
n̂-dependent 2PN (Kidder 1995 Eq. (2.4), Racine 2008 Eq. (2.7)) and 3PN (Bohé+ 2015 Eq. (A.2))
spin-spin terms — the model of PostNewtonian.jl, plus the 3PN spin-spin precession.  No spin-spin
part of ϖ is included (not available to us), and v̇ still uses the orbit-averaged energy and flux.
It exists to measure the difference between the two conventions (tests); it must resolve every orbit.

Events (all terminal), filled by :func:`events_precessing` / :func:`events_aligned`:
  0: v − v_end (requested end frequency, or v_max);   1: Ê′ (E′ = −νvÊ′ ≥ 0 ⇔ Ê′ ≤ 0);
  2: N·D (sign of v̇; a safety net: where N falls to zero event 6 fires first, where D does event 5,
     so only the spins' evolution can bring v̇ to zero);   3, 4: (1 + spin_tolerance) − |χᵢ|²;
  5: D − DEN_EPS: the denominator of v̇ (Ê′ for T1, the re-expanded Ê′/F̂ for T5; 1 for T4) about to
     vanish.  v̇ = K/D has a pole there with v* − v ∝ √(t* − t), which no step can cross; stopping at
     D = DEN_EPS = 1e-3 leaves t* − t ≈ DEN_EPS²/(2K|dD/dv|) ~ 1e-4 M (a phase of ~1e-5 rad) and
     v* − v ~ 1e-3.  (With 1e-6 the remaining interval, ~1e-10 M, is below the resolution of t ~ 1e5.)
  6: 11ND + (vN′)D − N(vD′) = v^{-10} D² ∂(v²v̇)/∂v / (32ν/5), at the current spins and ℓ̂: the
     orbital frequency's rate ω̇ = 3v²v̇/M stopped increasing.  Needed because event 2 alone is no end where
     N has a simple root v* (T4 with |χ| = 0.999 aligned at 3.5PN: v* = 0.6305): there v̇ ∝ v* − v, v
     approaches v* only exponentially, and the phase gained before round-off ends the run depends on atol
     (tens of radians).  LALSuite's SpinTaylor stops on this condition (d²ω/dt² ≤ 0 between steps, its
     code 1026, with ω = v³/M the variable it integrates): for aligned spins ω̈ = ω̇ ∂ω̇/∂v / (3v²/M) has
     the sign of ∂(v²v̇)/∂v, so the two tests agree; with precessing spins ours ignores the
     precession's slow modulation of v̇ through the spin invariants.
"""

import math

import numpy as np
from numba import njit

from .layout import (EV_ENERGY, EV_POLE, EV_SPIN1, EV_SPIN2, EV_V_END, EV_VDOT, EV_VDOT_PEAK, P_DEN, P_DEN_EPS, P_EP,
                     N_SS, P_ISS1, P_ISS2, P_L, P_NU, P_NUM, P_OMEGA_L, P_ROTOR, P_SHIFT, P_SO1, P_SO2, P_SPINTOL,
                     P_SS1, P_SS2, P_VARPI1, P_VARPI2, P_VDOT0, P_VEND, P_W1, P_W2, P_X1, P_X2,
                     P_HORIZON, P_HX1, P_HX2, Y_M1, Y_M2, Y_PHI, Y_R, Y_V, YA_PHI, YA_V)
from .flux import horizon_rates
from .series import eval_series

@njit(cache=True, inline="always")
def _ell_hat(w, x, y, z):
    """ℓ̂ = R ẑ R⁻¹ for the (possibly unnormalized) rotor R = (w, x, y, z): third column of the
    rotation matrix of R, the same convention as :func:`pnrotor.quaternion.qrotate`."""
    m = w * w + x * x + y * y + z * z
    c = 2.0 / m
    return c * (x * z + w * y), c * (y * z - w * x), (w * w - x * x - y * y + z * z) / m


@njit(cache=True, inline="always")
def _spin_basis(y, lx, ly, lz):
    """The spin invariants (ℓ̂·χ₁, ℓ̂·χ₂, χ₁·χ₂, (ℓ̂·χ₁)(ℓ̂·χ₂), χ₁², (ℓ̂·χ₁)², χ₂², (ℓ̂·χ₂)²) of the
    state ``y``: the basis b₁…b₈ of :mod:`pnrotor.pn.series`."""
    c1x, c1y, c1z = y[1], y[2], y[3]
    c2x, c2y, c2z = y[4], y[5], y[6]
    a1 = lx * c1x + ly * c1y + lz * c1z
    a2 = lx * c2x + ly * c2y + lz * c2z
    s11 = c1x * c1x + c1y * c1y + c1z * c1z
    s22 = c2x * c2x + c2y * c2y + c2z * c2z
    return a1, a2, c1x * c2x + c1y * c2y + c1z * c2z, a1 * a2, s11, a1 * a1, s22, a2 * a2


@njit(cache=True, inline="always")
def _series(p, off, v, lnv, b):
    """(S, v dS/dv) of the series S stored at ``p[off:]``, at v with the spin basis ``b``."""
    return eval_series(p, off, v, lnv, True, b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7])


@njit(cache=True, inline="always")
def _folded(p, off, v, lnv):
    """(S, v dS/dv) of the series S stored at ``p[off:]`` folded into b = 0 (the aligned state), at v."""
    return eval_series(p, off, v, lnv, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@njit(cache=True, inline="always")
def horizon_flux(p, v, a1, s11, a2, s22):
    """(F̂_H, v ∂F̂_H/∂v) of both horizons (:func:`pnrotor.pn.flux.horizon_rates`) at v, with ℓ̂·χᵢ = aᵢ, χᵢ² = sᵢᵢ."""
    f1, f1_v, _, _ = horizon_rates(p[P_HX1], p[P_NU], v, a1, s11)
    f2, f2_v, _, _ = horizon_rates(p[P_HX2], p[P_NU], v, a2, s22)
    return f1 + f2, f1_v + f2_v


@njit(cache=True, inline="always")
def add_horizon(p, f, f_v, num, num_v, den, den_v):
    """(N, vN′, D, vD′) of v̇ with the flux into the horizons F̂_H (and v ∂F̂_H/∂v) in the energy balance at first
    order: added to N (T1: F̂ + F̂_H; T4: F̂/Ê′ + F̂_H, p[P_HORIZON] = 1), subtracted from D = [Ê′/F̂] (T5, −1)."""
    if p[P_HORIZON] > 0.0:
        return num + f, num_v + f_v, den, den_v
    return num, num_v, den - f, den_v - f_v


@njit(cache=True, inline="always")
def _vdot(p, v, num, den):
    """v̇ = (32ν/5) v⁹ N/D from N(v) and D(v) (module docstring)."""
    v3 = v * v * v
    return p[P_VDOT0] * v3 * v3 * v3 * num / den


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def rhs_precessing(t, y, p, dydt):
    """Right-hand side for the precessing state [v, χ₁, χ₂, R, Φ] (see module docstring)."""
    v = y[Y_V]
    lnv = math.log(v)
    c1x, c1y, c1z = y[1], y[2], y[3]
    c2x, c2y, c2z = y[4], y[5], y[6]
    rw, rx, ry, rz = y[7], y[8], y[9], y[10]
    lx, ly, lz = _ell_hat(rw, rx, ry, rz)

    X1 = p[P_X1]
    X2 = p[P_X2]
    b = _spin_basis(y, lx, ly, lz)
    a1, a2 = b[0], b[1]
    num = _series(p, P_NUM, v, lnv, b)[0]
    den = _series(p, P_DEN, v, lnv, b)[0]
    horizon = p[P_HORIZON] != 0.0
    s1 = s2 = m1 = m2 = 0.0
    if horizon:   # the flux into the horizons and the spins' and masses' rates (flux.horizon_rates; none for a star)
        f1, _, s1, m1 = horizon_rates(p[P_HX1], p[P_NU], v, a1, b[4])
        f2, _, s2, m2 = horizon_rates(p[P_HX2], p[P_NU], v, a2, b[6])
        num, _, den, _ = add_horizon(p, f1 + f2, 0.0, num, 0.0, den, 0.0)
    vdot = _vdot(p, v, num, den)
    v2 = v * v
    v3 = v2 * v
    v5 = v3 * v2
    v6 = v3 * v3
    v8 = v6 * v2

    # in-plane parts χᵢ⊥ = χᵢ − (ℓ̂·χᵢ) ℓ̂
    p1x, p1y, p1z = c1x - a1 * lx, c1y - a1 * ly, c1z - a1 * lz
    p2x, p2y, p2z = c2x - a2 * lx, c2y - a2 * ly, c2z - a2 * lz

    # Ω₁ = v⁵(σ₀+σ₂v²+σ₄v⁴) ℓ̂ + v⁶[c_j χ₂ + c_j⊥ χ₂⊥ + c_i⊥ χ₁⊥] + v⁸[...]: the series of precession.py, written out
    # (a loop over their terms changes how LLVM fuses products and sums into FMAs, and so the last bits)
    sig1 = p[P_SO1] + v2 * (p[P_SO1 + 1] + v2 * p[P_SO1 + 2])
    so1 = v5 * sig1
    kj1 = v6 * p[P_SS1] + v8 * p[P_SS1 + 1]
    kjp1 = v6 * p[P_SS1 + N_SS] + v8 * p[P_SS1 + N_SS + 1]
    kip1 = v6 * p[P_SS1 + 2 * N_SS] + v8 * p[P_SS1 + 2 * N_SS + 1]
    o1x = so1 * lx + kj1 * c2x + kjp1 * p2x + kip1 * p1x
    o1y = so1 * ly + kj1 * c2y + kjp1 * p2y + kip1 * p1y
    o1z = so1 * lz + kj1 * c2z + kjp1 * p2z + kip1 * p1z
    sig2 = p[P_SO2] + v2 * (p[P_SO2 + 1] + v2 * p[P_SO2 + 2])
    so2 = v5 * sig2
    kj2 = v6 * p[P_SS2] + v8 * p[P_SS2 + 1]
    kjp2 = v6 * p[P_SS2 + N_SS] + v8 * p[P_SS2 + N_SS + 1]
    kip2 = v6 * p[P_SS2 + 2 * N_SS] + v8 * p[P_SS2 + 2 * N_SS + 1]
    o2x = so2 * lx + kj2 * c1x + kjp2 * p1x + kip2 * p2x
    o2y = so2 * ly + kj2 * c1y + kjp2 * p1y + kip2 * p2y
    o2z = so2 * lz + kj2 * c1z + kjp2 * p1z + kip2 * p2z

    # χ̇ᵢ = Ωᵢ × χᵢ
    d1x = o1y * c1z - o1z * c1y
    d1y = o1z * c1x - o1x * c1z
    d1z = o1x * c1y - o1y * c1x
    d2x = o2y * c2z - o2z * c2y
    d2y = o2z * c2x - o2x * c2z
    d2z = o2x * c2y - o2y * c2x

    # Ω_ℓ = −ℓ̂ × (X₁²χ̇₁ + X₂²χ̇₂) / |L| with |L| = (ν/v)(1 + L₂v² + L₄v⁴).  Its spin-orbit part is
    # v⁶ Σᵢ uᵢ χᵢ⊥ with uᵢ = Xᵢ²(σ₀ + σ₂v² + σ₄v⁴)/(ν(1 + L₂v² + L₄v⁴)); with P_OMEGA_L = 1 that part
    # is replaced by Bohé et al.'s ⟨ϖ n̂⟩, uᵢ = ½(w₀ + w₂v² + w₄v⁴) (precession.py).
    q1 = X1 * X1
    q2 = X2 * X2
    ex1, ey1, ez1 = d1x - so1 * (ly * c1z - lz * c1y), d1y - so1 * (lz * c1x - lx * c1z), d1z - so1 * (lx * c1y - ly * c1x)
    ex2, ey2, ez2 = d2x - so2 * (ly * c2z - lz * c2y), d2y - so2 * (lz * c2x - lx * c2z), d2z - so2 * (lx * c2y - ly * c2x)
    if horizon:
        # the angular momentum Ṡᵢ each horizon absorbs, along χ̂ᵢ (ℓ̂ for a hole without spin), is the orbit's (so it
        # tilts ℓ̂ too, in Ω_ℓ); the mass ṁᵢ rescales χᵢ = Sᵢ/mᵢ²: χ̇ᵢ ∋ (Ṡᵢ/Xᵢ²) χ̂ᵢ − 2(ṁᵢ/Xᵢ) χᵢ
        t1x, t1y, t1z = _along_spin(s1 / q1, b[4], c1x, c1y, c1z, lx, ly, lz)
        t2x, t2y, t2z = _along_spin(s2 / q2, b[6], c2x, c2y, c2z, lx, ly, lz)
        ex1, ey1, ez1 = ex1 + t1x, ey1 + t1y, ez1 + t1z
        ex2, ey2, ez2 = ex2 + t2x, ey2 + t2y, ez2 + t2z
        h1, h2 = 2.0 * m1 / X1, 2.0 * m2 / X2
        d1x, d1y, d1z = d1x + t1x - h1 * c1x, d1y + t1y - h1 * c1y, d1z + t1z - h1 * c1z
        d2x, d2y, d2z = d2x + t2x - h2 * c2x, d2y + t2y - h2 * c2y, d2z + t2z - h2 * c2z
        dydt[Y_M1] = m1
        dydt[Y_M2] = m2
    sx = q1 * ex1 + q2 * ex2
    sy = q1 * ey1 + q2 * ey2
    sz = q1 * ez1 + q2 * ez2
    inv_vL = 1.0 / (p[P_NU] * (1.0 + v2 * (p[P_L] + v2 * p[P_L + 1])))   # 1/(v|L|)
    inv_L = v * inv_vL
    if p[P_OMEGA_L] == 0.0:
        u1 = q1 * sig1 * inv_vL
        u2 = q2 * sig2 * inv_vL
    else:
        u1 = 0.5 * (p[P_VARPI1] + v2 * (p[P_VARPI1 + 1] + v2 * p[P_VARPI1 + 2]))
        u2 = 0.5 * (p[P_VARPI2] + v2 * (p[P_VARPI2 + 1] + v2 * p[P_VARPI2 + 2]))
    wx = -(ly * sz - lz * sy) * inv_L + v6 * (u1 * p1x + u2 * p2x)
    wy = -(lz * sx - lx * sz) * inv_L + v6 * (u1 * p1y + u2 * p2y)
    wz = -(lx * sy - ly * sx) * inv_L + v6 * (u1 * p1z + u2 * p2z)

    # Φ̇ = v³ − |Σ wᵢ χᵢ⊥|² v⁹ / 4   (only if P_SHIFT)
    phidot = v3
    if p[P_SHIFT] != 0.0:
        ux = p[P_W1] * p1x + p[P_W2] * p2x
        uy = p[P_W1] * p1y + p[P_W2] * p2y
        uz = p[P_W1] * p1z + p[P_W2] * p2z
        phidot -= 0.25 * (ux * ux + uy * uy + uz * uz) * v6 * v3

    # frame angular velocity: Ω_ℓ (coprecessing) or Φ̇ ℓ̂ + Ω_ℓ (orbital)
    if p[P_ROTOR] != 0.0:
        wx += phidot * lx
        wy += phidot * ly
        wz += phidot * lz

    # dR/dt = ½ (0, Ω) R   (Hamilton product of the pure quaternion Ω with R)
    dydt[Y_R] = 0.5 * (-wx * rx - wy * ry - wz * rz)
    dydt[Y_R + 1] = 0.5 * (wx * rw + wy * rz - wz * ry)
    dydt[Y_R + 2] = 0.5 * (-wx * rz + wy * rw + wz * rx)
    dydt[Y_R + 3] = 0.5 * (wx * ry - wy * rx + wz * rw)

    dydt[Y_V] = vdot
    dydt[1] = d1x
    dydt[2] = d1y
    dydt[3] = d1z
    dydt[4] = d2x
    dydt[5] = d2y
    dydt[6] = d2z
    dydt[Y_PHI] = phidot


@njit(cache=True, inline="always")
def _along_spin(rate, chi_sq, cx, cy, cz, lx, ly, lz):
    """rate · χ̂ for the spin χ = (cx, cy, cz) of square norm chi_sq; rate · ℓ̂ where χ = 0."""
    if chi_sq > 0.0:
        g = rate / math.sqrt(chi_sq)
        return g * cx, g * cy, g * cz
    return rate * lx, rate * ly, rate * lz


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def rhs_precessing_instantaneous(t, y, p, dydt):
    """Right-hand side for [v, χ₁, χ₂, R, Φ] with the instantaneous precession (module docstring);
    R is the full orbital-frame rotor: n̂ = R x̂ R⁻¹, ℓ̂ = R ẑ R⁻¹."""
    v = y[Y_V]
    lnv = math.log(v)
    c1x, c1y, c1z = y[1], y[2], y[3]
    c2x, c2y, c2z = y[4], y[5], y[6]
    rw, rx, ry, rz = y[7], y[8], y[9], y[10]
    m = rw * rw + rx * rx + ry * ry + rz * rz
    c = 2.0 / m
    # columns of the rotation matrix of R: n̂ = R x̂ R⁻¹, λ̂ = R ŷ R⁻¹, ℓ̂ = R ẑ R⁻¹
    nx, ny, nz = 1.0 - c * (ry * ry + rz * rz), c * (rx * ry + rw * rz), c * (rx * rz - rw * ry)
    mx, my, mz = c * (rx * ry - rw * rz), 1.0 - c * (rx * rx + rz * rz), c * (ry * rz + rw * rx)
    lx, ly, lz = c * (rx * rz + rw * ry), c * (ry * rz - rw * rx), 1.0 - c * (rx * rx + ry * ry)

    b = _spin_basis(y, lx, ly, lz)
    dydt[Y_V] = _vdot(p, v, _series(p, P_NUM, v, lnv, b)[0], _series(p, P_DEN, v, lnv, b)[0])
    v2 = v * v
    v3 = v2 * v
    v5 = v3 * v2
    v6 = v3 * v3
    v8 = v6 * v2

    n1 = nx * c1x + ny * c1y + nz * c1z
    n2 = nx * c2x + ny * c2y + nz * c2z
    m1 = mx * c1x + my * c1y + mz * c1z
    m2 = mx * c2x + my * c2y + mz * c2z

    # Ω₁ = v⁵(σ…)ℓ̂ + v⁶[a_j χ₂ + a_jn (n̂·χ₂)n̂ + a_in (n̂·χ₁)n̂]
    #      + v⁸[b_j χ₂ + b_jn (n̂·χ₂)n̂ + b_jλ (λ̂·χ₂)λ̂ + b_in (n̂·χ₁)n̂ + b_iλ (λ̂·χ₁)λ̂]
    so1 = v5 * (p[P_SO1] + v2 * (p[P_SO1 + 1] + v2 * p[P_SO1 + 2]))
    kj = v6 * p[P_ISS1] + v8 * p[P_ISS1 + 3]
    kn = v6 * (p[P_ISS1 + 1] * n2 + p[P_ISS1 + 2] * n1) + v8 * (p[P_ISS1 + 4] * n2 + p[P_ISS1 + 6] * n1)
    km = v8 * (p[P_ISS1 + 5] * m2 + p[P_ISS1 + 7] * m1)
    o1x = so1 * lx + kj * c2x + kn * nx + km * mx
    o1y = so1 * ly + kj * c2y + kn * ny + km * my
    o1z = so1 * lz + kj * c2z + kn * nz + km * mz
    so2 = v5 * (p[P_SO2] + v2 * (p[P_SO2 + 1] + v2 * p[P_SO2 + 2]))
    kj = v6 * p[P_ISS2] + v8 * p[P_ISS2 + 3]
    kn = v6 * (p[P_ISS2 + 1] * n1 + p[P_ISS2 + 2] * n2) + v8 * (p[P_ISS2 + 4] * n1 + p[P_ISS2 + 6] * n2)
    km = v8 * (p[P_ISS2 + 5] * m1 + p[P_ISS2 + 7] * m2)
    o2x = so2 * lx + kj * c1x + kn * nx + km * mx
    o2y = so2 * ly + kj * c1y + kn * ny + km * my
    o2z = so2 * lz + kj * c1z + kn * nz + km * mz

    dydt[1] = o1y * c1z - o1z * c1y
    dydt[2] = o1z * c1x - o1x * c1z
    dydt[3] = o1x * c1y - o1y * c1x
    dydt[4] = o2y * c2z - o2z * c2y
    dydt[5] = o2z * c2x - o2x * c2z
    dydt[6] = o2x * c2y - o2y * c2x

    # Ω = v³ ℓ̂ + ϖ n̂,  ϖ = v⁶ Σᵢ wᵢ(v) (n̂·χᵢ)
    varpi = v6 * ((p[P_VARPI1] + v2 * (p[P_VARPI1 + 1] + v2 * p[P_VARPI1 + 2])) * n1
                  + (p[P_VARPI2] + v2 * (p[P_VARPI2 + 1] + v2 * p[P_VARPI2 + 2])) * n2)
    wx = v3 * lx + varpi * nx
    wy = v3 * ly + varpi * ny
    wz = v3 * lz + varpi * nz
    dydt[Y_R] = 0.5 * (-wx * rx - wy * ry - wz * rz)
    dydt[Y_R + 1] = 0.5 * (wx * rw + wy * rz - wz * ry)
    dydt[Y_R + 2] = 0.5 * (-wx * rz + wy * rw + wz * rx)
    dydt[Y_R + 3] = 0.5 * (wx * ry - wy * rx + wz * rw)
    dydt[Y_PHI] = v3


@njit(inline="always")
def vdot_peak(n, d, n_v, d_v):
    """Event 6 from N, D of v̇ and vN′, vD′ at one v: 11ND + (vN′)D − N(vD′), the sign of ∂(v²v̇)/∂v (module
    docstring); inlined where it is called, in the caller's floating-point mode."""
    return 11.0 * n * d + n_v * d - n * d_v


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def events_precessing(t, y, p, g):
    """Event functions for the precessing state (module docstring)."""
    v = y[Y_V]
    lnv = math.log(v) if v > 0.0 else -np.inf
    lx, ly, lz = _ell_hat(y[7], y[8], y[9], y[10])
    b = _spin_basis(y, lx, ly, lz)
    num, num_v = _series(p, P_NUM, v, lnv, b)
    den, den_v = _series(p, P_DEN, v, lnv, b)
    if p[P_HORIZON] != 0.0:
        f, f_v = horizon_flux(p, v, b[0], b[4], b[1], b[6])
        num, num_v, den, den_v = add_horizon(p, f, f_v, num, num_v, den, den_v)
    g[EV_V_END] = v - p[P_VEND]
    g[EV_ENERGY] = _series(p, P_EP, v, lnv, b)[0]
    g[EV_VDOT] = num * den
    g[EV_SPIN1] = 1.0 + p[P_SPINTOL] - b[4]
    g[EV_SPIN2] = 1.0 + p[P_SPINTOL] - b[6]
    g[EV_POLE] = den - p[P_DEN_EPS]
    g[EV_VDOT_PEAK] = vdot_peak(num, den, num_v, den_v)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def rhs_aligned(t, y, p, dydt):
    """Right-hand side for nonspinning / aligned-spin runs, y = [v, Φ]; the spin invariants are folded
    into the b = 0 column of the series at setup (:func:`pnrotor.pn.series.fold_basis`)."""
    v = y[YA_V]
    lnv = math.log(v)
    dydt[YA_V] = _vdot(p, v, _folded(p, P_NUM, v, lnv)[0], _folded(p, P_DEN, v, lnv)[0])
    dydt[YA_PHI] = v * v * v


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def events_aligned(t, y, p, g):
    """Event functions for the aligned state (events 3, 4 never fire: the spins are constant)."""
    v = y[YA_V]
    lnv = math.log(v) if v > 0.0 else -np.inf
    num, num_v = _folded(p, P_NUM, v, lnv)
    den, den_v = _folded(p, P_DEN, v, lnv)
    g[EV_V_END] = v - p[P_VEND]
    g[EV_ENERGY] = _folded(p, P_EP, v, lnv)[0]
    g[EV_VDOT] = num * den
    g[EV_SPIN1] = 1.0
    g[EV_SPIN2] = 1.0
    g[EV_POLE] = den - p[P_DEN_EPS]
    g[EV_VDOT_PEAK] = vdot_peak(num, den, num_v, den_v)
