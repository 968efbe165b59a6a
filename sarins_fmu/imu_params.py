"""Flat, named parameters of an :class:`~sarins_fmu.imu.ImuModel`.

Tools that speak in scalar parameters (FMUs, CSV sweeps) see an IMU model as
a list of names such as ``gyro_bias_x`` or ``accel_misalignment_yz``, each in
SI units.  :func:`flatten` turns a model into ``{name: value}``,
:func:`apply_overrides` builds a model from a preset plus any subset of those
names, and :data:`UNITS` gives the unit of each name.
"""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np

from .imu import ImuModel, TriadErrors
from .thermal import SENSORS, ThermalParams

AXES = "xyz"
_TRIAD_UNITS = {  # field -> (gyro unit, accelerometer unit)
    "bias": ("rad/s", "m/s2"),
    "scale_factor": ("1", "1"),
    "random_walk": ("rad/sqrt(s)", "m/s/sqrt(s)"),
    "bias_instability": ("rad/s", "m/s2"),
    "bias_corr_time": ("s", "s"),
    "bias_tc1": ("rad/s/degC", "m/s2/degC"),
    "bias_tc2": ("rad/s/degC2", "m/s2/degC2"),
    "scale_factor_tc": ("1/degC", "1/degC"),
    "quadratic": ("s/rad", "s2/m"),
    "bias_dtdt": ("rad/degC", "m/s/degC"),  # per degC/s of die temperature rate
    "scale_factor_dtdt": ("s/degC", "s/degC"),
    "hysteresis": ("rad/s", "m/s2"),
    "hysteresis_width": ("degC", "degC"),
    "flicker": ("rad/s", "m/s2"),
    "rate_random_walk": ("rad/s/sqrt(s)", "m/s2/sqrt(s)"),
    "turn_on_bias": ("rad/s", "m/s2"),
    "filter_time_constant": ("s", "s"),
    "rate_hysteresis": ("rad/s", "m/s2"),
    "rate_hysteresis_width": ("rad/s", "m/s2"),
    "rate_hysteresis_time": ("s", "s"),
    "rate_hysteresis_tc": ("1/degC", "1/degC"),
}
_PERIODIC_UNITS = {  # field -> (gyro unit, accelerometer unit); last in PARAMETERS (added after the others)
    "periodic_amplitude": ("rad/s", "m/s2"),
    "periodic_frequency": ("Hz", "Hz"),
}
_AXIAL_SCALARS = ("axial_drift_grad", "axial_block_time_constant", "axial_hysteresis", "axial_hysteresis_width",
                  "axial_hysteresis_relax_time")  # scalar ImuModel fields of the azimuth gyro's thermal terms
_OFF_DIAGONAL = [(i, j) for i in range(3) for j in range(3) if i != j]


def _names():
    """(name, unit, getter, setter-key) for every flat parameter."""
    out = []
    for t, triad in enumerate(("gyro", "accel")):
        for f, units in _TRIAD_UNITS.items():
            for i, ax in enumerate(AXES):
                out.append((f"{triad}_{f}_{ax}", units[t], (triad, f, i)))
        for i, j in _OFF_DIAGONAL:
            out.append((f"{triad}_misalignment_{AXES[i]}{AXES[j]}", "rad", (triad, "misalignment", (i, j))))
    for i in range(3):
        for j in range(3):
            out.append((f"g_sensitivity_{AXES[i]}{AXES[j]}", "rad/s/(m/s2)", ("g_sensitivity", (i, j))))
    for i in range(3):
        for j in range(3):  # accelerometer i's position, component j
            out.append((f"accel_lever_arm_{AXES[i]}{AXES[j]}", "m", ("accel_lever_arm", (i, j))))
    for i, ax in enumerate(AXES):
        out.append((f"lowrate_gain_{ax}", "1", ("lowrate_gain", i)))
        out.append((f"lowrate_width_{ax}", "rad/s", ("lowrate_width", i)))
    for i, (coef, unit) in enumerate(zip("abc", ("rad/s/degC2", "rad/s/degC", "rad/s"))):
        out.append((f"axial_drift_{coef}", unit, ("axial_drift_poly", i)))
        out.append((f"aging_sigma_{coef}", unit, ("aging_sigma", i)))
    out.append(("axial_drift_dtdt", "rad/degC", ("axial_drift_dtdt",)))
    out.append(("axial_drift_grad", "rad/s/degC", ("axial_drift_grad",)))
    out.append(("axial_block_time_constant", "s", ("axial_block_time_constant",)))
    out.append(("axial_hysteresis", "rad/s", ("axial_hysteresis",)))
    out.append(("axial_hysteresis_width", "degC", ("axial_hysteresis_width",)))
    out.append(("axial_hysteresis_relax_time", "s", ("axial_hysteresis_relax_time",)))
    out.append(("aging_corr_time", "s", ("aging_corr_time",)))
    out.append(("flicker_tau_min", "s", ("flicker_tau_min",)))
    out.append(("flicker_tau_max", "s", ("flicker_tau_max",)))
    for j, sensor in enumerate(SENSORS):
        out.append((f"self_heating_{sensor}", "degC", ("thermal", "self_heating", j)))
        out.append((f"time_constant_{sensor}", "s", ("thermal", "time_constant", j)))
        out.append((f"die_time_constant_{sensor}", "s", ("thermal", "die_time_constant", j)))
    for t, triad in enumerate(("gyro", "accel")):
        for f, units in _PERIODIC_UNITS.items():
            for i, ax in enumerate(AXES):
                out.append((f"{triad}_{f}_{ax}", units[t], (triad, f, i)))
    return out


PARAMETERS = _names()
PERIODIC_NAMES = tuple(name for name, _, key in PARAMETERS if key[1:2] and key[1] in _PERIODIC_UNITS)
UNITS = {name: unit for name, unit, _ in PARAMETERS}


def _get(model: ImuModel, key):
    if key[0] in ("gyro", "accel"):
        value = getattr(getattr(model, key[0]), key[1])
        return float(value[key[2]])
    if key[0] == "thermal":
        return float(getattr(model.thermal, key[1])[key[2]])
    value = getattr(model, key[0])
    return float(value if len(key) == 1 else np.asarray(value)[key[1]])


def flatten(model: ImuModel) -> dict:
    """All flat parameters of ``model`` as {name: float} (SI units, see UNITS)."""
    return {name: _get(model, key) for name, _, key in PARAMETERS}


def apply_overrides(model: ImuModel, overrides: dict) -> ImuModel:
    """Copy of ``model`` with the named flat parameters replaced.

    Raises ValueError naming any unknown parameter or non-finite value.
    """
    keys = {name: key for name, _, key in PARAMETERS}
    unknown = sorted(set(overrides) - set(keys))
    if unknown:
        raise ValueError(f"unknown IMU parameter(s): {', '.join(unknown)}")
    arrays = {
        "gyro": {f.name: np.array(getattr(model.gyro, f.name), float) for f in fields(TriadErrors)},
        "accel": {f.name: np.array(getattr(model.accel, f.name), float) for f in fields(TriadErrors)},
        "thermal": {f.name: list(getattr(model.thermal, f.name)) for f in fields(ThermalParams)},
        "top": {name: np.array(getattr(model, name), float) for name in
                ("g_sensitivity", "accel_lever_arm", "lowrate_gain", "lowrate_width", "axial_drift_poly",
                 "aging_sigma", "axial_drift_dtdt", "aging_corr_time", "flicker_tau_min", "flicker_tau_max",
                 *_AXIAL_SCALARS)},
    }
    for name, value in overrides.items():
        value = float(value)
        if not np.isfinite(value):
            raise ValueError(f"IMU parameter {name} must be finite, got {value}")
        key = keys[name]
        if key[0] in ("gyro", "accel", "thermal"):
            arrays[key[0]][key[1]][key[2]] = value
        elif len(key) == 1:
            arrays["top"][key[0]] = np.array(value)
        else:
            arrays["top"][key[0]][key[1]] = value
    _check_named(model, overrides)
    top = arrays["top"]
    return replace(
        model,
        gyro=TriadErrors(**arrays["gyro"]),
        accel=TriadErrors(**arrays["accel"]),
        thermal=ThermalParams(**{k: tuple(v) for k, v in arrays["thermal"].items()}),
        g_sensitivity=top["g_sensitivity"], accel_lever_arm=top["accel_lever_arm"],
        lowrate_gain=top["lowrate_gain"], lowrate_width=top["lowrate_width"],
        axial_drift_poly=top["axial_drift_poly"], aging_sigma=top["aging_sigma"],
        axial_drift_dtdt=float(top["axial_drift_dtdt"]), aging_corr_time=float(top["aging_corr_time"]),
        flicker_tau_min=float(top["flicker_tau_min"]), flicker_tau_max=float(top["flicker_tau_max"]),
        **{name: float(top[name]) for name in _AXIAL_SCALARS},
    )


def _check_named(model: ImuModel, overrides: dict) -> None:
    """The core's parameter checks (``sarins_imu_check_params``) on ``model`` with ``overrides``: ValueError
    naming the flat parameter at fault (the model's own checks would name its field, not the flat name)."""
    from .core import imu as core_imu

    flat = {**flatten(model), **{name: float(value) for name, value in overrides.items()}}
    problem = core_imu.check_params([flat[name] for name in core_imu.param_names()])
    if problem is not None:
        raise ValueError(f"IMU parameter {problem}")


# --------------------------------------------------------------------------- the C core's copy (one source)

C_HEADER = "sarins_fmu/core/imu_params.h"
C_SOURCE = "sarins_fmu/core/imu_params.c"
_GENERATED = ("/* Generated by `python -m sarins_fmu.imu_params` from sarins_fmu/imu_params.py and the presets of\n"
              " * sarins_fmu/imu.py (the one source); do not edit: tests/test_imu_params_c.py checks it is current. */\n")


def _c_name(name: str) -> str:
    return "SARINS_IMU_P_" + name.upper()


def c_sources() -> tuple[str, str]:
    """The C core's header and source of the flat parameters and the presets as data: the index of every
    name (``SARINS_IMU_P_<NAME>``, the order of :data:`PARAMETERS`), the names, and each preset's values
    (``repr`` of the float64, so the C values are the Python ones bit for bit)."""
    from .imu import PRESETS

    names = [name for name, _, _ in PARAMETERS]
    enum = ",\n".join(f"    {_c_name(n)}{' = 0' if i == 0 else ''}" for i, n in enumerate(names))
    header = (_GENERATED + "/* The flat IMU parameters (SI units, sarins_fmu/imu_params.py UNITS) and the presets.\n"
              " * A parameter vector holds SARINS_IMU_N_PARAMS doubles in this order. */\n"
              "#ifndef SARINS_IMU_PARAMS_H\n#define SARINS_IMU_PARAMS_H\n\n#include <stdint.h>\n\n"
              f"enum {{\n{enum},\n    SARINS_IMU_N_PARAMS\n}};\n\n"
              f"#define SARINS_IMU_N_PRESETS {len(PRESETS)}\n\n"
              "/* Name of parameter i (NULL outside 0..SARINS_IMU_N_PARAMS-1). */\n"
              "const char *sarins_imu_param_name(int64_t i);\n\n"
              "/* Index of the parameter called name, or -1. */\n"
              "int64_t sarins_imu_param_index(const char *name);\n\n"
              "/* Name of preset i (NULL outside 0..SARINS_IMU_N_PRESETS-1). */\n"
              "const char *sarins_imu_preset_name(int64_t i);\n\n"
              "/* The SARINS_IMU_N_PARAMS values of the preset called name into out; 0, or -1 for an unknown name\n"
              " * (out untouched). */\n"
              "int sarins_imu_preset_params(const char *name, double *out);\n\n#endif\n")
    rows = []
    for preset, model in PRESETS.items():
        flat = flatten(model)
        values = ",\n".join(f"        {flat[n]!r}" for n in names)
        rows.append(f"    {{\"{preset}\",\n     {{\n{values}\n     }}}}")
    name_list = ",\n".join(f'    "{n}"' for n in names)
    source = (_GENERATED + "#include \"smath.h\"\n\n"
              "#include <stddef.h>\n#include <stdint.h>\n#include <string.h>\n\n#include \"imu_params.h\"\n\n"
              f"static const char *const NAMES[SARINS_IMU_N_PARAMS] = {{\n{name_list}\n}};\n\n"
              "static const struct {\n    const char *name;\n    double values[SARINS_IMU_N_PARAMS];\n}"
              f" PRESETS[SARINS_IMU_N_PRESETS] = {{\n{(',' + chr(10)).join(rows)}\n}};\n\n"
              "const char *sarins_imu_param_name(int64_t i) {\n"
              "    return i >= 0 && i < SARINS_IMU_N_PARAMS ? NAMES[i] : NULL;\n}\n\n"
              "int64_t sarins_imu_param_index(const char *name) {\n"
              "    for (int64_t i = 0; name != NULL && i < SARINS_IMU_N_PARAMS; i++) {\n"
              "        if (strcmp(NAMES[i], name) == 0) return i;\n    }\n    return -1;\n}\n\n"
              "const char *sarins_imu_preset_name(int64_t i) {\n"
              "    return i >= 0 && i < SARINS_IMU_N_PRESETS ? PRESETS[i].name : NULL;\n}\n\n"
              "int sarins_imu_preset_params(const char *name, double *out) {\n"
              "    for (int i = 0; name != NULL && i < SARINS_IMU_N_PRESETS; i++) {\n"
              "        if (strcmp(PRESETS[i].name, name) == 0) {\n"
              "            memcpy(out, PRESETS[i].values, sizeof PRESETS[i].values);\n"
              "            return 0;\n        }\n    }\n    return -1;\n}\n")
    return header, source


def write_c_sources(root=None) -> None:
    """Write :func:`c_sources` under the project folder ``root`` (default: this package's parent)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] if root is None else Path(root)
    header, source = c_sources()
    (root / C_HEADER).write_text(header)
    (root / C_SOURCE).write_text(source)


if __name__ == "__main__":
    write_c_sources()
