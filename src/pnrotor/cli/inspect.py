"""`pnrotor inspect FILE`: print what a pnrotor HDF5 file holds.

For one run: its kind, schema and pnrotor version, creation time, the sample count and time range, every
array (shape, dtype, units), every scalar and every dict field (inputs, statistics) with exact values,
then a short summary — for post-Newtonian runs the duration in M and s, the number of orbits ΔΦ/2π,
the first and final v and the termination; for waveform modes which modes, their units, the span and the
largest amplitudes; for frame histories the formulation, method, tolerances, status and integrator work; for
a population file (`PopulationTable`) the count of each termination.  For a batch file: its runs, or one run
with ``--group``; for a file of ``pnrotor evolve --modes`` (groups ``run``, ``modes``): every group.

numpy and h5py are imported only when the command runs, so that the CLI starts quickly.
"""

import math


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "inspect",
        help="print the attributes and a summary of a pnrotor HDF5 file",
        description="Print the metadata, inputs, statistics and a summary of a run stored by pnrotor.",
    )
    parser.add_argument("file", help="a pnrotor HDF5 file, e.g. waveforms/NAME.h5")
    parser.add_argument("--group", metavar="NAME", help="the run NAME of a batch file (default: list its runs)")
    parser.set_defaults(func=run)


def run(args):
    from pnrotor import hdf5

    groups = evolve_groups(args.file, args.group)
    if len(groups) > 1:
        print("\n\n".join("\n".join(describe(args.file, group)) for group in groups))
        return 0
    runs = hdf5.list_runs(args.file)
    if args.group is None and runs != ["/"]:
        print(f"{args.file}: batch file with {len(runs)} run{'s' * (len(runs) != 1)}")
        for name in runs:
            meta = hdf5.metadata(args.file, name)
            print(f"  {name}  {meta['kind']}, created {meta['created']}")
        print("show one with: pnrotor inspect FILE --group NAME")
        return 0
    print("\n".join(describe(args.file, args.group)))
    return 0


EVOLVE_GROUPS = ("run", "modes", "polarizations")
"""The groups of a file of ``pnrotor evolve --modes`` or ``--polarizations``, in the order they are drawn."""


def evolve_groups(path, group):
    """The groups to show of `path`: `group` if given; all of them for a file of ``pnrotor evolve --modes`` (a run
    and its modes or polarizations); else the file's one run (None: `hdf5.read` names a batch file's runs)."""
    from pnrotor import hdf5

    if group is not None:
        return [group]
    runs = hdf5.list_runs(path)
    if "run" in runs and set(runs) <= set(EVOLVE_GROUPS):
        return [name for name in EVOLVE_GROUPS if name in runs]
    return [None]


def describe(path, group=None):
    """The lines `pnrotor inspect` prints for the run in `path` (batch group `group`)."""
    import dataclasses

    import numpy as np

    from pnrotor import hdf5

    meta = hdf5.metadata(path, group)
    result = hdf5.read(path, group)
    units = hdf5.UNITS.get(meta["kind"], {})
    where = path if group in (None, "/") else f"{path} run {group!r}"
    lines = [
        f"{where}: {meta['kind']}",
        f"  pnrotor schema {meta['pnrotor_schema']}, written by pnrotor {meta['pnrotor_version']}, created {meta['created']}",
    ]
    t = getattr(result, "t", None)
    if isinstance(t, np.ndarray) and t.ndim == 1 and not _is_population(result):
        span = f", t from {t[0].item()!r} to {t[-1].item()!r}" if t.size else ""
        lines.append(f"  {t.size} samples{span}")

    fields = [(f.name, getattr(result, f.name)) for f in dataclasses.fields(result) if f.name not in hdf5.NOT_WRITTEN]
    arrays = [(name, value) for name, value in fields if isinstance(value, np.ndarray)]
    lines.append("arrays")
    lines += _table((name, f"{value.shape} {value.dtype}" + (f"  [{units[name]}]" if name in units else "")) for name, value in arrays)
    scalars = [(name, value) for name, value in fields if not isinstance(value, (np.ndarray, dict))]
    lines.append("attributes")
    lines += _table((name, _format(value)) for name, value in scalars)
    for name, value in fields:
        if isinstance(value, dict):
            lines.append(name)
            lines += _items(value)
    lines.append("summary")
    lines += ["  " + line for line in summary(result)]
    return lines


def _is_population(result):
    """Whether `result` holds one state per binary (a `PopulationTable`): a termination per row."""
    import numpy as np

    return isinstance(getattr(result, "termination", None), np.ndarray)


def summary(result):
    """A few lines that say what the run did, from its fields (duck-typed, so any run kind works)."""
    if _is_population(result):
        from collections import Counter

        counts = Counter(result.termination.tolist()).most_common()
        return [f"{len(result.termination)} final states, one per binary",
                "terminations: " + ", ".join(f"{name} {count}" for name, count in counts)]
    t, v, Phi = (getattr(result, name, None) for name in ("t", "v", "Phi"))
    if v is not None and Phi is not None:
        if t.size == 0:
            return ["no samples"]
        duration = f"{t[-1] - t[0]:.6g} M"
        t_seconds = getattr(result, "t_seconds", None)
        if t_seconds is not None:
            duration += f" = {t_seconds[-1] - t_seconds[0]:.6g} s"
        return [
            f"duration {duration}",
            f"orbits {(Phi[-1] - Phi[0]) / (2 * math.pi):.6g} (ΔΦ/2π)",
            f"v from {v[0]:.6g} to {v[-1]:.6g} (final)",
            f"termination: {getattr(result, 'termination', 'not recorded')}",
        ]
    if hasattr(result, "ell_m"):   # waveform modes
        return _modes_summary(result)
    if hasattr(result, "h_plus"):   # polarizations
        import numpy as np

        t, hp, hc = result.t_seconds, result.h_plus, result.h_cross
        if t.size == 0:
            return ["no samples"]
        return [f"h+, hx at inclination {result.inclination:g} rad, phi_ref {result.phi_ref:g} rad, strain at "
                f"{result.distance_Mpc:g} Mpc",
                f"duration {t[-1] - t[0]:.6g} s, max |h+| {np.abs(hp).max():.4g}, max |hx| {np.abs(hc).max():.4g}"]
    if hasattr(result, "formulation"):
        r = result
        return [
            f"{r.formulation} formulation, {r.method}, atol {r.atol:g}, rtol {r.rtol:g}",
            f"status {r.status}: {r.message}",
            f"{r.nfev} right-hand-side evaluations, {r.nsteps} steps ({r.naccepted} accepted, {r.nrejected} rejected), "
            f"{r.n_resets} generator resets, {r.wall_time:.3g} s wall time",
        ]
    return ["no summary for this kind of run"]


def _modes_summary(h):
    """What a `Modes` holds: which modes and in what units, the span, and the largest amplitudes."""
    import numpy as np

    order = h.inputs.get("amplitude_order") if isinstance(h.inputs, dict) else None
    lines = [f"{len(h.ell_m)} modes, l = 2 ... {h.ell_max}"
             + ("" if order is None else f", amplitude order {order:g} PN") + f", {h.frame} frame",
             f"units: strain at {h.distance_Mpc:g} Mpc" if h.distance_Mpc is not None else "units: r h / M"]
    if h.t.size == 0:
        return lines + ["no samples"]
    lines.append(f"duration {h.t[-1] - h.t[0]:.6g} M = {h.t_seconds[-1] - h.t_seconds[0]:.6g} s")
    peaks = np.abs(h.data).max(axis=1)
    ranked = np.argsort(-peaks, kind="stable")[:4]
    lines.append("largest max |h_lm|: " + ", ".join(f"({h.ell_m[k][0]}, {h.ell_m[k][1]}) {peaks[k]:.4g}"
                                                    for k in ranked))
    return lines


def _items(values, indent="  "):
    """A dict field as an aligned table, sorted by key, nested dicts indented below their key."""
    lines = _table(((name, _format(value)) for name, value in sorted(values.items()) if not isinstance(value, dict)), indent)
    for name, value in sorted(values.items()):
        if isinstance(value, dict):
            lines.append(f"{indent}{name}")
            lines += _items(value, indent + "  ")
    return lines


def _table(rows, indent="  "):
    rows = list(rows)
    width = max((len(name) for name, _ in rows), default=0)
    return [f"{indent}{name:<{width}}  {text}" for name, text in rows]


def _format(value):
    """Exact text for a stored value: shortest round-trip floats, small arrays in full, large ones summarized."""
    import numpy as np

    if isinstance(value, np.ndarray):
        if value.size <= 8:
            return f"{np.array2string(value, separator=', ', floatmode='unique')} {value.dtype}"
        if value.dtype.kind not in "biuf":   # text (e.g. a population's per-row options): its distinct values
            distinct = sorted({str(x) for x in value.flat})
            return f"{value.shape} {value.dtype}, {len(distinct)} distinct: " + ", ".join(map(repr, distinct[:8])) + \
                (", ..." if len(distinct) > 8 else "")
        finite = value[np.isfinite(value)] if value.dtype.kind == "f" else value.ravel()
        missing = value.size - finite.size   # NaN (a population's empty cell) or inf: counted apart
        span = f"from {finite.min().item()!r} to {finite.max().item()!r}" if finite.size else "no finite value"
        return f"{value.shape} {value.dtype}, {span}" + (f", {missing} not finite" if missing else "")
    return repr(value)
