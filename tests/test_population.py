"""`pnrotor evolve --batch F --population` (pnrotor.batch.population): each row's final state in one file of
columns, bitwise what single `pnrotor.evolve` calls give; rows that fail fail alone; the file reads back bitwise
(and in plain h5py); options of the other batch modes are usage errors that write nothing."""

import math
import os

import h5py
import numpy as np
import pytest
from test_hdf5 import assert_identical

import pnrotor
from pnrotor import hdf5
from pnrotor.batch import population
from pnrotor.cli import main
from pnrotor.pn.evolve import TERMINATION_MESSAGES

TABLE = """name,m1,m2,chi1,chi2,f_ref,f_min,f_max,approximant,pn_order,atol,sampling
fwd,30,10,"0.6,0,0.2","0,-0.4,0.1",100,,150,,,,
end,30,10,"0.6,0,0.2","0,-0.4,0.1",100,,,,,,final
back,25,12,"0.1,0.2,0.3","0,0,0.4",100,70,,,,,
t1,25,12,"0.1,0.2,0.3","0,0,0.4",100,,,T1,,1e-10,
aligned,20,20,"0,0,0.3","0,0,-0.2",120,,,TaylorT4,3,,
spin,10,10,"0,0,2","0,0,0",100,,,,,,
cell,abc,10,"0,0,0","0,0,0",100,,,,,,
both,30,10,"0,0,0","0,0,0",100,60,150,,,,
steps,30,10,"0,0,0","0,0,0",100,,,,,,steps
order,30,10,"0,0,0","0,0,0",100,,,,5,,
t1back,20,8,"0.2,0.1,0","0,0.3,0",100,80,,T1,,1e-10,
"""
GOOD = {
    "fwd": dict(m1=30.0, m2=10.0, chi1=(0.6, 0, 0.2), chi2=(0, -0.4, 0.1), f_ref=100.0, f_max=150.0),
    "end": dict(m1=30.0, m2=10.0, chi1=(0.6, 0, 0.2), chi2=(0, -0.4, 0.1), f_ref=100.0),
    "back": dict(m1=25.0, m2=12.0, chi1=(0.1, 0.2, 0.3), chi2=(0, 0, 0.4), f_ref=100.0, f_min=70.0),
    "t1": dict(m1=25.0, m2=12.0, chi1=(0.1, 0.2, 0.3), chi2=(0, 0, 0.4), f_ref=100.0, approximant="T1", atol=1e-10),
    "aligned": dict(m1=20.0, m2=20.0, chi1=(0, 0, 0.3), chi2=(0, 0, -0.2), f_ref=120.0, pn_order=3.0),
    "t1back": dict(m1=20.0, m2=8.0, chi1=(0.2, 0.1, 0), chi2=(0, 0.3, 0), f_ref=100.0, f_min=80.0, approximant="T1",
                   atol=1e-10),
}
FAILED = [
    "  FAILED row 6 (line 7) (spin): |chi1| = 2.0 exceeds 1",
    "  FAILED row 7 (line 8) (cell): m1 must be a number, got 'abc'",
    "  FAILED row 8 (line 9) (both): f_min and f_max are both given: the population mode gives one state per row, "
    "at f_max (forward), at f_min (backward) or at the end of the inspiral; give at most one of them",
    "  FAILED row 9 (line 10) (steps): sampling must be final (or empty) in the population mode, which gives final "
    "states only; got steps",
    "  FAILED row 10 (line 11) (order): pn_order must be a multiple of 0.5 in [0.0, 4.5], got 5.0",
]
STATE = ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat")


def evolve(capsys, *args):
    code = main(["evolve", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text(TABLE)
    return tmp_path


def single(kw):
    """(state by STATE, termination, nfev) of the state `pnrotor.evolve` gives for a row: with f_min its first sample
    (the state at f_min, integrated backward), otherwise its final state with sampling='final'."""
    if "f_min" in kw:
        e, i = pnrotor.evolve(**kw, sampling="steps"), 0
        return [getattr(e, k)[i] for k in STATE], e.stats["termination_backward"], e.stats["nfev_backward"]
    e = pnrotor.evolve(**kw, sampling="final")
    assert len(e) == 1
    return [getattr(e, k)[0] for k in STATE], e.termination, e.stats["nfev"]


def test_rows_equal_single_evolve_bitwise_and_failures_fail_alone(in_tmp, capsys):
    code, out, err = evolve(capsys, "--batch", "t.csv", "--population", "-o", "pop.h5")
    assert code == 1 and err == ""
    lines = out.splitlines()
    assert lines[0] == ("pnrotor evolve --batch t.csv --population: 11 binaries, final states by evolve_many in 1 chunk "
                        "of up to 10000 rows, on this process")
    assert lines[1:-1] == FAILED
    assert lines[-1].startswith("wrote 6 final states to pop.h5; 5 failed; ") and lines[-1].endswith(" rows/s)")
    assert sorted(os.listdir(in_tmp)) == ["pop.h5", "t.csv"]

    table = hdf5.read(in_tmp / "pop.h5")
    assert isinstance(table, population.PopulationTable) and len(table) == 6
    assert list(table.name) == list(GOOD) and list(table.inputs["row"]) == [1, 2, 3, 4, 5, 11]
    assert list(table.termination) == ["f_max", "energy_balance", "f_min", table.termination[3], table.termination[4],
                                       "f_min"]
    for i, (name, kw) in enumerate(GOOD.items()):
        state, termination, nfev = single(kw)
        for key, expected in zip(STATE, state):
            assert np.asarray(getattr(table, key)[i]).tobytes() == np.asarray(expected).tobytes(), (name, key)
        assert table.termination[i] == termination and table.nfev[i] == nfev, name
        assert table.message[i] == TERMINATION_MESSAGES[termination]
    inputs = table.inputs
    np.testing.assert_array_equal(inputs["m1_Msun"], [30, 30, 25, 25, 20, 20])
    np.testing.assert_array_equal(inputs["f_min_Hz"], [np.nan, np.nan, 70, np.nan, np.nan, 80])
    np.testing.assert_array_equal(inputs["f_max_Hz"], [150] + [np.nan] * 5)
    assert list(inputs["approximant"]) == ["T4", "T4", "T4", "T1", "T4", "T1"]
    np.testing.assert_array_equal(inputs["atol"], [1e-12, 1e-12, 1e-12, 1e-10, 1e-12, 1e-10])
    np.testing.assert_array_equal(inputs["pn_order"], [3.5, 3.5, 3.5, 3.5, 3.0, 3.5])
    assert math.isnan(inputs["spin_orbit_order"][0]) and inputs["sampling"] == "final" and inputs["rtol"] == 0.0

    with h5py.File(in_tmp / "pop.h5") as f:   # plain h5py: columns, units, checksums
        assert f.attrs["kind"].decode() == "PopulationTable" and f.attrs["pnrotor_schema"] == 2
        assert list(f["name"].asstr()[:]) == list(GOOD) and f["R"].shape == (6, 4) and f["R"].fletcher32
        assert f["termination"].fletcher32 and f["inputs/m1_Msun"].attrs["units"].decode() == "Msun"
        np.testing.assert_array_equal(f["v"][:], table.v)


def test_library_run_with_a_group_of_invalid_rows_only(tmp_path):
    (tmp_path / "bad.csv").write_text('m1,m2,chi1,chi2,f_ref\n10,10,"0,0,2","0,0,0",100\n-1,10,"0,0,0","0,0,0",100\n')
    outcome = population.run(tmp_path / "bad.csv", tmp_path / "none.h5")
    assert outcome.path is None and outcome.written == 0 and len(outcome.failed) == 2
    assert "m1" in outcome.rows[1].error and os.listdir(tmp_path) == ["bad.csv"]


@pytest.mark.parametrize("options", [dict(), dict(compression="gzip"), dict(checksum=False)])
def test_round_trip_is_bitwise(tmp_path, options):
    (tmp_path / "t.csv").write_text(TABLE)
    population.run(tmp_path / "t.csv", tmp_path / "a.h5", **options)
    first = hdf5.read(tmp_path / "a.h5")
    hdf5.write(tmp_path / "b.h5", first, **options)
    assert_identical(hdf5.read(tmp_path / "b.h5"), first)
    assert first.termination.dtype == object and type(first.termination[0]) is str
    assert first.nsteps.dtype == np.int64 and first.inputs["row"].dtype == np.int64


def test_strings_with_unicode_and_the_layout_checks(tmp_path):
    (tmp_path / "t.csv").write_text('name,m1,m2,chi1,chi2,f_ref\nbinär ✓,30,10,"0,0,0","0,0,0",100\n')
    population.run(tmp_path / "t.csv", tmp_path / "u.h5")
    assert list(hdf5.read(tmp_path / "u.h5").name) == ["binär ✓"]
    with h5py.File(tmp_path / "u.h5", "r+") as f:
        del f["inputs/m1_Msun"]
        del f["termination"]
        f["termination"] = np.zeros(1)
    with pytest.raises(ValueError, match=r"u\.h5: dataset 'inputs/m1_Msun' is missing; dataset 'termination' is a "
                                         r"float64 array, expected strings$"):
        hdf5.read(tmp_path / "u.h5")


def test_a_table_written_before_horizon_absorption_reads_with_it_false(tmp_path):
    """Schema-2 tables were written without ``inputs/horizon_absorption`` before the option came: they read, the
    option False for every row, and the rest as written."""
    (tmp_path / "t.csv").write_text(TABLE)
    population.run(tmp_path / "t.csv", tmp_path / "a.h5")
    table = hdf5.read(tmp_path / "a.h5")
    with h5py.File(tmp_path / "a.h5", "r+") as f:
        del f["inputs/horizon_absorption"]
    older = hdf5.read(tmp_path / "a.h5")
    assert older.inputs["horizon_absorption"].dtype == bool and not older.inputs["horizon_absorption"].any()
    assert_identical(older, table)


def test_a_pnrotor_without_the_kind_refuses_the_file_clearly(tmp_path, monkeypatch):
    """Schema 1 stays: a reader that does not know the kind refuses it by name before reading any field."""
    (tmp_path / "t.csv").write_text(TABLE)
    population.run(tmp_path / "t.csv", tmp_path / "p.h5")
    monkeypatch.delitem(hdf5.KINDS, "PopulationTable")
    with pytest.raises(ValueError, match=r"p\.h5: unknown run kind 'PopulationTable'; this pnrotor reads"):
        hdf5.read(tmp_path / "p.h5")


@pytest.mark.parametrize("args, message", [
    (["--jobs", "0"], "--jobs must be at least 1, got 0"),
    (["--jobs", "2", "--scheduler", "tcp://localhost:1"], "--jobs applies to local runs"),
    (["--modes", "--ell-max", "0", "--distance", "0"], "--modes, --ell-max, --distance cannot be combined"),
    (["--modes", "--ell-max", "3"], "--modes, --ell-max cannot be combined with --population"),
    (["--amplitude-order", "2", "--distance", "10"], "--amplitude-order, --distance cannot be combined"),
    (["--sampling", "1/4096"], "--sampling must be final with --population (final states only), got '1/4096'"),
    (["--m1", "30"], "--m1 cannot be combined with --batch"),
    (["-o", "missing/p.h5"], "folder missing does not exist"),
])
def test_usage_errors_exit_2_without_traceback_or_file(args, message, in_tmp, capsys, monkeypatch):
    monkeypatch.setattr(population, "_evolve", lambda *a: pytest.fail("computed"))
    code, out, err = evolve(capsys, "--batch", "t.csv", "--population", *args)
    assert code == 2 and out == "" and err.startswith("pnrotor evolve: error: ") and message in err, err
    assert err.count("\n") == 1 and os.listdir(in_tmp) == ["t.csv"]


def test_population_needs_a_batch(in_tmp, capsys):
    code, out, err = evolve(capsys, "--m1", "30", "--m2", "10", "--chi1", "0,0,0", "--chi2", "0,0,0", "--f-ref", "100",
                            "--population")
    assert code == 2 and err == "pnrotor evolve: error: --population applies to --batch runs only\n"
    assert os.listdir(in_tmp) == ["t.csv"]


def test_existing_output_is_refused_unless_overwrite(in_tmp, capsys, monkeypatch):
    (in_tmp / "waveforms").mkdir()
    (in_tmp / "waveforms" / "t.h5").write_bytes(b"old")
    code, _, err = evolve(capsys, "--batch", "t.csv", "--population")
    assert code == 2 and "waveforms/t.h5 exists; pass --overwrite" in err
    assert (in_tmp / "waveforms" / "t.h5").read_bytes() == b"old"
    code, out, _ = evolve(capsys, "--batch", "t.csv", "--population", "--overwrite", "-q", "--sampling", "final")
    assert code == 1 and out.splitlines()[:-1] == FAILED
    assert len(hdf5.read(in_tmp / "waveforms" / "t.h5")) == 6 and os.listdir(in_tmp / "waveforms") == ["t.h5"]


def test_interrupted_population_leaves_no_file(in_tmp, capsys, monkeypatch):
    """Ctrl-C while the table is being written (its temporary file exists): exit 130, no table nor temporary file
    left; the finished chunk is kept for --resume, which writes the table."""
    real = hdf5._put_run

    def interrupted(g, *args):
        if any(name.endswith(".pnrotor-tmp") for name in os.listdir(in_tmp)):
            raise KeyboardInterrupt
        return real(g, *args)

    monkeypatch.setattr(hdf5, "_put_run", interrupted)
    code, _, err = evolve(capsys, "--batch", "t.csv", "--population", "-o", "p.h5")
    assert code == 130 and err == ("pnrotor evolve: interrupted; 1 finished chunk kept in p.h5.parts; complete the "
                                   "population with --resume (resume=True)\n")
    assert sorted(os.listdir(in_tmp)) == ["p.h5.parts", "t.csv"]
    monkeypatch.setattr(hdf5, "_put_run", real)
    monkeypatch.setattr(population, "_evolve", lambda *a: pytest.fail("computed again"))
    code, out, _ = evolve(capsys, "--batch", "t.csv", "--population", "-o", "p.h5", "--resume", "-q")
    assert code == 1 and out.splitlines()[:-1] == FAILED and sorted(os.listdir(in_tmp)) == ["p.h5", "t.csv"]


def test_rows_evolve_refuses_fail_with_its_message(in_tmp, capsys):
    """A row's f_max must lie above f_ref and its f_min below, both finite, as `pnrotor.evolve` checks them
    (evolve_many itself takes a target on either side of f_ref, and NaN as the end of the inspiral): such rows
    fail alone, each with the message evolve gives for it (for a row with two faults, the one evolve names
    first); the others are written."""
    targets = {"below": ",50", "above": "150,", "equal": "100,", "nan": ",nan", "inf": "inf,", "spin": ",50"}
    chi1 = {"spin": (1.2, 0.0, 0.0)}
    (in_tmp / "r.csv").write_text("name,m1,m2,chi1,chi2,f_ref,f_min,f_max\n" + "".join(
        f'{name},30,10,"{",".join(map(str, chi1.get(name, (0, 0, 0))))}","0,0,0",100,{f}\n'
        for name, f in targets.items()) + 'ok,30,10,"0,0,0","0,0,0",100,,150\n')
    code, out, err = evolve(capsys, "--batch", "r.csv", "--population", "-o", "r.h5")
    assert code == 1 and err == ""
    for name, f in targets.items():
        f_min, f_max = (None if x == "" else float(x) for x in f.split(","))
        with pytest.raises(ValueError) as refused:
            pnrotor.evolve(30, 10, chi1.get(name, (0, 0, 0)), (0, 0, 0), 100, f_min=f_min, f_max=f_max,
                           sampling="final")
        assert f"({name}): {refused.value}" in out, name
    assert list(hdf5.read(in_tmp / "r.h5").name) == ["ok"]


def test_a_progress_bar_of_rows_on_a_terminal_unless_quiet(in_tmp, capsys, monkeypatch):
    import sys

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    code, _, err = evolve(capsys, "--batch", "t.csv", "--population", "-o", "a.h5")
    assert code == 1 and "11/11" in err and "row/s" in err
    code, _, err = evolve(capsys, "--batch", "t.csv", "--population", "-o", "b.h5", "-q")
    assert code == 1 and err == ""
