"""Population mode of a batch: the final state of every row of a table, from `pnrotor.evolve_many`, in one file.

``pnrotor evolve --batch F.csv --population`` (``pnrotor.batch.population.run(F.csv, OUT.h5)`` from Python).
This module owns that mode and :class:`PopulationTable`, the dataclass of its file (``kind`` =
``"PopulationTable"`` in `pnrotor.hdf5`; layout in docs/hdf5-schema.md):

* the rows are those of :mod:`~pnrotor.batch.table`, checked first (a bad value marks its row only); an
  empty sampling cell means ``final`` here, and a row this mode cannot compute is marked too
  (:func:`unsupported`): a sampling other than final, f_min and f_max together, or masses and frequencies that
  `pnrotor.evolve` refuses (its own check and message: e.g. an f_max not above f_ref, or a NaN cell, which
  `evolve_many` would take as the end of the inspiral);
* the rows that share the options `evolve_many` takes as shared (:data:`SHARED`) are computed by one call of
  it, each row to its own target: f_max forward, else f_min backward, else the end of the inspiral.  A row
  evolve_many marks ``'invalid'`` fails with its message; a group whose shared options it refuses (e.g. a
  pn_order of 5) fails whole, each row with that message;
* the rows that succeeded, in the table's order, are written as one :class:`PopulationTable` with
  `pnrotor.hdf5.write` (atomic: nothing is left by an error or Ctrl-C; checksums as for runs).

Each state is bitwise what `pnrotor.evolve` gives for that row: with f_max or neither, its final sample with
``sampling='final'``; with f_min, its first sample, the state at f_min (``evolve``'s ``'final'`` sampling is the
forward end, which a row with f_min does not ask for here).  The outcome is a `pnrotor.batch.Outcome`, as
for batches: failures in ``row.error``, the others written.
"""

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pnrotor.batch import Outcome, check_output, read_batch
from pnrotor.history import short_repr

__all__ = ["PopulationTable", "Plan", "plan", "run", "unsupported", "SHARED"]

SHARED = ("approximant", "pn_order", "spin_orbit_order", "spin_spin_order", "precession", "atol", "tidal_order",
          "horizon_absorption")
"""The table's columns that `evolve_many` takes as shared by all its binaries: one call per combination."""

FIELDS = ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat", "termination", "message", "nsteps", "nfev")
"""The fields of `pnrotor.Population` that a :class:`PopulationTable` keeps, row by row."""


@dataclass
class PopulationTable:
    """The final states of a table's rows (those that succeeded, in the table's order), one entry per row.

    Attributes
    ----------
    name : (N,) str — the row's name (its name column, or `pnrotor.batch.table.default_name`)
    t, t_seconds, v, Phi, chi1, chi2, R, ell_hat, termination, message, nsteps, nfev : as in
        `pnrotor.Population` (the state, why its integration stopped and that integration's work), (N,),
        (N, 3) or (N, 4)
    inputs : dict — per row (arrays of N): ``row`` (its number in the table, from 1), ``m1_Msun``,
        ``m2_Msun``, ``chi1``, ``chi2`` (at f_ref), ``f_ref_Hz``, ``f_min_Hz``, ``f_max_Hz`` (NaN where absent),
        ``approximant``, ``pn_order``, ``spin_orbit_order``, ``spin_spin_order`` (NaN: evolve's default),
        ``precession``, ``atol``, ``lambda1``, ``lambda2``, ``tidal_order`` (NaN: evolve's default),
        ``horizon_absorption`` (bool); and the options
        every row shares (``rtol``, ``rotor``, ...), as
        `Population.inputs` has them
    """

    name: np.ndarray
    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: np.ndarray
    message: np.ndarray
    nsteps: np.ndarray
    nfev: np.ndarray
    inputs: dict = field(default_factory=dict)

    __repr__ = short_repr

    def __len__(self):
        return self.t.shape[0]


def unsupported(params):
    """Why this mode cannot compute a row of `pnrotor.evolve` keywords (a message naming the column), or None."""
    sampling = params["sampling"]
    if sampling != "final":
        text = (f"per_orbit:{sampling[1]}" if isinstance(sampling, tuple) else
                f"a time step of {sampling!r} s" if isinstance(sampling, float) else sampling)
        return f"sampling must be final (or empty) in the population mode, which gives final states only; got {text}"
    if params["f_min"] is not None and params["f_max"] is not None:
        return ("f_min and f_max are both given: the population mode gives one state per row, at f_max (forward), "
                "at f_min (backward) or at the end of the inspiral; give at most one of them")
    # evolve's checks of the masses, spins and frequencies, in its order (so a row with two faults gets evolve's
    # message): evolve_many takes its target on either side of f_ref (and NaN as the end of the inspiral), while
    # a row's f_max must lie above f_ref and its f_min below, both finite
    from pnrotor.pn import initial, settings

    try:
        given = settings.masses_and_frequencies(*(params[key] for key in ("m1", "m2", "f_ref", "f_min", "f_max")))
        for name in ("chi1", "chi2"):
            initial.spin_vector(params[name], name)
        settings.frequencies(*given)
    except ValueError as error:
        return str(error)
    return None


@dataclass(eq=False)
class Plan:
    """A checked population, not yet computed: its rows (failures marked), the output file and its storage."""

    rows: list
    path: Path
    overwrite: bool = False
    storage: dict = field(default_factory=dict)
    create_folder: bool = False

    @property
    def groups(self):
        """{values of :data:`SHARED`: [row index]}: the rows each `evolve_many` call computes."""
        groups = {}
        for index, row in enumerate(self.rows):
            if row.error is None:
                groups.setdefault(_shared(row.params), []).append(index)
        return groups

    def run(self):
        """Compute the rows, one `evolve_many` call per group, then write the file of those that succeeded
        (none: no file) → `pnrotor.batch.Outcome` (no briefs)."""
        from pnrotor import hdf5

        start = time.perf_counter()
        parts, seconds = [], 0.0
        for shared, indices in self.groups.items():
            began = time.perf_counter()
            result = self._evolve(shared, [self.rows[i].params for i in indices])
            seconds += time.perf_counter() - began
            if isinstance(result, str):   # the group's shared options were refused
                for i in indices:
                    self.rows[i].error = result
                continue
            for i, termination, message in zip(indices, result.termination, result.message):
                if termination == "invalid":
                    self.rows[i].error = message
            parts.append((np.array(indices), result))
        table = self._table(parts)
        if table is not None:
            if self.create_folder:
                self.path.parent.mkdir(exist_ok=True)
            hdf5.write(self.path, table, overwrite=self.overwrite, **self.storage)
        written = 0 if table is None else len(table)
        return Outcome(self.rows, {}, self.path if written else None, written, time.perf_counter() - start, seconds)

    @staticmethod
    def _evolve(shared, params):
        """`evolve_many` on one group's rows → its `Population`, or the message of its ValueError."""
        from pnrotor.pn.many import evolve_many

        column = lambda key: [p[key] for p in params]  # noqa: E731
        f_end = [p["f_max"] if p["f_max"] is not None else p["f_min"] for p in params]
        try:
            return evolve_many(column("m1"), column("m2"), column("chi1"), column("chi2"), column("f_ref"),
                               f_end=[math.nan if f is None else f for f in f_end], lambda1=column("lambda1"),
                               lambda2=column("lambda2"), **dict(zip(SHARED, shared)))
        except ValueError as error:
            return str(error)

    def _table(self, parts):
        """The :class:`PopulationTable` of the rows that succeeded, in the table's order, or None."""
        if not parts:
            return None
        indices = np.concatenate([indices for indices, _ in parts])
        ok = np.concatenate([population.termination != "invalid" for _, population in parts])
        order = np.argsort(indices[ok])
        if not order.size:
            return None
        rows = [self.rows[i] for i in indices[ok][order]]
        columns = {name: np.concatenate([getattr(population, name) for _, population in parts])[ok][order]
                   for name in FIELDS}
        nan = lambda x: math.nan if x is None else x  # noqa: E731
        per_row = {
            "row": np.array([row.number for row in rows], dtype=np.int64),
            "m1_Msun": _floats(rows, "m1"), "m2_Msun": _floats(rows, "m2"),
            "chi1": _floats(rows, "chi1"), "chi2": _floats(rows, "chi2"), "f_ref_Hz": _floats(rows, "f_ref"),
            "f_min_Hz": _floats(rows, "f_min", nan), "f_max_Hz": _floats(rows, "f_max", nan),
            "approximant": _strings(_shared(row.params)[0] for row in rows),
            "pn_order": _floats(rows, "pn_order"),
            "spin_orbit_order": _floats(rows, "spin_orbit_order", nan),
            "spin_spin_order": _floats(rows, "spin_spin_order", nan),
            "precession": _strings(row.params["precession"] for row in rows), "atol": _floats(rows, "atol"),
            "lambda1": _floats(rows, "lambda1"), "lambda2": _floats(rows, "lambda2"),
            "tidal_order": _floats(rows, "tidal_order", nan),
            "horizon_absorption": np.array([row.params["horizon_absorption"] for row in rows], dtype=bool),
        }
        common = {key: value for key, value in parts[0][1].inputs.items() if key not in SHARED}
        return PopulationTable(name=_strings(row.name for row in rows), **columns,
                               inputs={**per_row, **common, "sampling": "final"})


def _shared(params):
    """A row's values of :data:`SHARED`, the approximant by its canonical name (so T4 and TaylorT4 share a call)."""
    from pnrotor.pn.settings import normalize_approximant

    return (normalize_approximant(params["approximant"]),) + tuple(params[key] for key in SHARED[1:])


def _floats(rows, key, convert=lambda x: x):
    return np.array([convert(row.params[key]) for row in rows], dtype=np.float64)


def _strings(values):
    values = list(values)
    strings = np.empty(len(values), dtype=object)
    strings[:] = values
    return strings


def plan(table, output, *, overwrite=False, compression=None, checksum=True, defaults=None, create_folder=False):
    """Check a population before it is computed → :class:`Plan`.

    ``table``: a CSV or TOML batch file (`pnrotor.batch.table.read_batch`; ``defaults`` fill its empty cells,
    then ``sampling='final'``, then the table's defaults) or rows already read.  Rows this mode cannot compute
    are marked (:func:`unsupported`).  ``output``: the file to write, refused if it exists unless
    ``overwrite``; its folder must exist, or is created (not its parents) with ``create_folder`` when there is
    a row to write.  ``compression`` and ``checksum`` as in `pnrotor.hdf5.write`."""
    given = {key: value for key, value in (defaults or {}).items() if value is not None}
    rows = table if isinstance(table, list) else read_batch(table, {"sampling": "final", **given})
    path = check_output(output, overwrite)
    for row in rows:
        if row.error is None:
            row.error = unsupported(row.params)
    return Plan(rows, path, overwrite, dict(compression=compression, checksum=checksum), create_folder)


def run(table, output, **options):
    """:func:`plan` then :meth:`Plan.run`: the whole population → `pnrotor.batch.Outcome`."""
    return plan(table, output, **options).run()
