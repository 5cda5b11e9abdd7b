"""The flux into black-hole horizons (``evolve(…, horizon_absorption=True)``, pnrotor.pn.flux.horizon_flux):
its test-mass limit against black-hole perturbation theory, its comparable-mass nonspinning form against Nagar &
Akcay 2012's, and the energy balance it enters, v̇ = −(F + F_H)/E′ (T1), against v̇ read off the run itself."""

import math

import numpy as np
import pytest

from pnrotor.pn import evolve
from pnrotor.pn.energy import energy_series
from pnrotor.pn.flux import flux_series, horizon_flux
from pnrotor.pn.series import basis_values, evaluate, kmax_from_orders, truncate


@pytest.mark.parametrize("q", [-0.9, -0.3, 0.0, 0.5, 0.9, 0.99])
def test_test_mass_limit_is_black_hole_perturbation_theory(q):
    """X → 1: a particle on a circular equatorial orbit of a Kerr black hole of spin q.  The v⁵ term is Tagoshi, Mano &
    Takasugi 1997's leading horizon flux −(1/4)(q + 3q³) (gr-qc/9711072); without spin the leading term is v⁸ with
    coefficient 1, Poisson & Sasaki 1995's Schwarzschild result (gr-qc/9412027); the small body (X → 0) absorbs
    nothing."""
    big, small = horizon_flux(1.0, q), horizon_flux(0.0, q)
    assert big[5] == pytest.approx(-0.25 * (q + 3 * q ** 3), rel=1e-15, abs=0)
    if q == 0.0:
        assert big == {5: 0.0, 8: 1.0}
    assert small == {5: 0.0, 8: 0.0}


@pytest.mark.parametrize("X1", [0.5, 0.75, 10 / 11])
def test_nonspinning_comparable_masses_are_nagar_and_akcay(X1):
    """Two nonspinning holes absorb (1 − 4ν + 2ν²) v⁸ of the Newtonian flux at leading order (Nagar & Akcay 2012,
    arXiv:1112.2840, the (2,2) horizon flux)."""
    nu = X1 * (1 - X1)
    total = horizon_flux(X1, 0.0)[8] + horizon_flux(1 - X1, 0.0)[8]
    assert total == pytest.approx(1 - 4 * nu + 2 * nu * nu, rel=1e-14)


def test_energy_balance_takes_the_horizon_flux():
    """T1 evaluates v̇ = (32ν/5) v⁹ (F̂ + F̂_H)/Ê′ as it is: its v̇ along a run, from 128 samples per orbit (a
    second-order difference), equals that formula evaluated here in numpy from the flux, energy and horizon-flux
    functions, to a small part of the horizon flux's own share of v̇; without the horizon flux it misses by that
    share."""
    m1, m2, a1, a2 = 50.0, 5.0, 0.9, -0.4
    run = evolve(m1, m2, (0, 0, a1), (0, 0, a2), 20.0, f_max=120.0, approximant="T1", pn_order=3.5,
                 spin_orbit_order=3.5, spin_spin_order=3.0, sampling=("per_orbit", 128), horizon_absorption=True)
    X1 = m1 / (m1 + m2)
    nu = X1 * (1 - X1)
    kmax = kmax_from_orders(3.5, 3.5, 3.0)
    b = basis_values(a1, a2, a1 * a2, a1 * a1, a2 * a2)
    v = run.v[2:-2]
    F = evaluate(truncate(flux_series(X1), kmax), v, b)
    E = truncate(energy_series(X1), kmax)
    Ep = sum(0.5 * (k + 2) * E[k, :, 0] @ b * v ** k + 0.5 * ((k + 2) * np.log(v) + 1) * (E[k, :, 1] @ b) * v ** k
             for k in range(E.shape[0]))
    H = sum(c * v ** k for X, a in ((X1, a1), (1 - X1, a2)) for k, c in horizon_flux(X, a).items())
    vdot = np.gradient(run.v, run.t, edge_order=2)[2:-2]
    with_h = 32 * nu / 5 * v ** 9 * (F + H) / Ep
    without = 32 * nu / 5 * v ** 9 * F / Ep
    share = np.abs(with_h / without - 1)
    assert share.min() > 5e-4
    assert np.max(np.abs(vdot / with_h - 1)) < 0.05 * share.min()
    assert np.max(np.abs(vdot / without - 1)) > 0.5 * share.max()


def test_dephasing_sign_and_options():
    """A hole spinning along ℓ̂ gives energy to the orbit (F_H < 0 at leading order): more orbits to the same
    frequency; against ℓ̂ it takes energy: fewer.  Precessing spins are refused, naming the option."""
    kw = dict(sampling="final", f_max=200.0)
    phase = {a: [evolve(50.0, 5.0, (0, 0, a), (0, 0, 0), 20.0, horizon_absorption=h, **kw).Phi[-1] for h in (False, True)]
             for a in (0.9, -0.9)}
    assert phase[0.9][1] - phase[0.9][0] > 0.05 and phase[-0.9][1] - phase[-0.9][0] < -0.05
    run = evolve(50.0, 5.0, (0, 0, 0.9), (0, 0, 0), 20.0, horizon_absorption=True, **kw)
    assert run.inputs["horizon_absorption"] is True
    with pytest.raises(ValueError, match="horizon_absorption takes nonspinning binaries and spins along ell_hat"):
        evolve(50.0, 5.0, (0.3, 0, 0.8), (0, 0, 0), 20.0, horizon_absorption=True)
    with pytest.raises(ValueError, match="horizon_absorption needs integrate_rotor=False"):
        evolve(50.0, 5.0, (0, 0, 0.8), (0, 0, 0), 20.0, horizon_absorption=True, integrate_rotor=True)
    with pytest.raises(ValueError, match="horizon_absorption must be True or False"):
        evolve(50.0, 5.0, (0, 0, 0.8), (0, 0, 0), 20.0, horizon_absorption="yes")
    assert math.isfinite(run.Phi[-1])
