"""IMU presets in files: a JSON preset that ``--imu FILE.json`` accepts, and its SSP parameter set.

A preset file holds the flat parameters of :mod:`sarins_fmu.imu_params` (SI units) over a named
built-in preset::

    {"sarins_imu_preset": 1,
     "name": "unit1",
     "base": "ideal",
     "source": "fitted by sarins allan --write-preset to LOG",
     "parameters": {"gyro_random_walk_x": 0.00071, ...},
     "units": {"gyro_random_walk_x": "rad/sqrt(s)", ...},
     "info": {...}}

``parameters`` may name any subset of the flat parameters (the others are the base preset's);
``units`` and ``info`` are for the reader (units must match :data:`sarins_fmu.imu_params.UNITS`
when given).  The file is plain JSON, at most :data:`MAX_PRESET_BYTES`.

The IMUThermal FMU takes the same model as start values: its String parameter ``preset`` = the
base, and one Real parameter per flat name (setting one overrides the preset).  :func:`write_ssv`
writes them as an SSP parameter-values file (``.ssv``, SSP 1.0) that an SSP system binds to the
IMUThermal component, so the master, and any SSP tool, runs the FMU on the fitted unit.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from xml.sax.saxutils import quoteattr

from .files import BudgetError, check_file_size, naming_path

FORMAT_KEY = "sarins_imu_preset"
FORMAT_VERSION = 1
MAX_PRESET_BYTES = 1 * 2**20  # a preset file larger than this is refused before it is read


class PresetFileError(ValueError):
    """A preset file that cannot be used; the message names the file."""


def is_preset_file(name: str) -> bool:
    """True if ``name`` names a preset file (ends in .json) rather than a built-in preset."""
    return str(name).lower().endswith(".json")


def write_preset(path, model, *, name: str, source: str, info: dict | None = None, base: str = "ideal") -> Path:
    """Write ``model`` as a preset file: every flat parameter that differs from ``base``'s."""
    from . import imu, imu_params

    flat, ref = imu_params.flatten(model), imu_params.flatten(imu.preset(base))
    params = {k: v for k, v in flat.items() if v != ref[k]}
    doc = {FORMAT_KEY: FORMAT_VERSION, "name": name, "base": base, "source": source, "parameters": params,
           "units": {k: imu_params.UNITS[k] for k in params}, "info": info or {}}
    path = Path(path)
    with naming_path(path):
        path.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return path


def read_preset(path):
    """The :class:`~sarins_fmu.imu.ImuModel` of a preset file; PresetFileError naming the file and the fault."""
    from . import imu, imu_params

    doc = _load(path)
    try:
        return imu_params.apply_overrides(imu.preset(doc["base"]), doc["parameters"])
    except ValueError as exc:
        raise PresetFileError(f"{path}: {exc}") from None


def _load(path) -> dict:
    from . import imu, imu_params

    path = Path(path)
    try:
        check_file_size(path, MAX_PRESET_BYTES, "an IMU preset file (MAX_PRESET_BYTES)")
        text = path.read_text(encoding="utf-8")
    except BudgetError as exc:
        raise PresetFileError(str(exc)) from None
    except FileNotFoundError:
        raise PresetFileError(f"{path}: no such IMU preset file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PresetFileError(f"{path}: cannot be read as a preset file ({exc})") from None
    try:
        doc = json.loads(text, parse_constant=_no_constant)
    except (ValueError, RecursionError) as exc:
        raise PresetFileError(f"{path}: not valid JSON ({' '.join(str(exc).split())[:120]})") from None
    if not isinstance(doc, dict) or doc.get(FORMAT_KEY) != FORMAT_VERSION:
        raise PresetFileError(f"{path}: not an IMU preset file (needs \"{FORMAT_KEY}\": {FORMAT_VERSION})")
    if doc.get("base") not in imu.PRESETS:
        raise PresetFileError(f"{path}: base must be one of {', '.join(imu.PRESETS)}, got {doc.get('base')!r}")
    params = doc.get("parameters")
    if not isinstance(params, dict):
        raise PresetFileError(f"{path}: 'parameters' must be an object of flat IMU parameters")
    for key, value in params.items():
        if key not in imu_params.UNITS:
            raise PresetFileError(f"{path}: unknown IMU parameter {key!r}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise PresetFileError(f"{path}: parameter {key} must be a finite number")
    units = doc.get("units", {})
    if not isinstance(units, dict):
        raise PresetFileError(f"{path}: 'units' must be an object")
    for key, unit in units.items():
        if imu_params.UNITS.get(key) != unit:
            raise PresetFileError(f"{path}: parameter {key} is in {imu_params.UNITS.get(key)!r}, the file says {unit!r}")
    return doc


def _no_constant(name):
    raise ValueError(f"{name} is not a number a preset can hold")


def fmu_start_values(path) -> dict:
    """The IMUThermal FMU's start values for a preset file: {'preset': base, flat name: value, ...}
    (every flat parameter, so the FMU's result does not depend on its own defaults)."""
    from . import imu_params

    doc = _load(path)
    return {"preset": doc["base"], **imu_params.flatten(read_preset(path))}


def write_ssv(path, preset_path, *, name: str = "imu_preset") -> Path:
    """An SSP 1.0 parameter-values file (.ssv) with :func:`fmu_start_values` of a preset file: bind it
    to the IMUThermal component of a system (``ssd:ParameterBinding source=...``)."""

    values = fmu_start_values(preset_path)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
             f'version="1.0" name={quoteattr(name)}>', "  <ssv:Parameters>",
             f'    <ssv:Parameter name="preset"><ssv:String value={quoteattr(values.pop("preset"))}/></ssv:Parameter>']
    for key, value in values.items():
        lines.append(f'    <ssv:Parameter name="{key}"><ssv:Real value="{value!r}"/></ssv:Parameter>')
    lines += ["  </ssv:Parameters>", "</ssv:ParameterSet>", ""]
    path = Path(path)
    with naming_path(path):
        path.write_text("\n".join(lines), encoding="utf-8")
    return path
