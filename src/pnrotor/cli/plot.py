"""`pnrotor plot FILE`: draw a run stored by pnrotor into a PNG (needs the plot extra, matplotlib).

Post-Newtonian runs (fields ``ell_hat``, ``v``, ``chi1``, ``chi2``): the path of ℓ̂ on the unit sphere,
v(t), and the components of χ₁ and χ₂. Frame histories: the path of the frame vector R ẑ R⁻¹ on the unit
sphere and its components, the rotor components w, x, y, z against t, and for runs longer than `ZOOM`
samples the rotor components of the first `ZOOM` samples. Frame histories of the paper's precessing and
nutating binary (those of ``pnrotor verify -o``, whose inputs describe it:
`PrecessingNutatingBinary.from_inputs`) add the frame error δ(t) of eq:error_norm against its exact
rotor, on a log scale, with its maximum. Waveform modes (``pnrotor evolve --modes``, group ``modes``):
|h_ℓm|(t) of the modes m ≥ 0 that reach 1e-3 of max |h₂₂|, and h₊, h× seen from ``--inclination`` and
``--phi-ref``; stored polarizations (``--polarizations``): h₊, h× against t in seconds. A file of
``pnrotor evolve --modes`` (groups ``run``, ``modes``) is drawn whole without ``--group``. Times are in M with
seconds on a second axis, and v(t) has the GW frequency f = v³/(π M) beside it. Lines of more than
`MAX_POINTS` samples are drawn from every k-th sample (δ: the largest of each k samples), and the panel says so.

numpy, h5py, matplotlib and pnrotor's numba code are imported only when the command runs, so that the CLI
starts quickly.
"""

import sys
import warnings
from pathlib import Path

from pnrotor.cli import UsageError
from pnrotor.cli.inspect import evolve_groups
from pnrotor.files import replaced_on_success

MAX_POINTS = 50_000
ZOOM = 2000


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "plot",
        help="draw a pnrotor HDF5 file into a PNG (needs pnrotor[plot])",
        description="Draw a run stored by pnrotor: ℓ̂ on the sphere, v(t) and spins for post-Newtonian runs; "
        "the ẑ frame vector and rotor components for frame histories, and the frame error δ(t) for those of "
        "the paper's binary (pnrotor verify -o).",
    )
    parser.add_argument("file", help="a pnrotor HDF5 file, e.g. waveforms/NAME.h5")
    parser.add_argument("-o", "--output", metavar="PNG", help="image to write, replaced if present (default: FILE with .png)")
    parser.add_argument("--group", metavar="NAME", help="the run NAME of a batch file (modes: --group modes, or NAME.modes in a batch file)")
    parser.add_argument("--inclination", type=float, default=0.0, metavar="RAD",
                        help="modes: the line of sight's inclination for h+ and hx (default 0)")
    parser.add_argument("--phi-ref", type=float, default=0.0, metavar="RAD",
                        help="modes: the reference phase of the line of sight, LALSuite's convention (default 0)")
    parser.set_defaults(func=run)


def run(args):
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise UsageError("plotting needs matplotlib: pip install 'pnrotor[plot]'") from None
    output = Path(args.output) if args.output else _default_output(Path(args.file), args.group)
    if not output.parent.is_dir():
        raise FileNotFoundError(f"folder {output.parent} does not exist (writing {output})")
    from pnrotor import hdf5

    results = [(group, hdf5.read(args.file, group)) for group in evolve_groups(args.file, args.group)]
    for group, result in results:
        _check_drawable(args.file, result)
    heights, draws = zip(*(_panel(result) for _, result in results))
    figure = Figure(figsize=(12, sum(heights)), layout="constrained")
    title = args.file if args.group in (None, "/") else f"{args.file} run {args.group!r}"
    figure.suptitle(f"{title}: " + ", ".join(f"{type(result).__name__}" + (f" ({group})" if len(results) > 1 else "")
                                             for group, result in results))
    panels = figure.subfigures(len(results), 1, height_ratios=heights) if len(results) > 1 else [figure]
    with warnings.catch_warnings(record=True) as caught:   # each on one line, as pnrotor evolve prints them
        warnings.simplefilter("always")
        for panel, draw in zip(panels, draws):
            draw(panel, args)
    for warning in caught:
        print(f"pnrotor plot: warning: {warning.message}", file=sys.stderr)
    with replaced_on_success(output) as temporary:
        figure.savefig(temporary, dpi=100)
    print(f"wrote {output}")
    return 0


def _check_drawable(file, result):
    kind = type(result).__name__
    if kind == "PopulationTable":
        raise UsageError(f"{file} holds the final states of unrelated binaries (a PopulationTable): nothing to "
                         "draw against time; `pnrotor inspect` or h5py reads it")
    n = result.t_seconds.size if kind == "Polarizations" else result.t.size
    if n < 2:
        raise UsageError(f"{file} holds {n} sample{'s' * (n != 1)} of its {kind} (sampling "
                         "'final'?): nothing to draw against time; `pnrotor inspect` prints it")


def _post_newtonian_run(result):
    return all(hasattr(result, name) for name in ("ell_hat", "v", "chi1", "chi2"))


def _panel(result):
    """(height in inches, draw(figure, args)) of `result`'s panels (the paper's binary adds a row for δ(t))."""
    kind = type(result).__name__
    if kind == "Modes":
        return 8.5, lambda figure, args: _modes(figure, result, args.inclination, args.phi_ref)
    if kind == "Polarizations":
        return 4.5, lambda figure, args: _polarizations(figure.add_subplot(1, 1, 1), result)
    if _post_newtonian_run(result):
        return 8.5, lambda figure, args: _post_newtonian(figure, result)
    binary = _binary(result)
    return 8.5 if binary is None else 12.5, lambda figure, args: _frame_history(figure, result, binary)


def _default_output(file, group):
    return file.with_name(file.stem + ("" if group in (None, "/") else f"-{group}") + ".png")


def _post_newtonian(figure, result):
    every = _stride(result.t.size)
    t = result.t[::every]
    _sphere(figure.add_subplot(2, 2, 1, projection="3d"), result.ell_hat[::every], "ℓ̂ (orbital plane normal)", every)
    v = figure.add_subplot(2, 2, 2)
    v.plot(t, result.v[::every])
    v.set(ylabel="v = (M Ω)^(1/3)", title="v(t) and the GW frequency f = v³/(π M)")
    M = _seconds_per_M(result)
    _time_axes(v, M)
    if M is not None:
        import numpy as np

        v.secondary_yaxis("right", functions=(lambda x: x ** 3 / (np.pi * M), lambda f: np.cbrt(np.pi * M * f))
                          ).set_ylabel("GW frequency [Hz]")
    for position, name, symbol in ((3, "chi1", "χ₁"), (4, "chi2", "χ₂")):
        axes = figure.add_subplot(2, 2, position)
        for component, label in enumerate("xyz"):
            axes.plot(t, getattr(result, name)[::every, component], label=f"{symbol}{label}")
        axes.set(ylabel=symbol, title=f"{symbol} components (inertial frame)")
        _time_axes(axes, _seconds_per_M(result))
        axes.legend(loc="best")


def _modes(figure, modes, inclination, phi_ref):
    """|h_ℓm|(t) of the modes reaching 1e-3 of max |h₂₂| (log scale), and h₊, h× from (ι, φ_ref)."""
    import numpy as np

    every = _stride(modes.t.size)
    t = modes.t[::every]
    inertial = modes.in_frame("inertial")
    unit = "strain" if modes.distance_Mpc is not None else "r h / M"
    amplitudes = figure.add_subplot(2, 1, 1)
    floor = 1e-3 * np.abs(inertial.mode(2, 2)).max()
    for ell, m in modes.ell_m:
        magnitude = np.abs(inertial.mode(ell, m))
        if m >= 0 and magnitude.max() > floor:
            amplitudes.semilogy(t, magnitude[::every], lw=0.8, label=f"({ell},{m})")
    _time_axes(amplitudes, _seconds_per_M(modes))
    amplitudes.set(ylabel=f"|h_lm| [{unit}]",
                   title=f"inertial modes, m ≥ 0, those above 1e-3 of max |h22| ({modes.frame} frame stored)"
                   f"{_sampling(every)}")
    amplitudes.legend(loc="upper left", ncol=6, fontsize="small")
    plus, cross = modes.polarizations(inclination, phi_ref)
    waves = figure.add_subplot(2, 1, 2)
    waves.plot(t, plus[::every], lw=0.6, label="h+")
    waves.plot(t, cross[::every], lw=0.6, label="hx")
    _time_axes(waves, _seconds_per_M(modes))
    waves.set(ylabel=unit, title=f"polarizations, inclination {inclination:g} rad, "
              f"phi_ref {phi_ref:g} rad{_sampling(every)}")
    waves.legend(loc="upper left")


def _polarizations(axes, result):
    """h₊ and h× (strain) against t in seconds."""
    every = _stride(result.t_seconds.size)
    t = result.t_seconds[::every]
    axes.plot(t, result.h_plus[::every], lw=0.6, label="h+")
    axes.plot(t, result.h_cross[::every], lw=0.6, label="hx")
    axes.set(xlabel="t [s]", ylabel=f"strain at {result.distance_Mpc:g} Mpc",
             title=f"polarizations, inclination {result.inclination:g} rad, phi_ref {result.phi_ref:g} rad"
             f"{_sampling(every)}")
    axes.legend(loc="upper left")


def _seconds_per_M(result):
    """The total mass M in seconds (G M / c³) of a run or its modes, or None if its inputs do not say."""
    inputs = getattr(result, "inputs", None)
    return inputs.get("M_seconds") if isinstance(inputs, dict) else None


def _time_axes(axes, M):
    """t in M on the x axis, and in seconds (t_seconds = t M) on a second x axis above it when M is known."""
    axes.set_xlabel("t [M]")
    if M is not None:
        axes.secondary_xaxis("top", functions=(lambda t: t * M, lambda s: s / M)).set_xlabel("t [s]")


def _binary(result):
    """The `PrecessingNutatingBinary` whose ω the frame history `result` integrated, or None."""
    from pnrotor.analytic import PrecessingNutatingBinary

    return PrecessingNutatingBinary.from_inputs(result.inputs)


def _frame_history(figure, result, binary):
    import numpy as np

    from pnrotor.quaternion import rotate

    grid = figure.add_gridspec(2 if binary is None else 3, 2)
    every = _stride(result.t.size)
    t, R = result.t[::every], result.R[::every]
    z = rotate(R, np.array([0.0, 0.0, 1.0])) if R.size else np.empty((0, 3))
    _sphere(figure.add_subplot(grid[0, 0], projection="3d"), z, "frame vector R ẑ R⁻¹", every)
    _components(figure.add_subplot(grid[0, 1]), t, z, "xyz", f"R ẑ R⁻¹ components{_sampling(every)}")
    _components(figure.add_subplot(grid[1, 0]), t, R, "wxyz", f"rotor components{_sampling(every)}")
    if result.t.size > ZOOM:  # fast rotation fills the full-range panel; show its start at full resolution
        title = f"rotor components, first {ZOOM} samples"
        _components(figure.add_subplot(grid[1, 1]), result.t[:ZOOM], result.R[:ZOOM], "wxyz", title)
    if binary is not None:
        _frame_error(figure.add_subplot(grid[2, :]), result, binary, every)


def _frame_error(axes, result, binary, every):
    """δ(t) of eq:error_norm against the exact rotor of `binary`, the largest of each `every` samples."""
    import numpy as np

    delta = binary.frame_error(result.t, result.R)
    title = "frame error δ against the exact rotor (Boyle 2016, eq:error_norm)"
    if delta.size:
        worst = int(delta.argmax())
        starts = np.arange(0, delta.size, every)
        axes.plot(result.t[starts], np.maximum.reduceat(delta, starts), lw=0.8)
        title += f", max δ = {delta[worst]:.3e} at t = {result.t[worst]:.10g}"
        if every > 1:
            title += f"\n(the largest δ of each {every} samples)"
    axes.set_yscale("log")
    axes.set(xlabel="t", ylabel="δ", title=title)


def _components(axes, t, values, labels, title):
    for component, label in enumerate(labels):
        axes.plot(t, values[:, component], label=label, lw=0.8)
    axes.set(xlabel="t", ylabel="component", title=title)
    axes.legend(loc="upper right")


def _sphere(axes, path, name, every):
    """The unit sphere as a light wireframe, `path` (K, 3) on it, its start and end marked."""
    import numpy as np

    u, w = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    axes.plot_wireframe(np.cos(u) * np.sin(w), np.sin(u) * np.sin(w), np.cos(w), color="0.85", lw=0.5)
    axes.plot(*path.T, lw=0.8)
    if len(path):
        axes.scatter(*path[0], color="green", label="start")
        axes.scatter(*path[-1], color="red", label="end")
        axes.legend(loc="upper left")
    axes.set(xlabel="x", ylabel="y", zlabel="z", title=f"{name} on the unit sphere{_sampling(every)}")
    axes.set_box_aspect((1, 1, 1))


def _stride(n):
    return max(1, -(-n // MAX_POINTS))


def _sampling(every):
    return "" if every == 1 else f"\n(drawn from every k-th sample, k = {every})"
