"""A new approximant is one registry entry plus its v̇ function (pnrotor.approximants): a toy one registered here
runs end to end through evolve and evolve_many, and its runs follow the closed-form solution of its v̇."""

import numpy as np
import pytest
from numba import njit

import pnrotor
from pnrotor import approximants
from pnrotor.pn import vdot


@njit(cache=True)
def newtonian(Ep, F, kmax, N, D):
    """A toy approximant's v̇ (pnrotor.pn.vdot.VDOT_SIG): the leading order whatever the PN order, N = D = 1."""
    N[0, 0, 0] = 1.0
    D[0, 0, 0] = 1.0


@pytest.fixture
def toy():
    a = approximants.register(approximants.Approximant("TN", newtonian, "Newtonian v̇", aliases=("TaylorTN",)))
    yield a
    approximants.unregister("TN")


def closed_form(v0, v, nu):
    """(t, Φ) at v from v0 (t = Φ = 0) of v̇ = (32ν/5) v⁹, Φ̇ = v³: t = (v0⁻⁸ − v⁻⁸)/(8K), Φ = (v0⁻⁵ − v⁻⁵)/(5K)."""
    K = 32.0 * nu / 5.0
    return (v0 ** -8 - v ** -8) / (8.0 * K), (v0 ** -5 - v ** -5) / (5.0 * K)


def test_a_registered_approximant_runs_end_to_end(toy):
    m1, m2 = 10.0, 5.0
    nu = m1 * m2 / (m1 + m2) ** 2
    for chi in ((0.0, 0.0, 0.0), (0.0, 0.0, 0.6)):   # nonspinning and aligned: Φ̇ = v³
        run = pnrotor.evolve(m1, m2, chi, chi, 20.0, f_min=12.0, f_max=300.0, approximant="taylortn", atol=1e-14)
        assert run.inputs["approximant"] == "TN" and run.termination == "f_max"
        t, phi = closed_form(run.inputs["v_ref"], run.v, nu)
        np.testing.assert_allclose(run.t, t, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(run.Phi, phi, rtol=1e-9, atol=1e-8)
    pop = pnrotor.evolve_many(np.array([m1, 30.0]), np.array([m2, 10.0]), np.zeros((2, 3)), np.zeros((2, 3)), 20.0,
                              frequencies=[15.0, 40.0], approximant="TN", atol=1e-14)
    assert pop.reached.all()
    for i, (a, b) in enumerate(((m1, m2), (30.0, 10.0))):
        v0 = pnrotor.pn.initial.v_from_frequency(20.0, pnrotor.pn.initial.total_mass_seconds(a, b))
        t, phi = closed_form(v0, pop.v[i], a * b / (a + b) ** 2)
        np.testing.assert_allclose(pop.t[i], t, rtol=1e-9)
        np.testing.assert_allclose(pop.Phi[i], phi, rtol=1e-9)


def test_a_registered_approximant_states_what_it_lacks(toy):
    with pytest.raises(ValueError, match="TN has no LALSuite counterpart"):
        pnrotor.pn.lalsuite_orders("TN")
    with pytest.raises(ValueError, match="TN takes no tides"):
        pnrotor.evolve(1.4, 1.3, (0, 0, 0), (0, 0, 0), 100.0, approximant="TN", lambda1=400.0, sampling="final")
    with pytest.raises(ValueError, match="name 'TaylorTN' is taken"):
        approximants.register(approximants.Approximant("TM", newtonian, "", aliases=("TaylorTN",)))


def test_an_unregistered_approximant_is_refused_and_a_name_can_be_registered_anew(toy):
    args = (10.0, 5.0, (0.1, 0.2, 0.3), (0.0, -0.3, 0.1), 20.0)
    pnrotor.evolve(*args, approximant="TN", sampling="final")   # cached under the toy
    approximants.unregister("TN")
    with pytest.raises(ValueError, match="approximant must be one of T1, T4, T5 "):
        pnrotor.evolve(*args, approximant="TN")
    approximants.register(approximants.Approximant("TN", vdot.taylor_t4, "T4 under another name"))
    np.testing.assert_array_equal(pnrotor.evolve(*args, approximant="TN").Phi, pnrotor.evolve(*args).Phi)
