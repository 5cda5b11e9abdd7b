"""evolve_many's states at targets a binary did not reach (issue 36 item 5): NaN with ``reached`` False, the state
where it stopped in ``stopped_at``; its inputs per binary; the derived θ₁, θ₂, φ₁₂, χ_eff, χ_p against the
`precession` package; a pandas DataFrame as input and ``to_pandas``."""

import math

import numpy as np
import pytest

from pnrotor.pn import evolve, evolve_many

MSUN_S = 4.925490947641267e-06
ENDS = {"v_max", "energy_balance", "vdot_nonpositive", "vdot_peak", "vdot_divergent"}


def _binaries():
    """Eight precessing binaries: four light ones whose inspirals pass 100 Hz, four heavy ones (80 + 40 M☉ and more)
    whose inspirals end below it."""
    rng = np.random.default_rng(3)
    m1 = np.array([10.0, 14.0, 20.0, 25.0, 80.0, 90.0, 100.0, 120.0])
    m2 = m1 / np.array([1.5, 2.0, 1.2, 3.0, 2.0, 1.5, 1.1, 2.5])
    chi1, chi2 = rng.uniform(-0.5, 0.5, (8, 3)), rng.uniform(-0.5, 0.5, (8, 3))
    return m1, m2, chi1, chi2


def test_states_at_a_target_not_reached_are_nan_and_the_stopped_state_stays():
    """f_end = 100 Hz: the heavy binaries end first (energy_balance or another end of the inspiral) and gave that
    end's state as if at 100 Hz, with no NaN (the issue: 513 of 1,000 binaries "at 100 Hz" were at 57-66 Hz).  Now
    their state is NaN and reached False, and stopped_at holds evolve's final state for every binary, bitwise."""
    m1, m2, chi1, chi2 = _binaries()
    pop = evolve_many(m1, m2, chi1, chi2, 20.0, f_end=100.0)
    assert pop.reached.dtype == bool and list(pop.reached) == [True] * 4 + [False] * 4
    assert list(pop.termination[:4]) == ["f_max"] * 4 and set(pop.termination[4:]) <= ENDS - {"v_max"}
    f_gw = pop.v ** 3 / (np.pi * (m1 + m2) * MSUN_S)
    np.testing.assert_allclose(f_gw[:4], 100.0, rtol=1e-12)
    for name in ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat"):
        assert np.all(np.isnan(getattr(pop, name)[4:])) and not np.any(np.isnan(getattr(pop, name)[:4])), name
    stopped = pop.stopped_at["v"] ** 3 / (np.pi * (m1 + m2) * MSUN_S)
    assert np.all(stopped[4:] < 100.0) and np.all(stopped[4:] > 20.0)
    for i in range(8):
        e = evolve(m1[i], m2[i], chi1[i], chi2[i], 20.0, f_max=100.0, sampling="final")
        assert e.termination == pop.termination[i]
        for name in ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat"):
            np.testing.assert_array_equal(pop.stopped_at[name][i], getattr(e, name)[-1], err_msg=f"{i} {name}")
    assert np.all(np.isnan(pop.theta1[4:])) and not np.any(np.isnan(pop.chi_p[:4]))


def test_per_target_reached_with_a_list_and_the_end_of_the_inspiral_as_a_target():
    """A list of frequencies: reached per binary and target (a target past the end of its inspiral is NaN, the
    nearer ones are states); f_end NaN (the end of the inspiral) is reached by every end of the inspiral."""
    m1, m2, chi1, chi2 = _binaries()
    pop = evolve_many(m1, m2, chi1, chi2, 20.0, frequencies=[15.0, 30.0, 100.0])
    assert pop.reached.shape == (8, 3) and pop.stopped_at["chi1"].shape == (8, 3, 3)
    assert np.all(pop.reached[:, :2]) and list(pop.reached[:, 2]) == [True] * 4 + [False] * 4
    assert np.all(np.isnan(pop.chi1[4:, 2])) and not np.any(np.isnan(pop.chi1[:, :2]))
    np.testing.assert_array_equal(pop.stopped_at["v"][:, :2], pop.v[:, :2])
    end = evolve_many(m1, m2, chi1, chi2, 20.0, f_end=[np.nan] * 7 + [15.0])
    assert np.all(end.reached) and set(end.termination[:7]) <= ENDS and end.termination[7] == "f_min"
    np.testing.assert_array_equal(end.stopped_at["v"][4:7], pop.stopped_at["v"][4:7, 2])
    np.testing.assert_array_equal(end.v[4:7], pop.stopped_at["v"][4:7, 2])


def test_max_steps_is_not_reaching_the_end_of_the_inspiral():
    """An integration stopped by the integrator's step limit did not reach the end of its inspiral: NaN state."""
    pop = evolve_many([30.0, 30.0], 10.0, [0, 0, 0.3], [0, 0, 0], 20.0, f_end=[np.nan, 100.0], max_steps=5)
    assert list(pop.termination) == ["max_steps"] * 2 and not pop.reached.any() and np.all(np.isnan(pop.v))
    assert np.all(np.isfinite(pop.stopped_at["v"]))


def test_inputs_per_binary():
    m1, m2, chi1, chi2 = _binaries()
    pop = evolve_many(m1, m2, chi1, chi2, [20.0] * 7 + [25.0], f_end=100.0, kappa1=2.0, ell_hat=(0.6, 0.0, 0.8))
    inputs = pop.inputs
    for key, value in (("m1_Msun", m1), ("m2_Msun", m2), ("chi1", chi1), ("chi2", chi2), ("kappa1", [2.0] * 8),
                       ("kappa2", [1.0] * 8), ("f_ref_Hz", [20.0] * 7 + [25.0]), ("f_end_Hz", [100.0] * 8),
                       ("ell_hat", [(0.6, 0.0, 0.8)] * 8), ("n_hat", [(1.0, 0.0, 0.0)] * 8)):
        np.testing.assert_array_equal(inputs[key], value, err_msg=key)
    assert inputs["approximant"] == "T4" and inputs["atol"] == 1e-12
    listed = evolve_many(m1, m2, chi1, chi2, 20.0, frequencies=[30.0, 15.0])
    assert "f_end_Hz" not in listed.inputs and listed.inputs["frequencies_Hz"].tolist() == [[30.0, 15.0]] * 8


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
def test_derived_quantities_equal_the_precession_packages():
    """θ₁, θ₂, φ₁₂ (precession's deltaphi, taken in [0, 2π]), χ_eff and the heuristic χ_p of Schmidt et al. 2015, at
    the states of a population, against `precession` 2.1 (its q = m₂/m₁ ≤ 1: the bodies swapped where m₁ < m₂);
    NaN where the target was not reached, and φ₁₂ where the spins have no part in the orbital plane."""
    precession = pytest.importorskip("precession")
    m1, m2, chi1, chi2 = _binaries()
    m1[1], m2[1] = m2[1], m1[1]      # a binary with the heavier body second
    chi1[2], chi2[2] = (0.0, 0.0, 0.3), (0.0, 0.0, -0.4)     # spins along ℓ̂ = ẑ: they stay so, no φ₁₂
    pop = evolve_many(m1, m2, chi1, chi2, 20.0, f_end=[60.0] * 4 + [30.0] * 3 + [100.0])
    assert list(pop.reached) == [True] * 7 + [False]
    ok = pop.reached
    heavy = m1 >= m2
    c_a = np.where(heavy[:, None], pop.chi1, pop.chi2)[ok]
    c_b = np.where(heavy[:, None], pop.chi2, pop.chi1)[ok]
    q = np.minimum(m1, m2)[ok] / np.maximum(m1, m2)[ok]
    t_a, t_b, dphi = precession.vectors_to_angles(pop.ell_hat[ok], c_a, c_b)
    theta1, theta2 = np.where(heavy[ok], t_a, t_b), np.where(heavy[ok], t_b, t_a)
    np.testing.assert_allclose(pop.theta1[ok], theta1, rtol=0, atol=1e-13)
    np.testing.assert_allclose(pop.theta2[ok], theta2, rtol=0, atol=1e-13)
    phi12 = np.mod(np.where(heavy[ok], dphi, -dphi), 2 * np.pi)
    assert math.isnan(pop.phi12[2]) and pop.theta1[2] == 0.0 and pop.theta2[2] == np.pi
    keep = ~np.isnan(pop.phi12[ok])
    np.testing.assert_allclose(pop.phi12[ok][keep], phi12[keep], rtol=0, atol=1e-12)
    chi_a, chi_b = np.linalg.norm(c_a, axis=1), np.linalg.norm(c_b, axis=1)
    np.testing.assert_allclose(pop.chi_eff[ok], precession.eval_chieff(t_a, t_b, q, chi_a, chi_b), rtol=0, atol=1e-15)
    chi_p = precession.eval_chip(theta1=t_a, theta2=t_b, deltaphi=dphi, r=np.full(q.size, 100.0), q=q, chi1=chi_a,
                                 chi2=chi_b, which="heuristic")
    np.testing.assert_allclose(pop.chi_p[ok], chi_p, rtol=0, atol=1e-15)
    assert np.isnan(pop.theta1[7]) and np.isnan(pop.chi_eff[7])


def _frame():
    pd = pytest.importorskip("pandas")
    m1, m2, chi1, chi2 = _binaries()
    return pd.DataFrame({"name": [f"b{i}" for i in range(8)], "m1": m1, "m2": m2, "chi1": list(chi1),
                         "chi2": [",".join(map(repr, c.tolist())) for c in chi2], "f_ref": 20.0,
                         "f_max": [100.0, np.nan, 60.0, np.nan, 100.0, np.nan, np.nan, np.nan],
                         "f_min": [np.nan, 15.0, np.nan, np.nan, np.nan, 12.0, np.nan, np.nan],
                         "approximant": "T4", "atol": [1e-11] * 7 + [np.nan]})


def test_a_dataframe_with_the_table_columns_equals_the_arrays():
    """A DataFrame with a batch table's columns (spins as sequences or "x,y,z" text, f_max forward and f_min
    backward per row, one approximant and atol): bitwise the population of the same arrays."""
    frame = _frame()
    m1, m2, chi1, chi2 = _binaries()
    pop = evolve_many(frame, rtol=0.0)
    f_end = frame["f_max"].fillna(frame["f_min"]).to_numpy()
    arrays = evolve_many(m1, m2, chi1, chi2, 20.0, f_end=f_end, atol=1e-11)
    assert list(pop.termination[[1, 5]]) == ["f_min"] * 2 and pop.inputs["atol"] == 1e-11
    for name in ("t", "v", "chi1", "chi2", "R", "ell_hat", "termination", "reached", "nfev"):
        assert getattr(pop, name).tobytes() == getattr(arrays, name).tobytes(), name


def test_a_dataframe_target_on_the_wrong_side_is_invalid_as_evolve_says():
    """A row's f_max must lie above its f_ref and its f_min below (evolve's checks and messages), not be taken
    in the other direction as f_end would be."""
    frame = _frame()
    frame.loc[0, "f_max"], frame.loc[1, "f_min"] = 15.0, 30.0
    pop = evolve_many(frame)
    for i, kw in ((0, dict(f_max=15.0)), (1, dict(f_min=30.0))):
        with pytest.raises(ValueError) as refusal:
            evolve(frame.m1[i], frame.m2[i], frame.chi1[i], _binaries()[3][i], 20.0, **kw)
        assert pop.termination[i] == "invalid" and pop.message[i] == str(refusal.value)
    assert pop.termination[2] == "f_max"


@pytest.mark.parametrize("change, match", [
    (lambda f: f.rename(columns={"f_ref": "fref"}), r"unknown: 'fref'; missing: f_ref"),
    (lambda f: f.assign(approximant=["T4", "T1"] * 4), "column approximant of the DataFrame holds several values"),
    (lambda f: f.assign(m1=f.m1.astype(str)), "column m1 of the DataFrame must be numbers"),
    (lambda f: f.assign(chi1=["0,0"] * 8), r"column chi1 of the DataFrame must hold three numbers per row .* '0,0'"),
    (lambda f: f.assign(f_min=f.f_max), "rows 0, 2, 4 of the DataFrame have both f_min and f_max"),
    (lambda f: f.assign(sampling="steps"), "column sampling of the DataFrame must be final or empty"),
    (lambda f: f.iloc[:0], "and a row"),
])
def test_a_dataframe_that_does_not_fit_is_a_value_error(change, match):
    with pytest.raises(ValueError, match=match):
        evolve_many(change(_frame()))


def test_dataframe_keywords_given_twice():
    frame = _frame()
    with pytest.raises(ValueError, match="m2, f_ref must not be given with a DataFrame"):
        evolve_many(frame, frame.m2, f_ref=20.0)
    with pytest.raises(ValueError, match=r"atol is given twice, as 1e-09 and as the DataFrame's column, 1e-11"):
        evolve_many(frame, atol=1e-9)
    with pytest.raises(ValueError, match="f_end and frequencies must not be given too"):
        evolve_many(frame, f_end=50.0)
    with pytest.raises(TypeError, match="evolve_many.. missing chi2, f_ref"):
        evolve_many(30.0, 10.0, (0, 0, 0))


def test_to_pandas():
    """One row per binary (and target): inputs, state, reached, derived columns, the stopped states; the shared
    options in attrs."""
    pytest.importorskip("pandas")
    m1, m2, chi1, chi2 = _binaries()
    pop = evolve_many(m1, m2, chi1, chi2, 20.0, f_end=100.0)
    frame = pop.to_pandas()
    assert len(frame) == 8 and frame.attrs["approximant"] == "T4"
    np.testing.assert_array_equal(frame["m1_Msun"], m1)
    np.testing.assert_array_equal(frame["chi1_ref_y"], chi1[:, 1])
    np.testing.assert_array_equal(frame["chi2_z"], pop.chi2[:, 2])
    np.testing.assert_array_equal(frame["R_w"], pop.R[:, 0])
    np.testing.assert_array_equal(frame["theta1"], pop.theta1)
    np.testing.assert_array_equal(frame["stopped_v"], pop.stopped_at["v"])
    assert frame["reached"].tolist() == pop.reached.tolist() and frame["termination"][7] == pop.termination[7]
    listed = evolve_many(m1[:2], m2[:2], chi1[:2], chi2[:2], 20.0, frequencies=[30.0, 15.0, 60.0]).to_pandas()
    assert listed[["binary", "target"]].values.tolist() == [[0, 0], [0, 1], [0, 2], [1, 0], [1, 1], [1, 2]]
    assert listed["frequency_Hz"].tolist() == [30.0, 15.0, 60.0] * 2 and listed["m1_Msun"].tolist()[2:4] == [m1[0], m1[1]]
