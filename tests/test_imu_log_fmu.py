"""IMULog FMU: a recorded log played into the StrapdownINS FMU (the HIL path)."""

import numpy as np
import pytest

from fmus.build import build_fmus
from sarins_fmu.experiments.replay import replay
from sarins_fmu.experiments.static_run import run_static
from sarins_fmu.imu_log import read_log, write_log
from tests.fmu_driver import Slave, check_parameter_error

pytestmark = [pytest.mark.integration, pytest.mark.slow]  # builds its own two FMUs
ALIGN, NAV = 900.0, 300.0
INCREMENTS = ["dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z", "temp_gyro_z", "increment_end_time"]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    out = tmp_path_factory.mktemp("logfmus")
    build_fmus(out, ["IMULog", "StrapdownINS"])
    return out


@pytest.fixture(scope="module")
def log_file(tmp_path_factory):
    chunks = []
    run_static(imu="nav-rlg", align_hours=ALIGN / 3600, nav_hours=NAV / 3600, seed=2,
               on_increments=lambda *c: chunks.append(c))
    cols = [np.concatenate([c[j] for c in chunks]) for j in range(4)]
    return write_log(tmp_path_factory.mktemp("log") / "run.csv", *cols[:3], temps=cols[3], lat_deg=28.222)


def test_log_played_into_the_ins_fmu_equals_the_in_process_replay(fmus, log_file):
    player, ins = Slave(fmus / "IMULog.fmu", "player"), Slave(fmus / "StrapdownINS.fmu", "ins")
    try:
        player.set(log_file=str(log_file))
        ins.set(lat0=np.radians(28.222), align_time=ALIGN, coarse_time=300.0)
        for s in (player, ins):
            s.fmu.enterInitializationMode()
        for s in (player, ins):
            s.fmu.exitInitializationMode()
        assert player.get("lat_deg", "log_step") == [pytest.approx(28.222), 1.0]
        rows = []
        for k in range(int(ALIGN + NAV)):
            player.fmu.doStep(float(k), 1.0)
            ins.fmu.setReal([ins.vr[n] for n in INCREMENTS], player.get(*INCREMENTS))
            ins.fmu.doStep(float(k), 1.0)
            rows.append(ins.get("lat_error", "lon_error", "position_error"))
        # one step past the end of the log fails the step
        from fmpy.fmi1 import FMICallException

        with pytest.raises(FMICallException):
            player.fmu.doStep(ALIGN + NAV, 1.0)
        assert any("the log ends" in text for _, _, text in player.log)
    finally:
        player.free()
        ins.free()
    cosim = np.array(rows)[int(ALIGN):]
    ref = replay(read_log(log_file), align_hours=ALIGN / 3600)
    for j, series in enumerate((ref.lat_error, ref.lon_error, ref.position_error)):
        scale = np.max(np.abs(series))
        assert scale > 0 and np.max(np.abs(cosim[:, j] - series)) <= 1e-9 * scale


def test_imu_log_fmu_refuses_a_missing_or_bad_log(fmus, tmp_path):
    check_parameter_error(fmus / "IMULog.fmu", {}, "log_file is empty")
    check_parameter_error(fmus / "IMULog.fmu", {"log_file": str(tmp_path / "none.csv")}, "no such log file")
    bad = tmp_path / "bad.csv"
    bad.write_text("# sarins-imu-log 1\n# lat_deg: 10\ntime_s,dtheta_x_rad\n1,0\n")
    check_parameter_error(fmus / "IMULog.fmu", {"log_file": str(bad)}, "needs the columns")
