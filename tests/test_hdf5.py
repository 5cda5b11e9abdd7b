"""pnrotor.hdf5: bitwise round trips, the stored schema read with plain h5py, atomic writes under
interruption and kill, refusal to overwrite, the batch writer (atomic, a cost per run that does not grow
with the file), and clear errors for missing, truncated and foreign files."""

import dataclasses
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
from datetime import datetime, timedelta, timezone
from pathlib import Path

import h5py
import numpy as np
import pytest
from helpers import default_signals
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pnrotor import __version__, hdf5
from pnrotor.io import atomic
from pnrotor.history import FrameHistory

DOCS = Path(__file__).resolve().parents[1] / "docs" / "hdf5-schema.md"
TEMPORARY = re.compile(r".+\.[^.]+\.[0-9]+\.[0-9a-f]{8}\.pnrotor-tmp$")


def frame_history(n=101, **changes):
    t = np.linspace(0.0, 1.0e6, n)
    angle = 2 * np.pi * t / 1000
    R = np.stack([np.cos(angle / 2), 0.1 * np.ones(n), 0.2 * np.sin(angle), np.sin(angle / 2)], axis=1)
    R /= np.linalg.norm(R, axis=1)[:, None]
    values = dict(
        t=t, R=R, formulation="rotor", method="dop853", atol=1e-12, rtol=1e-10, nfev=1234, nsteps=100,
        naccepted=97, nrejected=3, n_resets=0, status=0, message="success: reached t_end", wall_time=0.25,
        inputs={"omega": "PrecessingNutatingBinary", "t_end": 1.0e6, "R0": np.array([1.0, 0, 0, 0]), "reset": True},
    )
    return FrameHistory(**(values | changes))


@dataclasses.dataclass
class EvolutionLike:
    """Shaped like the PN engineer's coming `pnrotor.pn.evolve.Evolution`."""

    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: str
    stats: dict
    inputs: dict
    dense: object = None


def evolution_like(n=257):
    t = np.linspace(-5.0e4, 0.0, n)
    v = 0.2 + 0.2 * (t - t[0]) / (t[-1] - t[0])
    chi1 = np.stack([0.3 * np.cos(t / 900), 0.3 * np.sin(t / 900), 0.4 + 0 * t], axis=1)
    ell = np.stack([0.2 * np.cos(t / 900), 0.2 * np.sin(t / 900), np.ones(n)], axis=1)
    ell /= np.linalg.norm(ell, axis=1)[:, None]
    R = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    return EvolutionLike(
        t=t, t_seconds=t * 4.925490947641267e-06 * 20, v=v, Phi=np.cumsum(v**3) * (t[1] - t[0]),
        chi1=chi1, chi2=-0.5 * chi1, R=R, ell_hat=ell, termination="f_max reached",
        stats={"nfev": 5000, "nsteps": 400, "naccepted": 390, "nrejected": 10, "wall_time": 0.03},
        inputs={
            "m1": 12.0, "m2": 8.0, "chi1": (0.3, 0.0, 0.4), "chi2": [-0.15, 0.0, -0.2], "f_ref": 20.0,
            "f_min": 10.0, "f_max": None, "approximant": "SpinTaylorT4", "pn_order": 7, "atol": 1e-12,
            "spin_orders": {"spin_orbit": 7, "spin_spin": 4, "quadrupole": np.array([1.0, 1.0])},
        },
        dense=lambda t: t,
    )


@pytest.fixture
def evolution_kind(monkeypatch):
    monkeypatch.setitem(hdf5.KINDS, "EvolutionLike", f"{EvolutionLike.__module__}:EvolutionLike")


def assert_identical(a, b, where="run"):
    """a and b hold the same values bitwise, of the same types (dataclass fields other than dense)."""
    assert type(a) is type(b), where
    if dataclasses.is_dataclass(a):
        for field in dataclasses.fields(a):
            if field.name != "dense":
                assert_identical(getattr(a, field.name), getattr(b, field.name), f"{where}.{field.name}")
    elif isinstance(a, np.ndarray) and a.dtype == object:   # strings: the objects, not their addresses
        assert (a.dtype, a.shape) == (b.dtype, b.shape), where
        assert [(type(x), x) for x in a.flat] == [(type(y), y) for y in b.flat], where
    elif isinstance(a, np.ndarray):
        assert (a.dtype, a.shape) == (b.dtype, b.shape), where
        assert a.tobytes() == b.tobytes(), where
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            assert_identical(a[key], b[key], f"{where}[{key!r}]")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_identical(x, y, f"{where}[{i}]")
    elif isinstance(a, float):
        assert np.float64(a).tobytes() == np.float64(b).tobytes(), where
    else:
        assert a == b, where


def no_temporaries(folder):
    return not [name for name in os.listdir(folder) if name.endswith(".pnrotor-tmp")]


# --------------------------------------------------------------------------------------------------
# round trips
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("checksum", [False, True])
@pytest.mark.parametrize("compression", [None, "gzip", "lzf"])
def test_frame_history_round_trip_is_bitwise(tmp_path, compression, checksum):
    history = frame_history(n=300_001)  # several chunks
    path = hdf5.write(tmp_path / "run.h5", history, compression=compression, checksum=checksum)
    assert path == tmp_path / "run.h5"
    back = hdf5.read(path)
    assert isinstance(back, FrameHistory)
    assert_identical(history, back)
    assert back.dense is None


def test_evolution_shaped_round_trip_is_bitwise(tmp_path, evolution_kind):
    run = evolution_like()
    hdf5.write(tmp_path / "pn.h5", run, compression="gzip")
    back = hdf5.read(tmp_path / "pn.h5")
    assert isinstance(back, EvolutionLike)
    assert_identical(run, back)
    assert type(back.inputs["chi1"]) is tuple and type(back.inputs["chi2"]) is list
    assert back.inputs["f_max"] is None and back.dense is None


def test_edge_values_round_trip(tmp_path):
    history = frame_history(
        n=0, atol=-0.0, rtol=math.nan, wall_time=math.inf, nfev=2**63 - 1, nsteps=-(2**63), message="χ₁ ℓ̂ ✓",
        inputs={"empty": {}, "blank": "", "big_endian": np.arange(3, dtype=">f8"), "ints": np.arange(4),
                "scalar": np.array(2.5), "flags": np.array([True, False]), "n": np.int32(7), "x": np.float32(0.1)},
    )
    hdf5.write(tmp_path / "edge.h5", history)
    back = hdf5.read(tmp_path / "edge.h5")
    assert back.t.shape == (0,) and back.R.shape == (0, 4)
    assert back.inputs["n"] == 7 and type(back.inputs["n"]) is int
    assert back.inputs["x"] == float(np.float32(0.1)) and type(back.inputs["x"]) is float
    history.inputs["n"], history.inputs["x"] = 7, float(np.float32(0.1))  # numpy scalars come back as Python numbers
    assert_identical(history, back)


names = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="/\x00"), min_size=1, max_size=6)
names = names.filter(lambda name: name != ".")
texts = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=20)
scalars = st.one_of(st.none(), st.booleans(), st.integers(-(2**63), 2**64 - 1), st.floats(), texts)
numeric_arrays = st.sampled_from([np.float64, np.dtype(">f8"), np.int64, np.bool_]).flatmap(lambda dtype: arrays(dtype, st.integers(0, 5)))
sequences = st.lists(st.floats(), max_size=4).map(tuple) | st.lists(st.integers(-(2**31), 2**31), max_size=4)
inputs = st.recursive(scalars | numeric_arrays | sequences, lambda children: st.dictionaries(names, children, max_size=4), max_leaves=12)


finite = st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def histories(draw):
    n = draw(st.integers(0, 40))
    R = draw(arrays(np.float64, (n, 4), elements=st.floats(-1e150, 1e150)))
    R[:, 0] = draw(arrays(np.float64, n, elements=st.floats(1e-150, 1e150) | st.floats(-1e150, -1e-150)))
    return FrameHistory(  # t finite and R rotors (what read and write check), the scalars any float
        t=draw(arrays(np.float64, n, elements=finite)), R=R,
        formulation=draw(texts),
        method=draw(st.sampled_from(["dop853", "bulirsch_stoer"])), atol=draw(st.floats()), rtol=draw(st.floats()),
        nfev=draw(st.integers(0, 2**62)), nsteps=draw(st.integers(0, 10**9)), naccepted=draw(st.integers(0, 10**9)),
        nrejected=draw(st.integers(0, 10**9)), n_resets=draw(st.integers(0, 10**9)), status=draw(st.integers(-5, 5)),
        message=draw(texts),
        wall_time=draw(st.floats(0, 1e6)), inputs=draw(st.dictionaries(names, inputs, max_size=5)),
    )


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(histories(), st.sampled_from([None, "gzip", "lzf"]), st.booleans())
def test_generated_histories_round_trip_bitwise(history, compression, checksum):
    with tempfile.TemporaryDirectory() as folder:
        path = hdf5.write(Path(folder) / "h.h5", history, compression=compression, checksum=checksum)
        assert_identical(history, hdf5.read(path))


# --------------------------------------------------------------------------------------------------
# what the file holds, read with plain h5py
# --------------------------------------------------------------------------------------------------


def text(attributes):
    """h5py's attributes with the strings decoded: pnrotor writes them as fixed-length UTF-8 (schema 2), which h5py
    reads as bytes."""
    return {name: value.decode() if isinstance(value, bytes) else value for name, value in attributes.items()}


def test_attributes_and_datasets_are_complete(tmp_path):
    history = frame_history()
    before = datetime.now(timezone.utc).replace(microsecond=0)
    hdf5.write(tmp_path / "run.h5", history, compression="gzip")
    with h5py.File(tmp_path / "run.h5", "r") as f:
        scalars = {f.name for f in dataclasses.fields(FrameHistory)} - {"t", "R", "inputs", "dense"}
        assert set(f.attrs) == scalars | {"kind", "pnrotor_schema", "pnrotor_version", "created", "pnrotor_strings_crc32"}
        assert text(f.attrs)["kind"] == "FrameHistory" and text(f.attrs)["pnrotor_version"] == __version__
        assert text(f.attrs)["pnrotor_schema"] == hdf5.SCHEMA_VERSION and isinstance(text(f.attrs)["pnrotor_schema"], np.integer)
        created = datetime.fromisoformat(text(f.attrs)["created"])
        assert created.utcoffset() == timedelta(0) and before <= created <= datetime.now(timezone.utc)
        for name in scalars:
            assert text(f.attrs)[name] == getattr(history, name)
        assert set(f) == {"t", "R", "inputs"}
        assert text(f["inputs"].attrs)["omega"] == "PrecessingNutatingBinary" and text(f["inputs"].attrs)["t_end"] == 1.0e6
        assert np.array_equal(f["inputs/R0"][()], [1.0, 0, 0, 0])
        for name, shape in [("t", (101,)), ("R", (101, 4))]:
            assert f[name].shape == shape and f[name].dtype == np.float64
            assert f[name].chunks is not None and f[name].fletcher32  # checksums by default
            assert (f[name].compression, f[name].compression_opts, f[name].shuffle) == ("gzip", 1, True)
            assert text(f[name].attrs)["units"] == hdf5.UNITS["FrameHistory"][name]
        assert "scalar-first" in text(f["R"].attrs)["units"]


def test_evolution_datasets_carry_units(tmp_path, evolution_kind):
    hdf5.write(tmp_path / "pn.h5", evolution_like())
    with h5py.File(tmp_path / "pn.h5", "r") as f:
        assert text(f.attrs)["kind"] == "EvolutionLike"
        assert text(f["stats"].attrs)["nfev"] == 5000 and text(f["inputs"].attrs)["approximant"] == "SpinTaylorT4"
    hdf5.UNITS["EvolutionLike"] = hdf5.UNITS["Evolution"]
    try:
        hdf5.write(tmp_path / "pn.h5", evolution_like(), overwrite=True)
    finally:
        del hdf5.UNITS["EvolutionLike"]
    with h5py.File(tmp_path / "pn.h5", "r") as f:
        assert text(f["t"].attrs)["units"].startswith("M") and text(f["t_seconds"].attrs)["units"] == "s"
        assert set(hdf5.UNITS["Evolution"]) <= set(f)


@pytest.mark.parametrize("compression, checksum", [("lzf", False), (None, True), ("gzip", True)])
def test_large_arrays_are_chunked_without_padding(tmp_path, compression, checksum):
    hdf5.write(tmp_path / "run.h5", frame_history(n=1_000_001), compression=compression, checksum=checksum)
    with h5py.File(tmp_path / "run.h5", "r") as f:
        for name in ("t", "R"):
            assert f[name].fletcher32 == checksum and f[name].compression == compression
            rows, chunk = f[name].shape[0], f[name].chunks[0]
            nchunks = -(-rows // chunk)
            assert chunk * f[name].dtype.itemsize * np.prod(f[name].shape[1:]) <= 1 << 20
            assert nchunks * chunk - rows < nchunks  # the last chunk is (almost) full


def test_documented_plain_h5py_reader_works(tmp_path, monkeypatch):
    text = DOCS.read_text()
    snippet = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    assert len(snippet.strip().splitlines()) <= 8
    history = frame_history()
    (tmp_path / "waveforms").mkdir()
    hdf5.write(tmp_path / "waveforms" / "run.h5", history)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(snippet, namespace)
    assert np.array_equal(namespace["t"], history.t) and np.array_equal(namespace["R"], history.R)
    assert namespace["attrs"]["formulation"] == "rotor" and namespace["inputs"]["t_end"] == 1.0e6


# --------------------------------------------------------------------------------------------------
# atomic writes
# --------------------------------------------------------------------------------------------------


def fail_on_dataset(monkeypatch, name, error=KeyboardInterrupt):
    create = h5py.Group.create_dataset

    def create_then_fail(self, dataset, *args, **kwargs):
        if dataset == name:
            raise error("interrupted while writing")
        return create(self, dataset, *args, **kwargs)

    monkeypatch.setattr(h5py.Group, "create_dataset", create_then_fail)


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
def test_interrupted_write_leaves_no_file(tmp_path, monkeypatch, error):
    fail_on_dataset(monkeypatch, "R", error)
    with pytest.raises(error):
        hdf5.write(tmp_path / "run.h5", frame_history())
    assert os.listdir(tmp_path) == []


def test_interrupted_overwrite_keeps_the_old_file(tmp_path, monkeypatch):
    old = frame_history(message="old")
    hdf5.write(tmp_path / "run.h5", old)
    hdf5.write(tmp_path / "batch.h5", old, group="a")
    fail_on_dataset(monkeypatch, "R")
    with pytest.raises(KeyboardInterrupt):
        hdf5.write(tmp_path / "run.h5", frame_history(message="new"), overwrite=True)
    with pytest.raises(KeyboardInterrupt):
        hdf5.write(tmp_path / "batch.h5", frame_history(message="new"), group="a", overwrite=True)
    with pytest.raises(KeyboardInterrupt):
        hdf5.write(tmp_path / "batch.h5", frame_history(message="new"), group="b")
    assert sorted(os.listdir(tmp_path)) == ["batch.h5", "run.h5"]
    assert_identical(hdf5.read(tmp_path / "run.h5"), old)
    assert hdf5.list_runs(tmp_path / "batch.h5") == ["a"]
    assert_identical(hdf5.read(tmp_path / "batch.h5", group="a"), old)


KILLED_WRITER = """
import sys, time
import h5py, numpy as np
from pnrotor import hdf5
from pnrotor.history import FrameHistory

create = h5py.Group.create_dataset
def create_then_pause(self, name, *args, **kwargs):
    dataset = create(self, name, *args, **kwargs)
    if name == "R":  # t and R (40 MB) are written; the scalars and inputs are not
        print("writing", flush=True)
        time.sleep(120)
    return dataset
h5py.Group.create_dataset = create_then_pause

n = 10**6
history = FrameHistory(t=np.arange(n, dtype=float), R=np.ones((n, 4)), formulation="rotor", method="dop853",
    atol=1e-12, rtol=1e-12, nfev=1, nsteps=1, naccepted=1, nrejected=0, n_resets=0, status=0, message="new",
    wall_time=1.0)
hdf5.write(sys.argv[1], history, overwrite=True)
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGKILL])
@pytest.mark.parametrize("existing", [False, True])
def test_killed_writer_leaves_target_absent_or_old(tmp_path, signum, existing):
    target = tmp_path / "big.h5"
    old = frame_history(message="old")
    if existing:
        hdf5.write(target, old)
    writer = subprocess.Popen([sys.executable, "-c", KILLED_WRITER, str(target)], stdout=subprocess.PIPE, text=True,
                              preexec_fn=default_signals)
    try:
        assert writer.stdout.readline() == "writing\n"
        temporaries = [name for name in os.listdir(tmp_path) if name != "big.h5"]
        assert len(temporaries) == 1 and TEMPORARY.match(temporaries[0]) and temporaries[0].startswith("big.h5.")
        writer.send_signal(signum)
        assert writer.wait(timeout=60) != 0
    finally:
        writer.kill()
        writer.stdout.close()
    if existing:
        assert_identical(hdf5.read(target), old)
    else:
        assert not target.exists()
    left = [name for name in os.listdir(tmp_path) if name != "big.h5"]
    if signum != signal.SIGKILL:
        assert left == []  # SIGINT, SIGTERM, SIGHUP raise KeyboardInterrupt during the write: cleaned up
    else:
        assert len(left) == 1 and TEMPORARY.match(left[0])  # SIGKILL can leave NAME.XXXXXXXX.pnrotor-tmp


def test_writeback_thread_leaves_every_signal_to_the_main_thread(tmp_path, monkeypatch):
    """The background fdatasync thread blocks all signals, so SIGINT/SIGTERM/SIGHUP reach the main thread
    (which raises KeyboardInterrupt at once) instead of waiting until the main thread next runs Python."""
    masks = []
    monkeypatch.setattr(atomic, "fsync", lambda path, sync=os.fsync: masks.append(
        signal.pthread_sigmask(signal.SIG_BLOCK, [])))
    writeback = atomic.Writeback(tmp_path / "any.h5")
    writeback.start()
    writeback.join()
    assert {signal.SIGINT, signal.SIGTERM, signal.SIGHUP} <= masks[0]
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])   # the main thread's own mask


def test_two_writers_of_a_new_path_never_both_succeed(tmp_path):
    """300 pairs of finished temporary files published to the same new path at the same instant (a
    barrier): exactly one of each pair succeeds, the other gets FileExistsError (issue 15: with a check
    and a rename both could report success, 59 of 300 times)."""
    import threading

    for i in range(300):
        target = tmp_path / f"run{i}.h5"
        temporaries = [atomic.temporary_beside(target) for _ in range(2)]
        for n, temporary in enumerate(temporaries):
            temporary.write_bytes(b"writer %d" % n)
        barrier, results = threading.Barrier(2), []

        def publish(temporary):
            barrier.wait()
            try:
                atomic.publish(temporary, target, overwrite=False)
                results.append(temporary.name)
            except FileExistsError:
                temporary.unlink()

        threads = [threading.Thread(target=publish, args=(t,)) for t in temporaries]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        assert len(results) == 1
        winner = temporaries.index(tmp_path / results[0])
        assert target.read_bytes() == b"writer %d" % winner
    assert sorted(os.listdir(tmp_path)) == sorted(f"run{i}.h5" for i in range(300))


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # the swallowed interrupt
def test_interrupt_swallowed_inside_a_cleanup_callback_still_stops_the_write(tmp_path, monkeypatch, default_sigint):
    """A Ctrl-C whose KeyboardInterrupt Python drops because it is raised inside a __del__ (as happens in
    h5py's cleanup callbacks: "Exception ignored ... KeyboardInterrupt") is raised again before the file is
    published: no file, no temporary file (issue 15: the run exited 0, 23 of 26 times)."""
    class Swallower:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)

    create = h5py.Group.create_dataset

    def create_and_swallow(self, name, *args, **kwargs):
        dataset = create(self, name, *args, **kwargs)
        if name == "R":
            Swallower()
        return dataset

    monkeypatch.setattr(h5py.Group, "create_dataset", create_and_swallow)
    with pytest.raises(KeyboardInterrupt):
        hdf5.write(tmp_path / "run.h5", frame_history())
    assert os.listdir(tmp_path) == []


def test_a_later_write_sweeps_the_temporaries_of_dead_writers(tmp_path):
    """NAME.HOST.PID.XXXXXXXX.pnrotor-tmp: the next write of NAME on this host removes those whose PID is no
    longer alive, and keeps live writers', other hosts', other targets' and other files (issue 15: stale
    temporaries of up to 566 MB were never removed)."""
    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                              text=True, check=True)
    dead = int(finished.stdout)
    host = atomic.HOST
    names = {"dead": f"run.h5.{host}.{dead}.0123abcd.pnrotor-tmp",
             "alive": f"run.h5.{host}.{os.getpid()}.89abcdef.pnrotor-tmp",
             "other host": f"run.h5.elsewhere.{dead}.0123abcd.pnrotor-tmp",
             "other target": f"other.h5.{host}.{dead}.0123abcd.pnrotor-tmp",
             "unrelated": "run.h5.notes.txt"}
    for name in names.values():
        (tmp_path / name).write_bytes(b"x")
    hdf5.write(tmp_path / "run.h5", frame_history())
    left = set(os.listdir(tmp_path))
    assert names["dead"] not in left
    assert {names[k] for k in ("alive", "other host", "other target", "unrelated")} <= left and "run.h5" in left
    assert all(TEMPORARY.match(names[k]) for k in ("dead", "alive", "other target"))


@pytest.mark.parametrize("checksum", [False, True])
def test_flipped_bytes_are_a_value_error_or_a_read_never_a_traceback(tmp_path, checksum):
    """200 single-bit flips at random places of a file: every read either succeeds or raises ValueError
    naming the file (issue 15: KeyError, TypeError, RuntimeError escaped).  With checksums nearly every
    flip is caught (measured 186-192 of 200; files use HDF5's 1.10 format, whose object headers carry
    checksums); without them flips in the data read back silently (why checksums exist)."""
    import random

    run = frame_history(n=2000)
    base = tmp_path / "base.h5"
    hdf5.write(base, run, checksum=checksum)
    data, rng, caught = base.read_bytes(), random.Random(15), 0
    for trial in range(200):
        flipped = bytearray(data)
        position = rng.randrange(len(flipped))
        flipped[position] ^= 1 << rng.randrange(8)
        damaged = tmp_path / f"damaged{trial}.h5"
        damaged.write_bytes(bytes(flipped))
        try:
            hdf5.read(damaged)
        except ValueError as error:
            assert str(damaged) in str(error)
            caught += 1
        damaged.unlink()
    if checksum:   # data by Fletcher-32, metadata and attributes by the object headers' own checksums
        assert caught >= 180


def test_new_file_permissions_follow_the_umask(tmp_path):
    previous = os.umask(0o027)
    try:
        hdf5.write(tmp_path / "run.h5", frame_history())
    finally:
        os.umask(previous)
    assert (tmp_path / "run.h5").stat().st_mode & 0o777 == 0o640


# --------------------------------------------------------------------------------------------------
# overwriting and batch files
# --------------------------------------------------------------------------------------------------


def test_refuses_to_overwrite_without_permission(tmp_path):
    hdf5.write(tmp_path / "run.h5", frame_history(message="first"))
    with pytest.raises(FileExistsError, match=r"run\.h5 exists.*overwrite=True \(--overwrite\)"):
        hdf5.write(tmp_path / "run.h5", frame_history(message="second"))
    assert hdf5.read(tmp_path / "run.h5").message == "first"
    hdf5.write(tmp_path / "run.h5", frame_history(message="second"), overwrite=True)
    assert hdf5.read(tmp_path / "run.h5").message == "second"
    assert os.listdir(tmp_path) == ["run.h5"]


def test_batch_file_runs(tmp_path, evolution_kind):
    path = tmp_path / "batch.h5"
    hdf5.write(path, frame_history(message="b"), group="b")
    hdf5.write(path, evolution_like(), group="a", compression="lzf")
    assert hdf5.list_runs(path) == ["a", "b"]
    assert hdf5.read(path, group="b").message == "b"
    assert_identical(hdf5.read(path, group="a"), evolution_like())
    assert hdf5.metadata(path, group="a")["kind"] == "EvolutionLike"
    with pytest.raises(FileExistsError, match=r"already has run 'b'.*--overwrite"):
        hdf5.write(path, frame_history(message="b2"), group="b")
    hdf5.write(path, frame_history(message="b2"), group="b", overwrite=True)
    assert hdf5.read(path, group="b").message == "b2" and hdf5.list_runs(path) == ["a", "b"]
    with pytest.raises(ValueError, match=r"batch file; choose a run with group=NAME .*\['a', 'b'\]"):
        hdf5.read(path)
    with pytest.raises(ValueError, match=r"has no run 'c'; its runs are \['a', 'b'\]"):
        hdf5.read(path, group="c")
    assert os.listdir(tmp_path) == ["batch.h5"]


def test_single_run_file_as_a_batch(tmp_path):
    hdf5.write(tmp_path / "run.h5", frame_history(message="one"))
    assert hdf5.list_runs(tmp_path / "run.h5") == ["/"]
    assert hdf5.read(tmp_path / "run.h5", group="/").message == "one"
    with pytest.raises(ValueError, match="holds a single run"):
        hdf5.write(tmp_path / "run.h5", frame_history(), group="x")
    with h5py.File(tmp_path / "foreign.h5", "w") as f:
        f["data"] = np.zeros(3)
    with pytest.raises(ValueError, match="not a pnrotor file"):
        hdf5.write(tmp_path / "foreign.h5", frame_history(), group="x")


def test_batch_writer_round_trip_is_bitwise(tmp_path, evolution_kind):
    runs = {f"h{i}": frame_history(n=50 + 30 * i, message=f"run {i}") for i in range(4)} | {"e": evolution_like()}
    hdf5.write(tmp_path / "one.h5", frame_history(message="one-run file"))
    path = tmp_path / "batch.h5"
    with hdf5.batch(path, compression="lzf") as batch:
        for name, run in runs.items():
            batch.add(name, run)
        batch.copy_from(tmp_path / "one.h5", "/", "copied")
        assert not path.exists() and len(batch) == 6 and batch.names == [*runs, "copied"]
    assert hdf5.list_runs(path) == sorted([*runs, "copied"])
    for name, run in runs.items():
        assert_identical(hdf5.read(path, group=name), run, name)
    assert_identical(hdf5.read(path, group="copied"), hdf5.read(tmp_path / "one.h5"))
    with h5py.File(path) as f:
        assert f.attrs["kind"].decode() == "batch" and f["h0/R"].compression == "lzf"
        assert f["copied/R"].compression is None  # copied as stored
    with hdf5.batch(tmp_path / "again.h5") as batch:  # copy_from keeps the name by default
        batch.copy_from(path, "e")
    assert_identical(hdf5.read(tmp_path / "again.h5", group="e"), evolution_like())
    assert sorted(os.listdir(tmp_path)) == ["again.h5", "batch.h5", "one.h5"]


@pytest.mark.parametrize("damage", ["nan", "kind", "missing", "string"])
def test_copy_from_copies_only_what_read_accepts(tmp_path, damage):
    """A source run read would refuse (a NaN, an unknown kind, a missing dataset, a damaged string) is not
    copied: the ValueError names the source, and the batch holds no such run nor its file."""
    source = tmp_path / "source.h5"
    hdf5.write(source, frame_history())
    with h5py.File(source, "r+") as f:
        if damage == "nan":
            f["R"][3, 1] = np.nan
        elif damage == "kind":
            f.attrs["kind"] = "Nope"
        elif damage == "missing":
            del f["R"]
        else:
            f.attrs["message"] = "edited without its CRC"
    with pytest.raises(ValueError, match=re.escape(str(source))):
        with hdf5.batch(tmp_path / "batch.h5") as batch:
            batch.add("fine", frame_history())
            batch.copy_from(source, "/", "copied")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["source.h5"]


def test_copy_from_reports_a_failed_write_as_the_targets(tmp_path, monkeypatch):
    """An error HDF5 meets while copying into the batch (here a file-size limit, errno 27 in its text) is the
    target's: one OSError line naming it, not "SOURCE is corrupt" (the source is fine)."""
    hdf5.write(tmp_path / "source.h5", frame_history())

    def too_large(self, *args, **kwargs):
        raise RuntimeError("Can't decrement id ref count (unable to extend file properly, errno = 27,\n"
                           " error message = 'File too large')")

    monkeypatch.setattr(h5py.Group, "copy", too_large)
    with pytest.raises(OSError, match=r"^\[Errno 27\] File too large while writing .*batch\.h5$"):
        with hdf5.batch(tmp_path / "batch.h5") as batch:
            batch.copy_from(tmp_path / "source.h5", "/", "copied")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["source.h5"]


def test_errors_about_other_files_in_a_batch_block_stay_theirs(tmp_path):
    """Only HDF5's reports about the file being written become "... while writing BATCH": a missing source of
    copy_from (checked or not) or a file the caller opens in the block keeps its own error and name."""
    (tmp_path / "text.h5").write_text("not HDF5")
    for verify in (True, False):
        with pytest.raises(FileNotFoundError, match=r"missing\.h5: no such file"):
            with hdf5.batch(tmp_path / "b.h5") as batch:
                batch.copy_from(tmp_path / "missing.h5", "/", "x", verify=verify)
        with pytest.raises(ValueError, match=r"text\.h5 is not an HDF5 file"):
            with hdf5.batch(tmp_path / "b.h5") as batch:
                batch.copy_from(tmp_path / "text.h5", "/", "x", verify=verify)
    with pytest.raises(FileNotFoundError, match="name = '.*other.h5'"):
        with hdf5.batch(tmp_path / "b.h5") as batch:
            batch.add("a", frame_history())
            h5py.File(tmp_path / "other.h5", "r")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["text.h5"]


def test_numpy_strings_are_written_as_strings(tmp_path):
    """np.str_ values (which evolve accepts for its string options) and numpy string arrays are written as the
    str and object arrays of str they equal, not refused by h5py after the layout check passed them."""
    run = frame_history(formulation=np.str_("rotor"))
    run.inputs.update(precession=np.str_("averaged"), names=np.array(["a", "bc"]))
    hdf5.write(tmp_path / "s.h5", run)
    back = hdf5.read(tmp_path / "s.h5")
    assert type(back.formulation) is str and back.formulation == "rotor"
    assert type(back.inputs["precession"]) is str and back.inputs["precession"] == "averaged"
    assert back.inputs["names"].dtype == object and back.inputs["names"].tolist() == ["a", "bc"]


@pytest.mark.parametrize("error", [KeyboardInterrupt, RuntimeError])
@pytest.mark.parametrize("existing", [None, "overwrite", "append"])
def test_batch_writer_interrupted_leaves_no_file_or_the_old_one(tmp_path, error, existing):
    path = tmp_path / "batch.h5"
    old = frame_history(message="old")
    if existing:
        hdf5.write(path, old, group="old")
    with pytest.raises(error):
        with hdf5.batch(path, overwrite=existing == "overwrite", append=existing == "append") as batch:
            batch.add("a", frame_history())
            batch.add("b", frame_history())
            assert len([name for name in os.listdir(tmp_path) if TEMPORARY.match(name)]) == 1
            raise error("interrupted in the middle")
    assert os.listdir(tmp_path) == (["batch.h5"] if existing else [])
    if existing:
        assert hdf5.list_runs(path) == ["old"]
        assert_identical(hdf5.read(path, group="old"), old)


def test_batch_writer_refuses_to_overwrite(tmp_path):
    path = tmp_path / "batch.h5"
    hdf5.write(path, frame_history(message="first"), group="a")
    with pytest.raises(FileExistsError, match=r"batch\.h5 exists; pass overwrite=True"):
        with hdf5.batch(path):
            pytest.fail("the block ran")
    with pytest.raises(FileExistsError, match=r"already has run 'a'; pass overwrite=True"):
        with hdf5.batch(path, append=True) as batch:
            batch.add("b", frame_history(message="b"))
            batch.add("a", frame_history(message="second"))
    assert hdf5.list_runs(path) == ["a"]  # b was not added either: the exception left the block
    with pytest.raises(ValueError, match="run 'x' was already added to this batch"):
        with hdf5.batch(tmp_path / "other.h5") as batch:
            batch.add("x", frame_history())
            batch.add("x", frame_history())
    with hdf5.batch(path, append=True, overwrite=True) as batch:
        batch.add("a", frame_history(message="second"))
        batch.add("b", frame_history(message="b"))
    assert hdf5.list_runs(path) == ["a", "b"] and hdf5.read(path, group="a").message == "second"
    with hdf5.batch(path, overwrite=True) as batch:
        batch.add("c", frame_history(message="c"))
    assert hdf5.list_runs(path) == ["c"]
    assert os.listdir(tmp_path) == ["batch.h5"]


def test_batch_writer_failed_run_and_empty_batch(tmp_path):
    path = tmp_path / "batch.h5"
    with hdf5.batch(path) as batch:
        with pytest.raises(TypeError, match="cannot write a set"):
            batch.add("bad", frame_history(inputs={"omega": {1, 2}}))
    assert os.listdir(tmp_path) == []  # no run added: nothing written, even though the failed one opened the file
    with hdf5.batch(path) as batch:
        batch.add("a", frame_history())
        with pytest.raises(TypeError, match="cannot write a set"):
            batch.add("bad", frame_history(inputs={"omega": {1, 2}}))
        batch.add("b", frame_history())
    assert hdf5.list_runs(path) == ["a", "b"] and batch.names == ["a", "b"]  # no half-written run "bad"
    with h5py.File(path) as f:
        assert sorted(f) == ["a", "b"]


def test_batch_writer_cost_does_not_grow_with_the_file(tmp_path, monkeypatch):
    """Each run is written into the one open temporary file: no copy of the file per run (what
    ``write(..., group=NAME)`` costs), one temporary file per batch, and one copy per appending batch."""
    calls = {"copy": 0, "temporary": 0}

    def count(key, function):
        def counted(*args, **kwargs):
            calls[key] += 1
            return function(*args, **kwargs)
        return counted

    for name in ("copy", "copy2", "copyfile", "copyfileobj"):
        monkeypatch.setattr(shutil, name, count("copy", getattr(shutil, name)))
    monkeypatch.setattr(atomic, "temporary_beside", count("temporary", atomic.temporary_beside))
    path = tmp_path / "batch.h5"
    with hdf5.batch(path) as batch:
        for i in range(30):
            batch.add(f"r{i}", frame_history(n=200))
    assert calls == {"copy": 0, "temporary": 1}
    with hdf5.batch(path, append=True) as batch:
        for i in range(30, 60):
            batch.add(f"r{i}", frame_history(n=200))
    assert calls == {"copy": 1, "temporary": 2}
    hdf5.write(path, frame_history(), group="one")  # one run through write: a copy of the file
    assert calls == {"copy": 2, "temporary": 3}
    assert len(hdf5.list_runs(path)) == 61 and os.listdir(tmp_path) == ["batch.h5"]


def test_batch_writer_not_durable_skips_the_fsyncs(tmp_path, monkeypatch):
    synced = []
    monkeypatch.setattr(atomic, "fsync", synced.append)
    for durable in (True, False):
        with hdf5.batch(tmp_path / f"{durable}.h5", durable=durable) as batch:
            batch.add("a", frame_history())
    assert len(synced) == 2 and synced[1] == tmp_path  # the durable batch's file, then its folder; none after
    assert TEMPORARY.match(synced[0].name) and synced[0].name.startswith("True.h5.")
    assert_identical(hdf5.read(tmp_path / "False.h5", group="a"), frame_history())


def test_command_line_starts_without_h5py():
    """h5py and numpy cost ~0.1 s to import: the CLI's parser (``pnrotor --help``) loads neither."""
    code = ("import sys; from pnrotor.cli import build_parser; build_parser(); "
            "print(sorted(m for m in ('h5py', 'numpy', 'pnrotor.hdf5') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout == "[]\n"


# --------------------------------------------------------------------------------------------------
# errors
# --------------------------------------------------------------------------------------------------


def test_write_target_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match=f"folder {re.escape(str(tmp_path / 'nope'))} does not exist"):
        hdf5.write(tmp_path / "nope" / "run.h5", frame_history())
    with pytest.raises(IsADirectoryError, match="is a folder"):
        hdf5.write(tmp_path, frame_history())
    with pytest.raises(ValueError, match="compression must be one of"):
        hdf5.write(tmp_path / "run.h5", frame_history(), compression="zstd")
    with pytest.raises(ValueError, match="not a valid HDF5 name"):
        hdf5.write(tmp_path / "run.h5", frame_history(), group="a/b")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(
    "inputs, error, message",
    [
        ({"a/b": 1.0}, ValueError, r"key of FrameHistory.inputs 'a/b' is not a valid HDF5 name"),
        ({1: 1.0}, TypeError, "must be a string"),
        ({"x": {"y": {1, 2}}}, TypeError, r"FrameHistory.inputs\['x'\]\['y'\]: cannot write a set"),
        ({"names": ["a", "b"]}, TypeError, "only numeric arrays and flat lists"),
        ({"nested": [[1.0], [2.0]]}, TypeError, "only numeric arrays and flat lists"),
        ({"ragged": [[1.0], [2.0, 3.0]]}, ValueError, r"FrameHistory.inputs\['ragged'\]"),
        ({"nul": "a\x00b"}, ValueError, r"cannot write FrameHistory.inputs\['nul'\]"),
        ({"huge": 2**64}, ValueError, r"cannot write FrameHistory.inputs\['huge'\]"),
    ],
)
def test_unwritable_values_are_named(tmp_path, inputs, error, message):
    with pytest.raises(error, match=message):
        hdf5.write(tmp_path / "run.h5", frame_history(inputs=inputs))
    assert os.listdir(tmp_path) == []


def test_only_registered_dataclasses_are_written(tmp_path, monkeypatch):
    with pytest.raises(TypeError, match="writes the run types"):
        hdf5.write(tmp_path / "x.h5", {"t": np.zeros(3)})
    with pytest.raises(TypeError, match="writes the run types"):
        hdf5.write(tmp_path / "x.h5", evolution_like())  # not registered

    @dataclasses.dataclass
    class Reserved:
        kind: str

    monkeypatch.setitem(hdf5.KINDS, "Reserved", f"{__name__}:{Reserved.__qualname__}")
    with pytest.raises(ValueError, match="reserved"):
        hdf5.write(tmp_path / "x.h5", Reserved("a"))
    assert os.listdir(tmp_path) == []


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        hdf5.read(tmp_path / "absent.h5")
    with pytest.raises(IsADirectoryError, match="is a folder"):
        hdf5.read(tmp_path)


@pytest.mark.parametrize("keep", [0.999, 0.5, 0.01, 200])
def test_truncated_file_is_reported(tmp_path, keep):
    path = hdf5.write(tmp_path / "run.h5", frame_history(n=20_001))
    data = path.read_bytes()
    path.write_bytes(data[: int(keep * len(data)) if keep < 1 else keep])
    with pytest.raises(ValueError, match="truncated or corrupt"):
        hdf5.read(path)


def flip_a_byte(path, dataset, at=100):
    """Flip a bit of byte `at` of the stored bytes of `dataset` (its first chunk if chunked); return the
    index of the element it lies in."""
    with h5py.File(path, "r") as f:
        d = f[dataset]
        offset = d.id.get_chunk_info(0).byte_offset if d.chunks else d.id.get_offset()
        shape = d.shape
    data = bytearray(path.read_bytes())
    data[offset + at] ^= 0x10
    path.write_bytes(data)
    return np.unravel_index(at // 8, shape)


@pytest.mark.parametrize("compression", [None, "gzip", "lzf"])
def test_damaged_data_is_reported_with_checksums(tmp_path, compression):
    path = hdf5.write(tmp_path / "run.h5", frame_history(n=20_001), compression=compression, checksum=True)
    with h5py.File(path, "r") as f:
        assert f["R"].fletcher32 and f["t"].fletcher32
    flip_a_byte(path, "R")
    with pytest.raises(ValueError, match="is corrupt: HDF5 cannot read it"):
        hdf5.read(path)


def test_without_checksums_arrays_are_contiguous_and_damage_goes_unnoticed(tmp_path):
    """The layout of ``checksum=False``: contiguous datasets, the array's own bytes, no checksum; a flipped byte then
    reads back as a changed number (what the default ``checksum=True`` is for)."""
    history = frame_history(n=20_001)
    path = hdf5.write(tmp_path / "run.h5", history, checksum=False)
    with h5py.File(path, "r") as f:
        for name in ("t", "R"):
            assert f[name].chunks is None and not f[name].fletcher32 and f[name].compression is None
    assert_identical(hdf5.read(path), history)
    where = flip_a_byte(path, "R")
    damaged = hdf5.read(path).R
    assert damaged[where] != history.R[where]
    damaged[where] = history.R[where]
    assert damaged.tobytes() == history.R.tobytes()


def test_checksum_option_of_batches_and_appends(tmp_path):
    with hdf5.batch(tmp_path / "batch.h5") as runs:  # checksums by default
        runs.add("a", frame_history())
    hdf5.write(tmp_path / "batch.h5", frame_history(message="b"), group="b", checksum=False)  # appended without
    hdf5.write(tmp_path / "batch.h5", frame_history(message="c"), group="c")
    with h5py.File(tmp_path / "batch.h5", "r") as f:
        assert [f[f"{name}/R"].fletcher32 for name in "abc"] == [True, False, True]
    assert hdf5.read(tmp_path / "batch.h5", group="b").message == "b"
    with pytest.raises(TypeError, match="checksum must be True or False"):
        hdf5.write(tmp_path / "x.h5", frame_history(), checksum="fletcher32")
    with pytest.raises(TypeError, match="checksum must be True or False"):
        with hdf5.batch(tmp_path / "x.h5", checksum=1):
            pass
    assert sorted(os.listdir(tmp_path)) == ["batch.h5"]


def test_files_of_the_former_layout_still_read(tmp_path):
    """Before checksums became an option every dataset was chunked with Fletcher-32 (what
    ``checksum=True`` writes); such a file, built here with plain h5py, reads back bitwise."""
    history = frame_history(n=1001)
    hdf5.write(tmp_path / "run.h5", history)
    with h5py.File(tmp_path / "run.h5", "r") as new, h5py.File(tmp_path / "old.h5", "w") as old:
        for name, value in new.attrs.items():
            old.attrs[name] = value
        new.copy("inputs", old)
        for name in ("t", "R"):
            d = old.create_dataset(name, data=new[name][...], chunks=(500,) + new[name].shape[1:], fletcher32=True)
            d.attrs["units"] = new[name].attrs["units"]
    assert_identical(hdf5.read(tmp_path / "old.h5"), history)


def test_durable_write_starts_the_writeback_of_large_datasets(tmp_path, monkeypatch):
    """Each dataset of ≥ 1 MiB starts a background fdatasync of the temporary file (none when not
    durable); the final fsync of the file and its folder stay, and an interrupted write leaves nothing."""
    started, synced = [], []

    def record(path, sync=os.fsync):
        (started if sync is os.fdatasync else synced).append(path)

    monkeypatch.setattr(atomic, "fsync", record)
    hdf5.write(tmp_path / "big.h5", frame_history(n=200_000))  # t: 1.6 MB, R: 6.4 MB
    assert 1 <= len(started) <= 2 and {p.name for p in started} == {synced[0].name}
    assert TEMPORARY.match(synced[0].name) and synced[1:] == [tmp_path]
    with hdf5.batch(tmp_path / "scratch.h5", durable=False) as runs:
        runs.add("a", frame_history(n=200_000))
    assert len(started) <= 2 and len(synced) == 2 and not hdf5._WRITEBACKS
    fail_on_dataset(monkeypatch, "R")
    with pytest.raises(KeyboardInterrupt):
        hdf5.write(tmp_path / "big.h5", frame_history(n=200_000), overwrite=True)
    assert sorted(os.listdir(tmp_path)) == ["big.h5", "scratch.h5"] and not hdf5._WRITEBACKS


def test_non_hdf5_and_empty_files(tmp_path):
    (tmp_path / "notes.h5").write_text("t,R\n0,1\n")
    with pytest.raises(ValueError, match=r"notes\.h5 is not an HDF5 file$"):
        hdf5.read(tmp_path / "notes.h5")
    (tmp_path / "empty.h5").touch()
    with pytest.raises(ValueError, match=r"is not an HDF5 file \(it is empty\)"):
        hdf5.read(tmp_path / "empty.h5")


def test_foreign_hdf5_file(tmp_path):
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["t"] = np.zeros(3)
        f.attrs["schema_version"] = 1
    with pytest.raises(ValueError, match="an HDF5 file but not a pnrotor file"):
        hdf5.read(tmp_path / "other.h5")


@pytest.mark.parametrize(
    "schema, message",
    [(3, r"schema version 3 \(written by pnrotor 9\.9\).*reads schema versions 1 to 2; upgrade pnrotor"),
     (0, r"schema version 0 .*reads schema versions 1 to 2$"),
     ("1", r"schema version '1' ")],
)
def test_unknown_schema_version(tmp_path, schema, message):
    path = hdf5.write(tmp_path / "run.h5", frame_history())
    with h5py.File(path, "r+") as f:
        f.attrs["pnrotor_schema"] = schema
        f.attrs["pnrotor_version"] = "9.9"
    with pytest.raises(ValueError, match=message):
        hdf5.read(path)


def test_unknown_kind_and_mismatched_fields(tmp_path):
    path = hdf5.write(tmp_path / "run.h5", frame_history())
    with h5py.File(path, "r+") as f:
        f.attrs["kind"] = "Waveform"
    with pytest.raises(ValueError, match=r"unknown run kind 'Waveform'; this pnrotor reads \["):
        hdf5.read(path)
    hdf5.write(path, frame_history(), overwrite=True)
    with h5py.File(path, "r+") as f:
        del f.attrs["nfev"]
    with pytest.raises(ValueError, match=r"run\.h5: attribute 'nfev' is missing$"):
        hdf5.read(path)


@pytest.mark.parametrize("name, value, message", [
    ("kind", np.array(["FrameHistory"] * 2, dtype=h5py.string_dtype()), "attribute 'kind' is not a string"),
    ("pnrotor_strings_crc32", np.array([1, 2], dtype="u4"), "attribute 'pnrotor_strings_crc32' is not a number"),
])
def test_array_attributes_are_named(tmp_path, name, value, message):
    """Stored as arrays (another writer, or damage), they made numpy's "truth value of an array is ambiguous",
    naming neither the file nor the attribute."""
    path = hdf5.write(tmp_path / "run.h5", frame_history())
    with h5py.File(path, "r+") as f:
        f.attrs[name] = value
    for call in (hdf5.read, hdf5.list_runs) if name == "kind" else (hdf5.read,):   # list_runs reads no CRC
        with pytest.raises(ValueError, match=f"run\\.h5: {message}"):
            call(path)


def test_registered_kinds_name_their_dataclasses():
    assert hdf5.KINDS["FrameHistory"] == f"{FrameHistory.__module__}:FrameHistory"
    from pnrotor.pn.evolve import Evolution
    assert dataclasses.is_dataclass(Evolution)
    assert hdf5.KINDS["Evolution"] == f"{Evolution.__module__}:{Evolution.__qualname__}"


def test_kind_whose_class_is_not_importable(tmp_path, monkeypatch, evolution_kind):
    hdf5.write(tmp_path / "pn.h5", evolution_like())
    monkeypatch.setitem(hdf5.KINDS, "EvolutionLike", "pnrotor.no_such_module:Evolution")
    with pytest.raises(ValueError, match="need pnrotor.no_such_module:Evolution, which is not importable"):
        hdf5.read(tmp_path / "pn.h5")


def test_a_full_disk_is_found_before_writing(tmp_path, monkeypatch):
    """Arrays and 1 MiB for metadata larger than the free space: one OSError (ENOSPC) naming the folder and the
    sizes, and neither the file nor a temporary one is left; the same for a run added to a batch or copied into
    one (whose HDF5 object copy died of a double free with a few kB free)."""
    import errno
    import shutil
    history = frame_history()
    hdf5.write(tmp_path / "source.h5", history)
    free = history.t.nbytes + history.R.nbytes + 2 ** 20 - 1
    monkeypatch.setattr(shutil, "disk_usage", lambda folder: shutil._ntuple_diskusage(10 ** 9, 10 ** 9 - free, free))
    with pytest.raises(OSError, match=r"no space for run\.h5 in .*: its arrays need 4.0 KiB and its metadata up to "
                       r"1\.0 MiB, 1\.0 MiB are free") as error:
        hdf5.write(tmp_path / "run.h5", history)
    assert error.value.errno == errno.ENOSPC
    with pytest.raises(OSError, match="no space"):
        with hdf5.batch(tmp_path / "many.h5") as runs:
            runs.add("a", history)
    with pytest.raises(OSError, match="no space"):
        with hdf5.batch(tmp_path / "many.h5") as runs:
            runs.copy_from(tmp_path / "source.h5", "/", "a")
    with pytest.raises(OSError, match="need .* before compression"):
        hdf5.write(tmp_path / "run.h5", history, compression="gzip")   # the raw size bounds the compressed one
    assert sorted(p.name for p in tmp_path.iterdir()) == ["source.h5"]


def test_hdf5s_full_disk_report_becomes_one_oserror(tmp_path, monkeypatch):
    """HDF5 reports a full disk met while writing as a RuntimeError or OSError whose text spans lines
    ("... errno = 28, error message = 'No space left on device' ..."): it becomes one OSError (ENOSPC) naming
    the folder and the file, and the temporary file goes (measured on a tmpfs: benchmarks/faults.py)."""
    import errno

    def full(g, run, compression, checksum):
        raise RuntimeError(f"Unable to flush raw data (file write failed: time = now\n, filename = '{g.file.filename}', "
                           "errno = 28, error message = 'No space left on device')")

    monkeypatch.setattr(hdf5, "_put_run", full)
    with pytest.raises(OSError, match=r"^\[Errno 28\] no space left on the device of .* while writing run\.h5$") as e:
        hdf5.write(tmp_path / "run.h5", frame_history())
    assert e.value.errno == errno.ENOSPC and list(tmp_path.iterdir()) == []
