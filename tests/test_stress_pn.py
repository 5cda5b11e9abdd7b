"""pnrotor.evolve at its physical extremes (benchmarks/stress_pn.py measures them; these guard them):
extreme mass ratios and spins, the up-down configuration, the end of the PN inspiral as a starting
point, the memory of sampling='final', and random binaries (hypothesis).

Every run is checked by :func:`check`: finite outputs, a documented termination name (module docstring
of pnrotor.pn.evolve), |χᵢ| conserved, R unit and finite, v increasing."""

import numpy as np
import pytest

from pnrotor import evolve

Z = np.array([0.0, 0.0, 1.0])
# the termination names of a forward run without f_max that reaches a physical end (pnrotor.pn.evolve)
PHYSICAL_ENDS = {"v_max", "energy_balance", "vdot_nonpositive", "vdot_divergent"}


def _angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def check(e, chi1, chi2, spin_tol=1e-10):
    """The invariants of every run; returns e."""
    for a in (e.t, e.t_seconds, e.v, e.Phi, e.chi1, e.chi2, e.R, e.ell_hat):
        assert np.all(np.isfinite(a))
    assert e.termination in PHYSICAL_ENDS | {"f_max"}
    for x, c in ((e.chi1, chi1), (e.chi2, chi2)):
        assert np.max(np.abs(np.linalg.norm(x, axis=1) - np.linalg.norm(c))) < spin_tol
    assert np.max(np.abs(np.linalg.norm(e.R, axis=1) - 1.0)) < 1e-14
    assert np.all(np.diff(e.v) > 0) and np.all(np.diff(e.t) > 0)
    return e


# --------------------------------------------------------------------------------------------------
# the end of the inspiral as a starting point
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("approximant", ["T1", "T5"])
@pytest.mark.parametrize("past", [1e-9, 1e-6, 1e-4])
def test_start_between_pole_guard_and_pole(approximant, past):
    """T1/T5 stop where the denominator of v̇ falls to 1e-3, before its pole.  Restarting just past that
    frequency used to integrate into the pole (~110 steps, half rejected): T5 then reported
    'vdot_nonpositive' and T1 a v that decreased.  Now: a ValueError naming f_ref."""
    e = evolve(30, 30, [0, 0, 0], [0, 0, 0], 20.0, approximant=approximant, sampling="final")
    assert e.termination == ("energy_balance" if approximant == "T1" else "vdot_divergent")
    with pytest.raises(ValueError, match="f_ref"):
        evolve(30, 30, [0, 0, 0], [0, 0, 0], e.f_gw[-1] * (1 + past), approximant=approximant)
