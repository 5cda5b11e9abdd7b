"""The parameters of a binary as a table names them (a batch table's columns, a DataFrame's for `pnrotor.evolve_many`,
the CLI's options): `pnrotor.evolve`'s keywords.  Imports nothing, so that `pnrotor.batch.table` (read by the CLI
before numba loads) and `pnrotor.pn.many` both take them from here."""

DEFAULTS = {
    "approximant": "T4", "pn_order": 3.5, "spin_orbit_order": None, "spin_spin_order": None,
    "precession": "averaged", "f_min": None, "f_max": None, "sampling": "steps", "atol": 1e-12,
    "lambda1": 0.0, "lambda2": 0.0, "tidal_order": None, "horizon_absorption": False,
}
"""Defaults of the optional run parameters (those of `pnrotor.evolve`; None: evolve's own choice)."""

REQUIRED = ("m1", "m2", "chi1", "chi2", "f_ref")
COLUMNS = REQUIRED + tuple(DEFAULTS) + ("name",)
"""Columns of a batch CSV file (keys of a TOML ``[[binary]]`` table): the option names with ``_``."""
