"""docs/imu-presets.md lists every preset number with its value and a source.

The tables are parsed: every flat parameter of every preset (and of the
'premise' unit) must be matched by a row whose value equals the code's (in
the row's display unit) and whose source is not empty; every campaign
constant listed must equal the module's.
"""

import fnmatch
import importlib
import math
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu import earth, imu, imu_params
from sarins_fmu.experiments.online_rls import premise_model
from sarins_fmu.units import ARCSEC_TO_RAD, DAY, DEG_TO_RAD, DPH_TO_RPS, DPSH_TO_RPSS, UG_TO_MPS2

DOC = Path(__file__).resolve().parents[1] / "docs" / "imu-presets.md"
OTHERS = "(every other parameter)"

# display unit -> SI factor (value_SI = value * factor)
UNITS = {
    "1": 1.0, "-": 1.0, "s": 1.0, "d": DAY, "degC": 1.0, "rad/s": 1.0, "s/rad": 1.0, "s2/m": 1.0,
    "deg/h": DPH_TO_RPS, "deg/s": DEG_TO_RAD, "deg/sqrt(h)": DPSH_TO_RPSS, "ppm": 1e-6, "arcsec": ARCSEC_TO_RAD,
    "ug": UG_TO_MPS2, "mg": 1e3 * UG_TO_MPS2, "ug/sqrt(Hz)": UG_TO_MPS2, "m/s/sqrt(h)": 1.0 / 60.0,
    "deg/h/degC": DPH_TO_RPS, "deg/h/degC2": DPH_TO_RPS, "deg/s/degC": DEG_TO_RAD, "deg/s/degC2": DEG_TO_RAD,
    "ug/degC": UG_TO_MPS2, "ug/degC2": UG_TO_MPS2, "ppm/degC": 1e-6,
    "deg/h per degC/h": DPH_TO_RPS * 3600.0, "deg/h per degC/min": DPH_TO_RPS * 60.0,
    "ug per degC/min": UG_TO_MPS2 * 60.0, "ppm per degC/min": 1e-6 * 60.0,
    "deg/h/sqrt(h)": DPH_TO_RPS / 60.0, "ug/sqrt(s)": UG_TO_MPS2, "deg/s/g": DEG_TO_RAD / earth.GAMMA_E,
    "ms": 1e-3, "mm": 1e-3, "g": earth.GAMMA_E, "1/degC": 1.0,
}


def parse_tables(text: str) -> dict:
    """{section heading: [(parameter, value, unit, source), ...]} of every 4-column table."""
    tables, heading = {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            heading = line[3:].strip()
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")] if line.startswith("|") else None
        if heading is None or cells is None or len(cells) != 4 or cells[0] in ("parameter", "---"):
            continue
        tables.setdefault(heading, []).append((cells[0].strip("`"), cells[1], cells[2], cells[3]))
    return tables


def numbers(value: str) -> list:
    return [float(v) for v in value.split(",")]


def check_unit(model, rows, fallback=None) -> list:
    """Problems with the rows of one unit's table against ``model`` (flat parameters)."""
    flat = imu_params.flatten(model)
    names = [name for name, _, _ in imu_params.PARAMETERS]
    problems, matched = [], set()
    for param, value, unit, source in rows:
        if not source or source in ("-", "—"):
            problems.append(f"{param}: no source")
        if param == OTHERS:
            rest = [n for n in names if n not in matched]
            if value == "nav-rlg":
                ref = imu_params.flatten(fallback)
                problems += [f"{n}: {flat[n]} differs from nav-rlg" for n in rest if flat[n] != ref[n]]
            else:
                problems += [f"{n} = {flat[n]} is not listed (the catch-all row says 0)" for n in rest if flat[n] != 0]
            matched.update(rest)
            continue
        hits = [n for n in names if fnmatch.fnmatchcase(n, param) and n not in matched]
        if not hits:
            problems.append(f"row {param!r} matches no parameter")
            continue
        if unit not in UNITS:
            problems.append(f"{param}: unknown unit {unit!r}")
            continue
        vals = numbers(value)
        if len(vals) == 1:
            vals = vals * len(hits)
        if len(vals) != len(hits):
            problems.append(f"{param}: {len(vals)} values for {len(hits)} parameters")
            continue
        for n, v in zip(hits, vals):
            if not math.isclose(v * UNITS[unit], flat[n], rel_tol=1e-9, abs_tol=1e-300):
                problems.append(f"{n}: doc {v} {unit} = {v * UNITS[unit]!r}, code {flat[n]!r}")
        matched.update(hits)
    problems += [f"{n} is not listed" for n in names if n not in matched]
    return problems


@pytest.fixture(scope="module")
def tables():
    return parse_tables(DOC.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", sorted(imu.PRESETS))
def test_every_preset_number_is_listed_with_a_source(tables, name):
    rows = tables.get(f"Preset `{name}`")
    assert rows, f"docs/imu-presets.md has no table for preset {name!r}"
    assert check_unit(imu.PRESETS[name], rows) == []


def test_the_premise_unit_is_listed(tables):
    rows = tables["Unit `premise` (seed 002 sensitivity only)"]
    assert check_unit(premise_model(), rows, fallback=imu.preset("nav-rlg")) == []


def test_campaign_constants_match_the_code(tables):
    rows = tables["Campaign constants and scale factors"]
    assert rows
    for param, value, _, source in rows:
        module, _, attr = param.rpartition(".")
        assert source, param
        assert math.isclose(float(getattr(importlib.import_module(module), attr)), float(value), rel_tol=1e-12), param


def test_the_checker_catches_a_missing_or_changed_number(tables):
    rows = tables["Preset `nav-rlg`"]
    changed = imu_params.apply_overrides(imu.preset("nav-rlg"), {"gyro_random_walk_z": 1e-7})
    assert any("gyro_random_walk_z" in p for p in check_unit(changed, rows))
    new_term = imu_params.apply_overrides(imu.preset("nav-rlg"), {"gyro_turn_on_bias_x": 1e-8})
    assert any("gyro_turn_on_bias_x" in p for p in check_unit(new_term, rows))
    unsourced = [(p, v, u, "" if p.startswith("gyro_bias_[") else s) for p, v, u, s in rows]
    assert any("no source" in p for p in check_unit(imu.preset("nav-rlg"), unsourced))


def test_parser_reads_cells():
    text = "## Preset `x`\n\n| parameter | value | unit | source |\n|---|---|---|---|\n| `a_[xyz]` | 1, 2 | s | here |\n"
    assert parse_tables(text) == {"Preset `x`": [("a_[xyz]", "1, 2", "s", "here")]}
    assert np.allclose(numbers("1e-6, -3"), [1e-6, -3])
