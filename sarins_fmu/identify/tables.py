"""CSV tables of named columns, and the packaged tables of seed 000.

A table is a ``dict`` of column name to 1-D numpy array: ``float`` for
columns whose every cell parses as a number, ``str`` otherwise.

Packaged data (``sarins_fmu/data/``), typed from seed 000 (Yu et al. 2012,
J. National Univ. Defense Technology 34(3)); the paper's site latitude is
28.222° (:data:`SEED000_SITE_LAT_DEG`).

``axial_rbf_table2_hot.csv`` (Table 2, hot start, 16 training samples; rows
1-8 are the table's left half, 9-16 its right half)
    ``sample``; ``lat_deg``, latitude *reading* after 4 h alignment + 12 h
    navigation (the network input in the paper), °; ``lat_error_deg`` =
    ``lat_deg`` - 28.222, °; ``temp_min_c``, ``temp_max_c``, the reported
    temperature range (a single value gives min = max), °C; ``temp_c``,
    its mean; ``temp_change_c``, its width max - min, °C; ``drift_dph``,
    the axial gyro drift taken as truth, °/h. Sample 2's range "28 ~ 39" is
    as printed, although hot starts are said to change by less than 3 °C.

``axial_rbf_table4_cold.csv`` (Table 4, cold start, 6 training samples)
    ``align_temp_min_c``, ``align_temp_max_c``, ``align_temp_diff_c``:
    temperature range and change during the alignment, °C;
    ``calib_temp_min_c``, ``calib_temp_max_c``, ``calib_temp_diff_c``: the
    same during the calibration (drift identification) time, °C;
    ``lat_deg``, ``lat_error_deg`` as above; ``temp_c``, the mean of the
    calibration-time range (the temperature the identified drift belongs
    to), °C; ``temp_change_c`` = ``align_temp_diff_c``, the alignment
    temperature change, °C; ``drift_dph``, true drift, °/h;
    ``hot_rbf_drift_dph``, the drift the hot-start RBF network identified, °/h.
"""

from __future__ import annotations

import csv
from importlib import resources
from pathlib import Path
from typing import TextIO

import numpy as np

from ..files import naming_path
from ..site import SITE_LAT_DEG as SEED000_SITE_LAT_DEG

__all__ = [
    "TableError",
    "SEED000_SITE_LAT_DEG",
    "read_table",
    "numeric_column",
    "write_table",
    "packaged_table_path",
    "axial_rbf_table2_hot",
    "axial_rbf_table4_cold",
]


TABLE2_HOT = "axial_rbf_table2_hot.csv"
TABLE4_COLD = "axial_rbf_table4_cold.csv"


class TableError(ValueError):
    """A CSV table could not be read; the message names the file (and line)."""


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """Read a CSV file with a header row into named columns.

    Parameters
    ----------
    path : str or Path
        CSV file: first row the column names, then one row per sample.

    Returns
    -------
    dict of str to ndarray, each shape (n,)
        Float arrays for numeric columns, str arrays otherwise.

    Raises
    ------
    TableError
        If the file is missing, unreadable, empty, has blank or duplicate
        column names, no data rows, blank lines between rows, or rows of the
        wrong length. Line numbers in messages count the header as line 1.
    """
    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except FileNotFoundError:
        raise TableError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise TableError(f"{path}: cannot read CSV: {exc}") from None
    while rows and not any(cell.strip() for cell in rows[-1]):
        rows.pop()  # trailing blank lines
    if not rows:
        raise TableError(f"{path}: empty file")
    header = [name.strip() for name in rows[0]]
    if any(not name for name in header):
        raise TableError(f"{path}: blank column name in the header")
    if len(set(header)) != len(header):
        raise TableError(f"{path}: duplicate column names in the header")
    data = rows[1:]
    if not data:
        raise TableError(f"{path}: no data rows")
    for line, row in enumerate(data, start=2):
        if not any(cell.strip() for cell in row):
            raise TableError(f"{path}: line {line} is blank")
        if len(row) != len(header):
            raise TableError(f"{path}: line {line} has {len(row)} fields, the header has {len(header)}")
    table: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        cells = [row[j].strip() for row in data]
        try:
            table[name] = np.array([float(c) for c in cells])
        except ValueError:
            table[name] = np.array(cells, dtype=str)
    return table


def numeric_column(table: dict[str, np.ndarray], name: str, path: str | Path) -> np.ndarray:
    """A column that must hold finite numbers; a :class:`TableError` otherwise.

    Parameters
    ----------
    table : dict
        From :func:`read_table`.
    name : str
        Column name.
    path : str or Path
        File name for the message.

    Returns
    -------
    ndarray, shape (n,)
    """
    if name not in table:
        raise TableError(f"{path}: no column '{name}' (columns: {', '.join(table)})")
    col = table[name]
    if col.dtype.kind != "f":
        bad = next(i for i, c in enumerate(col) if not _is_number(c))
        raise TableError(f"{path}: column '{name}' line {bad + 2}: {str(col[bad])!r} is not a number")
    if not np.all(np.isfinite(col)):
        bad = int(np.flatnonzero(~np.isfinite(col))[0])
        raise TableError(f"{path}: column '{name}' line {bad + 2}: value is not finite")
    return col


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def write_table(dest: str | Path | TextIO, table: dict[str, np.ndarray]) -> None:
    """Write named columns (equal lengths) as CSV.

    Floats are written in round-trip form (``repr``), integral ones as
    integers, so reading the file back gives the same values.

    Parameters
    ----------
    dest : str, Path or text stream
        Destination file, or an open text stream (e.g. ``sys.stdout``).
    table : dict of str to array_like, each shape (n,)
        Columns, in output order.
    """
    cols = {k: np.asarray(v) for k, v in table.items()}
    lengths = {v.shape for v in cols.values()}
    if len(lengths) > 1 or any(len(shape) != 1 for shape in lengths):
        raise ValueError(f"columns must be 1-D of one length, got shapes {sorted(lengths)}")
    n = next(iter(lengths))[0] if lengths else 0

    def _write(fh: TextIO) -> None:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(list(cols))
        for i in range(n):
            writer.writerow([_format_cell(v[i]) for v in cols.values()])

    if hasattr(dest, "write"):
        _write(dest)
    else:
        with naming_path(dest), open(dest, "w", newline="", encoding="utf-8") as fh:
            _write(fh)


def _format_cell(value: object) -> str:
    """Integral floats as integers, other floats in round-trip form."""
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return str(int(v)) if v.is_integer() and abs(v) < 1e15 else repr(v)
    return str(value)


def packaged_table_path(name: str) -> Path:
    """Path of a CSV shipped in ``sarins_fmu/data``.

    Parameters
    ----------
    name : str
        File name, e.g. ``"axial_rbf_table2_hot.csv"``.
    """
    path = Path(str(resources.files("sarins_fmu") / "data" / name))
    if not path.is_file():
        raise TableError(f"{path}: packaged table not found")
    return path


def axial_rbf_table2_hot() -> dict[str, np.ndarray]:
    """Seed 000 Table 2 (hot start, 16 samples); columns in the module docstring."""
    return read_table(packaged_table_path(TABLE2_HOT))


def axial_rbf_table4_cold() -> dict[str, np.ndarray]:
    """Seed 000 Table 4 (cold start, 6 samples); columns in the module docstring."""
    return read_table(packaged_table_path(TABLE4_COLD))
