"""Recorded IMU data: the log formats, their readers (with checks) and the writer.

The project's own format (version 1; grammar in docs/imu-log.md), CSV for readability, NPZ for
large logs, the same columns in both.  A CSV log is::

    # sarins-imu-log 1
    # lat_deg: 28.222
    # lon_deg: 0
    # height_m: 0
    time_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps,temp_gyro_x_c,...
    1,7.2e-06,...

* ``#`` lines come first (no blank lines): the tag line, then ``# key: value``
  metadata.  ``lat_deg`` (the static start of the alignment, deg) is
  required; ``lon_deg`` and ``height_m`` default to 0.  Any other key is
  kept as text.
* ``time_s``: time of each sample, s, strictly increasing on a uniform grid
  (the sample interval h is the first difference).  A sample covers
  (time - h, time].
* IMU outputs, SI and body axes (right-front-up), either the increments
  over each interval, ``dtheta_{x,y,z}_rad`` and ``dv_{x,y,z}_mps`` (as the
  IMUThermal FMU outputs them: coning and sculling applied), or the mean
  rates ``gyro_{x,y,z}_radps`` and ``accel_{x,y,z}_mps2`` (increments =
  rate * h).
* Optional: the six sensor temperatures ``temp_{gyro,accel}_{x,y,z}_c``
  (degC; all six or none) and a reference position ``ref_lat_deg``,
  ``ref_lon_deg``, ``ref_height_m`` (truth for the errors; without it the
  static start is the truth).

Besides it, :func:`read_log` reads what real sensors write (:class:`ReadOptions`): a vendor CSV
(optionally gzip) whose header names each column's unit (:mod:`sarins_fmu.imu_log_units`), the
KF-GINS / i2Nav IMU text file, and ROS 1/2 bags of ``sensor_msgs/Imu`` (:mod:`sarins_fmu.imu_log_ros`,
the optional ``rosbags`` package); the sensor's axes are rotated to right-front-up.  Every format
becomes one :class:`ImuLog` in SI units and right-front-up axes.

Reading is streamed (:mod:`sarins_fmu.imu_log_text`, :mod:`sarins_fmu.imu_log_stream`): a text
file is parsed in blocks of whole lines, its line grammar checked on each block, the samples
checked and stored as they come (a large log in a temporary file, mapped).  The unit checks
(:mod:`sarins_fmu.imu_log_checks`) refuse only what is certain and warn about what a real sensor
can also produce.

Size budget: a file larger than :data:`MAX_LOG_BYTES` (a gzip file: its text), or an NPZ log
whose members expand to more than that (or that has more than :data:`MAX_LOG_MEMBERS` members),
is refused before it is parsed or decompressed (a gzip file as soon as its text passes it); a
truncated or corrupted file is refused naming it.
"""

from __future__ import annotations

import io
import json
import math
import re
import warnings
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .files import BudgetError, check_file_size, check_zip_budget, naming_path
from .imu_log_checks import GRAVITY_RANGE, MAX_GYRO_RATE, MAX_SPECIFIC_FORCE, STATIC_RATE_LIMIT  # noqa: F401
from .imu_log_stream import LogBuilder
from .imu_log_text import TextError, TextReader, check_lines
from .imu_log_units import ColumnError, axes_matrix, temp_column, vector_column

TAG = "# sarins-imu-log 1"
AXES = "xyz"
INCREMENT_COLUMNS = [f"dtheta_{a}_rad" for a in AXES] + [f"dv_{a}_mps" for a in AXES]
RATE_COLUMNS = [f"gyro_{a}_radps" for a in AXES] + [f"accel_{a}_mps2" for a in AXES]
TEMP_COLUMNS = [f"temp_{s}_{a}_c" for s in ("gyro", "accel") for a in AXES]
REF_COLUMNS = ["ref_lat_deg", "ref_lon_deg", "ref_height_m"]
MAX_LOG_BYTES = 2 * 2**30  # bytes: a text file (a gzip file's text), or an NPZ's members uncompressed
MAX_LOG_MEMBERS = 64  # arrays in an NPZ log (the format has at most 19 columns and meta)
MAX_META_LINE = 1024  # characters of one metadata line (CSV) or value (NPZ)
MAX_META_KEYS = 64
MAX_DATA_LINE = 4096  # characters of one CSV data line (19 columns of 17-digit numbers need ~500)
TIME_START_TOLERANCE = 1e-6  # of h: the first time_s lies in [0, h]
KNOWN_COLUMNS = ("time_s", *INCREMENT_COLUMNS, *RATE_COLUMNS, *TEMP_COLUMNS, *REF_COLUMNS)
_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_WRONG_UNITS = {"_deg": "rad", "_dps": "radps", "_degps": "radps", "_g": "mps2", "_mg": "mps2", "_ug": "mps2",
                "_f": "c", "_k": "c"}


class LogError(ValueError):
    """A log that cannot be used; the message names the file and the line or row."""


@dataclass
class ImuLog:
    """A recorded IMU log in SI units and right-front-up body axes.

    time : (K,) s; dtheta (K, 3) rad; dv (K, 3) m/s (increments, whatever was stored);
    temps : (K, 6) degC or None; ref : (K, 3) lat rad, lon rad, height m, or None;
    lat (rad, None when neither the file nor the options state it), lon (rad), height (m): the static
    start; meta : all metadata as text; warnings : what the reader assumed (one line each); axes : the
    sensor's axes as declared (rotated to right-front-up); format : 'sarins', 'csv', 'i2nav' or 'ros';
    means : (M, 6) means over each whole second (rad/s, m/s^2); interval : the sample interval h, s.
    """

    time: np.ndarray
    dtheta: np.ndarray
    dv: np.ndarray
    temps: np.ndarray | None
    ref: np.ndarray | None
    lat: float | None
    lon: float = 0.0
    height: float = 0.0
    meta: dict = field(default_factory=dict)
    quantity: str = "increments"
    warnings: list = field(default_factory=list)
    axes: str = "rfu"
    format: str = "sarins"
    means: np.ndarray | None = None
    interval: float | None = None

    @property
    def step(self) -> float:
        """Sample interval h, s."""
        return float(self.interval) if self.interval is not None else float(self.time[1] - self.time[0])


def write_log(path, time, dtheta, dv, *, lat_deg: float, lon_deg: float = 0.0, height_m: float = 0.0,
              temps=None, ref=None, meta: dict | None = None) -> Path:
    """Write increments (and optional temperatures, reference) as a log; .npz or .csv by suffix.

    ref : (K, 3) lat, lon in rad and height in m (written in deg as the format says).
    """
    path = Path(path)
    cols = {"time_s": np.asarray(time, float)}
    for j, name in enumerate(INCREMENT_COLUMNS):
        cols[name] = np.asarray(dtheta if j < 3 else dv, float)[:, j % 3]
    if temps is not None:
        for j, name in enumerate(TEMP_COLUMNS):
            cols[name] = np.asarray(temps, float)[:, j]
    if ref is not None:
        ref = np.asarray(ref, float)
        cols.update(ref_lat_deg=np.degrees(ref[:, 0]), ref_lon_deg=np.degrees(ref[:, 1]), ref_height_m=ref[:, 2])
    info = {"lat_deg": repr(float(lat_deg)), "lon_deg": repr(float(lon_deg)), "height_m": repr(float(height_m)),
            **{k: str(v) for k, v in (meta or {}).items()}}
    with naming_path(path):  # a full disk names the file
        if path.suffix == ".npz":
            np.savez_compressed(path, meta=np.array(json.dumps(info)), **cols)
            return path
        with open(path, "w") as fh:
            fh.write(TAG + "\n")
            for k, v in info.items():
                fh.write(f"# {k}: {v}\n")
            np.savetxt(fh, np.column_stack(list(cols.values())), delimiter=",", fmt="%.17g",
                       header=",".join(cols), comments="")
    return path


@dataclass(frozen=True)
class ReadOptions:
    """What a log cannot say about itself, from the user (the ``sarins`` options of the same names).

    format : 'auto' (by content: the tag line -> the project's CSV, a first line of numbers -> i2Nav
        text, a ``.npz`` -> the project's NPZ, a ``.bag``/``.db3``/``.mcap`` file or a folder -> a ROS
        bag, else a vendor CSV), or one of :data:`FORMATS`;
    axes : the sensor's axes (``frd``, ...; :mod:`sarins_fmu.imu_log_units`), default the format's
        (``rfu``; i2Nav ``frd``; ROS ``flu``); the project's format is right-front-up by definition;
    rate_hz : sample rate of a log without a time column, Hz;
    lat_deg, lon_deg, height_m : the static start, for a file that does not state it;
    topic : the ROS topic of the ``sensor_msgs/Imu`` messages (when a bag has several);
    accept_units : read a log whose units look wrong (those refusals become warnings).
    """

    format: str = "auto"
    axes: str | None = None
    rate_hz: float | None = None
    lat_deg: float | None = None
    lon_deg: float | None = None
    height_m: float | None = None
    topic: str | None = None
    accept_units: bool = False


FORMATS = ("sarins", "csv", "i2nav", "ros")
DEFAULT_AXES = {"sarins": "rfu", "csv": "rfu", "i2nav": "frd", "ros": "flu"}
ROS_SUFFIXES = (".bag", ".db3", ".mcap")
MAX_HEAD_LINES = MAX_META_KEYS + 2  # tag, metadata, header


def _where_line(first_line: int):
    return lambda row: f"line {first_line + row}"


def _where_row(label: str = "row"):
    return lambda row: f"{label} {row}"


def read_log(path, options: ReadOptions | None = None) -> ImuLog:
    """Read and check a log in any supported format (see :class:`ReadOptions` and docs/imu-log.md).

    Raises LogError naming the file and the line, row or message; warnings (what a real sensor can
    also produce) are issued with :func:`warnings.warn` and kept in ``ImuLog.warnings``.
    """
    opts = options or ReadOptions()
    path = Path(path)
    fmt = _detect(path, opts)
    if fmt == "ros":
        from .imu_log_ros import read_bag

        log = read_bag(path, opts)
    else:
        if not path.is_file():
            raise LogError(f"{path}: no such log file")
        _check_budget(path)
        if path.suffix == ".npz":
            log = _read_npz_log(path, opts)
        elif fmt == "i2nav":
            log = _read_i2nav(path, opts)
        else:
            log = _read_text_csv(path, opts, fmt)
    for message in log.warnings:
        warnings.warn(LogWarning(message), stacklevel=2)
    return log


class LogWarning(UserWarning):
    """What a real sensor can also produce: the log is read, the message says what was assumed."""


def _detect(path: Path, opts: ReadOptions) -> str:
    if opts.format != "auto":
        if opts.format not in FORMATS:
            raise LogError(f"{path}: format {opts.format!r} is not one of auto, {', '.join(FORMATS)}")
        return opts.format
    if path.is_dir() or path.suffix in ROS_SUFFIXES:
        return "ros"
    if path.suffix == ".npz" or not path.is_file():
        return "sarins"
    try:
        with TextReader(path, MAX_LOG_BYTES, "an IMU log (MAX_LOG_BYTES)") as text:
            first = next(text.lines(1, lambda b: MAX_DATA_LINE), (1, b""))[1]
    except (TextError, OSError):
        return "csv"  # the reader says what is wrong
    if first.decode("utf-8", "replace") == TAG:
        return "sarins"
    fields = re.split(rb"[,\s]+", first.strip())
    try:
        [float(f) for f in fields]
        return "i2nav" if len(fields) >= 7 else "csv"
    except ValueError:
        return "csv"


def _check_budget(path: Path) -> None:
    try:
        if path.suffix == ".npz":
            check_zip_budget(path, MAX_LOG_BYTES, "an IMU log (MAX_LOG_BYTES)", MAX_LOG_MEMBERS)
        else:
            check_file_size(path, MAX_LOG_BYTES, "an IMU log (MAX_LOG_BYTES)")
    except BudgetError as exc:
        raise LogError(str(exc)) from None
    except (zipfile.BadZipFile, OSError, EOFError) as exc:
        kind = "NPZ log" if path.suffix == ".npz" else "log"
        raise LogError(f"{path}: not a readable {kind} ({_one_line(exc)})") from None


def _axes(path, opts: ReadOptions, fmt: str) -> tuple[np.ndarray, str, bool]:
    """(matrix, code, given) of the log's axes."""
    if fmt == "sarins" and opts.axes is not None and opts.axes.strip().lower() != "rfu":
        raise LogError(f"{path}: the project's log format is right-front-up by definition; --axes "
                       f"{opts.axes} does not apply to it")
    code = (opts.axes or DEFAULT_AXES[fmt]).strip().lower()
    try:
        return axes_matrix(code), code, opts.axes is not None
    except ValueError as exc:
        raise LogError(f"{path}: --axes: {exc}") from None


def _site(path, meta: dict, opts: ReadOptions) -> tuple[float | None, float, float]:
    """(lat rad or None, lon rad, height m) from the file's metadata or the options (not both)."""
    values = {}
    for key, option in (("lat_deg", opts.lat_deg), ("lon_deg", opts.lon_deg), ("height_m", opts.height_m)):
        flag = "--" + key.replace("_", "-")
        if key in meta and option is not None:
            raise LogError(f"{path}: the log states {key} {meta[key]}; {flag} applies only to a log without it")
        text = meta.get(key)
        if text is None:
            values[key] = option
            continue
        try:
            values[key] = float(text)
        except ValueError:
            raise LogError(f"{path}: lat_deg, lon_deg and height_m must be numbers") from None
    lat, lon, height = values["lat_deg"], values["lon_deg"] or 0.0, values["height_m"] or 0.0
    if not (math.isfinite(lon) and math.isfinite(height)) or (lat is not None and not (
            math.isfinite(lat) and abs(lat) <= 89.9)):
        raise LogError(f"{path}: lat_deg {lat} must be finite and within +-89.9 deg")
    for key in ("lat_deg", "lon_deg", "height_m"):
        if values[key] is not None and key not in meta:
            meta[key] = repr(float(values[key]))
    return (None if lat is None else math.radians(lat)), math.radians(lon), float(height)


def _finish(path, builder: LogBuilder, meta: dict, opts: ReadOptions, fmt: str, axes_code: str,
            axes_given: bool, quantity: str) -> ImuLog:
    table, h, notes, means = builder.finish()
    if fmt == "sarins" and "lat_deg" not in meta and opts.lat_deg is None:
        raise LogError(f"{path}: metadata lat_deg (static start latitude, deg) is required")
    lat, lon, height = _site(path, meta, opts)
    if fmt == "csv" and not axes_given:
        notes.append(_axes_note(path, means, axes_code))
    notes = [n for n in notes if n]
    temps = table[:, 7:13] if builder.has_temps else None
    ref = table[:, -3:] if builder.has_ref else None
    return ImuLog(time=table[:, 0], dtheta=table[:, 1:4], dv=table[:, 4:7], temps=temps, ref=ref, lat=lat,
                  lon=lon, height=height, meta=meta, quantity=quantity, warnings=notes, axes=axes_code,
                  format=fmt, means=means, interval=h)


def _axes_note(path, means: np.ndarray, code: str) -> str | None:
    """A vendor CSV read without --axes: say so if its specific force does not point up its z axis."""
    if means.shape[0] == 0:
        return None
    f = means[:, 3:].mean(axis=0)
    up = int(np.argmax(np.abs(f)))
    if up == 2 and f[2] > 0:
        return None
    return (f"{path}: axes taken as {code} (no --axes); at rest the specific force points along "
            f"{'-' if f[up] < 0 else '+'}{'xyz'[up]}, so give the sensor's axes with --axes (e.g. frd)")


# ------------------------------------------------------------------ the project's NPZ

def _read_npz_log(path: Path, opts: ReadOptions) -> ImuLog:
    columns, meta = _read_npz(path)
    if opts.rate_hz is not None:
        raise LogError(f"{path}: the project's log has time_s; --rate-hz applies to a log without time")
    axes, code, given = _axes(path, opts, "sarins")
    quantity, names, has_temps, has_ref = _sarins_columns(path, list(columns))
    used = ["time_s", *names] + (TEMP_COLUMNS if has_temps else []) + (REF_COLUMNS if has_ref else [])
    if len({len(columns[c]) for c in used}) != 1:
        raise LogError(f"{path}: columns have different lengths")
    builder = LogBuilder(path, _where_row(), strict=True, quantity=quantity, axes=axes, has_temps=has_temps,
                         has_ref=has_ref, accept_units=opts.accept_units)
    builder.names = {"time_s": ["time_s"], "imu": names, "temperature": TEMP_COLUMNS, "reference": REF_COLUMNS}
    builder.feed(columns["time_s"], np.column_stack([columns[c] for c in names]),
                 np.column_stack([columns[c] for c in TEMP_COLUMNS]) if has_temps else None,
                 np.column_stack([columns[c] for c in REF_COLUMNS]) if has_ref else None)
    return _finish(path, builder, meta, opts, "sarins", code, given, quantity)


def _sarins_columns(path, names: list) -> tuple[str, list, bool, bool]:
    """(quantity, the six IMU column names, has temperatures, has reference) of the project's columns."""
    for name in names:
        for bad, good in _WRONG_UNITS.items():
            if name.endswith(bad) and not name.startswith("ref_"):
                raise LogError(f"{path}: column {name!r}: the log takes SI units (…_{good}); convert it")
    if "time_s" not in names:
        raise LogError(f"{path}: no time_s column")
    if any(c in names for c in INCREMENT_COLUMNS) and any(c in names for c in RATE_COLUMNS):
        raise LogError(f"{path}: give increments (dtheta_/dv_ columns) or rates (gyro_/accel_ columns), not both")
    if all(c in names for c in INCREMENT_COLUMNS):
        quantity, imu_names = "increments", INCREMENT_COLUMNS
    elif all(c in names for c in RATE_COLUMNS):
        quantity, imu_names = "rates", RATE_COLUMNS
    else:
        raise LogError(f"{path}: needs the columns {', '.join(INCREMENT_COLUMNS)} or {', '.join(RATE_COLUMNS)}")
    has_temps = [c in names for c in TEMP_COLUMNS]
    if any(has_temps) and not all(has_temps):
        raise LogError(f"{path}: give all six temperature columns ({', '.join(TEMP_COLUMNS)}) or none")
    has_ref = [c in names for c in REF_COLUMNS]
    if any(has_ref) and not all(has_ref):
        raise LogError(f"{path}: give all of {', '.join(REF_COLUMNS)} or none")
    return quantity, imu_names, all(has_temps), all(has_ref)


# ------------------------------------------------------------------ text logs: the project's CSV and vendor CSV

def _head_limit(first: bytes) -> int:
    return MAX_META_LINE if first.startswith(b"#") else MAX_DATA_LINE


def _read_text_csv(path: Path, opts: ReadOptions, fmt: str) -> ImuLog:
    try:
        with TextReader(path, MAX_LOG_BYTES, "an IMU log (MAX_LOG_BYTES)") as text:
            meta, header, header_line, tagged = _csv_head(path, text)
            fmt = "sarins" if tagged else "csv"
            if tagged:
                _check_header(path, header_line, header)
                plan = _SarinsPlan(path, header)
            else:
                plan = _VendorPlan(path, header_line, header, opts)
            axes, code, given = _axes(path, opts, fmt)
            if opts.rate_hz is not None and plan.time_col is not None:
                raise LogError(f"{path}: the log has a time_s column; --rate-hz applies to a log without time")
            if opts.rate_hz is None and plan.time_col is None:
                raise LogError(f"{path}: line {header_line}: no time_s column; give the sample rate with --rate-hz")
            builder = LogBuilder(path, _where_line(header_line + 1), strict=tagged, quantity=plan.quantity,
                                 axes=axes, has_temps=plan.has_temps, has_ref=plan.has_ref, rate_hz=opts.rate_hz,
                                 accept_units=opts.accept_units)
            builder.names = plan.names
            n_cols = len(header)
            any_rows = False
            for block in text.blocks():
                data = _fast_numbers(block, n_cols, text.eol)
                if data is None:
                    check_lines(path, block, text.eol, n_cols - 1, MAX_DATA_LINE)
                    data = _parse_numbers(path, block, n_cols)
                any_rows = True
                plan.feed(builder, data)
            if not any_rows:
                raise LogError(f"{path}: no samples after the header (line {header_line})")
    except TextError as exc:
        raise LogError(str(exc)) from None
    return _finish(path, builder, meta, opts, fmt, code, given, plan.quantity)


def _csv_head(path, text: TextReader):
    """(metadata, header names, header line number, tagged) of a CSV log's head."""
    meta, tagged = {}, False
    for number, raw in text.lines(MAX_HEAD_LINES + 1, _head_limit):
        try:
            line = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise LogError(f"{path}: line {number}: not UTF-8 text") from None
        if not line.strip():
            raise LogError(f"{path}: line {number}: blank line (the log has none: metadata, header, samples)")
        if number == 1 and line.startswith("# sarins-imu-log"):
            if line != TAG:
                raise LogError(f"{path}: line 1 must be {TAG!r}, got {line[:60]!r}")
            tagged = True
            continue
        if not line.startswith("#"):
            return meta, [c.strip() for c in line.split(",")], number, tagged
        if number == 1 and not _META.fullmatch(line):
            raise LogError(f"{path}: line 1 must be {TAG!r} (the project's log), '# key: value' metadata or the "
                           f"column header, got {line[:60]!r}")
        if len(meta) >= MAX_META_KEYS:
            raise LogError(f"{path}: line {number}: more than {MAX_META_KEYS} metadata lines")
        key, sep, value = line[1:].partition(":")
        key = key.strip()
        if not sep or not _KEY.fullmatch(key):
            raise LogError(f"{path}: line {number}: metadata must read '# key: value' (key: letters, digits, '_')")
        if key in meta:
            raise LogError(f"{path}: line {number}: metadata {key} given twice")
        meta[key] = value.strip()
    raise LogError(f"{path}: no column header line")


_META = re.compile(r"#\s*[A-Za-z_][A-Za-z0-9_]*\s*:.*")


def _fast_numbers(block, n_cols: int, eol: bytes | None) -> np.ndarray | None:
    """The block's numbers from the C core (grammar checked, values bit-identical to numpy's), or None when
    it does not take the block (then :func:`check_lines` and :func:`_parse_numbers` read it and word errors)."""
    if eol is None or _core_parse is None:
        return None
    return _core_parse(block.data, n_cols, eol == b"\r\n", MAX_DATA_LINE)


try:
    from .core.log_parse import parse_block as _core_parse
except ImportError:  # the core is not built: numpy reads every block
    _core_parse = None


def _parse_numbers(path, block, n_cols: int) -> np.ndarray:
    """The numbers of a block of sample lines (K, n_cols), as numpy reads a float; errors name the line."""
    try:
        return np.loadtxt(io.BytesIO(block.data), delimiter=",", ndmin=2, comments=None, dtype=float,
                          encoding="latin-1")
    except ValueError as exc:
        raise LogError(f"{path}: {_csv_parse_message(str(exc), block.first_line - 1)}") from None


class _SarinsPlan:
    """The project's columns: SI names, strict clock."""

    def __init__(self, path, header):
        self.quantity, imu_names, self.has_temps, self.has_ref = _sarins_columns(path, header)
        idx = {name: j for j, name in enumerate(header)}
        self.time_col = idx["time_s"]
        self.imu_cols = [idx[c] for c in imu_names]
        self.temp_cols = [idx[c] for c in TEMP_COLUMNS] if self.has_temps else None
        self.ref_cols = [idx[c] for c in REF_COLUMNS] if self.has_ref else None
        self.names = {"time_s": ["time_s"], "imu": imu_names, "temperature": TEMP_COLUMNS, "reference": REF_COLUMNS}

    def feed(self, builder, data):
        builder.feed(data[:, self.time_col], data[:, self.imu_cols],
                     data[:, self.temp_cols] if self.temp_cols else None,
                     data[:, self.ref_cols] if self.ref_cols else None)


class _VendorPlan:
    """A vendor CSV: each column names its unit (:mod:`sarins_fmu.imu_log_units`)."""

    def __init__(self, path, line: int, header: list, opts: ReadOptions):
        seen = set()
        vectors, temps, one_temp, self.time_col = {}, {}, None, None
        for j, name in enumerate(header):
            if name in seen:
                raise LogError(f"{path}: line {line}: column {name} appears twice")
            seen.add(name)
            try:
                vec, temp = vector_column(name), temp_column(name)
            except ColumnError as exc:
                raise LogError(f"{path}: line {line}: {exc}") from None
            if name == "time_s":
                self.time_col = j
            elif vec is not None:
                vectors[(vec[0], vec[1])] = (j, vec[2], name)
            elif temp is not None:
                if temp[0] is None:
                    one_temp = (j, temp[1], name)
                else:
                    temps[temp[0]] = (j, temp[1], name)
            else:
                raise LogError(f"{path}: line {line}: column {name[:40]!r} is not a log column (time_s, "
                               "gyro_<axis>_{radps,dps,dph}, accel_<axis>_{mps2,g,mg}, dtheta_<axis>_{rad,deg}, "
                               "dv_<axis>_mps, temp_<sensor>_<axis>_{c,k} or temp_{c,k}; docs/imu-log.md)")
        rate = all(("gyro", a) in vectors for a in range(3)) and all(("accel", a) in vectors for a in range(3))
        inc = all(("dtheta", a) in vectors for a in range(3)) and all(("dv", a) in vectors for a in range(3))
        kinds = {q for q, _ in vectors}
        if kinds & {"gyro", "accel"} and kinds & {"dtheta", "dv"}:
            raise LogError(f"{path}: line {line}: give increments (dtheta_/dv_ columns) or rates (gyro_/accel_ "
                           "columns), not both")
        if not (rate or inc):
            raise LogError(f"{path}: line {line}: needs gyro_x/y/z and accel_x/y/z columns (rates) or dtheta_x/y/z "
                           "and dv_x/y/z columns (increments), each with its unit")
        self.quantity = "rates" if rate else "increments"
        qs = ("gyro", "accel") if rate else ("dtheta", "dv")
        picked = [vectors[(q, a)] for q in qs for a in range(3)]
        self.imu_cols = [p[0] for p in picked]
        self.imu_scale = np.array([p[1] for p in picked])
        if temps and one_temp:
            raise LogError(f"{path}: line {line}: give one temperature (temp_c) or six, not both")
        if temps and len(temps) != 6:
            raise LogError(f"{path}: line {line}: give all six sensor temperatures or none")
        self.has_temps = bool(temps) or one_temp is not None
        if one_temp is not None:
            self.temp_cols, self.temp_offset = [one_temp[0]] * 6, np.full(6, one_temp[1])
        elif temps:
            self.temp_cols = [temps[i][0] for i in range(6)]
            self.temp_offset = np.array([temps[i][1] for i in range(6)])
        self.has_ref = False
        self.names = {"time_s": ["time_s"], "imu": [p[2] for p in picked],
                      "temperature": [header[c] for c in self.temp_cols] if self.has_temps else []}

    def feed(self, builder, data):
        time = data[:, self.time_col] if self.time_col is not None else None
        temps = data[:, self.temp_cols] + self.temp_offset if self.has_temps else None
        builder.feed(time, data[:, self.imu_cols] * self.imu_scale, temps, None)


# ------------------------------------------------------------------ i2Nav / KF-GINS IMU text

GPS_WEEK = 604800.0  # s: GNSS seconds of week wrap at the week's end


def _read_i2nav(path: Path, opts: ReadOptions) -> ImuLog:
    """The KF-GINS / i2Nav IMU text file: per line GNSS seconds of week, angle increments x, y, z (rad),
    velocity increments x, y, z (m/s), forward-right-down, separated by commas, spaces or tabs; columns
    past the seventh (an odometer) are ignored, as KF-GINS does.  A week rollover is unwrapped."""
    axes, code, given = _axes(path, opts, "i2nav")
    if opts.rate_hz is not None:
        raise LogError(f"{path}: an i2Nav file has its time; --rate-hz applies to a log without time")
    meta = {"source_format": "i2Nav IMU text (KF-GINS)"}
    builder = LogBuilder(path, _where_line(1), strict=False, quantity="increments", axes=axes, has_temps=False,
                         has_ref=False, accept_units=opts.accept_units)
    builder.names = {"time_s": ["GNSS seconds of week"], "imu": [f"column {j}" for j in range(2, 8)]}
    week_offset, last_t, n_cols = 0.0, None, None
    try:
        with TextReader(path, MAX_LOG_BYTES, "an IMU log (MAX_LOG_BYTES)") as text:
            for block in text.blocks():
                check_lines(path, block, text.eol or (b"\r\n" if block.data.find(b"\r\n") >= 0 else b"\n"),
                            None, MAX_DATA_LINE)
                if text.eol is None:
                    text.eol = b"\r\n" if b"\r\n" in block.data[:block.data.find(b"\n") + 1] else b"\n"
                data = _parse_i2nav(path, block)
                if n_cols is None:
                    n_cols = data.shape[1]
                    if n_cols < 7:
                        raise LogError(f"{path}: line 1: {n_cols} columns; the i2Nav IMU file has 7 (GNSS seconds "
                                       "of week, dtheta x y z in rad, dv x y z in m/s)")
                elif data.shape[1] != n_cols:
                    raise LogError(f"{path}: line {block.first_line}: the number of columns changed from {n_cols} "
                                   f"to {data.shape[1]}")
                t = data[:, 0].copy()
                prev = np.concatenate(([last_t], t[:-1])) if last_t is not None else np.concatenate(([t[0]], t[:-1]))
                wraps = np.cumsum(t - prev < -GPS_WEEK / 2)
                t += week_offset + wraps * GPS_WEEK
                week_offset += wraps[-1] * GPS_WEEK if wraps.size else 0.0
                last_t = float(data[-1, 0])
                builder.feed(t, data[:, 1:7])
    except TextError as exc:
        raise LogError(str(exc)) from None
    if n_cols is None:
        raise LogError(f"{path}: no samples")
    if n_cols > 7:
        meta["ignored_columns"] = str(n_cols - 7)
    return _finish(path, builder, meta, opts, "i2nav", code, given, "increments")


def _parse_i2nav(path, block) -> np.ndarray:
    data = block.data.replace(b"\t", b" ")
    comma = b"," in data[:4096]
    if comma:
        data = data.replace(b", ", b",").replace(b" ,", b",")
    try:
        return np.loadtxt(io.BytesIO(data), delimiter="," if comma else None, ndmin=2, comments=None, dtype=float,
                          encoding="latin-1")
    except ValueError as exc:
        raise LogError(f"{path}: {_csv_parse_message(str(exc), block.first_line - 1)}") from None


# ------------------------------------------------------------------ shared helpers

def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())[:200] or type(exc).__name__


def _check_header(path, line: int, header: list) -> None:
    seen = set()
    for name in header:
        if name in seen:
            raise LogError(f"{path}: line {line}: column {name} appears twice")
        seen.add(name)
        if name not in KNOWN_COLUMNS and not any(name.endswith(bad) for bad in _WRONG_UNITS):
            raise LogError(f"{path}: line {line}: column {name[:40]!r} is not a log column ({_known()})")


def _csv_parse_message(text, header_lines):
    """numpy's parse error with the file's line number."""
    m = re.search(r"at row (\d+)", text)
    if m:  # numpy counts data rows from 0 in conversion errors and from 1 in column-count errors
        row0 = int(m.group(1)) - (1 if "columns changed" in text else 0)
        return f"line {header_lines + 1 + row0}: {text}"
    return text


def _read_npz(path):
    try:
        with np.load(path, allow_pickle=False) as z:
            members = list(z.files)
            unknown = [k for k in members if k != "meta" and k not in KNOWN_COLUMNS
                       and not any(k.endswith(bad) for bad in _WRONG_UNITS)]
            if unknown:
                raise LogError(f"{path}: member {unknown[0]!r} is not a log column ({_known()})")
            columns = {}
            for name in members:
                if name == "meta":
                    continue
                col = z[name]
                if col.dtype.kind not in "fiu":
                    raise LogError(f"{path}: column {name} holds {col.dtype} values; the log takes numbers "
                                   "(float or integer arrays)")
                if col.ndim != 1:
                    raise LogError(f"{path}: column {name} must be one-dimensional")
                columns[name] = col.astype(float)
            meta_text = None
            if "meta" in members:
                raw = z["meta"]
                if raw.dtype.kind != "U" or raw.ndim != 0:
                    raise LogError(f"{path}: meta must be one string (a JSON object), got {raw.dtype} "
                                   f"of shape {raw.shape}")
                meta_text = str(raw)
    except LogError:
        raise
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError, zlib.error) as exc:
        raise LogError(f"{path}: not a readable NPZ log ({_one_line(exc)})") from None
    meta = {}
    if meta_text is not None:
        try:
            meta = json.loads(meta_text)
        except ValueError as exc:
            raise LogError(f"{path}: meta is not JSON ({exc})") from None
        if not isinstance(meta, dict):
            raise LogError(f"{path}: meta must be a JSON object")
        if len(meta) > MAX_META_KEYS:
            raise LogError(f"{path}: meta has {len(meta)} keys, more than the {MAX_META_KEYS} allowed")
        for key, value in meta.items():
            if not _KEY.fullmatch(key):
                raise LogError(f"{path}: meta key {key[:40]!r} must be letters, digits and '_'")
            if isinstance(value, bool) or not isinstance(value, (str, int, float)):
                raise LogError(f"{path}: meta {key}: a value must be a string or a number")
            if len(str(value)) > MAX_META_LINE:
                raise LogError(f"{path}: meta {key}: value longer than {MAX_META_LINE} characters")
    return columns, {k: str(v) for k, v in meta.items()}


def _known() -> str:
    return "time_s, dtheta_/dv_, gyro_/accel_, temp_ or ref_ columns of docs/imu-log.md"


