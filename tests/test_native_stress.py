"""Stress: the identified 4-FMU system (Turntable -> IMUThermal -> StrapdownINS
-> RBFIdentifier, ``sarins.systems.standard_static_identified``) in many fresh
processes, Python hosts (the project's FMPy master) and C hosts
(tests/native_host/system.c, Gauss-Seidel in the same order, no Python in the
process), with numba: every process must exit 0 (no crash at exit).  A short
run (10 min alignment, identification 5 min into navigation) keeps each
process to a few seconds."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from fmus.cbuild import build_line

from sarins.systems import standard_static_identified

pytestmark = pytest.mark.slow

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

import fmu_runs  # noqa: E402
ALIGN, TRIGGER, STEPS = 600.0, 300.0, 1200
PARAMS = dict(turntable=dict(align_time=ALIGN), ins=dict(align_time=ALIGN, coarse_time=120.0),
              identifier=dict(trigger_time=TRIGGER))


def clean_env() -> dict:
    return {k: v for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "PYTHONHOME", "LD_PRELOAD", "LD_LIBRARY_PATH")}


def write_plan(system, fmu_dir: Path, unzip_root: Path, steps: int, step: float, prints) -> Path:
    """The C master's plan file for ``system`` (FMUs unzipped under ``unzip_root``)."""
    body, index, mds = fmu_runs.system_plan_lines(system, unzip_root, lambda comp: fmu_dir / Path(comp.source).name)
    lines = [f"steps {steps} {step!r}"] + body
    for comp, name in prints:
        lines.append(f"print {index[comp]} {mds[comp][name].valueReference}")
    plan = unzip_root / "plan.txt"
    plan.write_text("\n".join(lines) + "\n")
    return plan


def _system(fmu_dir):
    return standard_static_identified(fmu_dir, hours=STEPS / 3600.0, **PARAMS)


def test_identified_system_in_50_c_host_processes(fmu_dir, tmp_path):
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler for the native test master")
    import fmpy

    exe = tmp_path / "system"
    build_line([cc, "-O2", "-o", str(exe), str(HERE / "native_host" / "system.c"),
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}", "-ldl"])
    plan = write_plan(_system(fmu_dir), fmu_dir, tmp_path / "unzipped", STEPS, 1.0,
                      [("identifier", "axial_drift"), ("ins", "position_error")])

    def one(_):
        return subprocess.run([str(exe), str(plan)], capture_output=True, text=True, timeout=600, env=clean_env())

    with ThreadPoolExecutor(2) as pool:
        runs = list(pool.map(one, range(50)))
    bad = [(r.returncode, r.stdout[-500:], r.stderr[-500:]) for r in runs if r.returncode != 0]
    assert not bad, f"{len(bad)}/50 C-host processes failed: {bad[:3]}"
    values = {r.stdout for r in runs}
    assert len(values) == 1 and f"DONE {STEPS}" in runs[0].stdout  # same numbers every time


PY_RUN = """
import sys
from pathlib import Path
sys.path[:0] = [{root!r}]
from orchestration import simulate_system
from sarins.systems import standard_static_identified
system = standard_static_identified(Path({fmu_dir!r}), hours={hours!r}, **{params!r})
result = simulate_system(system, {stop!r}, 1.0, progress=False,
                         record=["identifier.axial_drift", "ins.position_error"])
print("DONE", result["identifier.axial_drift"][-1], result["ins.position_error"][-1])
"""


def test_identified_system_in_100_python_processes(fmu_dir):
    code = PY_RUN.format(root=str(ROOT), fmu_dir=str(fmu_dir), hours=STEPS / 3600.0, params=PARAMS,
                         stop=float(STEPS))

    def one(_):
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600,
                              env=clean_env())

    with ThreadPoolExecutor(2) as pool:
        runs = list(pool.map(one, range(100)))
    bad = [(r.returncode, r.stderr[-800:]) for r in runs if r.returncode != 0]
    assert not bad, f"{len(bad)}/100 Python-host processes failed: {bad[:3]}"
    assert len({r.stdout for r in runs}) == 1 and "DONE" in runs[0].stdout
