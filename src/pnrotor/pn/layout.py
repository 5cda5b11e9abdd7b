"""The layout of the post-Newtonian system: its state vectors, its events and its parameter vector ``p``.

The right-hand sides and events (:mod:`pnrotor.pn.rhs`) read the state and ``p`` by these indices; the parameter
vector is built by :mod:`pnrotor.pn.system`, the spin-independent part by the coefficient functions of
:mod:`pnrotor.pn.energy`, :mod:`pnrotor.pn.flux` and :mod:`pnrotor.pn.precession`.
"""

from .precession import SPIN_ORBIT_ORDERS, SPIN_SPIN
from .series import SERIES_SLOTS

# state layout
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

# parameter vector layout
P_X1 = 0
P_X2 = 1
P_NU = 2
P_VDOT0 = 3      # 32ν/5
P_VEND = 4       # v at which event 0 fires
P_ROTOR = 5      # 0 coprecessing, 1 orbital
P_SHIFT = 6      # 1: apply the precession phase shift
P_W1 = 7         # phase-shift weights w₁, w₂
P_W2 = 8
# the precession series (pnrotor.pn.precession), each term zeroed when truncated
N_SO = len(SPIN_ORBIT_ORDERS)   # terms of the spin-orbit series in v²
N_SS = len(SPIN_SPIN)           # terms of the spin-spin series (v⁶, v⁸, ...)
P_SO1 = 9                       # σ₀, σ₂, σ₄ of body 1
P_SO2 = P_SO1 + N_SO            # ... body 2
P_SS1 = P_SO2 + N_SO            # spin-spin of body 1: the series of c_j, then of c_j⊥, then of c_i⊥
P_SS2 = P_SS1 + 3 * N_SS        # ... body 2
P_L = P_SS2 + 3 * N_SS          # |L| = (ν/v)(1 + v²(L₂ + L₄v²))
P_SPINTOL = P_L + N_SO - 1      # |χ|² may exceed 1 by this much before event 3/4 fires
P_DEN_EPS = P_SPINTOL + 1       # event 5 fires when the denominator D of v̇ falls to this value
P_VARPI1 = P_DEN_EPS + 1        # w₀, w₂, w₄ of ϖ for body 1 ('averaged_varpi', 'instantaneous')
P_VARPI2 = P_VARPI1 + N_SO      # ... body 2
# instantaneous spin-spin precession (rhs_precessing_instantaneous only)
P_ISS1 = P_VARPI2 + N_SO        # body 1: 2PN a_j, a_jn, a_in; 3PN b_j, b_jn, b_jλ, b_in, b_iλ (zeroed when truncated)
P_ISS2 = P_ISS1 + 8             # ... body 2
P_OMEGA_L = P_ISS2 + 8          # 0: Ω_ℓ from −ℓ̂ × (Ṡ₁ + Ṡ₂)/|L| (LALSuite); 1: its spin-orbit part from ⟨ϖ n̂⟩ (Bohé+)
# the series N, D, Ê′, each a header and its coefficients (series.fold_and_store)
P_HORIZON = P_OMEGA_L + 1       # horizon absorption: 0 none; 1 F̂_H added to N (T1, T4); −1 subtracted from D (T5)
P_HX1 = P_HORIZON + 1           # with horizon absorption: X₁ if body 1 has a horizon (Λ₁ = 0), 0 for a neutron star
P_HX2 = P_HX1 + 1               # ... body 2
P_NUM = P_HX2 + 1
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
