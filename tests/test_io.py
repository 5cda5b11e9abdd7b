"""pnrotor.io.write: the format chosen by the file's suffix (HDF5 for .h5 and .hdf5), a clear error for any other,
before anything is computed on the command line."""

import os

import pytest

from pnrotor import hdf5, io
from pnrotor.cli import main
from test_hdf5 import assert_identical, frame_history


@pytest.mark.parametrize("name", ["run.h5", "run.HDF5"])
def test_write_by_suffix_is_the_hdf5_write(tmp_path, name):
    run = frame_history(n=500)
    assert io.write(tmp_path / name, run, compression="lzf") == tmp_path / name
    assert_identical(hdf5.read(tmp_path / name), run)
    with pytest.raises(FileExistsError, match="pass overwrite=True"):   # the format's own options and checks
        io.write(tmp_path / name, run)


@pytest.mark.parametrize("name, said", [("run.txt", "not '.txt'"), ("run", "not a name without a suffix")])
def test_a_suffix_no_format_writes_is_refused_before_writing(tmp_path, capsys, name, said):
    with pytest.raises(ValueError, match=f"run.*: pnrotor writes files ending in .h5, .hdf5, {said}"):
        io.write(tmp_path / name, frame_history())
    assert main(["verify", "--t-end", "10", "-o", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err and os.listdir(tmp_path) == []
