"""`pnrotor evolve`: the file of one run equals `pnrotor.evolve` bitwise, its default name and folder,
refusal to overwrite, one-line errors (exit 2, no file) for bad input, sampling variants, and batches
from CSV and TOML in this process, on worker processes and on a Dask cluster, with failures listed."""

import dataclasses
import importlib
import math
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from helpers import default_signals
from test_hdf5 import assert_identical

import pnrotor
from pnrotor import hdf5
from pnrotor.batch import backends, table
from pnrotor.cli import main

MAIN = ["--m1", "30", "--m2", "10", "--chi1", "0.6,0,0.2", "--chi2", "0,-0.4,0.1", "--f-ref", "20"]
MAIN_NAME = "T4_m30_m10_chi1-0.6,0,0.2_chi2-0,-0.4,0.1_f20.h5"
FAST = ["--m1", "30", "--m2", "10", "--chi1", "0.6,0,0.2", "--chi2", "0,-0.4,0.1", "--f-ref", "100"]
"""A cheap precessing binary: from 100 Hz, ~4 orbits to the end of the inspiral."""
FAST_KW = dict(m1=30.0, m2=10.0, chi1=(0.6, 0.0, 0.2), chi2=(0.0, -0.4, 0.1), f_ref=100.0)
WALL = {"wall_time_s", "wall_time_integrate_s"}


def evolve(capsys, *args):
    code = main(["evolve", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


def assert_same_run(a, b):
    """Equal bitwise except the wall times, which differ between any two runs."""
    for run in (a, b):
        assert WALL <= run.stats.keys()
    a_stats = {k: v for k, v in a.stats.items() if k not in WALL}
    b_stats = {k: v for k, v in b.stats.items() if k not in WALL}
    assert_identical(a_stats, b_stats, "stats")
    assert_identical(dataclasses.replace(a, stats={}), dataclasses.replace(b, stats={}))


@pytest.fixture
def in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


# --------------------------------------------------------------------------------------------------
# one run
# --------------------------------------------------------------------------------------------------


def test_main_job_writes_the_evolution_to_waveforms_with_a_summary(in_tmp, capsys):
    code, out, err = evolve(capsys, *MAIN)
    assert code == 0 and err == ""
    path = in_tmp / "waveforms" / MAIN_NAME
    assert os.listdir(in_tmp) == ["waveforms"] and os.listdir(in_tmp / "waveforms") == [MAIN_NAME]
    stored = hdf5.read(path)
    direct = pnrotor.evolve(30, 10, (0.6, 0, 0.2), (0, -0.4, 0.1), 20)
    assert isinstance(stored, pnrotor.Evolution)
    assert_same_run(stored, direct)

    s = direct.stats
    lines = out.splitlines()
    assert lines[0] == "pnrotor evolve: 30 + 10 Msun, chi1 (0.6, 0, 0.2), chi2 (0, -0.4, 0.1), f_ref 20 Hz (precessing)"
    assert lines[-1] == f"wrote waveforms/{MAIN_NAME}"
    assert "T4, PN order 3.5 (spin-orbit 3.5, spin-spin 3), precession averaged, atol 1e-12" in lines[1]
    M = direct.inputs["M_seconds"]
    assert f"duration       {direct.t[-1] * M:.6g} s = {direct.t[-1]:.6g} M" in out
    assert f"ΔΦ/2π          {direct.Phi[-1] / (2 * math.pi):.6g} orbits\n" in out
    assert f"v              {direct.v[0]:.6g} -> {direct.v[-1]:.6g}" in out
    assert f"GW frequency   20 Hz -> {direct.f_gw[-1]:.6g} Hz" in out
    assert f"forward        {direct.termination}: {s['termination_message']}" in out
    assert "backward       not_integrated: this half was not integrated (no f_min given)" in out
    assert f"work           {s['nfev']} evaluations, {s['nsteps']} steps ({s['naccepted']} accepted" in out
    assert f"samples        {len(direct)} (steps)" in out and "s evolving, " in out


def test_refuses_to_overwrite_before_computing_and_overwrites_when_asked(in_tmp, capsys, monkeypatch):
    path = in_tmp / "waveforms" / MAIN_NAME.replace("f20", "f100")
    assert evolve(capsys, *FAST)[0] == 0
    before = path.read_bytes()
    calls = []
    monkeypatch.setattr(backends, "evolve_row", lambda params: calls.append(params))
    code, out, err = evolve(capsys, *FAST)
    assert code == 2 and calls == [] and out == ""
    assert err == f"pnrotor evolve: error: {path.relative_to(in_tmp)} exists; pass --overwrite to replace it\n"
    assert path.read_bytes() == before
    monkeypatch.undo()
    monkeypatch.chdir(in_tmp)
    inode = path.stat().st_ino
    code, out, _ = evolve(capsys, *FAST, "--overwrite", "--sampling", "steps")  # the same name
    assert code == 0 and path.stat().st_ino != inode  # replaced (hdf5.write renames a new file over it)
    assert_same_run(hdf5.read(path), pnrotor.evolve(**FAST_KW))
    assert os.listdir(path.parent) == [path.name]


def test_output_option_and_compression(tmp_path, capsys):
    path = tmp_path / "run.h5"
    assert evolve(capsys, *FAST, "-o", path, "--compression", "lzf")[0] == 0
    with h5py.File(path) as f:
        assert f["R"].compression == "lzf" and f["v"].compression == "lzf"
    assert_same_run(hdf5.read(path), pnrotor.evolve(**FAST_KW))
    assert evolve(capsys, *FAST, "-o", path, "--overwrite", "--compression", "gzip", "--no-checksum")[0] == 0
    with h5py.File(path) as f:
        assert f["R"].compression == "gzip" and not f["R"].fletcher32
    assert evolve(capsys, *FAST, "-o", path, "--overwrite")[0] == 0  # checksums by default
    with h5py.File(path) as f:
        assert f["R"].fletcher32 and f["v"].fletcher32 and f["R"].compression is None
    assert evolve(capsys, *FAST, "-o", path, "--overwrite", "--checksum")[0] == 0  # the old flag: the default
    with h5py.File(path) as f:
        assert f["R"].fletcher32 and f["v"].fletcher32
    assert_same_run(hdf5.read(path), pnrotor.evolve(**FAST_KW))
    assert os.listdir(tmp_path) == ["run.h5"]


def test_default_name_lists_every_option_away_from_its_default(in_tmp, capsys):
    args = ["--f-min", "90", "--f-max", "200", "--approximant", "TaylorT5", "--pn-order", "3", "--spin-orbit-order",
            "2.5", "--spin-spin-order", "2", "--precession", "averaged_varpi", "--atol", "1e-10", "--sampling", "1/4096"]
    code, out, _ = evolve(capsys, *FAST, *args)
    name = ("T5_m30_m10_chi1-0.6,0,0.2_chi2-0,-0.4,0.1_f100_fmin90_fmax200_pn3_so2.5_ss2_atol1e-10_averaged_varpi"
            "_dt0.000244140625.h5")
    assert code == 0 and os.listdir(in_tmp / "waveforms") == [name]
    stored = hdf5.read(in_tmp / "waveforms" / name)
    direct = pnrotor.evolve(**FAST_KW, f_min=90, f_max=200, approximant="T5", pn_order=3, spin_orbit_order=2.5,
                            spin_spin_order=2, precession="averaged_varpi", atol=1e-10, sampling=1 / 4096)
    assert_same_run(stored, direct)
    assert direct.termination == "f_max" and direct.stats["termination_backward"] == "f_min"
    assert "backward       f_min: v reached the requested start frequency f_min" in out
    assert "T5, PN order 3 (spin-orbit 2.5, spin-spin 2), precession averaged_varpi, atol 1e-10" in out
    # -0.0 and 0 give the same name; instantaneous precession is named
    assert table.default_name(dict(FAST_KW, chi1=(-0.0, 0.0, 0.5), **table.DEFAULTS)).startswith(
        "T4_m30_m10_chi1-0,0,0.5_")
    code, _, _ = evolve(capsys, *FAST, "--precession", "instantaneous", "--sampling", "final")
    assert code == 0 and (in_tmp / "waveforms" / MAIN_NAME.replace("f20", "f100_instantaneous_final")).exists()


@pytest.mark.parametrize("sampling, expected, orbits", [
    ("steps", "steps", "exact"),
    ("final", "final", "exact"),
    ("0.000244", 0.000244, "approx"),
    ("1/2048", 1 / 2048, "approx"),
    ("per_orbit:8", ("per_orbit", 8), "approx"),
])
def test_sampling_variants_equal_evolve(sampling, expected, orbits, tmp_path, capsys):
    path = tmp_path / "run.h5"
    code, out, _ = evolve(capsys, *FAST, "--f-min", "95", "--sampling", sampling, "-o", path)
    assert code == 0
    direct = pnrotor.evolve(**FAST_KW, f_min=95, sampling=expected)
    assert_same_run(hdf5.read(path), direct)
    orbit_line = next(line for line in out.splitlines() if "ΔΦ/2π" in line)
    if sampling == "final":  # one sample, at the end: the start is not known
        assert "orbits unknown (one sample, not the start)" in orbit_line
    elif orbits == "exact":
        assert f"{(direct.Phi[-1] - direct.Phi[0]) / (2 * math.pi):.6g} orbits" in orbit_line and "~" not in orbit_line
    else:
        assert f"~{(direct.Phi[-1] - direct.Phi[0]) / (2 * math.pi):.6g} orbits (first to last sample)" in orbit_line
    v0 = (math.pi * direct.inputs["M_seconds"] * 95) ** (1 / 3)  # exact start of the integration, whatever the sampling
    assert f"v              {v0:.6g} -> {direct.stats['v_final']:.6g}" in out


@pytest.mark.parametrize("args, message", [
    (["--m1", "0"], "m1 must be a finite positive mass, got 0.0"),
    (["--m2", "-3"], "m2 must be a finite positive mass"),
    (["--m1", "nan"], "m1 must be a finite positive mass, got nan"),
    (["--chi1", "0.9,0.5,0.1"], "|chi1| = "),
    (["--chi2", "0,0,1.01"], "|chi2| = 1.01 exceeds 1"),
    (["--chi1", "nan,0,0"], "--chi1 must be three finite numbers separated by commas"),
    (["--chi1", "0.1,0.2"], "--chi1 must be three finite numbers separated by commas, such as 0.6,0,0.2; got '0.1,0.2'"),
    (["--chi2", "a,b,c"], "--chi2 must be three finite numbers"),
    (["--chi1", "0.1,0.2,0.3,0.4"], "--chi1 must be three"),
    (["--f-ref", "0"], "f_ref must be a finite positive frequency in Hz, got 0.0"),
    (["--f-ref", "-20"], "f_ref must be a finite positive frequency"),
    (["--f-min", "150"], "f_min = 150.0 Hz must be below f_ref = 100.0 Hz"),
    (["--f-max", "50"], "f_max = 50.0 Hz must be above f_ref"),
    (["--approximant", "T3"], "approximant must be one of T1, T4, T5"),
    (["--pn-order", "3.3"], "pn_order must be a multiple of 0.5 in [0.0, 4.5], got 3.3"),
    (["--pn-order", "5"], "pn_order must be a multiple of 0.5"),
    (["--spin-orbit-order", "5"], "spin_orbit_order must be a multiple of 0.5 in [-1.0, 4.0]"),
    (["--spin-spin-order", "3.5"], "spin_spin_order must be a multiple of 0.5 in [-1.0, 3.0]"),
    (["--atol", "0"], "atol must be > 0"),
    (["--atol", "-1e-9"], "atol must be > 0"),
    (["--sampling", "sometimes"], "--sampling must be steps, final, per_orbit:N or a time step in seconds"),
    (["--sampling", "per_orbit:0"], "--sampling per_orbit:N needs a positive integer N"),
    (["--sampling", "-0.001"], "sampling dt must be a finite positive time in seconds"),
    (["--sampling", "1/0"], "--sampling must be steps, final"),
    (["--jobs", "2"], "--jobs applies to --batch runs only"),
    (["--scheduler", "tcp://127.0.0.1:8786"], "--scheduler applies to --batch runs only"),
])
def test_bad_input_exits_2_naming_the_parameter_and_writes_nothing(args, message, in_tmp, capsys):
    given = dict(zip(FAST[::2], FAST[1::2]))
    given.update(zip(args[::2], args[1::2]))
    code, out, err = evolve(capsys, *[f"{option}={value}" for option, value in given.items()])
    assert code == 2 and out == ""
    assert err.startswith("pnrotor evolve: error: ") and message in err and err.count("\n") == 1
    assert os.listdir(in_tmp) == []  # not even waveforms/


def test_missing_options_and_output_folder_errors(in_tmp, capsys):
    code, _, err = evolve(capsys, "--m1", "30", "--chi1", "0,0,0", "--chi2", "0,0,0")
    assert code == 2 and "missing --m2, --f-ref (or give --batch FILE)" in err
    code, _, err = evolve(capsys, *FAST, "-o", "no/such/run.h5")
    assert code == 2 and err == "pnrotor evolve: error: folder no/such does not exist (-o no/such/run.h5); create it first\n"
    (in_tmp / "folder").mkdir()
    code, _, err = evolve(capsys, *FAST, "-o", "folder")
    assert code == 2 and "folder is a folder; give a file name such as folder/T4_m30" in err
    assert sorted(os.listdir(in_tmp)) == ["folder"] and os.listdir(in_tmp / "folder") == []


def test_quiet_prints_only_the_file(tmp_path, capsys):
    code, out, _ = evolve(capsys, *FAST, "-o", tmp_path / "run.h5", "-q")
    assert code == 0 and out == f"wrote {tmp_path / 'run.h5'}\n"


def test_console_script_exits_2_without_traceback(tmp_path):
    done = subprocess.run([sys.executable, "-m", "pnrotor", "evolve", *FAST[:-2], "--f-ref", "-5"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stdout == "" and "Traceback" not in done.stderr
    assert done.stderr == "pnrotor evolve: error: f_ref must be a finite positive frequency in Hz, got -5.0\n"
    assert os.listdir(tmp_path) == []


# --------------------------------------------------------------------------------------------------
# batches
# --------------------------------------------------------------------------------------------------

CSV = '''m1,m2,chi1,chi2,f_ref,f_min,sampling,approximant,name
30,10,"0.6,0,0.2","0,-0.4,0.1",100,,,,
25,12,"0.1,0.2,0.3","0,0,0.4",120,110,final,,
-5,10,"0,0,0","0,0,0",100,,,,negative
40,8,"0.3,0,0","0,0.2,0",100,,per_orbit:4,T1,light
20,20,"0,0,0","0,0,0",150,,,T5,
'''

TOML = '''
[[binary]]
m1 = 30
m2 = 10
chi1 = [0.6, 0, 0.2]
chi2 = "0,-0.4,0.1"
f_ref = 100

[[binary]]
name = "two"
m1 = 25.0
m2 = 12.0
chi1 = [0.1, 0.2, 0.3]
chi2 = [0.0, 0.0, 0.4]
f_ref = 120
f_min = 110
sampling = "final"

[[binary]]
m1 = 30
m2 = 10
chi1 = [0.0, 0.0, 1.5]
chi2 = [0, 0, 0]
f_ref = 100
name = "spin too large"

[[binary]]
m1 = 40
m2 = 8
chi1 = [0.3, 0, 0]
chi2 = [0, 0.2, 0]
f_ref = 100
sampling = 0.001
pn_order = 3
'''

CSV_KW = [
    dict(FAST_KW),
    dict(m1=25.0, m2=12.0, chi1=(0.1, 0.2, 0.3), chi2=(0.0, 0.0, 0.4), f_ref=120.0, f_min=110.0, sampling="final"),
    None,
    dict(m1=40.0, m2=8.0, chi1=(0.3, 0.0, 0.0), chi2=(0.0, 0.2, 0.0), f_ref=100.0, sampling=("per_orbit", 4),
         approximant="T1"),
    dict(m1=20.0, m2=20.0, chi1=(0.0, 0.0, 0.0), chi2=(0.0, 0.0, 0.0), f_ref=150.0, approximant="T5"),
]
CSV_NAMES = ["T4_m30_m10_chi1-0.6,0,0.2_chi2-0,-0.4,0.1_f100", "T4_m25_m12_chi1-0.1,0.2,0.3_chi2-0,0,0.4_f120_fmin110_final",
             "negative", "light", "T5_m20_m20_chi1-0,0,0_chi2-0,0,0_f150"]


def write_text(path, text):
    path.write_text(text)
    return path


def assert_batch(path, names, kwargs):
    assert hdf5.list_runs(path) == sorted(names)
    for name, kw in zip(names, kwargs):
        assert_same_run(hdf5.read(path, name), pnrotor.evolve(**kw))


def test_csv_batch_writes_the_good_rows_and_lists_the_bad_one(in_tmp, capsys):
    write_text(in_tmp / "params.csv", CSV)
    code, out, err = evolve(capsys, "--batch", "params.csv", "--jobs", "1")
    assert code == 1 and err == ""  # stderr is not a terminal: no progress bar
    path = in_tmp / "waveforms" / "params.h5"
    good = [0, 1, 3, 4]
    assert_batch(path, [CSV_NAMES[i] for i in good], [CSV_KW[i] for i in good])
    assert os.listdir(path.parent) == ["params.h5"]
    lines = out.splitlines()
    assert lines[0] == "pnrotor evolve --batch params.csv: 5 binaries, on this process"
    assert lines[1].startswith(f"  row 1 (line 2)  {CSV_NAMES[0]}: ") and "energy_balance" in lines[1]
    assert lines[2].startswith(f"  row 2 (line 3)  {CSV_NAMES[1]}: ") and "1 samples" in lines[2]
    assert lines[3].startswith("  row 4 (line 5)  light: ") and lines[4].startswith("  row 5 (line 6)  T5_m20")
    assert lines[5] == "  FAILED row 3 (line 4) (negative): m1 must be a finite positive mass, got -5.0"
    assert lines[6].startswith(f"wrote 4 runs to waveforms/params.h5; 1 failed; ") and len(lines) == 7


def test_toml_batch_with_command_line_defaults(in_tmp, capsys):
    write_text(in_tmp / "set.toml", TOML)
    code, out, _ = evolve(capsys, "--batch", "set.toml", "--jobs", "1", "--approximant", "T5", "--sampling", "final",
                          "-o", "set.h5", "--compression", "gzip", "-q")
    assert code == 1
    first = dict(FAST_KW, approximant="T5", sampling="final")
    two = dict(CSV_KW[1], approximant="T5")
    four = dict(m1=40.0, m2=8.0, chi1=(0.3, 0.0, 0.0), chi2=(0.0, 0.2, 0.0), f_ref=100.0, sampling=0.001, pn_order=3,
                approximant="T5")
    names = ["T5_m30_m10_chi1-0.6,0,0.2_chi2-0,-0.4,0.1_f100_final", "two", "T5_m40_m8_chi1-0.3,0,0_chi2-0,0.2,0_f100_pn3_dt0.001"]
    assert_batch(in_tmp / "set.h5", names, [first, two, four])
    with h5py.File(in_tmp / "set.h5") as f:
        assert f["two"]["R"].compression == "gzip"
    assert out.splitlines() == [
        "  FAILED row 3 ([[binary]] 3) (spin too large): |chi1| = 1.5 exceeds 1",
        out.splitlines()[-1],
    ] and out.splitlines()[-1].startswith("wrote 3 runs to set.h5; 1 failed;")
    assert sorted(os.listdir(in_tmp)) == ["set.h5", "set.toml"]


def test_batch_rows_with_bad_values_fail_alone(in_tmp, capsys):
    text = ('m1,m2,chi1,chi2,f_ref,sampling,name,pn_order\n'
            '30,10,"0,0,0","0,0,0",100,,ok,\n'
            'abc,10,"0,0,0","0,0,0",100,,,\n'
            '30,10,"0,0","0,0,0",100,,,\n'
            '30,10,"0,0,0","0,0,0",100,often,,\n'
            '30,10,"0,0,0","0,0,0",100,,a/b,\n'
            '30,10,"0,0,0","0,0,0",,,,\n'
            '30,10,"0,0,0","0,0,0",100,,,3.3\n'
            '30,x,"0,0,0","0,0,0",100,,named,\n')
    write_text(in_tmp / "b.csv", text)
    code, out, _ = evolve(capsys, "--batch", "b.csv", "--jobs", "1", "-q")
    assert code == 1 and hdf5.list_runs(in_tmp / "waveforms" / "b.h5") == ["ok"]
    assert out.splitlines()[:-1] == [
        "  FAILED row 2 (line 3): m1 must be a number, got 'abc'",
        "  FAILED row 3 (line 4): chi1 must be three finite numbers separated by commas, such as 0.6,0,0.2; got '0,0'",
        "  FAILED row 4 (line 5): sampling must be steps, final, per_orbit:N or a time step in seconds such as 1/4096, got 'often'",
        "  FAILED row 5 (line 6): name 'a/b' is not a valid group name (non-empty, no '/', not '.')",
        "  FAILED row 6 (line 7): f_ref is empty",
        "  FAILED row 7 (line 8) (T4_m30_m10_chi1-0,0,0_chi2-0,0,0_f100_pn3.3): pn_order must be a multiple of 0.5 in [0.0, 4.5], got 3.3",
        "  FAILED row 8 (line 9) (named): m2 must be a number, got 'x'",   # a bad row keeps its name
    ]


@pytest.mark.parametrize("name, text, message", [
    ("b.csv", "m1,m2,chi1,chi2,f_ref,mass_ratio\n", "unknown column 'mass_ratio'; the columns are m1, m2, chi1"),
    ("b.csv", "m1,m2,chi1,chi2\n30,10,0,0\n", "missing column f_ref"),
    ("b.csv", "m1,m2,chi1,chi2,f_ref\n30,10,0.1,0,0,0,0,0,100\n", "line 2: 9 fields for 5 columns (quote vectors"),
    ("b.csv", "m1,m2,chi1,chi2,f_ref,name\n30,10,\"0,0,0\",\"0,0,0\",100,x\n30,11,\"0,0,0\",\"0,0,0\",100,x\n",
     "row 1 (line 2) and row 2 (line 3) have the same name 'x'"),
    ("b.csv", "m1,m2,chi1,chi2,f_ref,m1\n", "repeated column m1"),
    ("b.csv", "", "is empty"),
    ("b.csv", "m1,m2,chi1,chi2,f_ref\n", "holds no binaries"),
    ("b.toml", "[[binary]]\nm1 = 30\nm2 = 10\nchi1 = [0, 0, 0]\nchi2 = [0, 0, 0]\nf_ref = 100\nspin = 1\n",
     "[[binary]] 1: unknown column 'spin'"),
    ("b.toml", "[[binaries]]\nm1 = 30\n", "must hold [[binary]] tables only; found 'binaries'"),
    ("b.toml", "[[binary]]\nm1 = \n", "is not valid TOML"),
    ("b.json", "{}", "must be .csv or .toml"),
])
def test_invalid_batch_file_exits_2_before_running(name, text, message, in_tmp, capsys, monkeypatch):
    monkeypatch.setattr(backends, "evolve_row", lambda params: pytest.fail("ran"))
    write_text(in_tmp / name, text)
    code, out, err = evolve(capsys, "--batch", name)
    assert code == 2 and out == "" and err.startswith("pnrotor evolve: error: ") and message in err
    assert err.count("\n") == 1 and os.listdir(in_tmp) == [name]


def test_batch_usage_errors(in_tmp, capsys):
    write_text(in_tmp / "p.csv", CSV)
    for args, message in [
        (["--m1", "30"], "--m1 cannot be combined with --batch; give it as the column m1"),
        (["--f-ref", "30"], "--f-ref cannot be combined with --batch"),
        (["--jobs", "0"], "--jobs must be at least 1, got 0"),
        (["--jobs", "2", "--scheduler", "tcp://x:1"], "--jobs applies to local runs"),
        (["-o", "missing/p.h5"], "folder missing does not exist"),
    ]:
        code, _, err = evolve(capsys, "--batch", "p.csv", *args)
        assert code == 2 and message in err, (args, err)
    code, _, err = evolve(capsys, "--batch", "nothing.csv")
    assert code == 2 and err == "pnrotor evolve: error: nothing.csv: no such file\n"
    (in_tmp / "waveforms").mkdir()
    (in_tmp / "waveforms" / "p.h5").write_bytes(b"old")
    code, _, err = evolve(capsys, "--batch", "p.csv", "--jobs", "1")
    assert code == 2 and "waveforms/p.h5 exists; pass --overwrite" in err
    assert (in_tmp / "waveforms" / "p.h5").read_bytes() == b"old"
    assert evolve(capsys, "--batch", "p.csv", "--jobs", "1", "--overwrite")[0] == 1
    assert len(hdf5.list_runs(in_tmp / "waveforms" / "p.h5")) == 4
    assert sorted(os.listdir(in_tmp / "waveforms")) == ["p.h5"]


@pytest.mark.parametrize("method", ["default", "forkserver"])
def test_parallel_batch_equals_serial_bitwise(method, in_tmp, capsys, monkeypatch):
    if method != "default":
        monkeypatch.setattr(backends, "start_method", lambda: method)
    rows = ["m1,m2,chi1,chi2,f_ref,sampling"]
    rng = np.random.default_rng(6)
    for _ in range(10):
        c1, c2 = rng.uniform(-0.5, 0.5, (2, 3)).tolist()
        sampling = rng.choice(["steps", "final", "1/4096", "per_orbit:3"])
        rows.append(f'{rng.uniform(20, 40)!r},{rng.uniform(5, 20)!r},"{",".join(map(repr, c1))}","{",".join(map(repr, c2))}",'
                    f"{rng.uniform(80, 120)!r},{sampling}")
    rows.append('10,10,"0,0,2","0,0,0",100,')  # fails in a worker
    write_text(in_tmp / "many.csv", "\n".join(rows) + "\n")
    code, out_serial, _ = evolve(capsys, "--batch", "many.csv", "--jobs", "1", "-o", "serial.h5", "--no-checksum")
    assert code == 1 and "on this process" in out_serial
    code, out_pool, _ = evolve(capsys, "--batch", "many.csv", "--jobs", "2", "--compression", "lzf")  # to waveforms/
    assert code == 1 and "on 2 worker processes" in out_pool
    assert "FAILED row 11 (line 12) (T4_m10_m10_chi1-0,0,2_chi2-0,0,0_f100): |chi1| = 2.0 exceeds 1" in out_pool
    pool = in_tmp / "waveforms" / "many.h5"
    names = hdf5.list_runs(in_tmp / "serial.h5")
    assert len(names) == 10 and hdf5.list_runs(pool) == names
    for name in names:
        assert_same_run(hdf5.read(pool, name), hdf5.read(in_tmp / "serial.h5", name))
    with h5py.File(pool) as f, h5py.File(in_tmp / "serial.h5") as g:
        assert f[names[0]]["t"].compression == "lzf" and f[names[0]]["t"].fletcher32  # kept by the parts' copy
        assert g[names[0]]["t"].compression is None and not g[names[0]]["t"].fletcher32
    # the same lines, in row order, whichever worker finished first
    strip = lambda out: [line.split(": ", 1)[0] for line in out.splitlines()[1:-1]]  # noqa: E731
    assert strip(out_pool) == strip(out_serial)
    assert sorted(os.listdir(in_tmp)) == ["many.csv", "serial.h5", "waveforms"]
    assert os.listdir(in_tmp / "waveforms") == ["many.h5"]  # no part files left


def test_progress_bar_on_a_terminal_and_quiet(in_tmp, capsys, monkeypatch):
    write_text(in_tmp / "p.csv", CSV)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    code, _, err = evolve(capsys, "--batch", "p.csv", "--jobs", "1", "-o", "a.h5")
    assert code == 1 and "evolve: 100%" in err and "5/5" in err  # rows that parse, the failing one included
    code, out, err = evolve(capsys, "--batch", "p.csv", "--jobs", "1", "-o", "b.h5", "--quiet")
    assert code == 1 and err == "" and len(out.splitlines()) == 2 and "FAILED row 3" in out


def test_interrupted_batch_keeps_finished_runs_for_resume(in_tmp, capsys, monkeypatch):
    write_text(in_tmp / "p.csv", CSV)
    real = backends.evolve_row
    calls = []

    def interrupt_second(params):
        calls.append(params)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(params)

    monkeypatch.setattr(backends, "evolve_row", interrupt_second)
    code, _, err = evolve(capsys, "--batch", "p.csv", "--jobs", "1")
    assert code == 130 and len(calls) == 2
    assert err == ("pnrotor evolve: interrupted; 1 finished run kept in waveforms/p.h5.parts; complete the "
                   "batch with --resume (resume=True)\n")
    assert os.listdir(in_tmp / "waveforms") == ["p.h5.parts"]   # no batch file yet
    monkeypatch.undo()
    monkeypatch.chdir(in_tmp)
    code, out, _ = evolve(capsys, "--batch", "p.csv", "--jobs", "1", "--resume")
    assert code == 1 and "wrote 4 runs to waveforms/p.h5" in out
    assert os.listdir(in_tmp / "waveforms") == ["p.h5"]


def test_dask_cluster_batch_equals_local(in_tmp, capsys):
    distributed = pytest.importorskip("distributed")
    write_text(in_tmp / "p.csv", CSV)
    assert evolve(capsys, "--batch", "p.csv", "--jobs", "1", "-o", "local.h5")[0] == 1
    with distributed.LocalCluster(n_workers=1, processes=True, threads_per_worker=1, dashboard_address=None) as cluster:
        code, out, _ = evolve(capsys, "--batch", "p.csv", "--scheduler", cluster.scheduler_address, "-o", "dask.h5")
    assert code == 1 and f"on Dask scheduler {cluster.scheduler_address}" in out
    assert "FAILED row 3 (line 4) (negative): m1 must be a finite positive mass, got -5.0" in out
    names = hdf5.list_runs(in_tmp / "local.h5")
    assert hdf5.list_runs(in_tmp / "dask.h5") == names and len(names) == 4
    for name in names:
        assert_same_run(hdf5.read(in_tmp / "dask.h5", name), hdf5.read(in_tmp / "local.h5", name))


def test_scheduler_without_dask_or_unreachable(in_tmp, capsys, monkeypatch):
    write_text(in_tmp / "p.csv", CSV)
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    code, _, err = evolve(capsys, "--batch", "p.csv", "--scheduler", "tcp://127.0.0.1:1")
    assert code == 2 and "pip install 'pnrotor[dask]'" in err
    monkeypatch.undo()
    pytest.importorskip("distributed")
    monkeypatch.chdir(in_tmp)
    monkeypatch.setattr(backends, "SCHEDULER_TIMEOUT", "0.5s")
    code, _, err = evolve(capsys, "--batch", "p.csv", "--scheduler", "tcp://127.0.0.1:1")
    assert code == 2 and "cannot connect to the Dask scheduler at tcp://127.0.0.1:1" in err
    assert os.listdir(in_tmp) == ["p.csv"]


def test_lazy_exports():
    from pnrotor.pn.evolve import Evolution, evolve as pn_evolve

    assert pnrotor.evolve is pn_evolve and pnrotor.Evolution is Evolution
    # the README's example writes with pnrotor.hdf5 after `import pnrotor` alone (it raised AttributeError)
    code = "import pnrotor; print(pnrotor.hdf5.write.__module__, pnrotor.quaternion.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["pnrotor.io.hdf5", "pnrotor.quaternion"]   # pnrotor.hdf5 is pnrotor.io.hdf5


def test_modes_written_beside_the_run(in_tmp, capsys):
    """--modes: the file holds the run and its modes (groups run, modes), each equal to the API's bitwise."""
    code, out, _ = evolve(capsys, *FAST, "--modes", "--ell-max", "3", "--amplitude-order", "2", "--distance", "50",
                          "-o", "w.h5")
    assert code == 0 and "modes          l <= 3, amplitude order 2, strain at 50 Mpc" in out
    assert sorted(hdf5.list_runs(in_tmp / "w.h5")) == ["modes", "run"]
    run = pnrotor.evolve(**FAST_KW)
    assert_same_run(hdf5.read(in_tmp / "w.h5", "run"), run)
    expected = pnrotor.modes(run, ell_max=3, amplitude_order=2, distance=50.0)
    np.testing.assert_array_equal(hdf5.read(in_tmp / "w.h5", "modes").data, expected.data)


@pytest.mark.parametrize("extra, message", [
    (["--modes", "--ell-max", "9"], "ell_max must be an integer from 2 to 8"),
    (["--modes", "--amplitude-order", "1.25"], "amplitude_order must be one of"),
    (["--modes", "--distance", "-3"], "distance must be a finite positive"),
    (["--ell-max", "4"], "--ell-max applies to --modes and --polarizations runs only"),
    (["--amplitude-order", "7"], "--amplitude-order applies to --modes and --polarizations runs only"),
    (["--distance", "-3"], "--distance applies to --modes and --polarizations runs only"),
])
def test_bad_modes_options_exit_2_before_running(extra, message, in_tmp, capsys, monkeypatch):
    monkeypatch.setattr(backends, "evolve_row", lambda params: pytest.fail("ran"))
    code, _, err = evolve(capsys, *FAST, *extra, "-o", "w.h5")
    assert code == 2 and message in err and os.listdir(in_tmp) == []


@pytest.mark.parametrize("extra, message", [
    (["--f-ref", "1e6"], "f_ref = 1000000.0 Hz gives v = 8.522 >= 1"),
    (["--m1", "-3"], "m1 must be"),
    (["--chi1", "0.9,0.9,0"], "chi1"),
    (["--pn-order", "5"], "pn_order must be"),
    (["--sampling", "-1"], "sampling"),
])
def test_bad_inputs_exit_2_before_the_cold_line_and_compiling(extra, message, in_tmp, capsys, monkeypatch):
    """Input errors that evolve's first stage finds are said at once: not after the cold cache's line and the start
    of the compiling processes (a review found --f-ref 1e6 waited ~2.5 s for them on a cold cache)."""
    from pnrotor.cli import evolve as cli_evolve
    monkeypatch.setattr(cli_evolve, "_warn_if_cold", lambda **kw: pytest.fail("said it compiles"))
    monkeypatch.setattr(backends, "evolve_row", lambda params: pytest.fail("ran"))
    code, _, err = evolve(capsys, *FAST, *extra, "-o", "w.h5")
    assert code == 2 and message in err and os.listdir(in_tmp) == []


def test_modes_with_batch_are_stored_beside_each_run(in_tmp, capsys, monkeypatch):
    """--batch --modes: the groups NAME and NAME.modes of each row (on a cold cache their kernels are compiled
    aside too); bad modes options exit 2 before running."""
    from pnrotor.cli import evolve as cli_evolve
    said = []
    monkeypatch.setattr(cli_evolve, "_warn_if_cold", lambda **kw: said.append(kw))
    write_text(in_tmp / "p.csv", "m1,m2,chi1,chi2,f_ref,name\n30,10,\"0.3,0,0.2\",\"0,0,0\",100,x\n")
    code, out, _ = evolve(capsys, "--batch", "p.csv", "--modes", "--ell-max", "3", "--amplitude-order", "1",
                          "-o", "p.h5")
    assert code == 0 and "with their modes" in out and said == [dict(here=True, modes=True)]
    assert sorted(hdf5.list_runs(in_tmp / "p.h5")) == ["x", "x.modes"]
    h = hdf5.read(in_tmp / "p.h5", "x.modes")
    assert h.ell_max == 3 and h.inputs["amplitude_order"] == 1.0
    np.testing.assert_array_equal(h.data, pnrotor.modes(hdf5.read(in_tmp / "p.h5", "x"), 3, 1.0).data)
    code, _, err = evolve(capsys, "--batch", "p.csv", "--modes", "--ell-max", "9", "-o", "q.h5")
    assert code == 2 and "ell_max must be an integer from 2 to 8" in err and not (in_tmp / "q.h5").exists()


def test_full_disk_is_one_line_and_leaves_no_file(in_tmp, capsys, monkeypatch):
    """An OSError while writing (ENOSPC here, as h5py reports a full disk): exit 1, one line, no traceback,
    neither the file nor a temporary one (issue 15: a 35-95-line traceback)."""
    import errno

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", "w.h5")

    monkeypatch.setattr(hdf5, "_put_run", full)
    code, out, err = evolve(capsys, *FAST, "-o", "w.h5")
    assert code == 1 and err.count("\n") == 1 and "No space left on device" in err and "Traceback" not in err
    assert os.listdir(in_tmp) == []


def test_out_of_memory_is_one_line_and_leaves_no_file(in_tmp, capsys, monkeypatch):
    """A MemoryError that the checks before allocating did not foresee (another process took the memory; numpy's
    words here): exit 1, one line, no traceback, no file (a review of 2026-11-28: a traceback)."""
    from pnrotor.waveform import modes

    def short(*args, **kwargs):
        raise MemoryError("Unable to allocate 4.77 GiB for an array with shape (77, 4161322) and data type complex128")

    monkeypatch.setattr(modes, "modes", short)
    code, out, err = evolve(capsys, *FAST, "--modes", "-o", "w.h5")
    assert code == 1 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("pnrotor evolve: error: out of memory: Unable to allocate 4.77 GiB")
    assert os.listdir(in_tmp) == []


def test_modes_defaults_are_those_of_pnrotor_modes():
    """The CLI keeps copies of modes()' defaults (parsing does not import numba): they must be modes()' own, of a run
    and of a binary, and those of the polarizations."""
    import inspect

    from pnrotor.cli import evolve as cli_evolve
    from pnrotor.waveform import modes, stream
    for function in (modes.modes, stream._binary_modes, stream.polarizations, stream.Stream.modes,
                     stream.Stream.polarizations):
        defaults = inspect.signature(function).parameters
        assert (cli_evolve.ELL_MAX, cli_evolve.AMPLITUDE_ORDER) == (defaults["ell_max"].default,
                                                                    defaults["amplitude_order"].default)


def test_one_line_before_compiling_on_a_cold_cache(in_tmp, capsys, monkeypatch):
    """With no compiled DOP853 core in numba's cache (an empty NUMBA_CACHE_DIR), one line on stderr says
    that the kernels are being compiled, once, and the core's compilation starts in another process; with
    the cache filled, nothing; a run writing modes also starts the modes kernels' compilation aside while
    they are missing; while the core compiles aside, this process compiles two of its callees."""
    from pnrotor import numba_cache
    from pnrotor.cli import evolve as cli_evolve
    from pnrotor.pn import many
    from pnrotor.waveform import amplitudes
    dop853 = importlib.import_module("pnrotor.ode.dop853")   # the module (pnrotor.ode.dop853 is also its function)
    started, here = [], []
    monkeypatch.setattr(numba_cache, "compile_aside", started.append)
    monkeypatch.setattr(dop853, "compile_core_parts", lambda: here.append("core parts"))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(in_tmp / "empty-cache"))
    cli_evolve._warn_if_cold()
    assert capsys.readouterr().err == ("pnrotor: compiling its numba kernels for this machine, once (~10-25 s idle, up "
                                       "to ~3x that on a busy machine); later runs load them in a few seconds\n")
    assert started == ["core"] and here == ["core parts"]
    core = Path(numba_cache.cache_folder()) / _index_file(dop853.core)
    assert core.parent.parent == in_tmp / "empty-cache"
    core.parent.mkdir(parents=True)
    core.touch()
    cli_evolve._warn_if_cold()
    assert capsys.readouterr().err == "" and started == ["core"]
    cli_evolve._warn_if_cold(modes=True)
    assert "(~20-35 s idle" in capsys.readouterr().err and started == ["core", "modes"] and here == ["core parts"]
    kernels = Path(numba_cache.cache_folder("waveform")) / _index_file(amplitudes._sum)
    assert kernels.parent.parent == in_tmp / "empty-cache"
    kernels.parent.mkdir(parents=True)
    kernels.touch()
    cli_evolve._warn_if_cold(modes=True)
    assert capsys.readouterr().err == "" and started == ["core", "modes"]
    # a population run compiles evolve_many's loop (which holds the core): said while that is missing, with
    # nothing compiled aside (the core is cached)
    cli_evolve._warn_if_cold(population=True)
    assert capsys.readouterr().err.startswith("pnrotor: compiling its numba kernels") and started == ["core", "modes"]
    loop = Path(numba_cache.cache_folder("pn")) / _index_file(many._integrate_all)
    assert loop.parent.parent == in_tmp / "empty-cache"
    loop.parent.mkdir(parents=True)
    loop.touch()
    cli_evolve._warn_if_cold(here=False, population=True)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("what, kernel, package", [("core", "dop853.core", "ode"),
                                                   ("modes", "amplitudes._sum", "waveform")])
def test_what_is_compiled_aside_is_what_the_cache_then_holds(tmp_path, monkeypatch, what, kernel, package):
    """compile_aside's process fills the cache it is given (here a fresh one: a real compilation, ~10-15 s)
    and exits cleanly, with the index file `_index_file` names; waiting for it twice is harmless."""
    from pnrotor import numba_cache
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert numba_cache.is_cold(kernel, package)
    numba_cache.compile_aside(what)
    process = numba_cache._asides[what]
    numba_cache.wait_for_aside(what)
    numba_cache.wait_for_aside(what)
    assert process.returncode == 0 and what not in numba_cache._asides
    assert not numba_cache.is_cold(kernel, package)
    module, name = kernel.split(".")
    index = _index_file(getattr(importlib.import_module(f"pnrotor.{package}.{module}"), name))
    assert (Path(numba_cache.cache_folder(package)) / index).is_file()


def _index_file(kernel):
    """The name of numba's cache index of the njit function ``kernel``: MODULE.QUALNAME-LINE.pyXY.nbi, LINE that
    of its first line (its decorator's), as numba's _CacheImpl names it."""
    function = kernel.py_func
    return (f"{function.__module__.rpartition('.')[2]}.{function.__qualname__}-{function.__code__.co_firstlineno}"
            f".py{sys.version_info[0]}{sys.version_info[1]}.nbi")


SHARED = """import sys
from pnrotor.pn.evolve import evolve
import pnrotor.ode.dop853
d, e = sys.modules["pnrotor.ode.dop853"], sys.modules["pnrotor.ode.events"]
d.compile_core_parts()
n = len(compiled)
d.compile_core()
evolve(10.0, 10.0, (0, 0, 0), (0, 0, 0), 20.0, f_max=30.0)
evolve(30.0, 10.0, (0.6, 0, 0.2), (0, -0.4, 0.1), 20.0, f_max=30.0, sampling=1 / 256)
print([c for c in compiled[n:] if any(k in c for k in ("locate_root", "_append_segment"))])
print(len(e.locate_root.signatures), len(d._append_segment.signatures))
print(str(d.core) in compiled[n:])
"""


def test_the_core_parts_compiled_here_are_the_ones_the_core_calls(cold_python):
    """What the CLI compiles in this process while another compiles the core (compile_core_parts: two callees the
    core then loads) is compiled for exactly the types the core calls them with: neither is compiled again by the
    core or by evolve (a second signature would be each compiled twice, the time not saved; evolve_many's loop
    compiles its own locate_root for a literal event index).  In one fresh process with an empty cache (~30-40 s)."""
    out = cold_python(SHARED)
    assert out.split("\n")[:3] == ["[]", "1 1", "True"], out


SLOW_RUN = """
import sys, time
from pnrotor.batch import backends
from pnrotor.cli import main
def slow(params):
    print("computing", flush=True)
    time.sleep(120)
backends.evolve_row = slow
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_stop_a_command_like_ctrl_c(signame, in_tmp):
    """Signalled while a run computes: exit 130 with the interrupted line, no file, no traceback."""
    import signal

    process = subprocess.Popen([sys.executable, "-c", SLOW_RUN, "evolve", *FAST, "-o", "w.h5"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=default_signals)
    try:
        assert process.stdout.readline() == "computing\n"
        process.send_signal(getattr(signal, signame))
        _, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130 and err == "pnrotor evolve: interrupted\n", err
    assert os.listdir(in_tmp) == []


def test_the_cache_folder_is_the_one_numba_uses(tmp_path, monkeypatch):
    """numba_cache.cache_folder (found without importing numba, for the cold-start message) against numba's own
    cache locators for the DOP853 core and evolve_many's loop: with NUMBA_CACHE_DIR, in the source tree, and
    user-wide where the package folder is read-only (a system install)."""
    import os

    from numba.core import caching, config

    from pnrotor import numba_cache
    from pnrotor.ode.dop853 import core
    from pnrotor.pn.many import _integrate_all
    kernels = {"ode": core, "pn": _integrate_all}

    def locators(cls):
        return {package: cls(f.py_func, f.py_func.__code__.co_filename).get_cache_path()
                for package, f in kernels.items()}

    def ours():
        return {package: numba_cache.cache_folder(package) for package in kernels}

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert ours() == locators(caching.InTreeCacheLocator)

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path / "numba"))
    assert ours() == locators(caching.UserProvidedCacheLocator)

    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "home-cache"))
    monkeypatch.setattr(os, "access", lambda path, mode: False)      # the package folder read-only
    assert ours() == locators(caching.UserWideCacheLocator)
