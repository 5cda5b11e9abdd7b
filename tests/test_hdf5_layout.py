"""pnrotor.hdf5's layout validation (issue 15, "Corruption detected"): valid files written by pnrotor, then
altered with plain h5py the way the issue's fault table did by hand (a dataset of the wrong shape, a float32
copy, a NaN, a length mismatch, a deleted input, a missing group or attribute), each make `read` raise one
ValueError naming the file and the problem, never a traceback and never a run with wrong numbers; `write`
refuses the same runs; valid files, of every kind and layout, still read back bitwise."""

import dataclasses
import re

import h5py
import numpy as np
import pytest
from test_hdf5 import assert_identical, frame_history

import pnrotor
from pnrotor import hdf5
from pnrotor.io import hdf5_read
from pnrotor.waveform.modes import modes

RUN = dict(m1=30.0, m2=10.0, chi1=(0.6, 0.0, 0.2), chi2=(0.0, -0.4, 0.1), f_ref=100.0)


@pytest.fixture(scope="module")
def evolution():
    return pnrotor.evolve(**RUN)


@pytest.fixture(scope="module")
def waveform(evolution):
    return modes(evolution, ell_max=3)


def replace(g, name, data):
    """Replace dataset `name` of group `g` by `data`, keeping its attributes."""
    attrs = dict(g[name].attrs)
    del g[name]
    g[name] = data
    g[name].attrs.update(attrs)


def set_nan(g, name, index, value=np.nan):
    data = g[name][...]
    data[index] = value
    replace(g, name, data)


# (alteration of the run group, what the error must say): the hand-made files and their kin
EVOLUTION_FAULTS = {
    "R (N, 3)": (lambda g: replace(g, "R", g["R"][:, :3]),
                 r"dataset 'R' has shape \((\d+), 3\), expected \(\1, 4\)"),
    "chi1 flat": (lambda g: replace(g, "chi1", g["chi1"][...].ravel()), r"dataset 'chi1' has shape \(\d+,\), expected"),
    "v float32": (lambda g: replace(g, "v", g["v"][...].astype(np.float32)),
                  "dataset 'v' is float32, expected float64"),
    "t int64": (lambda g: replace(g, "t", g["t"][...].astype(np.int64)), "dataset 't' is int64, expected float64"),
    "NaN in Phi": (lambda g: set_nan(g, "Phi", 7),
                   r"dataset 'Phi' has 1 non-finite value \(NaN or inf\), the first at index 7"),
    "inf in R": (lambda g: set_nan(g, "R", (3, 2), -np.inf), r"dataset 'R' has 1 non-finite value .* index \(3, 2\)"),
    "v shorter": (lambda g: replace(g, "v", g["v"][:-1]),
                  r"dataset 'v' has shape \((\d+),\), expected \(\d+,\) "
                  r"\(N = \d+ samples, as in 't' and 6 other arrays\)$"),
    "all shorter but t_seconds": (lambda g: [replace(g, k, g[k][:5]) for k in ("t", "v", "Phi", "chi1", "chi2", "R",
                                                                               "ell_hat")],
                                  r"dataset 't_seconds' has shape \(\d+,\), expected \(5,\)"),
    "t scalar": (lambda g: replace(g, "t", 1.0), r"dataset 't' has shape \(\), expected \(\d+,\)$"),
    "input deleted": (lambda g: g["inputs"].attrs.__delitem__("M_seconds"), "group 'inputs' lacks 'M_seconds'"),
    "stat deleted": (lambda g: g["stats"].attrs.__delitem__("nfev"), "group 'stats' lacks 'nfev'"),
    "inputs group missing": (lambda g: g.__delitem__("inputs"), "group 'inputs' is missing"),
    "stats group missing": (lambda g: g.__delitem__("stats"), "group 'stats' is missing"),
    "ell_hat missing": (lambda g: g.__delitem__("ell_hat"), "dataset 'ell_hat' is missing"),
    "termination missing": (lambda g: g.attrs.__delitem__("termination"), "attribute 'termination' is missing"),
    "termination a number": (lambda g: g.attrs.__setitem__("termination", 3),
                             "attribute 'termination' is int 3, expected a string"),
    "inputs an attribute": (lambda g: g.__delitem__("inputs") or g.attrs.__setitem__("inputs", "m1=30"),
                            "attribute 'inputs' is str 'm1=30', expected a group"),
    "R as a list": (lambda g: g["R"].attrs.__setitem__("sequence", "list"), "dataset 'R' is list .*numeric array"),
    "extra dataset": (lambda g: g.__setitem__("h22", np.zeros(3)), "dataset 'h22' is not a field of Evolution"),
    "created missing": (lambda g: g.attrs.__delitem__("created"), "attribute 'created' is missing"),
    "version a number": (lambda g: g.attrs.__setitem__("pnrotor_version", 1),
                         "attribute 'pnrotor_version' is not a string"),
}


def altered(path, alter, group=None):
    with h5py.File(path, "r+") as f:
        alter(f if group is None else f[group])


@pytest.mark.parametrize("fault", EVOLUTION_FAULTS)
@pytest.mark.parametrize("checksum", [True, False])
def test_altered_evolution_files_are_one_value_error(tmp_path, evolution, fault, checksum):
    alter, message = EVOLUTION_FAULTS[fault]
    path = hdf5.write(tmp_path / "run.h5", evolution, checksum=checksum)
    altered(path, alter)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}: (?:.*; )?{message}") as error:
        hdf5.read(path)
    assert error.value.__cause__ is None or isinstance(error.value.__cause__, ValueError)


def test_every_problem_is_named_in_the_one_error(tmp_path, evolution):
    path = hdf5.write(tmp_path / "run.h5", evolution)
    n = len(evolution)
    altered(path, lambda g: [replace(g, "R", g["R"][:, :3]), replace(g, "v", g["v"][...].astype(np.float32)),
                             set_nan(g, "Phi", 0), g["inputs"].attrs.__delitem__("v_ref")])
    with pytest.raises(ValueError) as error:
        hdf5.read(path)
    assert str(error.value) == (
        f"{path}: dataset 'v' is float32, expected float64; dataset 'Phi' has 1 non-finite value (NaN or inf), "
        f"the first at index 0; dataset 'R' has shape ({n}, 3), expected ({n}, 4); group 'inputs' lacks 'v_ref'")


def test_altered_runs_of_batch_files_name_file_and_run(tmp_path, evolution, waveform):
    path = tmp_path / "batch.h5"
    with hdf5.batch(path) as runs:
        runs.add("run", evolution)
        runs.add("modes", waveform)
    altered(path, lambda g: replace(g, "data", g["data"][:-1]), "modes")
    altered(path, lambda g: g["inputs"].attrs.__delitem__("m1_Msun"), "run")
    rows = (3 + 1) ** 2 - 4
    with pytest.raises(ValueError, match=re.escape(f"{path} run 'modes': dataset 'data' has shape ({rows - 1}, ")
                       + r"\d+\), expected \(" + f"{rows}, "):
        hdf5.read(path, "modes")
    with pytest.raises(ValueError, match=re.escape(f"{path} run 'run': group 'inputs' lacks 'm1_Msun'")):
        hdf5.read(path, "run")
    with h5py.File(path, "r+") as f:
        del f["run"].attrs["created"]
    with pytest.raises(ValueError, match=re.escape(f"{path} run 'run': attribute 'created' is missing")):
        hdf5.metadata(path, "run")


@pytest.mark.parametrize("fault, message", [
    (lambda g: replace(g, "data", g["data"][...].astype(np.complex64)),
     "dataset 'data' is complex64, expected complex128"),
    (lambda g: replace(g, "data", g["data"][...].real), "dataset 'data' is float64, expected complex128"),
    (lambda g: g.attrs.__setitem__("ell_max", 4), r"dataset 'data' has shape \(12, \d+\), expected \(21, \d+\)"),
    (lambda g: g.attrs.__setitem__("ell_max", 2.5), "attribute 'ell_max' is float 2.5, expected an integer"),
    (lambda g: set_nan(g, "data", (0, 1)), r"dataset 'data' has 1 non-finite value \(NaN or inf\), .* \(0, 1\)"),
    (lambda g: g.attrs.__setitem__("distance_Mpc", "far"), "attribute 'distance_Mpc' is str 'far', expected a number"),
])
def test_altered_modes_files(tmp_path, waveform, fault, message):
    path = hdf5.write(tmp_path / "modes.h5", waveform)
    altered(path, fault)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}: {message}"):
        hdf5.read(path)


@pytest.mark.parametrize("fault, message", [
    (lambda g: replace(g, "R", g["R"][...].T),
     r"dataset 'R' has shape \(4, 101\), expected \(101, 4\) \(N = 101 samples, as in 't'\)"),
    (lambda g: replace(g, "R", g["R"][:, :3]), r"dataset 'R' has shape \(101, 3\), expected \(101, 4\)"),
    (lambda g: set_nan(g, "t", 100), r"dataset 't' has 1 non-finite value \(NaN or inf\), the first at index 100"),
    (lambda g: g.attrs.__delitem__("nfev"), "attribute 'nfev' is missing"),
    (lambda g: g.attrs.__setitem__("nfev", True), "attribute 'nfev' is bool True, expected an integer"),
    (lambda g: g.attrs.__setitem__("atol", "1e-12"), "attribute 'atol' is str '1e-12', expected a number"),
    (lambda g: g.__delitem__("inputs"), "group 'inputs' is missing"),
])
def test_altered_frame_history_files(tmp_path, fault, message):
    path = hdf5.write(tmp_path / "run.h5", frame_history())
    altered(path, fault)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}: {message}$"):
        hdf5.read(path)


@pytest.mark.parametrize("compression", [None, "gzip", "lzf"])
@pytest.mark.parametrize("checksum", [True, False])
def test_valid_files_of_every_kind_still_read_bitwise(tmp_path, evolution, waveform, compression, checksum):
    empty = frame_history(n=0)
    for name, run in {"evolution": evolution, "modes": waveform, "history": frame_history(), "empty": empty}.items():
        path = hdf5.write(tmp_path / f"{name}.h5", run, compression=compression, checksum=checksum)
        assert_identical(hdf5.read(path), run, name)
        assert hdf5.layout_problems(type(run), hdf5_read.get_fields(h5py.File(path, "r"), skip=hdf5_read.NOT_FIELDS)) == []
    final = pnrotor.evolve(**RUN, sampling="final")  # one sample
    assert_identical(hdf5.read(hdf5.write(tmp_path / "final.h5", final)), final)


def test_big_endian_float64_and_the_former_layout_read(tmp_path, evolution):
    """float64 of either byte order is float64; files of the former layout (every dataset chunked with
    Fletcher-32) pass the checks as they did before."""
    path = hdf5.write(tmp_path / "run.h5", evolution, checksum=False)
    altered(path, lambda g: replace(g, "v", g["v"][...].astype(">f8")))
    back = hdf5.read(path)
    assert back.v.dtype == np.dtype(">f8") and np.array_equal(back.v, evolution.v)
    with h5py.File(tmp_path / "run.h5", "r") as new, h5py.File(tmp_path / "old.h5", "w") as old:
        for name, value in new.attrs.items():
            old.attrs[name] = value
        for name, item in new.items():
            if isinstance(item, h5py.Group):
                new.copy(name, old)
            else:
                d = old.create_dataset(name, data=item[...], chunks=(10,) + item.shape[1:], fletcher32=True)
                d.attrs.update(item.attrs)
    assert np.array_equal(hdf5.read(tmp_path / "old.h5").R, evolution.R)


@pytest.mark.parametrize("change, message", [
    (dict(v="nan"), r"dataset 'v' has 1 non-finite value \(NaN or inf\), the first at index 2"),
    (dict(R=lambda R: R[:, :3]), r"dataset 'R' has shape \((\d+), 3\), expected \(\1, 4\)"),
    (dict(t=lambda t: t.astype(np.float32)), "dataset 't' is float32, expected float64"),
    (dict(inputs=lambda inputs: {}), "group 'inputs' lacks 'm1_Msun', 'm2_Msun'"),
    (dict(termination=lambda term: None), "attribute 'termination' is empty, expected a string"),
])
def test_write_refuses_what_read_would_refuse(tmp_path, evolution, change, message):
    (name, how), = change.items()
    value = getattr(evolution, name)
    if how == "nan":
        value = value.copy()
        value[2] = np.nan
    else:
        value = how(value)
    bad = dataclasses.replace(evolution, **{name: value})
    with pytest.raises(ValueError, match=f"^cannot write this Evolution: {message}"):
        hdf5.write(tmp_path / "run.h5", bad)
    with pytest.raises(ValueError, match=f"^cannot write this Evolution: {message}"):
        with hdf5.batch(tmp_path / "batch.h5") as runs:
            runs.add("a", bad)
    assert list(tmp_path.iterdir()) == []


def test_required_keys_are_those_real_runs_have(evolution, waveform):
    """`REQUIRED_KEYS` must stay a subset of what pnrotor.evolve and pnrotor.modes produce."""
    for run in (evolution, waveform):
        for group, keys in hdf5.REQUIRED_KEYS[type(run).__name__].items():
            assert set(keys) <= set(getattr(run, group)), (type(run).__name__, group)
    for kind, arrays in hdf5.ARRAYS.items():
        cls = pnrotor.Population if kind == "Population" else hdf5_read.class_of(kind, "")   # not a kind of file
        top = {name for name in arrays if "/" not in name}   # GROUP/NAME: an array of a dict field
        assert top == {f.name for f in dataclasses.fields(cls) if f.type is np.ndarray}, kind
        assert {name.partition("/")[0] for name in arrays} - top <= {f.name for f in dataclasses.fields(cls)}, kind


@pytest.mark.parametrize("where, name, value", [
    ("", "termination", "vdot_peak"),                 # a valid value, but not the one written
    ("inputs", "spin_content", "nonspinning"),
    ("stats", "termination_message", "dv/dt <= 0: the PN energy balance gives no inspiral"),
])
def test_changed_strings_are_caught_by_their_crc(tmp_path, evolution, where, name, value):
    """HDF5 does not checksum variable-length strings; the run's CRC-32 of them does (a file without that
    attribute, as written before it existed, still reads)."""
    path = hdf5.write(tmp_path / "run.h5", evolution)
    with h5py.File(path, "r+") as f:
        assert f[where or "/"].attrs[name] != value
        f[where or "/"].attrs[name] = value
    with pytest.raises(ValueError, match=r"run\.h5: its string attributes are damaged"):
        hdf5.read(path)
    with h5py.File(path, "r+") as f:
        del f.attrs["pnrotor_strings_crc32"]
    run = hdf5.read(path)
    assert (getattr(run, where) if where else vars(run))[name] == value
