"""LALSuite's SpinTaylor orbit evolution, called the way pnrotor compares itself with it.

One place for the call that tests and benchmarks share.  With ``pnrotor.pn.lalsuite_orders(approximant)``
on pnrotor's side, ``lalsimulation.SimInspiralSpinTaylorPNEvolveOrbit`` is called with spinO = −1 (all
spin terms), tideO = 0, phaseO = 7 (3.5PN), lscorr = 0 and no tidal deformability; its conventions are
recorded in the project's ``LAL-CONVENTIONS.md``:

* fStart is the gravitational-wave frequency, spins in and out are the dimensionless χᵢ;
* the frame is n̂ = cos Φ E1 + sin Φ (L̂N × E1), λ̂ = L̂N × n̂, ℓ̂ = L̂N, with ℓ̂ = LNhat and n̂ = E1 at fStart;
* sample i is at t = i Δt after fStart, up to LAL's own end of the inspiral (fEnd = 0).

Importing this module needs ``lal`` and ``lalsimulation`` (``pip install lalsuite``).
"""

import lal
import lalsimulation
import numpy as np

__all__ = ["spintaylor_series", "spintaylor_orbit"]


def spintaylor_series(m1, m2, chi1, chi2, f_start, approximant="T4", delta_t=1.0 / 4096,
                      ell_hat=(0.0, 0.0, 1.0), e1=(1.0, 0.0, 0.0), kappa=(1.0, 1.0)):
    """LAL's 14 output ``REAL8TimeSeries`` (V, Phi, S1x..z, S2x..z, LNhatx..z, E1x..z), as LAL returns them.

    Masses in M☉, ``f_start`` in Hz (gravitational-wave frequency), ``delta_t`` in s, ``approximant`` one
    of "T1", "T4", "T5", ``kappa`` the spin-induced quadrupole parameters κ₁, κ₂ (1 for black holes).
    """
    approx = lalsimulation.GetApproximantFromString("SpinTaylor" + approximant)
    return lalsimulation.SimInspiralSpinTaylorPNEvolveOrbit(
        delta_t, m1 * lal.MSUN_SI, m2 * lal.MSUN_SI, f_start, 0.0, *chi1, *chi2, *ell_hat, *e1,
        0.0, 0.0, kappa[0], kappa[1], -1, 0, 7, 0, approx)


def spintaylor_orbit(*args, **kwargs):
    """:func:`spintaylor_series` as numpy arrays: a dict with ``v``, ``Phi`` (N,) and ``chi1``, ``chi2``,
    ``ell`` (L̂N, not renormalized by LAL), ``e1`` (N, 3)."""
    V, Phi, S1x, S1y, S1z, S2x, S2y, S2z, Lx, Ly, Lz, Ex, Ey, Ez = [s.data.data for s in
                                                                  spintaylor_series(*args, **kwargs)]
    return dict(v=V, Phi=Phi, chi1=np.column_stack((S1x, S1y, S1z)), chi2=np.column_stack((S2x, S2y, S2z)),
                ell=np.column_stack((Lx, Ly, Lz)), e1=np.column_stack((Ex, Ey, Ez)))
