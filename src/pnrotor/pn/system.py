r"""State layout, parameter vector and numba right-hand sides of the post-Newtonian system.

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

Approximant (TaylorT1/T4/T5), PN orders and spin content are *data*: the parameter vector ``p``
holds the series coefficients with every truncated term zeroed (see :mod:`pnrotor.pn.series`), so
one compiled function serves every approximant and order.  Each series is stored behind a header of
the powers of v that hold spin and logarithmic terms (:func:`~pnrotor.pn.series.fold_and_store`), so
an evaluation contracts the spin basis only where a term is, and :func:`~pnrotor.pn.series.eval_series`
gives v dS/dv with S (event 6).

Equations (units G = c = M = 1, t in units of M)
-------------------------------------------------
* Energy balance: v̇ = −F/E′ = (32ν/5) v⁹ N(v)/D(v), with E = −(νv²/2)Ê and F = (32/5)ν²v¹⁰F̂
  (:mod:`~pnrotor.pn.energy`, :mod:`~pnrotor.pn.flux`), and

      TaylorT1: N = F̂, D = Ê′ evaluated as they are;
      TaylorT4: N = [F̂/Ê′] re-expanded and truncated, D = 1;
      TaylorT5: N = 1, D = [Ê′/F̂] re-expanded and truncated (the inverse, Ajith 2011, arXiv:1107.1267);

  with neutron-star tides, the 5PN and 6PN tidal terms of Ê and F̂ (Vines et al. 2011) added to F̂ and Ê′ (T1)
  or carried through the re-expansion to first order in Λᵢ (T4, T5), as LALSuite's SpinTaylor does
  (:func:`_add_tides`).  With horizon absorption (p[P_HORIZON] ≠ 0, precessing state only) the flux into both
  horizons (a body with Λᵢ > 0, a neutron star, has none), averaged over the orbit
  (:func:`pnrotor.pn.flux.horizon_rates`), is computed at the current spins in the right-hand side and the events
  and added at first order: N + F̂_H (T1, T4), D − F̂_H (T5).

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

import functools
import math

import numpy as np
from numba import njit

from ..ode.common import events_function
from .energy import energy_derivative_series, energy_series
from .flux import flux_series, horizon_rates
from .precession import (angular_momentum_coefficients, phase_shift_weights, precession_terms, spin_orbit_precession,
                         spin_spin_precession_2pn, spin_spin_precession_3pn, spin_spin_precession_3pn_instantaneous,
                         varpi_coefficients)
from .series import (SERIES_SLOTS, TIDAL_K, divide, eval_at, eval_series, fold_and_store, shape_of, truncate,
                     v_derivative)

# ---------------------------------------------------------------------------------------------------
# state layout
# ---------------------------------------------------------------------------------------------------
Y_V = 0
Y_CHI1 = 1      # 1, 2, 3
Y_CHI2 = 4      # 4, 5, 6
Y_R = 7         # 7, 8, 9, 10  (w, x, y, z)
Y_PHI = 11
N_PRECESSING = 12
# with horizon absorption (P_HORIZON ≠ 0) the precessing state carries the masses too: [v, χ₁, χ₂, R, Φ, m₁, m₂]
Y_M1 = 12
Y_M2 = 13
# aligned state
YA_V = 0
YA_PHI = 1
N_ALIGNED = 2

N_EVENTS = 7
EV_V_END, EV_ENERGY, EV_VDOT, EV_SPIN1, EV_SPIN2, EV_POLE, EV_VDOT_PEAK = range(N_EVENTS)

# ---------------------------------------------------------------------------------------------------
# parameter vector layout
# ---------------------------------------------------------------------------------------------------
P_X1 = 0
P_X2 = 1
P_NU = 2
P_VDOT0 = 3      # 32ν/5
P_VEND = 4       # v at which event 0 fires
P_ROTOR = 5      # 0 coprecessing, 1 orbital
P_SHIFT = 6      # 1: apply the precession phase shift
P_W1 = 7         # phase-shift weights w₁, w₂
P_W2 = 8
P_SO1 = 9        # σ₀, σ₂, σ₄ of body 1 (zeroed when truncated)
P_SO2 = 12       # σ₀, σ₂, σ₄ of body 2
P_SS2_1 = 15     # 2PN spin-spin: c_j, c_j⊥, c_i⊥ for body 1
P_SS2_2 = 18     # ... body 2
P_SS3_1 = 21     # 3PN spin-spin: c_j, c_j⊥, c_i⊥ for body 1
P_SS3_2 = 24     # ... body 2
P_L2 = 27        # |L| = (ν/v)(1 + L₂v² + L₄v⁴)
P_L4 = 28
P_SPINTOL = 29   # |χ|² may exceed 1 by this much before event 3/4 fires
P_DEN_EPS = 30   # event 5 fires when the denominator D of v̇ falls to this value
# instantaneous precession (rhs_precessing_instantaneous only)
P_VARPI1 = 31    # w₀, w₂, w₄ of ϖ for body 1 (zeroed when truncated)
P_VARPI2 = 34    # ... body 2
P_ISS1 = 37      # body 1: 2PN a_j, a_jn, a_in; 3PN b_j, b_jn, b_jλ, b_in, b_iλ (zeroed when truncated)
P_ISS2 = 45      # ... body 2
P_OMEGA_L = 53   # 0: Ω_ℓ from −ℓ̂ × (Ṡ₁ + Ṡ₂)/|L| (LALSuite); 1: its spin-orbit part from ⟨ϖ n̂⟩ (Bohé+ 2013)
P_HORIZON = 54   # horizon absorption: 0 none; 1 F̂_H added to N (T1, T4); −1 subtracted from D (T5)
P_HX1 = 55       # with horizon absorption: X₁ if body 1 has a horizon (Λ₁ = 0), 0 for a neutron star (no absorption)
P_HX2 = 56       # ... body 2
# the series N, D, Ê′, each a header and its coefficients (series.fold_and_store)
P_NUM = 57
P_DEN = P_NUM + SERIES_SLOTS
P_EP = P_DEN + SERIES_SLOTS
P_SIZE = P_EP + SERIES_SLOTS

SPIN_TOL = 1e-10
DEN_EPS = 1e-3


def spin_tolerance(atol, rtol):
    """How far |χᵢ|² may exceed 1 before events 3/4 end a run: 1000 (atol + rtol), at least SPIN_TOL and at
    most 1e-3 (a drift of that size is a failed integration whatever was asked).  The
    equations conserve |χᵢ|; the integration lets it drift by a few atol, which with a fixed 1e-10 ended such runs
    as 'spin_magnitude' from atol 1e-10 up (at
    1e-6, at 21 Hz instead of 197): only a real failure ends a run here, not the requested tolerance."""
    return min(1e-3, max(SPIN_TOL, 1e3 * (atol + rtol)))


# ---------------------------------------------------------------------------------------------------
# numba kernels
# ---------------------------------------------------------------------------------------------------

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
def _horizon_flux(p, v, a1, s11, a2, s22):
    """(F̂_H, v ∂F̂_H/∂v) of both horizons (:func:`pnrotor.pn.flux.horizon_rates`) at v, with ℓ̂·χᵢ = aᵢ, χᵢ² = sᵢᵢ."""
    f1, f1_v, _, _ = horizon_rates(p[P_HX1], p[P_NU], v, a1, s11)
    f2, f2_v, _, _ = horizon_rates(p[P_HX2], p[P_NU], v, a2, s22)
    return f1 + f2, f1_v + f2_v


@njit(cache=True, inline="always")
def _add_horizon(p, f, f_v, num, num_v, den, den_v):
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
        num, _, den, _ = _add_horizon(p, f1 + f2, 0.0, num, 0.0, den, 0.0)
    vdot = _vdot(p, v, num, den)
    v2 = v * v
    v3 = v2 * v
    v5 = v3 * v2
    v6 = v3 * v3
    v8 = v6 * v2

    # in-plane parts χᵢ⊥ = χᵢ − (ℓ̂·χᵢ) ℓ̂
    p1x, p1y, p1z = c1x - a1 * lx, c1y - a1 * ly, c1z - a1 * lz
    p2x, p2y, p2z = c2x - a2 * lx, c2y - a2 * ly, c2z - a2 * lz

    # Ω₁ = v⁵(σ₀+σ₂v²+σ₄v⁴) ℓ̂ + v⁶[c_j χ₂ + c_j⊥ χ₂⊥ + c_i⊥ χ₁⊥] + v⁸[...]   (precession.py)
    sig1 = p[P_SO1] + v2 * (p[P_SO1 + 1] + v2 * p[P_SO1 + 2])
    so1 = v5 * sig1
    kj1 = v6 * p[P_SS2_1] + v8 * p[P_SS3_1]
    kjp1 = v6 * p[P_SS2_1 + 1] + v8 * p[P_SS3_1 + 1]
    kip1 = v6 * p[P_SS2_1 + 2] + v8 * p[P_SS3_1 + 2]
    o1x = so1 * lx + kj1 * c2x + kjp1 * p2x + kip1 * p1x
    o1y = so1 * ly + kj1 * c2y + kjp1 * p2y + kip1 * p1y
    o1z = so1 * lz + kj1 * c2z + kjp1 * p2z + kip1 * p1z
    sig2 = p[P_SO2] + v2 * (p[P_SO2 + 1] + v2 * p[P_SO2 + 2])
    so2 = v5 * sig2
    kj2 = v6 * p[P_SS2_2] + v8 * p[P_SS3_2]
    kjp2 = v6 * p[P_SS2_2 + 1] + v8 * p[P_SS3_2 + 1]
    kip2 = v6 * p[P_SS2_2 + 2] + v8 * p[P_SS3_2 + 2]
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
    inv_vL = 1.0 / (p[P_NU] * (1.0 + v2 * (p[P_L2] + v2 * p[P_L4])))   # 1/(v|L|)
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
        f, f_v = _horizon_flux(p, v, b[0], b[4], b[1], b[6])
        num, num_v, den, den_v = _add_horizon(p, f, f_v, num, num_v, den, den_v)
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


# ---------------------------------------------------------------------------------------------------
# parameter vector
# ---------------------------------------------------------------------------------------------------

APPROXIMANTS = ("T1", "T4", "T5")


def vdot_series(X1, approximant, kmax, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """(N, D, Ê′) series of v̇ = (32ν/5) v⁹ N/D for the approximant, truncated by ``kmax``."""
    if approximant not in APPROXIMANTS:
        raise ValueError(f"approximant must be one of {APPROXIMANTS}, got {approximant!r}")
    E, F = energy_series(X1, kappa1, kappa2, lambda1, lambda2), flux_series(X1, kappa1, kappa2, lambda1, lambda2)
    approx = APPROXIMANTS.index(approximant)
    N, D, Ep = _vdot_series(E, F, kmax, approx)
    _add_tides(E, F, kmax, approx, N, D, Ep)
    return N, D, Ep


@njit(cache=True)
def _vdot_series(E_raw, F_raw, kmax, approx):
    """(N, D, Ê′) from the untruncated Ê and F̂; approx 0, 1, 2 = T1, T4, T5 (module docstring), without their tidal
    terms (k ≥ TIDAL_K), which :func:`_add_tides` adds."""
    E = truncate(E_raw.copy(), kmax)   # the point-particle and spin terms (k ≤ 9: no tidal term is kept)
    Ep = energy_derivative_series(E)   # the derivative keeps the powers of v, so it stays truncated
    F = truncate(F_raw.copy(), kmax)
    one = np.zeros_like(E)
    one[0, 0, 0] = 1.0
    if approx == 0:
        N, D = F, Ep.copy()
    elif approx == 1:
        N, D = divide(F, Ep, kmax), one
    else:
        N, D = one, divide(Ep, F, kmax)
    return N, D, Ep


def _add_tides(E_raw, F_raw, kmax, approx, N, D, Ep):
    """Add the tidal terms of E_raw and F_raw (b = 0, TIDAL_K ≤ k ≤ kmax[3], linear in Λ, no logarithm) to N, D and
    Ê′ in place: series of one binary (NK, NB, NL), or of n binaries, n first (numpy, elementwise: each binary's
    numbers are those of a call with its own series).

    T1 adds them to F̂ and Ê′ as they are.  T4 and T5 re-expand the ratio to first order in Λ, every tidal term
    kept to kmax[3] whatever the point-particle order: with Q = F̂/Ê′ (T4), Q_t = (F̂_t − Q_pp Ê′_t)/Ê′_pp, and
    the same with F̂ and Ê′ exchanged for T5 (series.divide's recursion, Q_k = (N_k − Σ_{i≥1} D_i Q_{k−i})/D_0,
    on the tidal powers).  Only the point-particle terms up to v² reach k ≤ 12 times a tidal term (there are no
    spin terms below v³ and no logarithms below v⁶), so Q_pp and Ê′_pp are taken at 1PN, without spins: LALSuite's
    fixed SpinTaylorT4 and T5 tidal coefficients (``XLALSimInspiralTaylorT4wdot_1{0,2}PNTidalCoeff``,
    ``XLALSimInspiralTaylorT2dtdv_1{0,2}PNTidalCoeff``), which tests/test_pn_tides.py checks these against.
    In numpy on the coefficients, not compiled: they add nothing to a cold start."""
    top = min(int(kmax[3]), N.shape[-3] - 1)
    powers = range(TIDAL_K, top + 1)
    e_t = {k: 0.5 * (k + 2) * E_raw[..., k, 0, 0] for k in powers}   # Ê′ of the tidal energy terms
    f_t = {k: F_raw[..., k, 0, 0] for k in powers}
    if not any(np.any(e_t[k]) or np.any(f_t[k]) for k in powers):
        return
    if approx == 0:
        N_t, D_t = f_t, e_t
    else:
        e1 = [0.5 * (k + 2) * E_raw[..., k, 0, 0] for k in range(3)]   # the 1PN Ê′ and F̂
        f1 = [F_raw[..., k, 0, 0] for k in range(3)]
        num_pp, den_pp, num_t, den_t = (f1, e1, f_t, e_t) if approx == 1 else (e1, f1, e_t, f_t)
        q = []                           # Q_pp to v²
        for k in range(3):
            x = num_pp[k]
            for i in range(1, k + 1):
                x = x - den_pp[i] * q[k - i]
            q.append(x / den_pp[0])
        t = {}                           # Q_t
        for k in powers:
            x = num_t[k]
            for i in range(3):
                if k - i in den_t:
                    x = x - q[i] * den_t[k - i]
            for i in range(1, min(k - TIDAL_K, 2) + 1):
                x = x - den_pp[i] * t[k - i]
            t[k] = x / den_pp[0]
        N_t, D_t = (t, {}) if approx == 1 else ({}, t)
    for k in powers:
        for series, terms in ((N, N_t), (D, D_t), (Ep, e_t)):
            if k in terms:
                series[..., k, 0, 0] += terms[k]


@njit(cache=True)
def _store_series(N, D, Ep, basis, fold, p, v0):
    """Store N, D, Ê′ (folded for the aligned RHS) in p; return N, D, Ê′ and event 6 at v0 (N, D with the flux into
    the horizons where p[P_HORIZON] asks for it, at the spin invariants ``basis``)."""
    # offsets as np.int64: a plain constant would compile fold_and_store once per offset (Literal[int])
    fold_and_store(N, basis, fold, p, np.int64(P_NUM))
    fold_and_store(D, basis, fold, p, np.int64(P_DEN))
    fold_and_store(Ep, basis, fold, p, np.int64(P_EP))
    Nv, Dv = v_derivative(N), v_derivative(D)
    n0, d0 = eval_at(N, v0, basis), eval_at(D, v0, basis)
    n0_v, d0_v = eval_at(Nv, v0, basis), eval_at(Dv, v0, basis)
    if p[P_HORIZON] != 0.0:
        f, f_v = _horizon_flux(p, v0, basis[1], basis[5], basis[2], basis[7])
        n0, n0_v, d0, d0_v = _add_horizon(p, f, f_v, n0, n0_v, d0, d0_v)
    peak0 = vdot_peak(n0, d0, n0_v, d0_v)
    return n0, d0, eval_at(Ep, v0, basis), peak0


_SCAN_FROM, _SCAN_STEP = 0.05, 0.045
"""The grid below v₀ on which :func:`earlier_end` looks for an end of the inspiral: from v = 0.05 in steps of
~0.045 in ln v (4.6% in v)."""


@njit(cache=True)
def earlier_end(c_addr, jit_addr, y0, p):
    """The first v below v₀ = y0[0] where event 1, 2, 5 or 6 of the system's events function (its addresses, as
    :data:`pnrotor.ode.common.FUNCTIONS_LAYOUT` gives them) at the state y0 with that v reaches zero, or 0.0: a v₀
    beyond it lies past the end of the inspiral even where the events are positive again at v₀ (a review found
    f_ref = 1000 Hz accepted for an aligned 30 + 10 M☉ binary whose inspiral ends at 455 Hz, while 600 Hz was
    refused).  Found on a geometric grid from 0.05 to v₀ (:data:`_SCAN_STEP`: a band of failing events narrower
    than 4.6% in v can be missed, as :func:`inspiral_end`'s finer grid can miss narrower ones) and refined by
    bisection to 1e-12.  The events are the run's own compiled function, called by address: one small kernel for
    every system."""
    v0 = y0[Y_V]
    if not v0 > _SCAN_FROM:
        return 0.0
    g = events_function(c_addr, jit_addr)
    y = y0.copy()
    values = np.empty(N_EVENTS)
    points = math.ceil(math.log(v0 / _SCAN_FROM) / _SCAN_STEP)
    ratio = (v0 / _SCAN_FROM) ** (1.0 / points)
    lo = hi = _SCAN_FROM
    for _ in range(points):
        if _past_end(g, y, p, values, hi):
            while lo < hi and hi - lo > 1e-12:   # lo passed (or is the grid's first point)
                mid = 0.5 * (lo + hi)
                if _past_end(g, y, p, values, mid):
                    hi = mid
                else:
                    lo = mid
            return hi
        lo, hi = hi, hi * ratio
    return 0.0


@njit(cache=True)
def _past_end(events, y, p, values, v):
    """Whether event 1, 2, 5 or 6 of ``events`` at the state y with y[0] set to v is ≤ 0."""
    y[Y_V] = v
    events(0.0, y, p, values)
    return not (values[EV_ENERGY] > 0.0 and values[EV_VDOT] > 0.0 and values[EV_POLE] > 0.0
                and values[EV_VDOT_PEAK] > 0.0)


def make_parameters(X1, approximant, kmax, *, so_order, ss_order, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0,
                    v_end=1.0, spin_tol=SPIN_TOL, rotor="coprecessing", phase_shift=False, aligned_basis=None,
                    omega_l="torque", basis=None, v_check=None, horizon=False):
    """Build the parameter vector p.

    ``kmax``: from :func:`pnrotor.pn.series.kmax_from_orders`.  ``aligned_basis``: the nine
    invariants for the aligned/nonspinning right-hand side (folded into the series), or None for the
    precessing one.
    With ``v_check`` (and the invariants ``basis`` at that point) it returns (p, (N, D, Ê′, event 6) at
    v_check) instead of p, for checking the initial point.
    ``spin_tol``: how far |χᵢ|² may exceed 1 before events 3/4 end the run (:func:`spin_tolerance`).
    ``horizon``: the flux into the horizons in the energy balance and the spins' and masses' rates
    (:func:`pnrotor.pn.flux.horizon_rates`; p[P_HORIZON], :func:`_add_horizon`), for the precessing right-hand side
    with the state [v, χ₁, χ₂, R, Φ, m₁, m₂] (not with ``aligned_basis``).
    Everything but v_end, spin_tol and the stored series comes from :func:`_spin_independent_parts` (cached).
    :func:`start_rows` builds the same p for many binaries at once.
    """
    head, N, D, Ep = _spin_independent_parts(
        (X1, approximant, tuple(np.asarray(kmax).tolist()), so_order, ss_order, kappa1, kappa2,
         math.copysign(1.0, kappa1), math.copysign(1.0, kappa2), lambda1, lambda2, rotor, bool(phase_shift), omega_l,
         bool(horizon)))
    p = np.zeros(P_SIZE)
    p[:P_NUM] = head
    p[P_VEND] = v_end
    p[P_SPINTOL] = spin_tol
    fold = aligned_basis is not None
    if horizon and fold:
        raise ValueError("horizon absorption needs the precessing right-hand side: no aligned_basis")
    b = np.asarray(aligned_basis if fold else (basis if basis is not None else _UNIT_BASIS), dtype=np.float64)
    at_v = _store_series(N, D, Ep, b, fold, p, 0.5 if v_check is None else float(v_check))
    return p if v_check is None else (p, at_v)


@njit(cache=True)
def start_rows(heads, N, D, Ep, rows, bases, fold, v_end, spin_tol, c_addr, jit_addr, Y0, P, checks):
    """:func:`make_parameters` with ``v_check`` and :func:`earlier_end` for binaries i = 0 … n−1 (``evolve_many``'s
    set-up of a population, ``pnrotor.pn.evolve.build_rows``): P[i] (zeros on entry) is binary i's parameter
    vector, from row rows[i] of the spin-independent parts (heads, N, D, Ê′ of :func:`spin_independent_parts`),
    its spin invariants bases[i] (folded into the series if ``fold``, the aligned right-hand side), its end v_end[i]
    and ``spin_tol``; checks[i] = (N, D, Ê′, event 6) at v₀ = Y0[i, 0] and the :func:`earlier_end` of its initial
    state Y0[i] with the events at these addresses.  The head is copied element by element: an array slice
    assignment would compile numba's shape-mismatch error path, ~4 s on a cold cache (benchmarks/bench_compile.py)."""
    for i in range(P.shape[0]):
        j = rows[i]
        for k in range(P_NUM):
            P[i, k] = heads[j, k]
        P[i, P_VEND] = v_end[i]
        P[i, P_SPINTOL] = spin_tol
        checks[i, 0], checks[i, 1], checks[i, 2], checks[i, 3] = _store_series(N[j], D[j], Ep[j], bases[i], fold,
                                                                                P[i], Y0[i, Y_V])
        checks[i, 4] = earlier_end(c_addr, jit_addr, Y0[i], P[i])


@functools.lru_cache(maxsize=64)
def _spin_independent_parts(key):
    """:func:`spin_independent_parts` of one binary, ``key`` = (X1, approximant, kmax as a tuple, so_order,
    ss_order, κ₁, κ₂, the signs of κ₁ and κ₂ (a κ of −0.0 gives other signed zeros), Λ₁, Λ₂, rotor, phase_shift,
    omega_l, horizon), as (p head, N, D, Ê′), kept in a small LRU cache (repeated runs of one binary, or of one mass
    ratio, skip its ~65 µs of Python; code that replaces a coefficient function must call
    ``_spin_independent_parts.cache_clear()``).  The arrays are shared: make_parameters copies the head and only
    reads the series."""
    X1, approximant, kmax, so_order, ss_order, kappa1, kappa2, _, _, lambda1, lambda2, rotor, phase_shift, omega_l, \
        horizon = key
    p, N, D, Ep = spin_independent_parts(X1, kappa1, kappa2, approximant, kmax, so_order, ss_order, rotor,
                                         phase_shift, omega_l, lambda1, lambda2, horizon)
    return p[0], N[0], D[0], Ep[0]


def spin_independent_parts(X1, kappa1, kappa2, approximant, kmax, so_order, ss_order, rotor, phase_shift, omega_l,
                           lambda1=0.0, lambda2=0.0, horizon=False):
    """Everything :func:`make_parameters` (and :func:`start_rows`) builds that does not depend on the spins or
    v_end, for n binaries that share the options and differ in X1, κ₁, κ₂, Λ₁, Λ₂ (arrays (n,), or floats for one
    binary): (heads (n, P_NUM), p before the series, without v_end; N, D, Ê′ (n, NK, NB, NL), the series of
    :func:`vdot_series`).  Arrays take one pass of numpy over the binaries
    (``evolve_many``).  The numbers are built with the binaries
    last (p[j] = x is then a row) and turned binaries-first at the end (only the head of p: with all of it
    transposed they took ~10 µs per binary).  Binary i gets bitwise the numbers of a
    call with its floats: the coefficient functions are elementwise and use only +, −, ×, / (powers are
    written as products, since numpy's x ** k is not libm's pow on every CPU)."""
    if approximant not in APPROXIMANTS:
        raise ValueError(f"approximant must be one of {APPROXIMANTS}, got {approximant!r}")
    if rotor not in ("coprecessing", "orbital"):
        raise ValueError(f"rotor must be 'coprecessing' or 'orbital', got {rotor!r}")
    if omega_l not in ("torque", "varpi"):
        raise ValueError(f"omega_l must be 'torque' or 'varpi', got {omega_l!r}")

    def put(off, values):
        for j, x in enumerate(values):
            p[off + j] = x

    X2 = 1.0 - X1
    nu = X1 * X2
    p = np.zeros((P_NUM,) + shape_of(X1))    # p[j, i] of binary i
    p[P_X1] = X1
    p[P_X2] = X2
    p[P_NU] = nu
    p[P_VDOT0] = 32.0 * nu / 5.0
    p[P_ROTOR] = 1.0 if rotor == "orbital" else 0.0
    p[P_SHIFT] = 1.0 if phase_shift else 0.0
    p[P_OMEGA_L] = 1.0 if omega_l == "varpi" else 0.0
    if horizon:   # a body with a tidal deformability is a neutron star: no horizon
        p[P_HORIZON] = -1.0 if approximant == "T5" else 1.0
        p[P_HX1] = np.where(np.asarray(lambda1) == 0.0, X1, 0.0)
        p[P_HX2] = np.where(np.asarray(lambda2) == 0.0, X2, 0.0)
    put(P_W1, phase_shift_weights(X1, X2))
    inc = precession_terms(so_order, ss_order)
    keep_so = (inc["so_lo"], inc["so_nlo"], inc["so_nnlo"])
    for so, ss2, ss3, w, iss, (Xi, Xj, ki) in ((P_SO1, P_SS2_1, P_SS3_1, P_VARPI1, P_ISS1, (X1, X2, kappa1)),
                                                (P_SO2, P_SS2_2, P_SS3_2, P_VARPI2, P_ISS2, (X2, X1, kappa2))):
        put(so, [c if keep else 0.0 for c, keep in zip(spin_orbit_precession(Xi, Xj), keep_so)])
        put(w, [c if keep else 0.0 for c, keep in zip(varpi_coefficients(Xi, Xj), keep_so)])
        if inc["ss_2pn"]:
            put(ss2, spin_spin_precession_2pn(Xi, Xj, ki))
            # instantaneous Kidder/Racine: Ωᵢ ∋ v⁶[−Xⱼ²χⱼ + 3Xⱼ²(n̂·χⱼ)n̂ + 3νκᵢ(n̂·χᵢ)n̂]
            put(iss, (-(Xj * Xj), 3.0 * (Xj * Xj), 3.0 * nu * ki))
        if inc["ss_3pn"]:
            put(ss3, spin_spin_precession_3pn(Xi, Xj, ki))
            put(iss + 3, spin_spin_precession_3pn_instantaneous(Xi, Xj, ki))
    L2, L4 = angular_momentum_coefficients(nu)
    p[P_L2] = L2 if inc["so_nlo"] else 0.0
    p[P_L4] = L4 if inc["so_nnlo"] else 0.0
    p[P_DEN_EPS] = DEN_EPS
    E, F = energy_series(X1, kappa1, kappa2, lambda1, lambda2), flux_series(X1, kappa1, kappa2, lambda1, lambda2)
    kmax, approx = np.array(kmax, dtype=np.int64), APPROXIMANTS.index(approximant)
    if not shape_of(X1):   # one binary (evolve): _vdot_series_each would cost 3.5 s more to compile, cold
        N, D, Ep = _vdot_series(E, F, kmax, approx)
        if lambda1 or lambda2:
            _add_tides(E, F, kmax, approx, N, D, Ep)
        return p[None], N[None], D[None], Ep[None]
    E, F = (np.ascontiguousarray(np.moveaxis(x, -1, 0)) for x in (E, F))
    N, D, Ep = _vdot_series_each(E, F, kmax, approx)
    if np.any(lambda1) or np.any(lambda2):
        _add_tides(E, F, kmax, approx, N, D, Ep)
    return np.ascontiguousarray(p.T), N, D, Ep


@njit(cache=True)
def _vdot_series_each(E_raw, F_raw, kmax, approx):
    """:func:`_vdot_series` of every binary i of E_raw[i], F_raw[i] → (N, D, Ê′), each (n, NK, NB, NL); the
    same arithmetic as a call per binary (no fastmath: nothing is fused or reordered), ~5 µs faster each.  The
    series are copied element by element (:func:`_copy`)."""
    N = np.empty_like(E_raw)
    D = np.empty_like(E_raw)
    Ep = np.empty_like(E_raw)
    for i in range(E_raw.shape[0]):
        n, d, ep = _vdot_series(E_raw[i], F_raw[i], kmax, approx)
        _copy(n, N[i])
        _copy(d, D[i])
        _copy(ep, Ep[i])
    return N, D, Ep


@njit(cache=True)
def _copy(src, dst):
    """dst[...] = src for C-contiguous arrays of one shape, element by element: numba compiles an array assignment
    with its shape-mismatch error message, whose string formatting took 5.4-5.7 s of a cold evolve_many (numba's
    compile events; README, "Populations")."""
    s, d = src.reshape(src.size), dst.reshape(dst.size)
    for k in range(s.size):
        d[k] = s[k]


_UNIT_BASIS = np.array([1.0, 0, 0, 0, 0, 0, 0, 0, 0])


def inspiral_end(X1, approximant, kmax, basis, kappa1=1.0, kappa2=1.0, lambda1=0.0, lambda2=0.0):
    """The smallest v at which one of the events 1, 2, 5, 6 (module docstring) reaches zero with the spin
    invariants fixed at ``basis``: where an inspiral from low frequency ends (for precessing spins, as far
    as the spins at the start decide it), or 1.0 if none does below v = 1.  Found on a grid of 2000 values
    of v in [10⁻³, 1] and refined by bisection to 1e-12."""
    from .series import evaluate

    N, D, Ep = vdot_series(X1, approximant, kmax, kappa1, kappa2, lambda1, lambda2)
    Nv, Dv = v_derivative(N), v_derivative(D)

    def smallest(v):
        n, d = evaluate(N, v, basis), evaluate(D, v, basis)
        peak = vdot_peak.py_func(n, d, evaluate(Nv, v, basis), evaluate(Dv, v, basis))   # on arrays of v
        return np.minimum.reduce([evaluate(Ep, v, basis), n * d, d - DEN_EPS, peak])

    v = np.geomspace(1e-3, 1.0, 2000)
    bad = np.flatnonzero(smallest(v) <= 0.0)
    if bad.size == 0:
        return 1.0
    if bad[0] == 0:
        return v[0]
    lo, hi = v[bad[0] - 1], v[bad[0]]
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if smallest(np.array([mid]))[0] <= 0.0 else (mid, hi)
    return hi
