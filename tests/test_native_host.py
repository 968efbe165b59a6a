"""The FMUs in a native host: a small C program (tests/native_host/host.c)
that dlopens an FMU's binary with no Python in the process and no
environment prepared (no PYTHONPATH, PYTHONHOME or LD_PRELOAD): the FMU finds
its Python runtime itself; the physics runs in the C core the FMU ships.
The slow tests stress process exit."""

from __future__ import annotations

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from fmus.cbuild import build_line
from fmpy import read_model_description


HERE = Path(__file__).resolve().parent
NAMES = ["Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier", "DriftModelUpdater", "VehicleMotion", "GNSSReceiver",
         "AidedINS"]
QUICK = {"IMUThermal": {"internal_rate": 10.0},  # plain-Python minor loop: keep the default run short
         # a static, level, north-pointing IMU at 28.222 deg (Earth rate and gravity per 1 s step)
         "StrapdownINS": {"dtheta_y": 6.4258e-5, "dtheta_z": 3.4486e-5, "dv_z": 9.7913, "align_time": 600.0},
         "AidedINS": {"step": 1.0, "lat0": 0.49256, "dtheta_y": 6.4258e-5, "dtheta_z": 3.4486e-5, "dv_z": 9.7913}}


@pytest.fixture(scope="session")
def host(tmp_path_factory):
    """The compiled C host (skipped without a C compiler)."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc) to build the native test host")
    import fmpy

    out = tmp_path_factory.mktemp("native_host") / "host"
    build_line([cc, "-O2", "-o", str(out), str(HERE / "native_host" / "host.c"),
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}", "-ldl"])
    return out


@pytest.fixture(scope="session")
def unzipped(fmu_dir, tmp_path_factory):
    """{name: (unzipped folder, model description)} of the session's FMUs."""
    out = tmp_path_factory.mktemp("native_fmus")
    result = {}
    for fmu in (fmu_dir / f"{name}.fmu" for name in NAMES):
        folder = out / fmu.stem
        with zipfile.ZipFile(fmu) as z:
            z.extractall(folder)
        result[fmu.stem] = (folder, read_model_description(str(fmu)))
    return result


def clean_env(**extra) -> dict:
    """The test process's environment without anything that would point the FMU at Python."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "LD_PRELOAD", "LD_LIBRARY_PATH", "VIRTUAL_ENV")}
    env.update(extra)
    return env


def run_host(host, folder, md, steps, *ops, env=None, timeout=300):
    cmd = [str(host), str(folder), md.coSimulation.modelIdentifier, md.guid, str(steps), *ops]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                          env=env if env is not None else clean_env())


def set_ops(md, values: dict) -> list[str]:
    by_name = {v.name: v for v in md.modelVariables}
    ops = []
    for name, value in values.items():
        var = by_name[name]
        kind = {"Real": "r", "Integer": "i", "String": "s"}[var.type]
        ops.append(f"{kind}{var.valueReference}={value}")
    return ops


@pytest.mark.parametrize("name", NAMES)
def test_each_fmu_runs_1000_steps_in_a_c_host(host, unzipped, name):
    folder, md = unzipped[name]
    proc = run_host(host, folder, md, 1000, *set_ops(md, QUICK.get(name, {})))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "STATUS" not in proc.stdout, proc.stdout
    assert proc.stdout.rstrip().endswith("DONE 1000"), proc.stdout


def test_bad_parameter_is_an_error_at_exit_initialization_in_a_c_host(host, unzipped):
    folder, md = unzipped["IMUThermal"]
    proc = run_host(host, folder, md, 10, *set_ops(md, {"preset": "bogus"}))
    assert proc.returncode == 0, proc.stderr
    assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout, proc.stdout
    assert "unknown IMU preset 'bogus'" in proc.stdout


def test_invalid_value_reference_is_an_error_not_fatal_in_a_c_host(host, unzipped):
    folder, md = unzipped["StrapdownINS"]
    integer_vr = next(v.valueReference for v in md.modelVariables if v.type == "Integer")
    proc = run_host(host, folder, md, 10, "probe-real=99999")
    assert "STATUS fmi2GetReal 3" in proc.stdout and "unknown value reference 99999" in proc.stdout, proc.stdout
    proc = run_host(host, folder, md, 10, f"probe-real={integer_vr}")
    assert "STATUS fmi2GetReal 3" in proc.stdout and "is an Integer, not a Real" in proc.stdout, proc.stdout
    assert proc.returncode == 0


def _unzip(fmu: Path, out: Path):
    folder = out / fmu.stem
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder, read_model_description(str(fmu))


def _final_values(proc) -> dict[int, float]:
    return {int(vr): float(v) for _, vr, v in (line.split() for line in proc.stdout.splitlines()
                                              if line.startswith("VALUE "))}


def test_the_standard_system_as_one_container_fmu_runs_in_a_c_host(host, fmu_dir, tmp_path):
    """FMPy's container binary loads our three FMUs in a process with no Python
    in it; after 1000 steps its INS output equals the master's Jacobi run."""
    from orchestration import simulate_system
    from orchestration.container import build_container_fmu
    from sarins.systems import standard_static

    for name in ("Turntable", "IMUThermal", "StrapdownINS"):
        shutil.copy2(fmu_dir / f"{name}.fmu", tmp_path / f"{name}.fmu")
    system = standard_static(tmp_path, hours=0.5, turntable=dict(align_time=600.0),
                             imu=dict(internal_rate=10.0), ins=dict(align_time=600.0))
    fmu = build_container_fmu(system, tmp_path / "System.fmu", step_size=1.0)
    folder, md = _unzip(fmu, tmp_path / "unzipped")
    outputs = ["ins.lat_error", "ins.position_error", "ins.nav_time"]
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    proc = run_host(host, folder, md, 1000, *(f"final-real={vrs[n]}" for n in outputs))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "STATUS" not in proc.stdout, proc.stdout
    assert proc.stdout.rstrip().endswith("DONE 1000"), proc.stdout
    values = _final_values(proc)
    # the host and this process run the same C core: bit for bit
    ours = simulate_system(system, 1000.0, 1.0, scheme="jacobi", record=outputs, progress=False)
    assert ours["ins.nav_time"][-1] == values[vrs["ins.nav_time"]] > 0
    for name in outputs:
        expected = ours[name][-1]
        assert values[vrs[name]] == expected, name


def test_the_identified_system_as_one_container_fmu_runs_in_a_c_host(host, fmu_dir, tmp_path):
    """Seed 000's whole loop (turntable -> IMU -> INS -> RBF identifier -> INS) as one FMU in a process
    with no Python: the identifier fires 600 s into navigation, the INS subtracts the drift from
    apply_from on, and every final output equals the master's Jacobi run bit for bit."""
    from orchestration import simulate_system
    from orchestration.container import build_container_fmu
    from sarins.systems import standard_static_identified

    for name in ("Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier"):
        shutil.copy2(fmu_dir / f"{name}.fmu", tmp_path / f"{name}.fmu")
    system = standard_static_identified(tmp_path, hours=0.6, turntable=dict(align_time=600.0),
                                        imu=dict(internal_rate=10.0), ins=dict(align_time=600.0),
                                        identifier=dict(trigger_time=600.0, latency=60.0))
    fmu = build_container_fmu(system, tmp_path / "Identified.fmu", step_size=1.0)
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []  # fmusim, for one, refuses a description FMPy finds problems in
    folder, md = _unzip(fmu, tmp_path / "unzipped")
    outputs = ["ins.lat_error", "ins.position_error", "ins.nav_time", "identifier.axial_drift",
               "identifier.apply_from"]
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    steps = 2000
    proc = run_host(host, folder, md, steps, *(f"final-real={vrs[n]}" for n in outputs))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "STATUS" not in proc.stdout, proc.stdout
    values = _final_values(proc)
    ours = simulate_system(system, float(steps), 1.0, scheme="jacobi", record=outputs, progress=False)
    assert ours["identifier.axial_drift"][-1] != 0.0  # identified within the run
    assert ours["ins.nav_time"][-1] > ours["identifier.apply_from"][-1] > 600.0
    for name in outputs:
        assert values[vrs[name]] == ours[name][-1], name


def test_the_imu_log_fmu_plays_a_log_in_a_c_host(host, tmp_path):
    """The HIL path's player (IMULog) in a native host, reading a simulated log."""
    import numpy as np

    from fmus.build import build_fmus
    from sarins_fmu.experiments.static_run import run_static
    from sarins_fmu.imu_log import write_log

    chunks = []
    run_static(imu="mems", align_hours=900 / 3600, nav_hours=200 / 3600, seed=3,
               on_increments=lambda *c: chunks.append(c))
    cols = [np.concatenate([c[j] for c in chunks]) for j in range(4)]
    log = write_log(tmp_path / "run.csv", *cols[:3], temps=cols[3], lat_deg=28.222)
    (fmu,) = build_fmus(tmp_path / "fmus", ["IMULog"])
    folder, md = _unzip(fmu, tmp_path / "unzipped")
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    proc = run_host(host, folder, md, 1000, *set_ops(md, {"log_file": str(log)}),
                    f"final-real={vrs['dtheta_x']}", f"final-real={vrs['increment_end_time']}")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "STATUS" not in proc.stdout, proc.stdout
    values = _final_values(proc)
    assert values[vrs["increment_end_time"]] == 1000.0
    assert values[vrs["dtheta_x"]] == cols[1][999, 0]
