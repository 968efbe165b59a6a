"""Per-engine comparison of every shipped system: the navigation solution at a common nav_time.

Runs each of sarins/systems' SSP systems under the master's Gauss-Seidel and
Jacobi, Ecos, libcosim and the FMPy container FMU, pairs the INS rows by
their ``nav_time`` tag (Jacobi engines add one step of latency per link) and
prints, per system, the value at the last common nav_time of each engine
and how many of the common rows are bit-identical to Gauss-Seidel.  Not a
speed benchmark: the numbers of the issue-11 table (docs/online-rls.md,
README).  Ecos and libcosim are skipped if not installed.

    python benchmarks/engine_table.py [--fmu-dir DIR] [--only NAME ...]
    python benchmarks/engine_table.py --write-readme [--fmu-dir DIR]

``--write-readme`` runs the master's Gauss-Seidel only and writes each system's
value into the README's engine table (its "value at that nav_time" column);
tests/test_docs_truth.py checks the README's ``standard_static`` value against
a fresh run.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import sarins_fmu.identify.axial  # noqa: E402,F401 - the FMUs' shared library copy must outlive each run
from fmus.build import build_fmus, fix_fmu_description  # noqa: E402
from orchestration import simulate_system, write_ssp  # noqa: E402
from sarins.systems import SYSTEMS  # noqa: E402

ALIGN = 4 * 3600.0  # s, the static systems' default alignment
# system -> (keyword arguments, nav_time compared at, value names); the static ones as the issue measured them
CASES = {
    "standard_static": ({"imu": {"seed": 0}}, 7000.0, ["position_error"]),
    "standard_static_identified": ({"imu": {"seed": 0}, "identifier": {"trigger_time": 3600.0}}, 7000.0,
                                   ["position_error"]),
    "vehicle_rins": ({}, 2900.0, ["lat", "lon"]),
    "vehicle_rins_online": ({}, 2790.0, ["lat", "lon"]),
}
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "position_error"]


def _rows(result, prefix="ins."):
    """{nav_time: tuple of NAV} (the first row of each nav_time: a Jacobi engine repeats the start)."""
    nav = np.asarray(result[prefix + "nav_time"])
    keep = np.concatenate([[True], np.diff(nav) != 0])
    values = np.column_stack([result[prefix + n] for n in NAV])[keep]
    return dict(zip(nav[keep].tolist(), map(tuple, values)))


def _align_time(system) -> float:
    ins = next(c for c in system.components if c.name == "ins")
    return float(ins.parameters.get("align_time", ALIGN))


def _engines(system, stop, tmp: Path):
    from fmu_fixtures.thirdparty import ensure_libtbb, has_module

    record = ["ins." + n for n in NAV] + ["ins.nav_time"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a shipped system runs without any warning
        for scheme in ("gauss-seidel", "jacobi"):
            yield f"master {scheme}", simulate_system(system, stop, 1.0, scheme=scheme, record=record, progress=False)
    if has_module("ecospy") and not ensure_libtbb():
        from orchestration.importers import simulate_with_ecos

        yield "Ecos", simulate_with_ecos(write_ssp(system, tmp / f"{system.name}.ssp"), stop, 1.0, record=record)
    if has_module("libcosimpy"):
        from orchestration.importers import simulate_with_libcosim

        yield "libcosim", simulate_with_libcosim(system, stop, 1.0, record=record)
    from fmpy import simulate_fmu

    from orchestration.container import build_container_fmu

    fmu = build_container_fmu(system, tmp / f"{system.name}.fmu", step_size=1.0)
    fix_fmu_description(fmu, [(c.name, c.source) for c in system.components])
    yield "container FMU", simulate_fmu(str(fmu), stop_time=stop, output_interval=1.0, output=record)


def compare(name: str, fmu_dir: Path, tmp: Path) -> list[str]:
    kwargs, nav_time, shown = CASES[name]
    stop = _stop(name, fmu_dir)
    system = SYSTEMS[name](fmu_dir, hours=stop / 3600.0, **kwargs)
    lines = []
    reference = None
    for engine, result in _engines(system, stop, tmp):
        rows = _rows(result)
        reference = reference or rows
        common = sorted(set(rows) & set(reference))
        same = sum(rows[t] == reference[t] for t in common)
        worst = max(max(abs(a - b) / max(abs(b), 1e-300) for a, b in zip(rows[t], reference[t])) for t in common)
        value = " / ".join(repr(float(rows[nav_time][NAV.index(n)])) for n in shown)
        lines.append(f"| {name} | {engine} | {value} | {same}/{len(common)} | {worst:.1e} |")
    return lines


def _stop(name: str, fmu_dir: Path) -> float:
    kwargs, nav_time, _ = CASES[name]
    return _align_time(SYSTEMS[name](fmu_dir, **kwargs)) + nav_time + 3.0  # Jacobi engines lag two steps at most


def reference_values(name: str, fmu_dir: Path) -> list[float]:
    """The ``shown`` values of system ``name`` at its compared nav_time under the master's Gauss-Seidel."""
    kwargs, nav_time, shown = CASES[name]
    stop = _stop(name, fmu_dir)
    system = SYSTEMS[name](fmu_dir, hours=stop / 3600.0, **kwargs)
    record = ["ins." + n for n in NAV] + ["ins.nav_time"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rows = _rows(simulate_system(system, stop, 1.0, scheme="gauss-seidel", record=record, progress=False))
    return [float(rows[nav_time][NAV.index(n)]) for n in shown]


README_ROW = {  # README engine-table row start -> (system, unit)
    "| `standard_static` (7000 s)": ("standard_static", "m"),
    "| `standard_static_identified`": ("standard_static_identified", "m"),
    "| `vehicle_rins` (2900 s)": ("vehicle_rins", "rad"),
    "| `vehicle_rins_online`": ("vehicle_rins_online", "rad"),
}


def readme_value(values: list[float], unit: str) -> str:
    """A README cell: the values' repr joined by ' / ', minus signs typeset, then the unit."""
    return " / ".join(repr(v).replace("-", "\u2212") for v in values) + f" {unit}"


def write_readme(fmu_dir: Path, readme: Path = ROOT / "README.md") -> None:
    """Write each system's Gauss-Seidel value into the README's engine table (second column)."""
    lines = readme.read_text(encoding="utf-8").split("\n")
    for i, line in enumerate(lines):
        for start, (name, unit) in README_ROW.items():
            if line.startswith(start):
                cells = line.split(" | ")
                cells[1] = readme_value(reference_values(name, fmu_dir), unit)
                lines[i] = " | ".join(cells)
                print(lines[i], flush=True)
    readme.write_text("\n".join(lines), encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fmu-dir", type=Path, default=None, help="built FMUs (default: build into a scratch folder)")
    parser.add_argument("--only", nargs="*", choices=list(CASES), default=list(CASES))
    parser.add_argument("--write-readme", action="store_true",
                        help="write the Gauss-Seidel values into README.md's engine table")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="engine_table_") as scratch:
        tmp = Path(scratch)
        fmu_dir = tmp / "fmus"
        if args.fmu_dir is None:
            build_fmus(fmu_dir, ["Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier", "VehicleMotion",
                                 "DriftModelUpdater"])
        else:
            shutil.copytree(args.fmu_dir, fmu_dir)
        if args.write_readme:
            write_readme(fmu_dir)
            return 0
        print("| system | engine | value at the common nav_time | rows bit-identical to GS | max relative "
              "difference |")
        print("|---|---|---|---|---|")
        for name in args.only:
            for line in compare(name, fmu_dir, tmp):
                print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
