"""Recorded IMU data: the log format, its reader (with checks) and writer.

Format (version 1), CSV for readability, NPZ for large logs; the same
columns in both.  A CSV log is::

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

An NPZ log holds one array per column (same names) and ``meta``, a JSON
object string of the metadata.  Numbers written by :func:`write_log` read
back bit for bit (CSV with 17 significant digits).

:func:`read_log` follows one grammar, written in docs/imu-log.md (line ends,
no blank lines, metadata and line-length limits, known columns only, numeric
NPZ columns, a clock starting at the recording's start) and refuses anything
else, naming the CSV line (or NPZ row); and the data checks: duplicated or
non-monotonic timestamps, gaps and rate changes, NaN or infinite values,
columns in other units, and unit mistakes over the whole log whether it rests
or moves (:func:`_check_units`).

Size budget: a CSV log larger than :data:`MAX_LOG_BYTES`, or an NPZ log
whose members expand to more than that (or that has more than
:data:`MAX_LOG_MEMBERS` members), is refused before it is parsed or
decompressed; a truncated or corrupted NPZ is refused naming the file.
"""

from __future__ import annotations

import json
import math
import re
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .files import BudgetError, check_file_size, check_zip_budget, naming_path

TAG = "# sarins-imu-log 1"
AXES = "xyz"
INCREMENT_COLUMNS = [f"dtheta_{a}_rad" for a in AXES] + [f"dv_{a}_mps" for a in AXES]
RATE_COLUMNS = [f"gyro_{a}_radps" for a in AXES] + [f"accel_{a}_mps2" for a in AXES]
TEMP_COLUMNS = [f"temp_{s}_{a}_c" for s in ("gyro", "accel") for a in AXES]
REF_COLUMNS = ["ref_lat_deg", "ref_lon_deg", "ref_height_m"]
MAX_GYRO_RATE = 35.0  # rad/s (2000 deg/s, the largest MEMS full scale)
STATIC_RATE_LIMIT = 1e-3  # rad/s (206 deg/h): Earth rate plus any plausible bias, at rest
MAX_LOG_BYTES = 2 * 2**30  # bytes: a CSV file, or an NPZ's members uncompressed (~240 days at 1 Hz, 13 columns)
MAX_LOG_MEMBERS = 64  # arrays in an NPZ log (the format has at most 19 columns and meta)
GRAVITY_RANGE = (9.0, 10.6)  # m/s^2, plausible |f| averaged over a static or turning start
MAX_SPECIFIC_FORCE = 16 * 9.80665  # m/s^2 (16 g, the largest MEMS accelerometer full scale)
STATIC_WINDOW = 60.0  # s, window of the gyro-against-tilt check, anywhere in the log
LEVEL_STEADY = 0.01  # rad: f keeps its body direction within this over a window -> no horizontal rotation
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
    """A recorded IMU log in SI units.

    time : (K,) s; dtheta (K, 3) rad; dv (K, 3) m/s (increments, whatever was stored);
    temps : (K, 6) degC or None; ref : (K, 3) lat rad, lon rad, height m, or None;
    lat, lon (rad), height (m): static start; meta : all metadata as text.
    """

    time: np.ndarray
    dtheta: np.ndarray
    dv: np.ndarray
    temps: np.ndarray | None
    ref: np.ndarray | None
    lat: float
    lon: float = 0.0
    height: float = 0.0
    meta: dict = field(default_factory=dict)
    quantity: str = "increments"

    @property
    def step(self) -> float:
        """Sample interval h, s."""
        return float(self.time[1] - self.time[0])


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


def _where(kind: str, first_data_line: int, row: int) -> str:
    return f"line {first_data_line + row}" if kind == "csv" else f"row {row}"


def read_log(path) -> ImuLog:
    """Read and check a log (see the module docstring); raises LogError naming the line."""
    path = Path(path)
    if not path.is_file():
        raise LogError(f"{path}: no such log file")
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
    if path.suffix == ".npz":
        kind, columns, meta, first = "npz", *_read_npz(path), 0
    else:
        kind, (columns, meta, first) = "csv", _read_csv(path)
    return _check(path, kind, columns, meta, first)


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


def _lines(path):
    """(number, text) of each line, EOL removed; refuses what the CSV grammar does not allow."""
    eol = None
    with open(path, "rb") as fh:
        for number, raw in enumerate(fh, start=1):
            ending = b"\r\n" if raw.endswith(b"\r\n") else b"\n" if raw.endswith(b"\n") else b""
            if ending:
                if eol is None:
                    eol = ending
                elif ending != eol:
                    raise LogError(f"{path}: line {number}: line ends in {_eol_name(ending)}, the lines before "
                                   f"in {_eol_name(eol)}; use one kind of line end")
            body = raw[: len(raw) - len(ending)]
            if b"\r" in body:
                raise LogError(f"{path}: line {number}: a carriage return inside the line")
            limit = MAX_META_LINE if body.startswith(b"#") else MAX_DATA_LINE
            if len(body) > limit:
                raise LogError(f"{path}: line {number}: longer than {limit} characters")
            try:
                text = body.decode("utf-8")
            except UnicodeDecodeError:
                raise LogError(f"{path}: line {number}: not UTF-8 text") from None
            if not text.strip():
                raise LogError(f"{path}: line {number}: blank line (the log has none: metadata, header, samples)")
            yield number, text


def _eol_name(ending: bytes) -> str:
    return "CRLF" if ending == b"\r\n" else "LF"


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())[:200] or type(exc).__name__


def _read_csv(path):
    meta, header, n_lines = {}, None, 0
    lines = _lines(path)
    for n_lines, line in lines:
        if n_lines == 1:
            if line != TAG:
                raise LogError(f"{path}: line 1 must be {TAG!r}, got {line[:60]!r}")
            continue
        if not line.startswith("#"):
            header = [c.strip() for c in line.split(",")]
            break
        if len(meta) >= MAX_META_KEYS:
            raise LogError(f"{path}: line {n_lines}: more than {MAX_META_KEYS} metadata lines")
        key, sep, value = line[1:].partition(":")
        key = key.strip()
        if not sep or not _KEY.fullmatch(key):
            raise LogError(f"{path}: line {n_lines}: metadata must read '# key: value' (key: letters, digits, '_')")
        if key in meta:
            raise LogError(f"{path}: line {n_lines}: metadata {key} given twice")
        meta[key] = value.strip()
    if header is None:
        raise LogError(f"{path}: no column header line")
    _check_header(path, n_lines, header)
    for number, line in lines:  # the line grammar of every sample line (numbers are parsed below)
        if line.startswith("#"):
            raise LogError(f"{path}: line {number}: a '#' line among the samples (metadata comes before the "
                           "column header)")
    first = n_lines + 1
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=n_lines, ndmin=2, comments=None, encoding="utf-8")
    except ValueError as exc:
        raise LogError(f"{path}: {_csv_parse_message(str(exc), n_lines)}") from None
    if data.shape[0] == 0:
        raise LogError(f"{path}: no samples after the header (line {n_lines})")
    if data.shape[1] != len(header):
        raise LogError(f"{path}: {len(header)} columns in the header, {data.shape[1]} in the data")
    return {name: data[:, j] for j, name in enumerate(header)}, meta, first


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
    import re

    m = re.search(r"at row (\d+)", text)
    if m:  # numpy counts data rows from 0 in conversion errors and from 1 in column-count errors
        row0 = int(m.group(1)) - (1 if "columns changed" in text else 0)
        return f"line {header_lines + 1 + row0}: {text}"
    return text


def _check(path, kind, columns, meta, first) -> ImuLog:
    where = lambda row: _where(kind, first, row)  # noqa: E731
    for name in columns:
        for bad, good in _WRONG_UNITS.items():
            if name.endswith(bad) and not name.startswith("ref_"):
                raise LogError(f"{path}: column {name!r}: the log takes SI units (…_{good}); convert it")
    if "time_s" not in columns:
        raise LogError(f"{path}: no time_s column")
    if any(c in columns for c in INCREMENT_COLUMNS) and any(c in columns for c in RATE_COLUMNS):
        raise LogError(f"{path}: give increments (dtheta_/dv_ columns) or rates (gyro_/accel_ columns), not both")
    if all(c in columns for c in INCREMENT_COLUMNS):
        quantity, names = "increments", INCREMENT_COLUMNS
    elif all(c in columns for c in RATE_COLUMNS):
        quantity, names = "rates", RATE_COLUMNS
    else:
        raise LogError(f"{path}: needs the columns {', '.join(INCREMENT_COLUMNS)} or {', '.join(RATE_COLUMNS)}")
    has_temps = [c in columns for c in TEMP_COLUMNS]
    if any(has_temps) and not all(has_temps):
        raise LogError(f"{path}: give all six temperature columns ({', '.join(TEMP_COLUMNS)}) or none")
    has_ref = [c in columns for c in REF_COLUMNS]
    if any(has_ref) and not all(has_ref):
        raise LogError(f"{path}: give all of {', '.join(REF_COLUMNS)} or none")
    used = ["time_s", *names] + (TEMP_COLUMNS if all(has_temps) else []) + (REF_COLUMNS if all(has_ref) else [])
    lengths = {len(columns[c]) for c in used}
    if len(lengths) != 1:
        raise LogError(f"{path}: columns have different lengths")
    data = np.column_stack([columns[c] for c in used])
    if data.shape[0] < 2:
        raise LogError(f"{path}: a log needs at least two samples")
    bad = ~np.isfinite(data)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise LogError(f"{path}: {where(row)}: {used[col]} is {data[row, col]} (NaN or infinite)")
    time = data[:, 0]
    dt = np.diff(time)
    if np.any(dt <= 0):
        row = int(np.argmax(dt <= 0)) + 1
        what = "duplicated" if dt[row - 1] == 0 else "earlier than the one before (non-monotonic)"
        raise LogError(f"{path}: {where(row)}: timestamp {float(time[row]):.10g} s is {what}")
    h = dt[0]
    off = np.abs(dt - h) > 1e-6 * h
    if off.any():
        row = int(np.argmax(off)) + 1
        kind_of = "a gap" if dt[row - 1] > 1.5 * h else "a rate change"
        raise LogError(f"{path}: {where(row)}: time step {dt[row - 1]:.9g} s differs from the log's "
                       f"{h:.9g} s ({kind_of}); logs must be uniformly sampled")
    outputs = data[:, 1:7]
    rates = outputs / h if quantity == "increments" else outputs
    fast = np.linalg.norm(rates[:, :3], axis=1) > MAX_GYRO_RATE
    if fast.any():
        row = int(np.argmax(fast))
        raise LogError(f"{path}: {where(row)}: angular rate {np.linalg.norm(rates[row, :3]):.4g} rad/s is beyond "
                       f"any IMU ({MAX_GYRO_RATE} rad/s): degrees logged as radians?")
    _check_time_start(path, where, time[0], h)
    _check_units(path, where, rates, h, quantity)
    if "lat_deg" not in meta:
        raise LogError(f"{path}: metadata lat_deg (static start latitude, deg) is required")
    try:
        lat, lon, height = (float(meta.get(k, "0")) for k in ("lat_deg", "lon_deg", "height_m"))
    except ValueError:
        raise LogError(f"{path}: lat_deg, lon_deg and height_m must be numbers") from None
    if not (math.isfinite(lat) and math.isfinite(lon) and math.isfinite(height)) or abs(lat) > 89.9:
        raise LogError(f"{path}: lat_deg {lat} must be finite and within +-89.9 deg")
    inc = outputs if quantity == "increments" else outputs * h
    temps = data[:, 7:13] if all(has_temps) else None
    ref = None
    if all(has_ref):
        r = data[:, -3:]
        ref = np.column_stack([np.radians(r[:, 0]), np.radians(r[:, 1]), r[:, 2]])
    return ImuLog(time=time, dtheta=np.ascontiguousarray(inc[:, :3]), dv=np.ascontiguousarray(inc[:, 3:]),
                  temps=temps, ref=ref, lat=math.radians(lat), lon=math.radians(lon), height=height, meta=meta,
                  quantity=quantity)


def _check_time_start(path, where, t0: float, h: float) -> None:
    """time_s counts from the start of the recording: the first sample ends within (0, h] (or is at 0)."""
    tol = TIME_START_TOLERANCE * h
    if not -tol <= t0 <= h + tol:
        raise LogError(f"{path}: {where(0)}: the first timestamp is {t0:.10g} s; time_s counts from the start of "
                       f"the recording, so the first sample lies in [0, h] = [0, {h:.9g}] s (subtract the start "
                       "time)")


def _check_units(path, where, rates: np.ndarray, h: float, quantity: str) -> None:
    """Unit mistakes, wherever the log moves or rests (docs/imu-log.md, 'Units'):

    * every sample: |rate| <= 35 rad/s (2000 deg/s) and |specific force| <= 16 g, the largest
      full scales of any IMU, so degrees or increments/rates confused show at once;
    * the whole log: the mean of |f| is gravity (9.0 .. 10.6 m/s^2) -- a vehicle's accelerations
      average out over a log, g units do not;
    * every 60 s window whose specific force keeps its direction: the gyros' horizontal rate
      (:func:`_check_level_rate`).
    """
    gyro_norm = np.linalg.norm(rates[:, :3], axis=1)
    fast = gyro_norm > MAX_GYRO_RATE
    if fast.any():
        row = int(np.argmax(fast))
        raise LogError(f"{path}: {where(row)}: angular rate {gyro_norm[row]:.4g} rad/s is beyond "
                       f"any IMU ({MAX_GYRO_RATE} rad/s): degrees logged as radians?")
    force = np.linalg.norm(rates[:, 3:], axis=1)
    strong = force > MAX_SPECIFIC_FORCE
    if strong.any():
        row = int(np.argmax(strong))
        raise LogError(f"{path}: {where(row)}: specific force {force[row]:.4g} m/s^2 is beyond any IMU "
                       f"({MAX_SPECIFIC_FORCE:.4g} m/s^2 = 16 g): rates logged as {quantity} or the reverse?")
    g_mean = float(np.mean(force))
    if not GRAVITY_RANGE[0] <= g_mean <= GRAVITY_RANGE[1]:
        raise LogError(f"{path}: {where(0)}..{where(len(force) - 1)}: mean specific force {g_mean:.4g} m/s^2 over "
                       "the log is not gravity (accelerations in g, or rates logged as increments or the reverse?)")
    _check_level_rate(path, where, rates, h)


def _check_level_rate(path, where, rates: np.ndarray, h: float) -> None:
    """Gyros against accelerometers: in a window where the specific force keeps its direction in the
    body (at rest, turning about the vertical, cruising level), the body does not rotate about a
    horizontal axis, so the gyros' rate perpendicular to f is the Earth's horizontal rate plus bias,
    Omega cos L + b <= 1e-3 rad/s.  Logged in degrees it is 57 times the Earth's, 4.2e-3 cos L rad/s
    (above the limit below 76 deg latitude); the turn rate about the vertical does not enter."""
    block = max(1, int(round(1.0 / h)))  # 1 s means first: the white noise of fast logs averages out
    n_blocks = len(rates) // block
    if n_blocks == 0:
        return
    means = rates[:n_blocks * block].reshape(n_blocks, block, 6).mean(axis=1)
    per_window = max(1, min(n_blocks, int(round(STATIC_WINDOW / (block * h)))))
    for start in range(0, n_blocks - per_window + 1, per_window):
        omega, force = means[start:start + per_window, :3], means[start:start + per_window, 3:]
        up = force.mean(axis=0)
        norm_up = np.linalg.norm(up)
        directions = force / np.linalg.norm(force, axis=1)[:, None]
        if norm_up == 0.0 or np.max(np.arccos(np.clip(directions @ (up / norm_up), -1.0, 1.0))) > LEVEL_STEADY:
            continue  # the body tilts in this window: its gyros' horizontal rate is free
        up /= norm_up
        horizontal = omega - np.outer(omega @ up, up)
        rate = float(np.median(np.linalg.norm(horizontal, axis=1)))
        if rate > STATIC_RATE_LIMIT:
            first, last = start * block, (start + per_window) * block - 1
            raise LogError(f"{path}: {where(first)}..{where(last)}: the gyros turn {rate:.3g} rad/s about a horizontal "
                           "axis while the accelerometers see no tilt (at most the Earth rate, 7.3e-5 rad/s, plus "
                           "bias): degrees logged as radians?")
