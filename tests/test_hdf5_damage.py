"""Damage is an error, never a hang (issue #36, item 2).

Schema 1 kept every string attribute in HDF5's global heap, which has no checksum: one flipped bit in a string's
size made HDF5's reader loop forever (at 100% CPU, deaf to Ctrl-C).  Schema 2 stores strings as fixed-length
attributes in the object headers, which the 1.10 format checksums.  Here: no file of any kind holds a
variable-length string; a flip of any bit position of every byte of a small file's metadata is an error or reads
back the same, each read ending within a bound (in a child process, killed past it); files of schema 1 still
read, the same runs bitwise."""

import dataclasses
import io
import os
import select
import signal
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest

import pnrotor
from pnrotor import hdf5
from pnrotor.history import FrameHistory

DATA = Path(__file__).resolve().parent / "data"
BINARY = dict(m1=30, m2=10, chi1=(0.5, 0.3, 0.2), chi2=(0.0, -0.4, 0.3), f_ref=20)


def same(a, b):
    """Whether two runs hold the same values bitwise (arrays by dtype, shape and bytes; NaN equals NaN)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and (a.tobytes() == b.tobytes() if a.dtype.kind != "O" else
                                            a.tolist() == b.tolist()))
    if isinstance(a, dict) or isinstance(b, dict):
        return isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys() and all(
            same(a[k], b[k]) for k in a)
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, float) and isinstance(b, float):
        return np.float64(a).tobytes() == np.float64(b).tobytes()
    return type(a) is type(b) and a == b


def small_history():
    """A FrameHistory of 3 samples with a string, a list and an array among its inputs: every kind of HDF5 object
    a run file holds (groups, chunked and checksummed datasets, attributes of each type) in ~5 kB."""
    return FrameHistory(t=np.linspace(0.0, 1.0, 3), R=np.tile([0.5, 0.5, 0.5, 0.5], (3, 1)), formulation="rotor",
                        method="DOP853", atol=1e-10, rtol=0.0, nfev=7, nsteps=2, naccepted=2, nrejected=0, n_resets=0,
                        status=0, message="success", wall_time=0.5,
                        inputs={"omega": "test", "axis": [0.0, 0.0, 1.0], "R0": np.array([1.0, 0.0, 0.0, 0.0]),
                                "none": None})


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """One result of every kind that pnrotor writes (the PopulationTable as `pnrotor evolve --population` makes
    it, of the table of the schema-1 file's)."""
    from pnrotor.batch import population

    run = pnrotor.evolve(**BINARY, f_max=21)
    path = tmp_path_factory.mktemp("population") / "population.h5"
    population.run(DATA / "schema1-population.csv", path)
    return {"Evolution": run, "Modes": pnrotor.modes(run, ell_max=2), "FrameHistory": small_history(),
            "PopulationTable": hdf5.read(path)}


def variable_length_strings(path):
    """Names of the attributes and datasets of the file `path` that hold variable-length strings (HDF5 keeps
    those in its global heap)."""
    found = []

    def look(name, obj):
        found.extend(f"{obj.name}@{key}" for key in obj.attrs
                     if h5py.check_vlen_dtype(obj.attrs.get_id(key).dtype) is not None)
        if isinstance(obj, h5py.Dataset) and h5py.check_vlen_dtype(obj.dtype) is not None:
            found.append(obj.name)

    with h5py.File(path, "r") as f:
        look("/", f)
        f.visititems(look)
    return found


@pytest.mark.parametrize("compression, checksum", [(None, True), ("gzip", False), (None, False)])
def test_no_file_holds_a_variable_length_string(runs, tmp_path, compression, checksum):
    for kind, run in runs.items():
        path = hdf5.write(tmp_path / f"{kind}.h5", run, compression=compression, checksum=checksum)
        assert variable_length_strings(path) == [], kind
        assert same(hdf5.read(path), run), kind
    with hdf5.batch(tmp_path / "batch.h5", compression=compression, checksum=checksum) as batch:
        for kind, run in runs.items():
            batch.add(kind, run)
    assert variable_length_strings(tmp_path / "batch.h5") == []
    with h5py.File(tmp_path / "batch.h5") as f:   # plain h5py: strings as bytes, decoded as UTF-8
        assert f.attrs["kind"].decode() == "batch" and f.attrs["pnrotor_schema"] == 2
        assert f["Evolution"].attrs["termination"].decode() == runs["Evolution"].termination
        assert f["Evolution/t"].attrs["units"].decode() == hdf5.UNITS["Evolution"]["t"]


def test_strings_round_trip_exactly(tmp_path):
    texts = ["", "é", "a b", "ℓ̂ χ₁", "x" * 70000, "\udcff"]   # empty, non-ASCII, long (dense storage), a surrogate
    history = dataclasses.replace(small_history(), message=texts[1],
                                  inputs={f"s{i}": text for i, text in enumerate(texts)})
    back = hdf5.read(hdf5.write(tmp_path / "s.h5", history))
    assert back.message == texts[1] and back.inputs == history.inputs
    assert all(type(value) is str for value in back.inputs.values())
    with pytest.raises(ValueError, match="may not contain NUL"):
        hdf5.write(tmp_path / "nul.h5", dataclasses.replace(history, message="a\0b"))
    assert not (tmp_path / "nul.h5").exists()


# --------------------------------------------------------------------------------------------------
# flipped bits
# --------------------------------------------------------------------------------------------------


def data_extents(path):
    """(offset, size) of the raw data of every dataset in `path`: contiguous, or each chunk."""
    extents = []

    def look(name, obj):
        if not isinstance(obj, h5py.Dataset):
            return
        if obj.chunks is None:
            if obj.id.get_offset() is not None:
                extents.append((obj.id.get_offset(), obj.id.get_storage_size()))
        else:
            for i in range(obj.id.get_num_chunks()):
                info = obj.id.get_chunk_info(i)
                extents.append((info.byte_offset, info.size))

    with h5py.File(path, "r") as f:
        f.visititems(look)
    return extents


class _Traced(io.BytesIO):
    """A file in memory that notes which of its bytes are read."""

    def __init__(self, data):
        super().__init__(data)
        self.read_bytes = np.zeros(len(data), dtype=bool)

    def readinto(self, buffer):
        at = self.tell()
        count = super().readinto(buffer)
        self.read_bytes[at:at + count] = True
        return count

    def read(self, size=-1):
        at = self.tell()
        data = super().read(size)
        self.read_bytes[at:at + len(data)] = True
        return data


def metadata_bytes(path):
    """Offsets of the bytes of `path` that HDF5 reads when every attribute and dataset is read (through h5py's
    file-object driver, which sees each of its reads), but the raw data of the datasets.  A byte HDF5 does not
    read (unused space HDF5 allocated in blocks) cannot change a read: the bytes it reads, and so what it does,
    stay the same."""
    traced = _Traced(Path(path).read_bytes())

    def read_all(name, obj):
        for key in obj.attrs:
            obj.attrs[key]
        if isinstance(obj, h5py.Dataset):
            obj[...]

    with h5py.File(traced, "r") as f:
        read_all("/", f)
        f.visititems(read_all)
    metadata = traced.read_bytes.copy()
    for offset, size in data_extents(path):
        metadata[offset:offset + size] = False
    return np.flatnonzero(metadata).tolist()


def _flip_child(data, positions, reference, group, out):
    """In a forked child: read `data` with bit (p % 8) of byte p flipped, for p in `positions`; one line
    ``p outcome`` per read on the pipe `out`; outcome: error (a ValueError naming the file), same, different or
    the exception's type."""
    folder = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        damaged = os.path.join(tmp, "damaged.h5")
        for p in positions:
            flipped = bytearray(data)
            flipped[p] ^= 1 << (p % 8)
            with open(damaged, "wb") as f:
                f.write(flipped)
            try:
                back = hdf5.read(damaged, group)
                outcome = "same" if same(back, reference) else "different"
            except ValueError as error:
                outcome = "error" if damaged in str(error) else "ValueError-unnamed"
            except Exception as error:   # noqa: BLE001 — reported
                outcome = type(error).__name__
            os.write(out, f"{p} {outcome}\n".encode())


def flip_outcomes(path, positions, reference, group=None, bound=10.0):
    """{position: outcome} of reading the file `path` with one bit of the byte at each position flipped (bit
    p % 8), in forked children (one for all, and a new one after each that does not end a read within `bound`
    seconds: outcome 'hang', killed, or dies: 'signal NAME')."""
    data, outcomes, todo = Path(path).read_bytes(), {}, list(positions)
    while todo:
        read_end, write_end = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(read_end)
            try:
                _flip_child(data, todo, reference, group, write_end)
            finally:
                os._exit(0)
        os.close(write_end)
        buffer = b""
        with os.fdopen(read_end, "rb", buffering=0) as pipe:
            while True:
                ready, _, _ = select.select([pipe], [], [], bound)
                if not ready:   # the read of todo[0] did not end within the bound
                    os.kill(pid, signal.SIGKILL)
                    break
                chunk = pipe.read(65536)
                if not chunk:
                    break
                buffer += chunk
                *lines, buffer = buffer.split(b"\n")
                for line in lines:   # the child reads in the order of todo
                    p, outcome = line.decode().split(" ", 1)
                    assert int(p) == todo.pop(0)
                    outcomes[int(p)] = outcome
        _, status = os.waitpid(pid, 0)
        if todo and os.WIFSIGNALED(status):
            name = signal.Signals(os.WTERMSIG(status)).name
            outcomes[todo.pop(0)] = "hang" if name == "SIGKILL" else f"signal {name}"
    return outcomes


def test_any_flipped_bit_of_the_metadata_is_an_error_or_harmless_never_a_hang(tmp_path):
    """Every byte of a small file's metadata (`metadata_bytes`), one bit each (bit p % 8 of byte p, so every bit
    position of every structure is hit): each read ends within the bound, and is a ValueError naming the file or
    reads back the same run (fields HDF5 ignores).  A file of schema 1 hung HDF5's reader at the size fields of its
    strings in the global heap."""
    history = small_history()
    path = hdf5.write(tmp_path / "small.h5", history)
    positions = metadata_bytes(path)
    assert 0 in positions and len(positions) > 0.5 * os.path.getsize(path)
    outcomes = flip_outcomes(path, positions, history)
    assert len(outcomes) == len(positions)
    bad = {p: o for p, o in outcomes.items() if o not in ("error", "same")}
    assert not bad, f"{len(bad)} of {len(positions)} flips: {dict(list(bad.items())[:20])}"
    assert list(outcomes.values()).count("error") > 0.8 * len(positions)


# --------------------------------------------------------------------------------------------------
# files of schema 1
# --------------------------------------------------------------------------------------------------


def test_files_of_schema_1_read_as_before(tmp_path):
    """tests/data/schema1.h5 was written by pnrotor before schema 2 (strings in the global heap): an Evolution, its
    Modes, a FrameHistory and a PopulationTable (of tests/data/schema1-population.csv).  Each reads back as the
    same computation gives today, bitwise (but wall times, and inputs added since), and writes again as schema 2,
    without a variable-length string."""
    from pnrotor.analytic import PrecessingNutatingBinary
    from pnrotor.batch import population

    old = DATA / "schema1.h5"
    assert hdf5.metadata(old, "evolution")["pnrotor_schema"] == 1 and len(variable_length_strings(old)) > 50
    run = pnrotor.evolve(**BINARY, f_max=21)
    binary = PrecessingNutatingBinary()
    population.run(DATA / "schema1-population.csv", tmp_path / "population.h5")
    expected = {"evolution": run, "evolution.modes": pnrotor.modes(run, ell_max=2),
                "history": pnrotor.integrate_angular_velocity(binary, (0.0, 10.0), binary.rotor(0.0), atol=1e-10),
                "population": hdf5.read(tmp_path / "population.h5")}
    assert hdf5.list_runs(old) == sorted(expected)
    for name, now in expected.items():
        back = hdf5.read(old, name)
        assert type(back) is type(now)
        for field in dataclasses.fields(now):
            if field.name in ("wall_time", "dense"):   # a time, and the integrator's function (not stored)
                continue
            a, b = getattr(back, field.name), getattr(now, field.name)
            if field.name == "stats":
                a, b = ({key: value for key, value in x.items() if not key.startswith("wall_time")} for x in (a, b))
            if field.name == "inputs":   # options added since (with their defaults) are not in the old file
                assert a.keys() <= b.keys(), (name, a.keys() - b.keys())
                b = {key: b[key] for key in a}
            assert same(a, b), (name, field.name)
        again = hdf5.write(tmp_path / f"again-{name}.h5", hdf5.read(old, name))
        assert variable_length_strings(again) == [] and hdf5.metadata(again)["pnrotor_schema"] == 2
        assert same(hdf5.read(again), hdf5.read(old, name)), name


if __name__ == "__main__":   # every kind, every byte of its metadata (minutes): python tests/test_hdf5_damage.py
    import collections
    import sys
    import time

    from pnrotor.batch import population

    with tempfile.TemporaryDirectory() as folder:
        run = pnrotor.evolve(**BINARY, f_max=21)
        population.run(DATA / "schema1-population.csv", Path(folder) / "population.h5")
        kinds = {"FrameHistory": small_history(), "Evolution": run, "Modes": pnrotor.modes(run, ell_max=2),
                 "PopulationTable": hdf5.read(Path(folder) / "population.h5")}
        print(f"pnrotor {pnrotor.__version__}, schema {hdf5.SCHEMA_VERSION}: one bit of every byte of the metadata")
        for kind, result in kinds.items():
            for compression, checksum in ((None, True), ("gzip", False)):
                path = hdf5.write(Path(folder) / f"{kind}.h5", result, compression=compression, checksum=checksum,
                                  overwrite=True)
                positions = metadata_bytes(path)
                start = time.perf_counter()
                counts = collections.Counter(flip_outcomes(path, positions, result).values())
                print(f"{kind:16s} compression {compression!s:5s} checksum {checksum!s:5s} {os.path.getsize(path):6d} "
                      f"bytes, {len(positions):5d} flipped: {dict(counts)} ({time.perf_counter() - start:.0f} s)")
                sys.stdout.flush()
