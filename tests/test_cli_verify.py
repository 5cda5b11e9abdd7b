"""`pnrotor verify` and `pnrotor bench` through the CLI dispatcher: output, exit status, files."""

import csv

import pytest

from pnrotor import hdf5
from pnrotor.cli import main


def test_verify_prints_the_error_and_passes(capsys):
    assert main(["verify", "--t-end", "2e4"]) == 0
    out = capsys.readouterr().out
    assert "rotor, DOP853, atol 1e-12" in out and "max δ" in out and "evaluations" in out
    max_delta = float(out.split("max δ")[1].split()[0])
    assert 1e-12 < max_delta < 1e-10
    assert out.rstrip().endswith("OK")


def test_verify_fails_above_the_limit_and_reports_resets(capsys):
    code = main(["verify", "--t-end", "2e4", "--formulation", "generator", "--method", "BS", "--atol", "1e-6",
                 "--max-error", "1e-9"])
    out = capsys.readouterr().out
    assert code == 1 and "FAILED: max δ above the limit" in out
    assert "Bulirsch-Stoer" in out and int(out.split("generator resets")[1].split()[0]) >= 20


def test_verify_fails_when_the_integration_does_not_reach_T(capsys):
    # backward, the paper's binary passes R = −1 (to ~5e-15) at t = −75000, where the unreset generator is singular;
    # a negative --t-end in exponent form is a value, not an unknown option
    code = main(["verify", "--formulation", "generator-noreset", "--atol", "1e-12", "--t-end", "-8e4"])
    out = capsys.readouterr().out
    assert code == 1 and "integration did not reach T" in out and "status           -2" in out
    assert float(out.split("(at t = ")[1].split(")")[0]) == pytest.approx(-75000.0, abs=1e-3)


def test_verify_writes_the_history(tmp_path, capsys):
    path = tmp_path / "run.h5"
    assert main(["verify", "--t-end", "3e3", "--formulation", "vectors2", "-o", str(path)]) == 0
    history = hdf5.read(path)
    assert history.formulation == "vectors2" and history.t[-1] == 3e3 and history.status == 0
    assert main(["verify", "--t-end", "3e3", "-o", str(path)]) == 2  # exists
    assert "--overwrite" in capsys.readouterr().err
    assert main(["verify", "--t-end", "3e3", "-o", str(path), "--overwrite"]) == 0
    assert hdf5.read(path).formulation == "rotor"


@pytest.mark.parametrize("args, message", [
    (["--formulation", "quaternion"], "unknown formulation"),
    (["--method", "RK4"], "unknown method"),
    (["--t-end", "0"], "--t-end"),
    (["--max-error", "-1"], "--max-error"),
])
def test_verify_rejects_bad_input(args, message, capsys):
    assert main(["verify", *args]) == 2
    assert message in capsys.readouterr().err


def test_bench_writes_the_table_figures_and_findings(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out_dir = tmp_path / "bench"
    assert main(["bench", "--t-end", "3e3", "--atols", "1e-6", "1e-9", "--repeat", "1", "-o", str(out_dir)]) == 0
    out = capsys.readouterr().out
    with open(out_dir / "bench.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0])[:8] == ["formulation", "method", "atol", "max_delta", "wall_s", "nfev", "steps", "resets"]
    studies = {}
    for r in rows:
        studies.setdefault(r["study"], set()).add((r["formulation"], r["method"], float(r["atol"]), r["damping"]))
    assert len(studies["sweep"]) == 6 * 2 * 2  # every formulation × method × atol
    assert studies["baseline"] == {("rotor", "scipy-DOP853", a, "") for a in (1e-6, 1e-9)}
    assert studies["equal-rtol"] == {("rotor", "DOP853", a, "") for a in (1e-6, 1e-9)}
    assert studies["damping"] == {("vectors-damped", m, 1e-8, rate) for m in ("DOP853", "Bulirsch-Stoer")
                                  for rate in ("0.0", "0.001", "0.01", "0.1", "1.0")}
    for r in rows:
        assert int(r["status"]) == 0 and float(r["t_final"]) == 3e3
        assert float(r["max_delta"]) < 1e3 * float(r["atol"])
    assert (out_dir / "error_vs_time.png").stat().st_size > 0 and (out_dir / "max_error.png").stat().st_size > 0
    assert "Findings:" in out and "× pnrotor's wall time" in out and "generator without reset / with reset" in out


def test_bench_rejects_bad_input(tmp_path, capsys):
    assert main(["bench", "--atols", "0", "-o", str(tmp_path)]) == 2
    assert "--atols" in capsys.readouterr().err
    for command in ("bench", "verify"):   # bench checked it after ~30 runs, its output folder made
        with pytest.raises(SystemExit) as parsed:
            main([command, "--damping", "nan", "1", "-o", str(tmp_path / "b")])
        err = capsys.readouterr().err
        assert parsed.value.code == 2 and "--damping: must be a finite number >= 0" in err and err.count("\n") == 1
        assert not (tmp_path / "b").exists()
    with pytest.raises(SystemExit) as parsed:   # growing constraint violations: refused, not "stopped"
        main(["verify", "--damping", "-1e-3", "1"])
    assert parsed.value.code == 2 and "--damping: must be a finite number >= 0, got '-1e-3'" in capsys.readouterr().err
    assert main(["bench", "--pn", "--damping", "1", "1", "-o", str(tmp_path / "b")]) == 2   # was ignored
    assert "--damping are for the paper's study, not --pn" in capsys.readouterr().err and not (tmp_path / "b").exists()


def test_cli_damping_default_is_the_librarys():
    import inspect

    from pnrotor.cli import DAMPING
    from pnrotor.integrate import integrate_angular_velocity
    assert inspect.signature(integrate_angular_velocity).parameters["damping"].default == DAMPING


@pytest.mark.parametrize("args, line", [
    (["evolve", "--f-ref", "abc"], "pnrotor evolve: error: argument --f-ref: invalid float value: 'abc' "
                                   "(see pnrotor evolve --help)\n"),
    (["evolve", "--compression", "bz2"], "pnrotor evolve: error: argument --compression: invalid choice: 'bz2' "
                                         "(choose from 'gzip', 'lzf') (see pnrotor evolve --help)\n"),
    (["evolve", "--bogus"], "pnrotor: error: unrecognized arguments: --bogus (see pnrotor --help)\n"),
    (["verify", "--damping", "abc", "1"], "pnrotor verify: error: argument --damping: must be a finite number >= 0, "
                                          "got 'abc' (see pnrotor verify --help)\n"),
])
def test_parsing_errors_are_one_line(args, line, capsys):
    """argparse printed its usage block (12 lines) before the error."""
    with pytest.raises(SystemExit) as parsed:
        main(args)
    assert parsed.value.code == 2 and capsys.readouterr().err == line


def test_bench_pn_writes_the_work_precision_study(tmp_path, capsys, monkeypatch):
    """`pnrotor bench --pn` on one case (the study's default is four): the JSON, the figure, and what it measures
    — the frame error against the converged reference falls with atol (down to round-off), LAL's SpinTaylorT4
    is within 1e-6 rad of it, and at atol 1e-12 the error is below 1e-10 rad."""
    pytest.importorskip("lalsimulation")
    pytest.importorskip("matplotlib")
    import json

    from pnrotor import pn_study
    monkeypatch.setattr(pn_study, "DEFAULT_CASES", ["BBH-aligned"])
    out_dir = tmp_path / "pn"
    assert main(["bench", "--pn", "--quick", "--no-scipy", "--repeat", "1", "-o", str(out_dir)]) == 0
    out = capsys.readouterr().out
    result = json.loads((out_dir / "pn_work_precision.json").read_text())
    rows = result["cases"]["BBH-aligned"]["rows"]
    frame = {r["tol"]: r["frame"] for r in rows if r["method"] == "pnrotor"}
    assert [frame[a] for a in (1e-6, 1e-8, 1e-10, 1e-12)] == sorted(frame[a] for a in (1e-6, 1e-8, 1e-10, 1e-12))[::-1]
    assert frame[1e-6] > 1e3 * frame[1e-12] and frame[1e-12] < 1e-10
    lal = next(r for r in rows if r["method"] == "LAL T4")
    assert 1e-12 < lal["frame"] < 1e-6 and lal["ms"] > 0
    assert (out_dir / "pn_work_precision.png").stat().st_size > 0 and "at LAL's accuracy pnrotor is" in out


def test_bench_pn_rejects_the_options_of_the_papers_study(tmp_path, capsys):
    assert main(["bench", "--pn", "--t-end", "1e4", "-o", str(tmp_path)]) == 2
    assert "--t-end" in capsys.readouterr().err


def test_negative_values_are_values_not_options():
    """argparse (Python 3.11) read '-1e6' and '-0.6,0,0.2' as unknown options ("expected one argument")."""
    from pnrotor.cli import build_parser
    args = build_parser().parse_args(["evolve", "--m1", "30", "--m2", "10", "--chi1", "-0.6,0,0.2", "--chi2",
                                      "-.1,0,0", "--f-ref", "20"])
    assert (args.chi1, args.chi2) == ("-0.6,0,0.2", "-.1,0,0")
    assert build_parser().parse_args(["verify", "--t-end", "-1E+6"]).t_end == -1e6
    with pytest.raises(SystemExit):
        build_parser().parse_args(["verify", "--t-end", "-x"])   # an option still, unknown
