"""The standard and the identified static system with K-second communication steps (FMI 3.0, every second of
a step in arrays: ``standard_static(seconds_per_step=K)``): the 1 s system's numbers, bit for bit, at every
K-th second, with the IMU on one or two threads of its own; bad K refused."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from orchestration import Master
from sarins.systems import standard_static, standard_static_identified
from sarins_fmu.experiments import run_static

pytestmark = pytest.mark.integration

K = 60                     # s per communication step
ALIGN, HOURS = 900.0, 1.0  # s of alignment, h of the whole run
RECORD = ["ins.lat_error", "ins.lon_error", "ins.position_error", "ins.yaw", "ins.nav_time"]


@pytest.fixture(scope="module")
def fmus3(fmu3_dir, tmp_path_factory):
    """The session's FMI 3.0 Turntable, IMUThermal and StrapdownINS with an FMI 3.0 RBFIdentifier beside them."""
    from fmus import SLAVES
    from fmus.native_fmu import build_native_fmu

    folder = tmp_path_factory.mktemp("fmus3_identified")
    for name in ("Turntable", "IMUThermal", "StrapdownINS"):
        (folder / f"{name}.fmu").write_bytes((fmu3_dir / f"{name}.fmu").read_bytes())
    build_native_fmu("RBFIdentifier", SLAVES["RBFIdentifier"], folder, fmi=3, win64=False, aarch64=False)
    return folder


def simulate(system, record=RECORD):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no input left unconnected, no other complaint
        with Master(system, record=record) as master:
            return master.simulate(system.stop_time, system.step_size, progress=False)


def aligned(**extra):
    return dict(turntable=dict(align_time=ALIGN), ins=dict(align_time=ALIGN), hours=HOURS, **extra)


@pytest.mark.parametrize("threads", [1, 2])
def test_k_second_steps_give_the_in_process_run(fmus3, threads):
    res = simulate(standard_static(fmus3, seconds_per_step=K, threads=threads, **aligned()))
    assert len(res) == HOURS * 3600 / K + 1 and np.array_equal(res["time"], np.arange(0.0, HOURS * 3600 + 1, K))
    ref = run_static(align_hours=ALIGN / 3600, nav_hours=HOURS - ALIGN / 3600, seed=0)
    nav = int(ALIGN) // K + 1  # the first row in navigation; in-process row i is the end of navigation second i
    for field in ("lat_error", "position_error"):
        got, want = res[f"ins.{field}"][nav:], getattr(ref, field)[K - 1::K]
        assert got.tobytes() == want.tobytes(), field
    assert np.max(np.abs(ref.lat_error)) > 0  # navigation errors grew


def test_an_alignment_off_the_step_grid_still_gives_the_in_process_run(fmus3):
    """930 s of alignment with 60 s steps: navigation starts inside a step; every recorded row in navigation
    is the in-process run's at that time, bit for bit."""
    align = 930.0
    res = simulate(standard_static(fmus3, seconds_per_step=K, threads=2, hours=HOURS,
                                   turntable=dict(align_time=align), ins=dict(align_time=align)))
    ref = run_static(align_hours=align / 3600, nav_hours=HOURS - align / 3600, seed=0)
    nav = res["time"] > align
    second = (res["time"][nav] - align).astype(int)  # in-process row i ends navigation second i + 1
    assert second[0] == 30 and res["ins.lat_error"][nav].tobytes() == ref.lat_error[second - 1].tobytes()


def test_the_identified_system_at_k_seconds_is_the_1s_system(fmus3, fmu_dir):
    identifier = dict(trigger_time=1200.0)  # s of navigation: on the grid of K, the network evaluated once
    record = RECORD + ["identifier.axial_drift", "identifier.apply_from"]
    fast = simulate(standard_static_identified(fmus3, seconds_per_step=K, threads=2, identifier=identifier,
                                               **aligned()), record)
    slow = simulate(standard_static_identified(fmu_dir, identifier=identifier, **aligned()), record)
    assert fast["identifier.axial_drift"][-1] != 0.0  # it fired, and the INS subtracted it
    for name in record:
        assert fast[name].tobytes() == slow[name][::K].tobytes(), name


def test_the_imu_threads_default_to_the_in_process_run(fmus3, monkeypatch):
    monkeypatch.setenv("SARINS_THREADS", "3")
    imu = standard_static(fmus3, seconds_per_step=K).components[1]
    assert imu.parameters["threads"] == 3 and imu.parameters["sub_inputs"] == 1
    assert "threads" not in standard_static(fmus3).components[1].parameters  # 1 s steps: no threads


@pytest.mark.parametrize("bad", [0, 2.5, -60, 100_001, True, "60"])
def test_bad_seconds_per_step_are_refused(fmus3, bad):
    with pytest.raises(ValueError, match="seconds_per_step must be a whole number of seconds in 1 .. 100000"):
        standard_static(fmus3, seconds_per_step=bad)


def test_the_written_60s_systems_run_from_their_ssp_files(fmus3, tmp_path):
    """write_systems3 (``sarins build-fmus --fmi 3``): each .ssp read back runs as the system it was written
    from, bit for bit."""
    import shutil

    from orchestration.ssp_reader import read_system
    from sarins.systems import SECONDS_PER_STEP, SYSTEMS3, write_systems3

    for fmu in fmus3.glob("*.fmu"):
        shutil.copy2(fmu, tmp_path / fmu.name)
    paths = write_systems3(tmp_path)
    assert [p.name for p in paths] == [f"{name}.ssp" for name in SYSTEMS3]
    written = read_system(paths[0])
    assert written.step_size == SECONDS_PER_STEP
    shorter = [standard_static(tmp_path, seconds_per_step=K), written]  # the defaults: 4 h of alignment
    for system in shorter:
        system.stop_time = HOURS * 3600
    a, b = (simulate(s) for s in shorter)
    for name in RECORD:
        assert a[name].tobytes() == b[name].tobytes(), name
    assert np.ptp(a["ins.yaw"]) > 0  # the alignment's heading estimate moves
