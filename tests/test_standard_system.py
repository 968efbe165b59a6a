"""The standard static system (Turntable -> IMUThermal -> StrapdownINS) under
the FMPy master, a third-party engine (Ecos) and as one container FMU,
compared with the in-process library (schemes stated per test)."""

import os

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from fmu_fixtures.thirdparty import ensure_libtbb, has_module
from sarins.systems import SYSTEM_FMUS, SYSTEMS, build_system_fmu, standard_static
from orchestration import simulate_system, write_ssp
from sarins_fmu.experiments import run_static

SHORT_TT = dict(align_time=600.0)
SHORT_INS = dict(align_time=600.0, coarse_time=120.0)
RECORD = ["ins.lat_error", "ins.lon_error", "ins.position_error"]


@pytest.fixture(scope="module")
def short_ssp(fmu_dir):
    system = standard_static(fmu_dir, hours=0.5, turntable=SHORT_TT, ins=SHORT_INS, imu=dict(seed=4))
    return write_ssp(system, fmu_dir / "short.ssp")


def test_cosimulated_16h_equals_in_process(fmu_dir):
    """Issue acceptance: 4 h alignment + 12 h navigation, nav-rlg preset,
    Gauss-Seidel; the latitude error equals the in-process run's (1e-9)."""
    result = simulate_system(fmu_dir / "standard_static.ssp", 16 * 3600.0, 1.0, record=RECORD, progress=False)
    assert result.meta["scheme"] == "gauss-seidel"
    ref = run_static(align_hours=4.0, nav_hours=12.0, seed=0)
    lat = result["ins.lat_error"][1:][4 * 3600:]
    assert len(lat) == len(ref.lat_error)
    assert np.max(np.abs(lat - ref.lat_error)) <= 1e-9 * np.max(np.abs(ref.lat_error))
    assert np.max(np.abs(result["ins.position_error"][1:][4 * 3600:] - ref.position_error)) <= \
        1e-9 * np.max(ref.position_error)


def test_ecos_runs_the_same_ssp_with_the_same_numbers(short_ssp):
    """Ecos is a Jacobi engine: compare with the master's Jacobi scheme."""
    if not has_module("ecospy"):
        pytest.skip("ecospy is not installed (it is in the test extra)")
    reason = ensure_libtbb()
    if reason:
        pytest.skip(f"ecospy cannot load: {reason}")
    from orchestration.importers import simulate_with_ecos

    ours = simulate_system(short_ssp, 1800.0, 1.0, scheme="jacobi", record=RECORD, progress=False)
    ecos = simulate_with_ecos(short_ssp, 1800.0, 1.0, record=RECORD)
    assert ecos.meta["scheme"] == "jacobi"
    n = min(len(ours), len(ecos))
    for name in RECORD:
        scale = np.max(np.abs(ours[name]))
        assert scale > 0
        assert np.max(np.abs(ecos[name][-n:] - ours[name][-n:])) <= 1e-12 * scale


def test_system_as_one_container_fmu(fmu_dir, short_ssp, tmp_path):
    """The standard system packed as one FMU (FMPy container, FMI 2.0)
    validates and, run by FMPy, equals the master's Jacobi run."""
    import shutil

    for name in ("Turntable", "IMUThermal", "StrapdownINS"):
        shutil.copy2(fmu_dir / f"{name}.fmu", tmp_path / f"{name}.fmu")
    system = standard_static(tmp_path, hours=0.5, turntable=SHORT_TT, ins=SHORT_INS, imu=dict(seed=4))
    from orchestration.container import build_container_fmu
    from fmus.build import fix_fmu_description

    fmu = build_container_fmu(system, tmp_path / "System.fmu", step_size=1.0)
    fix_fmu_description(fmu, [(c.name, c.source) for c in system.components])
    assert validate_fmu(str(fmu)) == []
    packed = simulate_fmu(str(fmu), stop_time=1800.0, output_interval=1.0, output=RECORD)
    ours = simulate_system(short_ssp, 1800.0, 1.0, scheme="jacobi", record=RECORD, progress=False)
    for name in RECORD:
        a, b = packed[name][-1000:], ours[name][-1000:]
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))
    if os.environ.get("X_ECOS", "1") == "1" and has_module("ecospy") and not ensure_libtbb():  # and under Ecos, as a one-component system
        from orchestration import Component, System
        from orchestration.importers import simulate_with_ecos

        one = System(name="packed", components=[Component("sys", fmu)], connections=[])
        ecos = simulate_with_ecos(one, 1800.0, 1.0, record=[f"sys.{n}" for n in RECORD])
        for name in RECORD:
            a, b = ecos[f"sys.{name}"][-1000:], ours[name][-1000:]
            assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))


@pytest.mark.parametrize("name", list(SYSTEM_FMUS))
def test_build_fmus_system_option_validates(fmu_dir, name):
    path = build_system_fmu(fmu_dir, name)
    assert path.name == f"{name}.fmu" and validate_fmu(str(path)) == []


@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_imu_initialises_from_the_tables_start_temperature(fmu_dir, scheme):
    """The master sets connected inputs before each FMU leaves Initialization
    Mode, so the IMU's thermal state starts at the chamber's temperature
    (35 degC here), not at its own input's start value (20 degC)."""
    record = ["turntable.ambient_temp", "imu.temp_gyro_z"]
    runs = {}
    for ambient in (20.0, 35.0):
        system = standard_static(fmu_dir, hours=0.1, turntable=dict(ambient_mean=ambient, **SHORT_TT),
                                 ins=SHORT_INS, imu=dict(thermal_start="cold"))
        runs[ambient] = simulate_system(system, 60.0, 1.0, scheme=scheme, record=record, progress=False)
    assert runs[35.0]["turntable.ambient_temp"][0] == 35.0
    assert runs[35.0]["imu.temp_gyro_z"][0] - runs[20.0]["imu.temp_gyro_z"][0] == pytest.approx(15.0, abs=1e-6)


@pytest.mark.parametrize("name", list(SYSTEMS))
def test_shipped_systems_run_without_any_warning(fmu_dir, name, recwarn):
    """No input left unconnected by accident, no algebraic loop: the master has nothing to warn about
    (every shipped system, under both schemes)."""
    vehicle = name.startswith("vehicle_gnss")
    system = SYSTEMS[name](fmu_dir) if vehicle else SYSTEMS[name](fmu_dir, hours=0.01)
    for scheme in ("gauss-seidel", "jacobi"):  # vehicle_gnss*: the trajectory's own duration, its 0.01 s step
        simulate_system(system, 5.0, system.step_size, scheme=scheme, progress=False)
    assert [str(w.message) for w in recwarn] == []


@pytest.mark.parametrize("name", list(SYSTEMS))
def test_shipped_ssd_is_the_system_function(name):
    """sarins/systems/<name>/SystemStructure.ssd is what ``SYSTEMS[name]`` writes (rewrite it with
    ``sarins.systems.write_shipped_ssds()`` after changing a system)."""
    from pathlib import Path

    from orchestration.ssp_reader import read_system
    from sarins.systems import SHIPPED

    shipped = read_system(SHIPPED / name / "SystemStructure.ssd")
    made = SYSTEMS[name](Path("resources"))
    assert [(c.name, Path(c.source).name, c.parameters) for c in shipped.components] == \
        [(c.name, Path(c.source).name, c.parameters) for c in made.components]
    key = lambda c: (c.start_component, c.start_variable, c.end_component, c.end_variable)  # noqa: E731
    assert sorted(map(key, shipped.connections)) == sorted(map(key, made.connections))
    assert (shipped.start_time, shipped.stop_time, shipped.step_size) == (made.start_time, made.stop_time,
                                                                          made.step_size)
