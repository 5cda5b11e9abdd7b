"""Batch tables: CSV or TOML files of binaries → rows of `pnrotor.evolve` keywords, checked before anything runs.

A CSV file has one binary per row, with columns named like `pnrotor.evolve`'s keywords (:data:`COLUMNS`;
vectors as ``"x,y,z"`` strings); a TOML file has one ``[[binary]]`` table per binary with the same keys
(vectors as arrays).  Empty cells take the caller's defaults (the CLI's options), then :data:`DEFAULTS`.
The population mode also reads Parquet and HDF5 tables, in pieces (:class:`TableFile`).
Problems of the file itself (missing, unreadable, unknown or missing columns, repeated names) raise
``ValueError`` (``FileNotFoundError``/``IsADirectoryError`` for the path); a bad value only marks its row
(:attr:`Row.error`), so one bad binary does not stop the others.  Group names default to
:func:`default_name`, built from the parameters.
"""

import contextlib
import functools
import math
from pathlib import Path

from pnrotor.options import COLUMNS, DEFAULTS, REQUIRED  # noqa: F401 - the table's columns, named here too


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
    from pnrotor.approximants import normalize_approximant

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
        records = list(_csv_records(path))
    elif suffix == ".toml":
        records = _toml_records(path)
    else:
        raise ValueError(f"batch file {path} must be .csv or .toml")
    if not records:
        raise ValueError(f"batch file {path} holds no binaries")
    rows = [parse_row(number, label, record, cli_defaults) for number, (label, record) in enumerate(records, 1)]
    seen = {}
    for row in rows:
        if row.name is not None and row.error is None:   # a failed row keeps its name for its FAILED line only
            if row.name in seen:
                raise ValueError(f"batch file {path}: {seen[row.name].label} and {row.label} have the same name "
                                 f"{row.name!r}; give each a distinct name column")
            seen[row.name] = row
    return rows


def parse_row(number, label, record, cli_defaults):
    """The :class:`Row` of a record (column → cell; empty cells absent): its parameters and name, or its error."""
    from pnrotor.hdf5 import valid_name   # what can name a group (not at import: the CLI starts without h5py)

    row = Row(number, label)
    try:
        row.params, row.name = _row_parameters(record, cli_defaults)
    except ValueError as error:
        row.error = str(error)
        if valid_name(record.get("name")):   # a failure still says which row it is
            row.name = record["name"]
    return row


class TableFile:
    """A batch table file read in pieces, whatever its length: CSV and TOML as :func:`read_batch` reads them, and
    Parquet (``.parquet``: a column per name, vectors as lists of three numbers or ``"x,y,z"`` text, null cells
    empty) or HDF5 (``.h5``, ``.hdf5``: a dataset per column at the root, of N rows, vectors (N, 3), text as
    strings; NaN and empty strings are empty cells, as HDF5 has no null).

    Opening it checks its structure (the columns, and each CSV line's fields) and counts its rows, :attr:`rows`;
    :meth:`records` then yields (number, label, record) row by row, reading a piece at a time; :attr:`digest` is
    the SHA-256 of its bytes.  A bad value is the business of :func:`parse_row` (its row only)."""

    SUFFIXES = (".csv", ".toml", ".parquet", ".h5", ".hdf5")
    _PIECE = 4096
    """Rows read at a time from Parquet and HDF5 files."""

    def __init__(self, path):
        self.path = path = Path(path)
        if path.is_dir():
            raise IsADirectoryError(f"{path} is a folder, not a batch file")
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such file")
        self.suffix = path.suffix.lower()
        if self.suffix not in self.SUFFIXES:
            raise ValueError(f"batch file {path} must be .csv, .toml, .parquet, .h5 or .hdf5")
        if self.suffix == ".csv":
            self.rows = sum(1 for _ in _csv_records(path))
        elif self.suffix == ".toml":
            self.rows = len(_toml_records(path))
        elif self.suffix == ".parquet":
            self.rows = self._parquet().metadata.num_rows
        else:
            with self._hdf5() as (_, rows):
                self.rows = rows
        if not self.rows:
            raise ValueError(f"batch file {path} holds no binaries")

    def records(self):
        """(number from 1, label, record) of each row in order, a record being column → cell without the empty
        cells, as :func:`parse_row` takes it."""
        if self.suffix == ".csv":
            records = _csv_records(self.path)
        elif self.suffix == ".toml":
            records = _toml_records(self.path)
        elif self.suffix == ".parquet":
            records = ((None, {key: value for key, value in record.items() if value is not None})
                       for piece in self._parquet().iter_batches(self._PIECE) for record in piece.to_pylist())
        else:
            records = self._hdf5_records()
        for number, (label, record) in enumerate(records, 1):
            yield number, label or f"row {number}", record

    @functools.cached_property
    def digest(self):
        """The SHA-256 of the file's bytes, in hex (read once)."""
        import hashlib

        sha = hashlib.sha256()
        with open(self.path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                sha.update(block)
        return sha.hexdigest()

    def _parquet(self):
        try:
            import pyarrow.parquet as pq
        except ImportError:
            raise ValueError("Parquet tables need pyarrow: pip install 'pnrotor[parquet]'") from None
        try:
            table = pq.ParquetFile(self.path)
        except Exception as error:   # noqa: BLE001 - pyarrow's errors of a file that is not Parquet
            raise ValueError(f"batch file {self.path} is not a Parquet file ({error})") from None
        _check_columns(table.schema_arrow.names, f"batch file {self.path}")
        return table

    @contextlib.contextmanager
    def _hdf5(self):
        """(the open h5py File, its rows), its columns checked: datasets at its root, of equal lengths."""
        import h5py

        try:
            f = h5py.File(self.path, "r")
        except OSError as error:
            raise ValueError(f"batch file {self.path} is not an HDF5 file HDF5 can open ({error})") from None
        with f:
            where = f"batch file {self.path}"
            _check_columns(list(f), where)
            if not all(isinstance(f[key], h5py.Dataset) for key in f):
                raise ValueError(f"{where}: its columns must be datasets at the root of the file")
            lengths = {key: f[key].shape[0] if f[key].ndim in (1, 2) else None for key in f}
            if len(set(lengths.values())) != 1 or None in lengths.values():
                raise ValueError(f"{where}: its columns must be datasets of one length N, (N,) or (N, 3); got "
                                 + ", ".join(f"{key} {f[key].shape}" for key in f))
            yield f, lengths[next(iter(f))]

    def _hdf5_records(self):
        import h5py

        with self._hdf5() as (f, rows):
            for start in range(0, rows, self._PIECE):
                columns = {}
                for key in f:
                    data = f[key].asstr()[start:start + self._PIECE] if h5py.check_string_dtype(f[key].dtype) \
                        else f[key][start:start + self._PIECE]
                    columns[key] = data.tolist()
                for i in range(len(next(iter(columns.values())))):
                    yield None, {key: cell for key, cells in columns.items() if _filled(cell := cells[i])}


def _filled(cell):
    """Whether a cell of an HDF5 table holds a value (NaN and empty text are empty cells)."""
    return cell != "" and cell == cell


def _check_columns(keys, where):
    unknown = [key for key in keys if key not in COLUMNS]
    if unknown:
        raise ValueError(f"{where}: unknown column{'s' * (len(unknown) > 1)} {', '.join(map(repr, unknown))}; "
                         f"the columns are {', '.join(COLUMNS)}")
    missing = [key for key in REQUIRED if key not in keys]
    if missing:
        raise ValueError(f"{where}: missing column{'s' * (len(missing) > 1)} {', '.join(missing)}")


def _csv_records(path):
    """(label, record) of each row of a CSV batch file, read as they are yielded; a structural fault raises then."""
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
            count = 0
            for cells in reader:
                if not any(cell.strip() for cell in cells):
                    continue
                if len(cells) != len(header):
                    raise ValueError(f"batch file {path} line {reader.line_num}: {len(cells)} fields for "
                                     f"{len(header)} columns (quote vectors: \"0.6,0,0.2\")")
                count += 1
                yield (f"row {count} (line {reader.line_num})",
                       {key: cell.strip() for key, cell in zip(header, cells) if cell.strip()})
    except UnicodeDecodeError as error:
        raise ValueError(f"batch file {path} is not UTF-8 text ({error})") from None
    except csv.Error as error:
        raise ValueError(f"batch file {path} is not valid CSV ({error})") from None


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
    from pnrotor.hdf5 import valid_name

    name = record.get("name")
    if name is None:
        name = default_name(params)
    elif not valid_name(name):
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
