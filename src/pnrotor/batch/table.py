"""Batch tables: CSV or TOML files of binaries → rows of `pnrotor.evolve` keywords, checked before anything runs.

A CSV file has one binary per row, with columns named like `pnrotor.evolve`'s keywords (:data:`COLUMNS`;
vectors as ``"x,y,z"`` strings); a TOML file has one ``[[binary]]`` table per binary with the same keys
(vectors as arrays).  Empty cells take the caller's defaults (the CLI's options), then :data:`DEFAULTS`.
Problems of the file itself (missing, unreadable, unknown or missing columns, repeated names) raise
``ValueError`` (``FileNotFoundError``/``IsADirectoryError`` for the path); a bad value only marks its row
(:attr:`Row.error`), so one bad binary does not stop the others.  Group names default to
:func:`default_name`, built from the parameters.
"""

import math
from pathlib import Path

DEFAULTS = {
    "approximant": "T4", "pn_order": 3.5, "spin_orbit_order": None, "spin_spin_order": None,
    "precession": "averaged", "f_min": None, "f_max": None, "sampling": "steps", "atol": 1e-12,
    "lambda1": 0.0, "lambda2": 0.0, "tidal_order": None, "horizon_absorption": False,
}
"""Defaults of the optional run parameters (those of `pnrotor.evolve`; None: evolve's own choice)."""

REQUIRED = ("m1", "m2", "chi1", "chi2", "f_ref")
COLUMNS = REQUIRED + tuple(DEFAULTS) + ("name",)
"""Columns of a batch CSV file (keys of a TOML ``[[binary]]`` table): the option names with ``_``."""


def parse_vector(text, name):
    """Three finite floats from ``"x,y,z"`` (or a sequence of three numbers); the error names `name`."""
    items = text.split(",") if isinstance(text, str) else text
    try:
        if isinstance(items, (str, bytes)) or len(items) != 3 or any(isinstance(x, bool) for x in items):
            raise ValueError
        vector = tuple(float(x) for x in items)
    except (TypeError, ValueError):
        vector = ()
    if len(vector) != 3 or not all(math.isfinite(x) for x in vector):
        raise ValueError(f"{name} must be three finite numbers separated by commas, such as 0.6,0,0.2; got {text!r}")
    return vector


def parse_sampling(value, name="--sampling"):
    """`pnrotor.evolve`'s ``sampling`` from 'steps', 'final', 'per_orbit:N' or Δt seconds ('1/4096', '0.000244')."""
    if not isinstance(value, str):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        raise ValueError(f"{name} must be a string or a number of seconds, got {value!r}")
    text = value.strip().lower()
    if text in ("steps", "final"):
        return text
    if text.startswith("per_orbit:"):
        count = text.partition(":")[2].strip()
        if not (count.isascii() and count.isdigit()) or int(count) < 1:   # '²'.isdigit() is True
            raise ValueError(f"{name} per_orbit:N needs a positive integer N, got {value!r}")
        return ("per_orbit", int(count))
    try:
        numerator, slash, denominator = text.partition("/")
        return float(numerator) / float(denominator) if slash else float(text)
    except (ValueError, ZeroDivisionError):
        raise ValueError(f"{name} must be steps, final, per_orbit:N or a time step in seconds such as 1/4096, "
                         f"got {value!r}") from None


def _number(x):
    """Shortest exact text of a float, without a trailing '.0' (30.0 → '30', 1/4096 → '0.000244140625')."""
    text = repr(float(x) + 0.0)  # + 0.0: no '-0'
    return text[:-2] if text.endswith(".0") else text


def default_name(p):
    """Readable, deterministic, filesystem-safe name of a run from its parameters (`pnrotor.evolve`'s
    keywords): approximant, masses, spins and f_ref, then every option that differs from its default,
    e.g. ``T4_m30_m10_chi1-0.6,0,0.2_chi2-0,-0.4,0.1_f20`` or ``..._f20_fmin10_dt0.000244140625``."""
    from pnrotor.pn.evolve import normalize_approximant

    vector = ",".join
    parts = [normalize_approximant(p["approximant"]), f"m{_number(p['m1'])}", f"m{_number(p['m2'])}",
             f"chi1-{vector(map(_number, p['chi1']))}", f"chi2-{vector(map(_number, p['chi2']))}",
             f"f{_number(p['f_ref'])}"]
    for key, tag in (("f_min", "fmin"), ("f_max", "fmax"), ("pn_order", "pn"), ("spin_orbit_order", "so"),
                     ("spin_spin_order", "ss"), ("atol", "atol"), ("lambda1", "lambda1-"), ("lambda2", "lambda2-"),
                     ("tidal_order", "tides")):
        if p[key] is not None and p[key] != DEFAULTS[key]:
            parts.append(f"{tag}{_number(p[key])}")
    if p["precession"] != DEFAULTS["precession"]:
        parts.append(str(p["precession"]))
    if p["horizon_absorption"]:
        parts.append("horizon")
    sampling = p["sampling"]
    if isinstance(sampling, tuple):
        parts.append(f"perorbit{sampling[1]}")
    elif isinstance(sampling, float):
        parts.append(f"dt{_number(sampling)}")
    elif sampling != "steps":
        parts.append(str(sampling))
    return "_".join(parts)


class Row:
    """One binary of a batch: its number and label, its `pnrotor.evolve` parameters and group name, or the
    error that stops it."""

    def __init__(self, number, label):
        self.number, self.label = number, label
        self.params = self.name = self.error = None

    def __repr__(self):
        return f"{self.label} ({self.name})" if self.name else self.label


def read_batch(path, cli_defaults):
    """The rows of a CSV or TOML batch file, each with parameters and name or its error.

    Problems of the file itself (missing, unreadable, unknown or missing columns, repeated names) raise
    ``ValueError``/``FileNotFoundError``; a bad value only marks its row."""
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder, not a batch file")
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        records = _csv_records(path)
    elif suffix == ".toml":
        records = _toml_records(path)
    else:
        raise ValueError(f"batch file {path} must be .csv or .toml")
    if not records:
        raise ValueError(f"batch file {path} holds no binaries")
    from pnrotor.hdf5 import _valid_name   # what can name a group (not at import: the CLI starts without h5py)

    rows = []
    for number, (label, record) in enumerate(records, 1):
        row = Row(number, label)
        try:
            row.params, row.name = _row_parameters(record, cli_defaults)
        except ValueError as error:
            row.error = str(error)
            if _valid_name(record.get("name")):   # a failure still says which row it is
                row.name = record["name"]
        rows.append(row)
    seen = {}
    for row in rows:
        if row.name is not None and row.error is None:   # a failed row keeps its name for its FAILED line only
            if row.name in seen:
                raise ValueError(f"batch file {path}: {seen[row.name].label} and {row.label} have the same name "
                                 f"{row.name!r}; give each a distinct name column")
            seen[row.name] = row
    return rows


def _check_columns(keys, where):
    unknown = [key for key in keys if key not in COLUMNS]
    if unknown:
        raise ValueError(f"{where}: unknown column{'s' * (len(unknown) > 1)} {', '.join(map(repr, unknown))}; "
                         f"the columns are {', '.join(COLUMNS)}")
    missing = [key for key in REQUIRED if key not in keys]
    if missing:
        raise ValueError(f"{where}: missing column{'s' * (len(missing) > 1)} {', '.join(missing)}")


def _csv_records(path):
    import csv

    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise ValueError(f"batch file {path} is empty")
            header = [name.strip() for name in header]
            _check_columns(header, f"batch file {path}")
            duplicated = sorted({name for name in header if header.count(name) > 1})
            if duplicated:
                raise ValueError(f"batch file {path}: repeated column {', '.join(duplicated)}")
            records = []
            for cells in reader:
                if not any(cell.strip() for cell in cells):
                    continue
                if len(cells) != len(header):
                    raise ValueError(f"batch file {path} line {reader.line_num}: {len(cells)} fields for "
                                     f"{len(header)} columns (quote vectors: \"0.6,0,0.2\")")
                record = {key: cell.strip() for key, cell in zip(header, cells) if cell.strip()}
                records.append((f"row {len(records) + 1} (line {reader.line_num})", record))
    except UnicodeDecodeError as error:
        raise ValueError(f"batch file {path} is not UTF-8 text ({error})") from None
    except csv.Error as error:
        raise ValueError(f"batch file {path} is not valid CSV ({error})") from None
    return records


def _toml_records(path):
    import tomllib

    try:
        with open(path, "rb") as f:
            document = tomllib.load(f)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"batch file {path} is not valid TOML ({error})") from None
    extra = [key for key in document if key != "binary"]
    tables = document.get("binary")
    if extra or not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        raise ValueError(f"batch file {path} must hold [[binary]] tables only"
                         + (f"; found {', '.join(map(repr, extra))}" if extra else ""))
    records = []
    for number, table in enumerate(tables, 1):
        _check_columns(list(table), f"batch file {path} [[binary]] {number}")
        records.append((f"row {number} ([[binary]] {number})", table))
    return records


def _row_parameters(record, cli_defaults):
    """`pnrotor.evolve` keywords and the group name of one batch record; CLI options fill empty cells."""
    params = {}
    for key in REQUIRED:
        value = record[key] if key in record else None
        if value is None:
            raise ValueError(f"{key} is empty")
        params[key] = parse_vector(value, key) if key.startswith("chi") else _float(value, key)
    for key, default in DEFAULTS.items():
        value = record.get(key, cli_defaults.get(key))
        if value is None:
            params[key] = default
        elif key == "sampling":
            params[key] = parse_sampling(value, "sampling")
        elif key in ("approximant", "precession"):
            params[key] = str(value)
        elif key == "horizon_absorption":
            params[key] = _bool(value, key)
        else:
            params[key] = _float(value, key)
    from pnrotor.hdf5 import _valid_name

    name = record.get("name")
    if name is None:
        name = default_name(params)
    elif not _valid_name(name):
        raise ValueError(f"name {name!r} is not a valid group name (non-empty, no '/', not '.')")
    else:
        default_name(params)  # checks the approximant before the run
    return params, name


def _bool(value, key):
    """True or False from a TOML boolean or a CSV cell true/false (any case), 1/0."""
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if text in ("true", "1"):
        return True
    if text in ("false", "0"):
        return False
    raise ValueError(f"{key} must be true or false (or 1, 0), got {value!r}")


def _float(value, key):
    if isinstance(value, bool):
        raise ValueError(f"{key} must be a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{key} must be a number, got {value!r}") from None
