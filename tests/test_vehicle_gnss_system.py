"""The vehicle_gnss system (TrajectoryIMU -> GNSSReceiver -> AidedINS, TrajectoryIMU -> AidedINS) through the
project's master: under Gauss-Seidel and Jacobi the rows at each nav_time equal the in-process aided run
(aided.navigate(aiding=('gnss',)) on the core stream's IMU, aided.corrupt(stream='core')) bit for bit:
navigation, bias estimates and the filter's sigmas, the GNSS outage included; with TrajectoryIMU's odometer
wired in (vehicle_gnss_odometer) likewise navigate(aiding=('gnss', 'odometer')), and with its ZUPT / NHC rows
too (vehicle_gnss_zupt) navigate(aiding=('gnss', 'zupt', 'zaru', 'nhc', 'odometer'), imu_stream='core'), and with
the stops detected by AidedINS from the vibrating IMU's increments (vehicle_gnss_zupt(zupt_detect='imu',
vibration=...)) navigate(..., zupt_detect='imu', vibration=..., imu_stream='core')."""

from __future__ import annotations

import numpy as np
import pytest

from orchestration import simulate_system, write_ssp
from sarins.systems import GNSS_DRIVE, vehicle_gnss, vehicle_gnss_odometer, vehicle_gnss_zupt
from sarins_fmu import aided, gnss
from sarins_fmu import zero_velocity as zv
from sarins_fmu import trajectory as tr

SEED = 4
OUTAGES = ((60.0, 80.0),)
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
OUT = NAV + [f"bias_{q}_{a}" for q in "ga" for a in "xyz"] + [f"sigma_{q}_{a}" for q in ("pos", "vel", "att")
                                                            for a in "enu"]


def navigate_rows(aiding, imu_stream=None, **kwargs):
    """navigate's rows (every 10th IMU step) and their times, and the valid fixes it applies (the IMU of the
    core's stream; ``imu_stream='core'``: the ZUPT / NHC jitter too; ``kwargs`` to navigate)."""
    truth = tr.generate(tr.Trajectory.from_dict(GNSS_DRIVE), 0.01)
    noise = aided.IMU_NOISE["tactical"]
    how = {"imu_stream": "core"} if imu_stream else {"imu": aided.corrupt(truth, noise, SEED, stream="core")}
    result = aided.navigate(truth, noise=noise, gnss=gnss.preset("sps", rate_hz=1.0), aiding=aiding,
                            outages=OUTAGES, seed=SEED, **how, **kwargs)
    sigma = np.sqrt(np.diagonal(result.cov, axis1=1, axis2=2)[:, :9])
    return result.time, np.column_stack([result.nav, result.bias_g, result.bias_a, sigma]), result.gnss_used


@pytest.fixture(scope="module")
def expected():
    return navigate_rows(("gnss",))


@pytest.fixture(scope="module")
def expected_odometer(expected):
    """navigate(aiding=('gnss', 'odometer')): other rows than GNSS alone, the filter's horizontal sigma at the
    outage's worst below 0.8 times GNSS alone's (1.06 m against 1.48 m)."""
    rows = navigate_rows(("gnss", "odometer"))
    outage = (rows[0] > OUTAGES[0][0]) & (rows[0] <= OUTAGES[0][1])
    assert not np.array_equal(rows[1], expected[1])
    sigma = [np.hypot(r[1][outage, -9], r[1][outage, -8]).max() for r in (rows, expected)]  # sigma_pos_e, _n
    assert sigma[0] < 0.8 * sigma[1], sigma
    return rows


@pytest.fixture(scope="module")
def expected_zupt(expected_odometer):
    """navigate(aiding gnss, zupt, zaru, nhc, odometer; imu_stream 'core'): other rows than the odometer's, the
    filter's horizontal sigma at the outage's worst below the odometer alone's."""
    rows = navigate_rows(("gnss", "zupt", "zaru", "nhc", "odometer"), imu_stream="core")
    outage = (rows[0] > OUTAGES[0][0]) & (rows[0] <= OUTAGES[0][1])
    assert not np.array_equal(rows[1], expected_odometer[1])
    sigma = [np.hypot(r[1][outage, -9], r[1][outage, -8]).max() for r in (rows, expected_odometer)]
    assert sigma[0] < sigma[1], sigma
    return rows


VIBRATION = zv.VIBRATION["car"]
ALL_AIDING = ("gnss", "zupt", "zaru", "nhc", "odometer")


@pytest.fixture(scope="module")
def expected_detected(expected_zupt):
    """navigate(all aiding, zupt_detect 'imu', the car's vibration, imu_stream 'core'): the detector finds the two
    stops, late by its window (of the truth's 2000 still steps 1901, and no moving step), the ZUPT and ZARU at
    those steps, other rows than at the truth's stops."""
    truth = tr.generate(tr.Trajectory.from_dict(GNSS_DRIVE), 0.01)
    noise = aided.IMU_NOISE["tactical"]
    dtheta, dv, _, _ = aided.corrupt(truth, noise, SEED, stream="core")
    vib_theta, vib_v = zv.vibrate(truth, VIBRATION, SEED, stream="core")
    found = zv.detect(dtheta + vib_theta, dv + vib_v, 0.01, noise.vrw, noise.arw).stationary
    still = truth.stationary()
    samples = zv.DetectorSettings().samples(0.01)
    assert not np.any(found & ~still) and still.sum() - 2 * samples <= found.sum() < still.sum()
    result = aided.navigate(truth, noise=noise, gnss=gnss.preset("sps", rate_hz=1.0), aiding=ALL_AIDING,
                            outages=OUTAGES, seed=SEED, imu_stream="core", zupt_detect="imu", vibration=VIBRATION)
    assert result.zupt_steps == result.zaru_steps == found.sum()
    rows = navigate_rows(ALL_AIDING, imu_stream="core", zupt_detect="imu", vibration=VIBRATION)
    assert not np.array_equal(rows[1], expected_zupt[1])
    return rows


@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_system_with_detected_stops_equals_navigate_bit_for_bit(fmu_dir, tmp_path, expected_detected, scheme):
    """TrajectoryIMU's vibrating increments -> AidedINS's stillness detector (zupt_source 1): navigate(all aiding,
    zupt_detect='imu', vibration=car, imu_stream='core')."""
    system = vehicle_gnss_zupt(fmu_dir, seed=SEED, outages=OUTAGES, zupt_detect="imu", vibration=VIBRATION)
    check_system(system, tmp_path, expected_detected, scheme)


def test_navigate_command_with_detected_stops_gives_the_systems_numbers(tmp_path, capsys, expected_detected):
    """``sarins navigate --aiding gnss,zupt,zaru,nhc,odometer --zupt-detect imu --imu-stream core --json`` (the car's
    vibration by default with --zupt-detect imu) prints the summary of the run whose rows the detected system
    gives (expected_detected: navigate's rows, equal to the system's in the test above)."""
    import json

    from sarins.cli import main

    path = tmp_path / "drive.json"
    path.write_text(json.dumps(GNSS_DRIVE))
    assert main(["navigate", "--trajectory", str(path), "--aiding", ",".join(ALL_AIDING), "--gnss-outage", "60:80",
                 "--seed", str(SEED), "--imu-stream", "core", "--zupt-detect", "imu", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    truth = tr.generate(tr.Trajectory.from_dict(GNSS_DRIVE), 0.01)
    time, rows, used = expected_detected
    true_rows = truth.nav_rows(np.round(time / 0.01).astype(int))
    nav = rows[:, :9]
    result = aided.AidedResult(time=time, nav=nav, truth=true_rows, error=aided.nav_errors(nav, true_rows),
                               cov=np.tile(np.eye(15), (len(time), 1, 1)), bias_g=nav[:, :3], bias_a=nav[:, :3],
                               bias_g_true=nav[:, :3], bias_a_true=nav[:, :3], gnss_used=used)
    made = aided.summary(result, OUTAGES)
    for key in ("horizontal_error_rms_m", "horizontal_error_max_m", "vertical_error_rms_m", "velocity_error_rms_mps",
                "tilt_error_rms_deg", "heading_error_rms_deg", "final_horizontal_error_m", "gnss_fixes_used"):
        assert made[key] == printed[key], key
    assert made["outages"][0]["horizontal_error_m"] == printed["outages"][0]["horizontal_error_m"]
    assert printed["zupt_steps"] == printed["zaru_steps"] < 2000


@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_system_with_zupt_and_nhc_equals_navigate_bit_for_bit(fmu_dir, tmp_path, expected_zupt, scheme):
    """TrajectoryIMU's odometer and ZUPT / NHC rows (ZARU from the same still flag) -> AidedINS:
    navigate(aiding=('gnss', 'zupt', 'zaru', 'nhc', 'odometer'), imu_stream='core')."""
    system = vehicle_gnss_zupt(fmu_dir, seed=SEED, outages=OUTAGES)
    assert system.name == "vehicle_gnss_zupt"
    check_system(system, tmp_path, expected_zupt, scheme)


@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_system_equals_navigate_bit_for_bit(fmu_dir, tmp_path, expected, scheme):
    check_system(vehicle_gnss(fmu_dir, seed=SEED, outages=OUTAGES), tmp_path, expected, scheme)


@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_system_with_the_odometer_equals_navigate_bit_for_bit(fmu_dir, tmp_path, expected_odometer, scheme):
    """TrajectoryIMU's odometer (10 Hz, seed SEED) -> AidedINS: navigate(aiding=('gnss', 'odometer'))."""
    system = vehicle_gnss_odometer(fmu_dir, seed=SEED, outages=OUTAGES)
    assert system.name == "vehicle_gnss_odometer"
    check_system(system, tmp_path, expected_odometer, scheme)


def check_system(system, tmp_path, expected, scheme):
    """The system's rows at each nav_time equal ``expected`` (navigate_rows) bit for bit, under ``scheme``."""
    path = write_ssp(system, tmp_path / f"{system.name}.ssp")
    names = [f"ins.{n}" for n in OUT] + ["ins.nav_time", "ins.fixes_used"]
    rows = simulate_system(path, scheme=scheme, record=names, progress=False)
    nav_time = np.asarray(rows["ins.nav_time"])
    got = np.column_stack([rows[n] for n in names[:len(OUT)]])
    time, want, used = expected
    lag = 0 if scheme == "gauss-seidel" else 2  # Jacobi: the fixes' path has two links, the INS waits for them
    np.testing.assert_array_equal(nav_time[lag:], np.asarray(rows["time"])[:len(nav_time) - lag])
    index = np.round(time / 0.01).astype(int) + lag  # the row whose nav_time is navigate's time
    keep = index < len(nav_time)
    assert keep.sum() == np.sum(time <= nav_time[-1]) >= len(time) - 1  # Jacobi: the last row is 2 steps late
    np.testing.assert_array_equal(nav_time[index[keep]], time[keep])
    np.testing.assert_array_equal(got[index[keep]], want[keep])
    assert rows["ins.fixes_used"][-1] == used > 100  # 124 fixes, 20 of them in the outage


def test_navigate_command_and_the_system_give_the_same_numbers(fmu_dir, tmp_path, capsys):
    """``sarins navigate --trajectory FILE --aiding gnss --json`` (its default stream: the core's) and the system's
    rows give
    the same summary numbers (every one computed from the navigation rows: errors, fixes used, the outage's
    error; NEES and the predicted sigma need P's off-diagonal terms, which the FMU does not output)."""
    import json

    from sarins.cli import main

    path = tmp_path / "drive.json"
    path.write_text(json.dumps(GNSS_DRIVE))
    assert main(["navigate", "--trajectory", str(path), "--aiding", "gnss", "--gnss-outage", "60:80", "--seed",
                 str(SEED), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["imu_stream"] == "core"
    assert main(["navigate", "--trajectory", str(path), "--aiding", "gnss", "--gnss-outage", "60:80", "--seed",
                 str(SEED), "--imu-stream", "numpy", "--json"]) == 0
    numpy_run = json.loads(capsys.readouterr().out)
    system = vehicle_gnss(fmu_dir, trajectory=str(path), seed=SEED, outages=OUTAGES)
    rows = simulate_system(system, scheme="jacobi", record=[f"ins.{n}" for n in NAV] + ["ins.nav_time",
                                                                                         "ins.fixes_used"],
                           progress=False)
    truth = tr.generate(tr.Trajectory.from_dict(GNSS_DRIVE), 0.01)
    index = np.arange(10, truth.n_steps + 1, 10)  # navigate's output steps
    row = np.searchsorted(np.round(np.asarray(rows["ins.nav_time"]) / 0.01), index)
    keep = row < len(rows)
    nav = np.column_stack([rows[f"ins.{n}"] for n in NAV])[row[keep]]
    true_rows = truth.nav_rows(index[keep])
    result = aided.AidedResult(time=truth.time[index[keep]], nav=nav, truth=true_rows,
                               error=aided.nav_errors(nav, true_rows), cov=np.tile(np.eye(15), (keep.sum(), 1, 1)),
                               bias_g=nav[:, :3], bias_a=nav[:, :3], bias_g_true=nav[:, :3], bias_a_true=nav[:, :3],
                               gnss_used=int(rows["ins.fixes_used"][-1]))
    made = aided.summary(result, OUTAGES)
    assert keep.all()  # the last output row (124.6 s) lies 3 steps before the end: Jacobi, 2 steps late, has it
    for key in ("duration_s", "horizontal_error_rms_m", "horizontal_error_max_m", "vertical_error_rms_m",
                "velocity_error_rms_mps", "tilt_error_rms_deg", "heading_error_rms_deg", "final_horizontal_error_m",
                "gnss_fixes_used"):
        assert made[key] == printed[key], key
    assert made["outages"][0]["horizontal_error_m"] == printed["outages"][0]["horizontal_error_m"]
    assert numpy_run["horizontal_error_rms_m"] != printed["horizontal_error_rms_m"]  # other draws: other numbers


def _tagged(fmu, name, params, steps):
    """Run ``steps`` (t, {input: value}) through one FMU; returns the log's texts and the status of the last."""
    from fmu_driver import Slave

    slave = Slave(fmu, name)
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        for t, values in steps:
            slave.set(**values)
            try:
                slave.fmu.doStep(t, 0.01)
            except Exception as exc:  # FMICallException: the refused step
                return [text for _, _, text in slave.log], str(exc)
        return [text for _, _, text in slave.log], "ok"
    finally:
        slave.free()


def test_out_of_order_tags_are_refused(fmu_dir):
    """A skipped interval, a NaN fix_horizon (AidedINS) and a truth tag out of order (GNSSReceiver) are refused
    with a reason; a repeated tag waits."""
    aided_params = {"step": 0.01, "lat0": 0.5}
    tags = [(0.0, {"increment_end_time": 0.01, "fix_horizon": 0.01}), (0.01, {"increment_end_time": 0.01}),
            (0.02, {"increment_end_time": 0.04})]
    log, status = _tagged(fmu_dir / "AidedINS.fmu", "ai_tags", aided_params, tags)
    assert "status 3" in status and any("the interval ending at 0.02 s was expected" in t for t in log), log
    log, status = _tagged(fmu_dir / "AidedINS.fmu", "ai_nan", aided_params,
                          [(0.0, {"increment_end_time": 0.01, "fix_horizon": float("nan")})])
    assert "status 3" in status and any("fix_horizon" in t for t in log), log
    rx = {"rate_hz": 10.0}
    log, status = _tagged(fmu_dir / "GNSSReceiver.fmu", "rx_tags", rx,
                          [(0.0, {"truth_time": 0.0}), (0.01, {"truth_time": 0.0}), (0.02, {"truth_time": 0.01}),
                           (0.03, {"truth_time": 0.04})])
    assert "status 3" in status and any("truth_time" in t for t in log), log
