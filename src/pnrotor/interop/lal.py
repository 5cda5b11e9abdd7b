"""LALSuite's SpinTaylor orbit evolution, called the way pnrotor compares itself with it, and pnrotor's
modes handed to LALSuite.

One place for the call that tests and benchmarks share.  With ``pnrotor.pn.lalsuite_orders(approximant)``
on pnrotor's side, ``lalsimulation.SimInspiralSpinTaylorPNEvolveOrbit`` is called with spinO = −1 (all
spin terms), phaseO = 7 (3.5PN), lscorr = 0 and, unless given, no tidal deformability (lambda1 = lambda2 = 0,
tideO = 0; with Λᵢ, tideO as :func:`pnrotor.pn.lalsuite_orders` maps it); its conventions,
read from LALSimInspiralSpinTaylor.c and checked by tests/test_pn_lal.py against LAL's runs:

* fStart is the gravitational-wave frequency, spins in and out are the dimensionless χᵢ;
* the frame is n̂ = cos Φ E1 + sin Φ (L̂N × E1), λ̂ = L̂N × n̂, ℓ̂ = L̂N, with ℓ̂ = LNhat and n̂ = E1 at fStart;
* sample i is at t = i Δt after fStart, up to LAL's own end of the inspiral (fEnd = 0).

:func:`sph_harm_time_series` and :func:`polarization_series` give :class:`pnrotor.waveform.modes.Modes` to
LALSuite as its ``SphHarmTimeSeries`` and ``REAL8TimeSeries`` (what ``SimInspiralChooseTDModes`` and
``SimInspiralChooseTDWaveform`` return), for LAL's own tools.

Importing this module needs ``lal`` and ``lalsimulation`` (``pip install lalsuite``).
"""

import lal
import lalsimulation
import numpy as np

from .. import approximants

__all__ = ["spintaylor_series", "spintaylor_orbit", "sph_harm_time_series", "polarization_series"]


def spintaylor_series(m1, m2, chi1, chi2, f_start, approximant="T4", delta_t=1.0 / 4096,
                      ell_hat=(0.0, 0.0, 1.0), e1=(1.0, 0.0, 0.0), kappa=(1.0, 1.0), lambdas=(0.0, 0.0), tideO=0):
    """LAL's 14 output ``REAL8TimeSeries`` (V, Phi, S1x..z, S2x..z, LNhatx..z, E1x..z), as LAL returns them.

    Masses in M☉, ``f_start`` in Hz (gravitational-wave frequency), ``delta_t`` in s, ``approximant`` one
    with a LALSuite counterpart (its ``lal_name`` in :mod:`pnrotor.approximants`: "T1", "T4", "T5"), ``kappa`` the spin-induced quadrupole parameters κ₁, κ₂ (1 for black holes),
    ``lambdas`` the dimensionless tidal deformabilities Λ₁, Λ₂ and ``tideO`` LAL's tidal order (−1 all, 10 the
    5PN terms only, 0 none).
    """
    approx = lalsimulation.GetApproximantFromString(approximants.get(approximant).lal_name)
    return lalsimulation.SimInspiralSpinTaylorPNEvolveOrbit(
        delta_t, m1 * lal.MSUN_SI, m2 * lal.MSUN_SI, f_start, 0.0, *chi1, *chi2, *ell_hat, *e1,
        lambdas[0], lambdas[1], kappa[0], kappa[1], -1, tideO, 7, 0, approx)


def spintaylor_orbit(*args, **kwargs):
    """:func:`spintaylor_series` as numpy arrays: a dict with ``v``, ``Phi`` (N,) and ``chi1``, ``chi2``,
    ``ell`` (L̂N, not renormalized by LAL), ``e1`` (N, 3)."""
    V, Phi, S1x, S1y, S1z, S2x, S2y, S2z, Lx, Ly, Lz, Ex, Ey, Ez = [s.data.data for s in
                                                                  spintaylor_series(*args, **kwargs)]
    return dict(v=V, Phi=Phi, chi1=np.column_stack((S1x, S1y, S1z)), chi2=np.column_stack((S2x, S2y, S2z)),
                ell=np.column_stack((Lx, Ly, Lz)), e1=np.column_stack((Ex, Ey, Ez)))


def _uniform_step(modes):
    """Δt in s of modes sampled uniformly (``sampling=Δt``: that Δt exactly, if the times still have it), else a
    ValueError: LAL's series have one Δt."""
    t = modes.t_seconds
    if t.size < 2:
        raise ValueError("LAL time series need at least 2 samples")
    dt = (t[-1] - t[0]) / (t.size - 1)
    # t = k Δt carries the rounding of its product (units of M times M in s), a few ulp of t: allowed too
    tolerance = 1e-9 * dt + 8.0 * np.spacing(np.max(np.abs(t)))
    if np.max(np.abs(np.diff(t) - dt)) > tolerance:
        raise ValueError("LAL time series need uniform samples: evolve with sampling=Δt (seconds)")
    asked = modes.inputs.get("sampling_value") if modes.inputs.get("sampling") == "dt" else None
    return float(asked) if asked is not None and abs(asked - dt) <= tolerance else dt   # not if samples were taken out


def _series(create, name, epoch, dt, unit, data):
    series = create(name, lal.LIGOTimeGPS(epoch), 0.0, dt, unit, data.size)
    series.data.data[:] = data
    return series


def sph_harm_time_series(modes):
    """The inertial modes h_ℓm of ``modes`` (strain at their distance) as LAL's ``SphHarmTimeSeries``: one
    ``COMPLEX16TimeSeries`` per (ℓ, m), epoch the first sample's time (t = 0 at f_ref), Δt the sampling.

    LAL's Python binding of ``SphHarmTimeSeriesAddMode`` returns the list it was given in a second owning
    wrapper (freeing both crashes the interpreter); the given one is disowned."""
    if modes.distance_Mpc is None:
        raise ValueError("LAL's modes are strain: compute the modes with a distance (pnrotor.modes(run, "
                         "distance=...))")
    dt = _uniform_step(modes)
    inertial = modes.in_frame("inertial")
    hlms = None
    for (ell, m), h in zip(inertial.ell_m, inertial.data):
        mode = _series(lal.CreateCOMPLEX16TimeSeries, f"h{ell}{m}", modes.t_seconds[0], dt, lal.StrainUnit, h)
        appended = lalsimulation.SphHarmTimeSeriesAddMode(hlms, mode, ell, m)   # copies the mode
        if hlms is not None:
            hlms.this.disown()
        hlms = appended
    return hlms


def polarization_series(modes, inclination, phi_ref=0.0, distance=None, psi=0.0):
    """h₊, h× of :meth:`pnrotor.waveform.modes.Modes.polarizations` (same arguments) as two LAL
    ``REAL8TimeSeries`` (strain; epoch the first sample's time, Δt the sampling)."""
    if distance is None and modes.distance_Mpc is None:
        raise ValueError("LAL's polarizations are strain: give a distance (here or to pnrotor.modes)")
    dt = _uniform_step(modes)
    hp, hc = modes.polarizations(inclination, phi_ref, distance, psi)
    return tuple(_series(lal.CreateREAL8TimeSeries, name, modes.t_seconds[0], dt, lal.StrainUnit, h)
                 for name, h in (("hplus", hp), ("hcross", hc)))
