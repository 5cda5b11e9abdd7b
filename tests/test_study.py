"""pnrotor.study, the work-precision study of ``pnrotor bench`` (Boyle 2016, Sec. V-B, Figs. 2 and 3), at
a short span: the rows it makes, the accuracy they show, scipy's baseline against pnrotor's DOP853 at the
same tolerances, the damping probe against the sweep, and the derived costs, findings and figures."""

import math

import numpy as np
import pytest

from pnrotor import study
from pnrotor.formulations import FORMULATIONS
from pnrotor.integrate import METHODS

T_END = 2000.0
ATOLS = [1e-4, 1e-8, 1e-12]


@pytest.fixture(scope="module")
def result():
    return study.sweep(T_END, ATOLS, 1, (0.01, 0.01), True)


def select(rows, **keys):
    return [r for r in rows if all(r[k] == v for k, v in keys.items())]


def test_one_successful_row_per_formulation_method_and_tolerance(result):
    rows, curves = result
    for formulation in FORMULATIONS:
        for method in METHODS:
            runs = select(rows, study="sweep", formulation=formulation, method=method)
            assert [r["atol"] for r in runs] == ATOLS
            assert all(r["status"] == 0 and r["t_final"] == T_END and r["rtol"] == 0.0 for r in runs)
    assert all(set(r) == set(study.COLUMNS) for r in rows)
    # δ(t) curves of the rotor with DOP853, one per tolerance, each over [0, T]
    assert sorted(curves) == sorted(ATOLS)
    assert all(t[0] == 0.0 and t[-1] == T_END and len(t) == len(d) for t, d in curves.values())


@pytest.mark.parametrize("method", list(METHODS))
def test_rotor_error_decreases_with_the_tolerance(result, method):
    rows, _ = result
    deltas = [r["max_delta"] for r in select(rows, study="sweep", formulation="rotor", method=method)]
    assert all(a > b for a, b in zip(deltas, deltas[1:])), deltas
    assert all(d < 100 * atol for d, atol in zip(deltas, ATOLS)), deltas


def test_scipy_baseline_agrees_with_pnrotor_at_equal_tolerances(result):
    rows, _ = result
    for atol in ATOLS:
        (scipy,) = select(rows, study="baseline", atol=atol)
        (ours,) = select(rows, study="equal-rtol", atol=atol)
        assert scipy["method"] == study.SCIPY and ours["method"] == "DOP853" and ours["formulation"] == "rotor"
        assert scipy["rtol"] == ours["rtol"] == study.SCIPY_RTOL
        assert scipy["status"] == ours["status"] == 0 and scipy["t_final"] == T_END
        # the same method at the same tolerances: the same order of magnitude of error and work
        assert abs(math.log10(scipy["max_delta"] / ours["max_delta"])) < 1, (scipy["max_delta"], ours["max_delta"])
        assert 0.5 < scipy["nfev"] / ours["nfev"] < 2
        assert scipy["accepted"] + scipy["rejected"] == scipy["steps"]


def test_damping_probe_starts_from_vectors2_and_stiffens(result):
    rows, _ = result
    probe = study.DAMPING_PROBE
    for method in METHODS:
        runs = select(rows, study="damping", method=method)
        assert [r["damping"] for r in runs] == probe["rates"]
        assert all(r["atol"] == probe["atol"] and r["t_end"] == min(T_END, probe["t_end"]) for r in runs)
        (undamped,) = select(rows, study="sweep", formulation="vectors2", method=method, atol=probe["atol"])
        assert (runs[0]["nfev"], runs[0]["max_delta"]) == (undamped["nfev"], undamped["max_delta"])
        assert runs[-1]["nfev"] > 5 * runs[0]["nfev"]


def test_cost_at_interpolates_between_the_bracketing_runs(result):
    rows, _ = result
    runs = select(rows, study="sweep", formulation="rotor", method="DOP853")
    for r in runs:
        assert math.isclose(study.cost_at(rows, "rotor", "DOP853", "nfev", r["max_delta"]), r["nfev"], rel_tol=1e-12)
    coarse, fine = runs[0], runs[1]
    mid = math.sqrt(coarse["max_delta"] * fine["max_delta"])
    assert coarse["nfev"] < study.cost_at(rows, "rotor", "DOP853", "nfev", mid) < fine["nfev"]
    assert math.isnan(study.cost_at(rows, "rotor", "DOP853", "nfev", 10 * coarse["max_delta"]))


def test_findings_list_every_configuration_at_the_reference_tolerance(result):
    rows, _ = result
    lines = study.findings(rows, T_END)
    assert "Findings:" in lines
    key_rows = lines[2:lines.index("")]
    for formulation in FORMULATIONS:
        for method in METHODS:
            assert sum(line.split()[:3] == [formulation, method, "1e-12"] for line in key_rows) >= 1
    assert any(line.startswith("  scipy solve_ivp DOP853") for line in lines)


def test_envelope_keeps_the_largest_error_of_each_bin():
    t = np.linspace(0.0, 1.0, 10 * study.CURVE_POINTS + 7)
    delta = np.random.default_rng(1).random(t.size)
    te, de = study._envelope(t, delta)
    assert len(te) == study.CURVE_POINTS and de.max() == delta.max()
    assert np.all(np.diff(te) > 0) and np.all(np.isin(de, delta))


def test_figures_are_written(result, tmp_path):
    pytest.importorskip("matplotlib")
    rows, curves = result
    paths = study.figures(tmp_path, rows, curves, T_END)
    assert [p.name for p in paths] == ["error_vs_time.png", "max_error.png"]
    assert all(p.read_bytes().startswith(b"\x89PNG") for p in paths)
