"""The read-only file commands `pnrotor inspect` and `pnrotor plot`: what they print and draw (δ(t) of
`pnrotor verify -o` files, against the exact rotor), and one-line errors with exit status 2 (no traceback)
for missing, truncated, foreign and other bad files."""

import math
import re
import subprocess
import sys

import h5py
import numpy as np
import pytest
from test_hdf5 import evolution_kind, evolution_like, frame_history  # noqa: F401 (evolution_kind: a fixture)

from pnrotor import __version__, hdf5, integrate_angular_velocity
from pnrotor import quaternion as quat
from pnrotor.analytic import PrecessingNutatingBinary
from pnrotor.cli import main


@pytest.fixture
def files(tmp_path, evolution_kind):
    paths = {"frames": tmp_path / "frames.h5", "pn": tmp_path / "pn.h5", "batch": tmp_path / "batch.h5"}
    hdf5.write(paths["frames"], frame_history(n=4001))
    hdf5.write(paths["pn"], evolution_like())
    hdf5.write(paths["batch"], evolution_like(), group="pn")
    hdf5.write(paths["batch"], frame_history(), group="frames")
    return paths


def inspect_output(capsys, *args):
    assert main(["inspect", *map(str, args)]) == 0
    return capsys.readouterr().out


# --------------------------------------------------------------------------------------------------
# inspect
# --------------------------------------------------------------------------------------------------


def test_inspect_frame_history_prints_every_attribute_and_input(files, capsys):
    out = inspect_output(capsys, files["frames"])
    history = frame_history(n=4001)
    created = hdf5.metadata(files["frames"])["created"]
    assert out.startswith(f"{files['frames']}: FrameHistory\n")
    assert f"pnrotor schema {hdf5.SCHEMA_VERSION}, written by pnrotor {__version__}, created {created}" in out
    assert "4001 samples, t from 0.0 to 1000000.0" in out
    assert "(4001, 4) float64" in out and "scalar-first" in out
    for name in ("formulation", "method", "atol", "rtol", "nfev", "nsteps", "naccepted", "nrejected", "n_resets",
                 "status", "message", "wall_time"):
        assert f"  {name} " in out and repr(getattr(history, name)) in out
    for line in ("  omega  'PrecessingNutatingBinary'", "  reset  True", "  t_end  1000000.0", "  R0     [1., 0., 0., 0.] float64"):
        assert line in out.splitlines()
    summary = out.split("summary\n")[1]
    assert "rotor formulation, dop853, atol 1e-12, rtol 1e-10" in summary and "status 0: success: reached t_end" in summary
    assert "1234 right-hand-side evaluations, 100 steps (97 accepted, 3 rejected), 0 generator resets" in summary


def test_inspect_post_newtonian_run_summary(files, capsys):
    out = inspect_output(capsys, files["pn"])
    run = evolution_like()
    orbits = (run.Phi[-1] - run.Phi[0]) / (2 * math.pi)
    duration_s = run.t_seconds[-1] - run.t_seconds[0]
    summary = out.split("summary\n")[1].splitlines()
    assert summary == [
        f"  duration 50000 M = {duration_s:.6g} s",
        f"  orbits {orbits:.6g} (ΔΦ/2π)",
        "  v from 0.2 to 0.4 (final)",
        "  termination: f_max reached",
    ]
    lines = out.splitlines()
    for line in ("  approximant  'SpinTaylorT4'", "  chi1         (0.3, 0.0, 0.4)", "  f_max        None",
                 "  m1           12.0", "  nfev       5000", "  spin_orders", "    spin_orbit  7", "    quadrupole  [1., 1.] float64"):
        assert line in lines
    assert lines[lines.index("stats") + 1 : lines.index("stats") + 6] == [
        "  naccepted  390", "  nfev       5000", "  nrejected  10", "  nsteps     400", "  wall_time  0.03"
    ]


def test_inspect_large_input_array_is_summarized(tmp_path, capsys):
    hdf5.write(tmp_path / "run.h5", frame_history(inputs={"t_eval": np.linspace(0.0, 10.0, 1001)}))
    out = inspect_output(capsys, tmp_path / "run.h5")
    assert "  t_eval  (1001,) float64, from 0.0 to 10.0" in out.splitlines()


def test_inspect_large_array_with_nans_gives_the_span_of_its_finite_values(tmp_path, capsys):
    """A population column with empty cells (NaN) on some rows: the span of the others and the count of NaNs,
    not "from nan to nan"; a column of NaNs only says so."""
    f_max = np.where(np.arange(10) % 2, 100.0, np.nan)
    hdf5.write(tmp_path / "run.h5", frame_history(inputs={"f_max": f_max, "none": np.full(9, np.nan)}))
    lines = inspect_output(capsys, tmp_path / "run.h5").splitlines()
    assert "  f_max  (10,) float64, from 100.0 to 100.0, 5 not finite" in lines
    assert "  none   (9,) float64, no finite value, 9 not finite" in lines


def test_inspect_large_text_array_lists_its_values(tmp_path, capsys):
    """A population's per-row options are text arrays: their distinct values, not a min and max of strings."""
    names = np.array(["T4", "T1", "T4"] * 4, dtype=object)
    hdf5.write(tmp_path / "run.h5", frame_history(inputs={"approximant": names}))
    out = inspect_output(capsys, tmp_path / "run.h5")
    assert "  approximant  (12,) object, 2 distinct: 'T1', 'T4'" in out.splitlines()


def test_inspect_batch_file(files, capsys):
    out = inspect_output(capsys, files["batch"])
    lines = out.splitlines()
    assert lines[0] == f"{files['batch']}: batch file with 2 runs"
    assert lines[1].startswith("  frames  FrameHistory, created ") and lines[2].startswith("  pn  EvolutionLike, created ")
    out = inspect_output(capsys, files["batch"], "--group", "pn")
    assert out.startswith(f"{files['batch']} run 'pn': EvolutionLike\n") and "termination: f_max reached" in out


def test_inspect_empty_run(tmp_path, capsys):
    hdf5.write(tmp_path / "empty.h5", frame_history(n=0))
    out = inspect_output(capsys, tmp_path / "empty.h5")
    assert "  0 samples\n" in out and "(0, 4) float64" in out


# --------------------------------------------------------------------------------------------------
# plot
# --------------------------------------------------------------------------------------------------


def assert_sensible_png(path, shape):
    image = pytest.importorskip("matplotlib.image").imread(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert image.shape[:2] == shape
    assert image[..., :3].std() > 0.05  # not a blank canvas


@pytest.mark.parametrize("which", ["frames", "pn"])
def test_plot_writes_a_png(files, which, capsys):
    pytest.importorskip("matplotlib")
    png = files[which].with_suffix(".png")
    assert main(["plot", str(files[which])]) == 0
    assert capsys.readouterr().out == f"wrote {png}\n"
    assert_sensible_png(png, (850, 1200))


def test_inspect_modes_summary(tmp_path, capsys):
    """A modes group's summary (it said "no summary for this kind of run"): the modes and their units, the span,
    and the four largest peak amplitudes, each as computed here from the modes themselves."""
    import pnrotor
    run = pnrotor.evolve(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 100.0, sampling=1 / 4096)
    h = pnrotor.modes(run, ell_max=3, amplitude_order=1.5, distance=250.0)
    with hdf5.batch(tmp_path / "w.h5") as groups:
        groups.add("run", run)
        groups.add("modes", h)
    lines = inspect_output(capsys, tmp_path / "w.h5", "--group", "modes").splitlines()
    summary = lines[lines.index("summary") + 1:]
    peaks = {mode: np.abs(h.mode(*mode)).max() for mode in h.ell_m}
    top = sorted(peaks, key=lambda mode: -peaks[mode])[:4]
    assert summary == [
        "  12 modes, l = 2 ... 3, amplitude order 1.5 PN, inertial frame",
        "  units: strain at 250 Mpc",
        f"  duration {run.t[-1] - run.t[0]:.6g} M = {run.t_seconds[-1] - run.t_seconds[0]:.6g} s",
        "  largest max |h_lm|: " + ", ".join(f"({ell}, {m}) {peaks[(ell, m)]:.4g}" for ell, m in top)]
    assert top[0] == (2, 2)


def test_plot_draws_modes_and_polarizations(tmp_path, capsys):
    """The modes group of `pnrotor evolve --modes`: |h_lm| and h+, hx from a chosen direction."""
    pytest.importorskip("matplotlib")
    import pnrotor
    run = pnrotor.evolve(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 100.0, sampling=1 / 4096)
    with hdf5.batch(tmp_path / "w.h5") as groups:
        groups.add("run", run)
        groups.add("modes", pnrotor.modes(run, ell_max=4, distance=100.0))
    assert main(["plot", str(tmp_path / "w.h5"), "--group", "modes", "--inclination", "0.7"]) == 0
    assert capsys.readouterr().out == f"wrote {tmp_path / 'w-modes.png'}\n"
    assert_sensible_png(tmp_path / "w-modes.png", (850, 1200))
    assert main(["plot", str(tmp_path / "w.h5"), "--group", "modes", "--inclination", "nan", "-o",
                 str(tmp_path / "nan.png")]) == 2
    assert "inclination must be a finite angle" in capsys.readouterr().err and not (tmp_path / "nan.png").exists()


def test_plot_refuses_a_population_table(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    (tmp_path / "p.csv").write_text('m1,m2,chi1,chi2,f_ref\n30,10,"0,0,0","0,0,0",100\n20,10,"0,0,0","0,0,0",100\n')
    assert main(["evolve", "--batch", str(tmp_path / "p.csv"), "--population", "-o", str(tmp_path / "p.h5")]) == 0
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "p.h5")]) == 2
    err = capsys.readouterr().err
    assert "final states of unrelated binaries" in err and err.count("\n") == 1
    assert not (tmp_path / "p.png").exists()


@pytest.mark.parametrize("modes", [False, True])
def test_plot_refuses_a_single_sample(tmp_path, capsys, modes):
    """A run sampled 'final' (and its modes) has no line to draw: a one-line refusal, no empty panels."""
    pytest.importorskip("matplotlib")
    path = tmp_path / "f.h5"
    assert main(["evolve", "--m1", "30", "--m2", "10", "--chi1", "0.6,0,0.2", "--chi2", "0,-0.4,0.1", "--f-ref", "100",
                 "--sampling", "final", "-o", str(path)]
                + ["--modes"] * modes) == 0
    capsys.readouterr()
    assert main(["plot", str(path)] + ["--group", "modes"] * modes) == 2
    err = capsys.readouterr().err
    assert "holds 1 sample of its" in err and "nothing to draw against time" in err and err.count("\n") == 1
    assert not list(tmp_path.glob("*.png"))


def test_plot_long_run_and_batch_group(files, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    hdf5.write(tmp_path / "long.h5", frame_history(n=200_001))
    assert main(["plot", str(tmp_path / "long.h5"), "-o", str(tmp_path / "long-plot.png")]) == 0
    assert_sensible_png(tmp_path / "long-plot.png", (850, 1200))
    assert main(["plot", str(files["batch"]), "--group", "pn"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == f"wrote {tmp_path / 'batch-pn.png'}"
    assert_sensible_png(tmp_path / "batch-pn.png", (850, 1200))


def test_verify_file_carries_the_binary_and_plot_draws_its_frame_error(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path = tmp_path / "verify.h5"
    assert main(["verify", "--t-end", "3e4", "-o", str(path)]) == 0
    printed = re.search(r"max δ +(\S+) at t = (\S+) ", capsys.readouterr().out)
    history = hdf5.read(path)
    alpha = math.pi / 8  # the paper's binary (eq:precession_constants), which verify integrates
    paper = {"omega": "PrecessingNutatingBinary", "Omega_orb": 2 * math.pi / 1000, "Omega_prec": 2 * math.pi / 10000,
             "alpha": alpha, "alpha_dot": 2 * alpha / 1e5, "nu": math.pi / 80, "T": 1e6}
    assert {name: history.inputs[name] for name in paper} == paper
    assert np.allclose(history.inputs["binary_R0"], [math.cos(0.3 * alpha), -math.sin(0.3 * alpha), 0, 0], atol=1e-16)
    exact = PrecessingNutatingBinary().rotor(history.t)
    assert np.array_equal(PrecessingNutatingBinary.from_inputs(history.inputs).rotor(history.t), exact)
    delta = quat.frame_error(history.R, exact)
    worst = int(delta.argmax())
    assert (f"{delta[worst]:.3e}", f"{history.t[worst]:.10g}") == printed.groups()
    assert main(["plot", str(path)]) == 0
    assert capsys.readouterr().out == f"wrote {path.with_suffix('.png')}\n"
    assert_sensible_png(path.with_suffix(".png"), (1250, 1200))  # one row more than without δ


def test_plot_draws_the_largest_frame_error_of_each_k_samples():
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from pnrotor.cli import plot

    binary = PrecessingNutatingBinary()
    n = 2 * plot.MAX_POINTS + 1
    t_eval = np.linspace(0.0, 3e4, n)
    history = integrate_angular_velocity(binary, (0.0, 3e4), binary.rotor(0.0), atol=1e-8, t_eval=t_eval)
    figure = Figure()
    plot._frame_history(figure, history, PrecessingNutatingBinary.from_inputs(history.inputs))
    axes = figure.axes[-1]
    delta = quat.frame_error(history.R, binary.rotor(history.t))
    assert axes.get_yscale() == "log" and f"max δ = {delta.max():.3e}" in axes.get_title()
    assert "the largest δ of each 3 samples" in axes.get_title()
    t, drawn = axes.lines[0].get_data()
    assert np.array_equal(t, history.t[::3])
    assert np.array_equal(drawn, [delta[i : i + 3].max() for i in range(0, n, 3)])


def test_plot_without_matplotlib(files, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)
    assert main(["plot", str(files["pn"])]) == 2
    assert capsys.readouterr().err == "pnrotor plot: error: plotting needs matplotlib: pip install 'pnrotor[plot]'\n"
    assert not files["pn"].with_suffix(".png").exists()


def test_plot_output_folder_missing(files, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    assert main(["plot", str(files["pn"]), "-o", str(tmp_path / "no" / "x.png")]) == 2
    assert f"folder {tmp_path / 'no'} does not exist" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------------
# bad files: exit 2, one line, no traceback
# --------------------------------------------------------------------------------------------------


def bad_file(tmp_path, what):
    path = tmp_path / f"{what}.h5"
    if what == "truncated":
        hdf5.write(path, frame_history(n=5001))
        path.write_bytes(path.read_bytes()[:20_000])
    elif what == "foreign":
        with h5py.File(path, "w") as f:
            f["data"] = np.arange(3.0)
    elif what == "text":
        path.write_text("not hdf5\n")
    elif what == "newer":
        hdf5.write(path, frame_history())
        with h5py.File(path, "r+") as f:
            f.attrs["pnrotor_schema"] = 99
    return path


BAD = [
    ("missing", "no such file"),
    ("truncated", "is truncated or corrupt"),
    ("foreign", "an HDF5 file but not a pnrotor file"),
    ("text", "is not an HDF5 file"),
    ("newer", "schema version 99 .*upgrade pnrotor"),
]


@pytest.mark.parametrize("command", ["inspect", "plot"])
@pytest.mark.parametrize("what, message", BAD)
def test_bad_files_exit_2_with_one_line(tmp_path, capsys, command, what, message):
    path = bad_file(tmp_path, what)
    assert main([command, str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert len(captured.err.splitlines()) == 1
    assert captured.err.startswith(f"pnrotor {command}: error: ")
    assert re.search(message, captured.err)


def test_missing_batch_group(files, capsys):
    assert main(["inspect", str(files["batch"]), "--group", "nope"]) == 2
    assert "has no run 'nope'; its runs are ['frames', 'pn']" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["inspect", "plot"])
def test_command_line_without_traceback(tmp_path, command):
    path = bad_file(tmp_path, "truncated")
    done = subprocess.run([sys.executable, "-m", "pnrotor", command, str(path)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith(f"pnrotor {command}: error: {path} is truncated or corrupt: HDF5 cannot open it (")
    assert done.stderr.count("\n") == 1


def test_plot_and_inspect_show_a_run_with_its_modes_without_options(tmp_path, capsys, monkeypatch):
    """The file of `pnrotor evolve --modes` (groups run and modes): `plot FILE` draws both (it said "is a batch
    file; choose a run"), its time axes in M and in seconds (t_seconds = t M), the v panel with the GW frequency
    f = v³/(π M); `inspect FILE` prints both groups."""
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    import pnrotor
    run = pnrotor.evolve(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 100.0, sampling=1 / 4096)
    with hdf5.batch(tmp_path / "w.h5") as groups:
        groups.add("run", run)
        groups.add("modes", pnrotor.modes(run, ell_max=3))
    drawn = []
    savefig = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda self, *args, **kw: (drawn.append(self), savefig(self, *args, **kw))[1])
    assert main(["plot", str(tmp_path / "w.h5")]) == 0
    assert capsys.readouterr().out == f"wrote {tmp_path / 'w.png'}\n"
    assert_sensible_png(tmp_path / "w.png", (1700, 1200))
    axes = drawn[0].axes
    titles = [a.get_title() for a in axes]
    assert any(t.startswith("v(t)") for t in titles) and any(t.startswith("inertial modes") for t in titles)
    assert any(t.startswith("polarizations") for t in titles)
    M = run.t_seconds[-1] / run.t[-1]
    timed = [a for a in axes if a.get_xlabel() == "t [M]"]
    assert len(timed) == 5  # v, χ₁, χ₂, |h_lm|, h+ and hx
    for a in timed:
        seconds = [c for c in a.child_axes if c.get_xlabel() == "t [s]"]
        assert len(seconds) == 1 and np.allclose(seconds[0].get_xlim(), np.array(a.get_xlim()) * M, rtol=1e-12)
    v_panel = next(a for a in axes if a.get_title().startswith("v(t)"))
    (f_axis,) = [c for c in v_panel.child_axes if c.get_ylabel() == "GW frequency [Hz]"]
    assert np.allclose(f_axis.get_ylim(), np.array(v_panel.get_ylim()) ** 3 / (math.pi * M), rtol=1e-12)
    assert np.isclose(run.f_gw[0], run.v[0] ** 3 / (math.pi * M), rtol=1e-12)  # the panel's f is the run's f_gw

    out = inspect_output(capsys, tmp_path / "w.h5")
    assert f"{tmp_path / 'w.h5'} run 'run': Evolution\n" in out and f"{tmp_path / 'w.h5'} run 'modes': Modes\n" in out
    assert out.count("summary\n") == 2 and "12 modes, l = 2 ... 3" in out and "batch file" not in out


def test_plot_prints_the_coarse_sampling_warning_on_one_line(tmp_path, capsys):
    """The modes of a run sampled at its steps draw coarse polarizations: pnrotor plot says so in one line, as
    pnrotor evolve does (it printed Python's warning with its source line)."""
    pytest.importorskip("matplotlib")
    import pnrotor
    run = pnrotor.evolve(30.0, 10.0, (0.6, 0.0, 0.2), (0.0, -0.4, 0.1), 20.0)   # steps of > pi/2
    with hdf5.batch(tmp_path / "w.h5") as groups:
        groups.add("run", run)
        groups.add("modes", pnrotor.modes(run, ell_max=2))
    assert main(["plot", str(tmp_path / "w.h5")]) == 0
    err = capsys.readouterr().err
    assert err.startswith("pnrotor plot: warning: polarizations of a run sampled at sampling='steps' are coarse")
    assert err.count("\n") == 1
