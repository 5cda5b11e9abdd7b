"""pnrotor.files: tables, summaries and figures are written whole or not at all (an interrupted write left a
half-written bench.csv, JSON or PNG under the expected name: a review's finding)."""

import os

import pytest

from pnrotor.files import replaced_on_success


def _names(folder):
    return sorted(os.listdir(folder))


def test_a_finished_write_replaces_the_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("old\n")
    with replaced_on_success(path) as temporary:
        assert temporary.parent == tmp_path and temporary.suffix == ".csv" and temporary != path
        temporary.write_text("new\n")
        assert path.read_text() == "old\n"   # nothing under the name until the write is done
    assert path.read_text() == "new\n" and _names(tmp_path) == ["table.csv"]


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
@pytest.mark.parametrize("existed", [True, False])
def test_an_interrupted_write_leaves_the_file_as_it_was(tmp_path, error, existed):
    path = tmp_path / "figure.png"
    if existed:
        path.write_bytes(b"old")
    with pytest.raises(error):
        with replaced_on_success(path) as temporary:
            temporary.write_bytes(b"half")
            raise error
    assert _names(tmp_path) == (["figure.png"] if existed else [])
    if existed:
        assert path.read_bytes() == b"old"


def test_plot_keeps_the_old_figure_when_drawing_fails(tmp_path, capsys, monkeypatch):
    """`pnrotor plot` whose savefig dies half-way (a full disk, Ctrl-C): the previous PNG stays whole."""
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from pnrotor import hdf5
    from pnrotor.cli import main
    from pnrotor.pn import evolve

    run_file = tmp_path / "run.h5"
    hdf5.write(run_file, evolve(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 100.0))
    assert main(["plot", str(run_file)]) == 0
    png = tmp_path / "run.png"
    before = png.read_bytes()

    def half_then_fail(self, fname, **kwargs):
        with open(fname, "wb") as f:
            f.write(b"\x89PNG half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", half_then_fail)
    assert main(["plot", str(run_file)]) == 1
    assert png.read_bytes() == before and _names(tmp_path) == ["run.h5", "run.png"]
    capsys.readouterr()
