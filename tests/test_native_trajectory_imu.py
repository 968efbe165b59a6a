"""The native TrajectoryIMU FMU (fmus/c/trajectory_imu/model.c over the core's traj.h + aided_imu.h).

After doStep(t_k, h) its outputs are the truth row k + 1 of sarins_fmu.trajectory.generate and the measured
increments of step k of aided.corrupt(..., stream='core') bit for bit, and its odometer's readings those
navigate's odometer aiding applies (aided.per_step_aiding), its ZUPT and NHC rows those of
aided.per_step_aiding(..., stream='core'); the core stream's errors have the stated statistics; an FMU state taken
mid-run repeats the rest, a state of the previous version is refused; bad parameters are refused naming them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu_driver import Slave, check_parameter_error
from fmus.native_fmu import build_native_fmu
from sarins_fmu import aided
from sarins_fmu import trajectory as tr

STEP = 0.01
SEED = 7
SEGMENTS = ({"kind": "stop", "duration": 1}, {"kind": "accelerate", "to_speed": 8, "accel": 2.0},
            {"kind": "turn", "rate_dps": 15, "angle_deg": 45}, {"kind": "climb", "to_pitch_deg": 2, "duration": 1},
            {"kind": "cruise", "duration": 1})
START = tr.Start(lat_deg=35.0, lon_deg=118.0, height=20.0, heading_deg=-30.0)
NOISE = aided.IMU_NOISE["tactical"]
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
OUT = NAV + [f"omega_ib_{a}" for a in "xyz"] + ["truth_time"] + [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"] \
    + ["increment_end_time"] + [f"true_bias_{q}_{a}" for q in "ga" for a in "xyz"]


def parameters(trajectory, noise, seed, step) -> dict:
    """The FMU's start values for a trajectory, an IMU noise grade and a seed (as sarins.systems writes them)."""
    start = trajectory.start.array()
    table = trajectory.table(step)
    params = {"segments": "; ".join(" ".join(repr(float(x)) for x in row) for row in table), "step": step}
    params.update(dict(zip(["lat0", "lon0", "height0", "speed0", "yaw0", "pitch0"], start.tolist())))
    params.update(dict(zip(["arw", "vrw", "gyro_bias_std", "accel_bias_std", "gyro_rw", "accel_rw"],
                           noise.array().tolist())))
    params["seed"] = seed
    return params


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    return build_native_fmu("TrajectoryIMU", "trajectory_imu_slave.py", tmp_path_factory.mktemp("ti"), win64=False,
                            aarch64=False)


@pytest.fixture(scope="module")
def expected():
    trajectory = tr.Trajectory(START, SEGMENTS)
    truth = tr.generate(trajectory, STEP)
    dtheta, dv, bg, ba = aided.corrupt(truth, NOISE, SEED, stream="core")
    k = truth.n_steps
    t = np.arange(1, k + 1) * STEP
    rows = np.column_stack([truth.nav_rows()[1:], truth.omega_ib_b[1:], t, dtheta, dv, t, bg, ba])
    return parameters(trajectory, NOISE, SEED, STEP), rows


def _run(fmu, params, n, state_at=None):
    slave = Slave(fmu, "ti")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        first = slave.get(*OUT)
        out, again = [], []
        for k in range(n):
            if k == state_at:
                state = slave.fmu.getFMUstate()
            slave.fmu.doStep(k * STEP, STEP)
            out.append(slave.get(*OUT))
        if state_at is not None:
            slave.fmu.setFMUstate(state)
            for k in range(state_at, n):
                slave.fmu.doStep(k * STEP, STEP)
                again.append(slave.get(*OUT))
        return np.array(first), np.array(out), np.array(again)
    finally:
        slave.free()


def test_fmu_equals_generate_and_corrupt_bit_for_bit(fmu, expected):
    params, rows = expected
    first, got, again = _run(fmu, params, len(rows), state_at=150)
    np.testing.assert_array_equal(got, rows)
    np.testing.assert_array_equal(again, rows[150:])
    truth = tr.generate(tr.Trajectory(START, SEGMENTS), STEP)
    np.testing.assert_array_equal(first[:12], np.concatenate([truth.nav_rows()[0], truth.omega_ib_b[0]]))
    assert first[12] == first[19] == 0.0  # both tags at the start time: no increments yet


def test_a_step_past_the_end_is_refused(fmu, expected):
    params, rows = expected
    slave = Slave(fmu, "end")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        for k in range(len(rows)):
            slave.fmu.doStep(k * STEP, STEP)
        with pytest.raises(Exception, match="status 3"):
            slave.fmu.doStep(len(rows) * STEP, STEP)
        assert any("past the trajectory's end" in text for _, _, text in slave.log)
    finally:
        slave.free()


def test_core_stream_statistics():
    """White parts: std arw sqrt(h), vrw sqrt(h); constant biases: std bias_std; random walk: the bias
    change over the run has std rw sqrt(T).  Each sample std within 5 sigma of its chi-square law."""
    noise = aided.ImuNoise(arw=2e-4, vrw=3e-3, gyro_bias_std=1e-5, accel_bias_std=2e-3, gyro_rw=1e-6, accel_rw=1e-5)
    truth = tr.generate(tr.Trajectory(START, ({"kind": "stop", "duration": 20},)), STEP)
    k = truth.n_steps
    dtheta, dv, bg, ba = aided.corrupt(truth, noise, 3, stream="core")
    white_g = (dtheta - truth.dtheta - bg * STEP).ravel()
    white_a = (dv - truth.dv - ba * STEP).ravel()
    for values, sigma in ((white_g, noise.arw * math.sqrt(STEP)), (white_a, noise.vrw * math.sqrt(STEP))):
        n = values.size
        assert abs(np.std(values) / sigma - 1) < 5 / math.sqrt(2 * n)
        assert abs(np.mean(values)) < 5 * sigma / math.sqrt(n)
    seeds = range(400)
    b0 = np.array([np.concatenate(aided.corrupt(truth, noise, s, stream="core")[2:])[[0, k]] for s in seeds])
    for j, sigma in ((0, noise.gyro_bias_std), (1, noise.accel_bias_std)):
        values = b0[:, j].ravel()
        assert abs(np.std(values) / sigma - 1) < 5 / math.sqrt(2 * values.size)
    walk = np.diff(bg, axis=0).ravel()  # the gyro bias step per IMU step: rw sqrt(h)
    assert abs(np.std(walk) / (noise.gyro_rw * math.sqrt(STEP)) - 1) < 5 / math.sqrt(2 * walk.size)


@pytest.mark.parametrize("params, text", [
    ({"segments": ""}, "segments"),
    ({"segments": "10 0 0"}, "segments"),
    ({"segments": "1.5 0 0 0"}, "segments"),
    ({"step": 0.0}, "step"),
    ({"substeps": 0}, "substeps"),
    ({"arw": -1.0}, "arw"),
    ({"lat0": 1.6}, "lat0"),
    ({"speed0": -1.0}, "speed0"),
    ({"seed": -1}, "seed"),
    ({"odo_rate_hz": -1.0}, "odo_rate_hz"),
    ({"odo_rate_hz": 30.0}, "odo_rate_hz = 30: 1 / (odo_rate_hz step) = 3.33"),
    ({"odo_rate_hz": 200.0}, "odo_rate_hz"),
    ({"odo_noise_std": -0.1}, "odo_noise_std"),
    ({"odo_scale_factor": 0.5}, "odo_scale_factor"),
    ({"odo_seed": -1}, "odo_seed"),
    ({"zupt_enable": 3}, "zupt_enable = 3 must be 0 or 1 (or 2"),
    ({"vib_accel_rms": -0.1}, "vib_accel_rms = -0.10000000000000001 must be finite and >= 0"),
    ({"vib_rate_rms": float("inf")}, "vib_rate_rms"),
    ({"nhc_enable": -1}, "nhc_enable = -1 must be 0 or 1"),
    ({"zupt_std": -0.01}, "zupt_std"),
    ({"nhc_std": float("nan")}, "nhc_std"),
    ({"jitter_seed": -1}, "jitter_seed"),
])
def test_bad_parameters_are_refused(fmu, params, text):
    check_parameter_error(fmu, params, text)


@pytest.mark.parametrize("rate_hz", [10.0, 100.0])
def test_odometer_equals_navigates_readings_bit_for_bit(fmu, expected, rate_hz):
    """odo_valid after the steps per_step_aiding gives a reading to, odo_speed its reading (seed odo_seed), the
    rest of the outputs unchanged; an FMU state taken between readings repeats the rest."""
    trajectory = tr.Trajectory(START, SEGMENTS)
    truth = tr.generate(trajectory, STEP)
    odometer = aided.OdometerConfig(rate_hz=rate_hz, scale_factor=0.01)
    aid = aided.per_step_aiding(truth, ("odometer",), aided.FilterSettings(), odometer, None, 11)
    params, rows = expected
    params = {**params, "odo_rate_hz": rate_hz, "odo_scale_factor": 0.01, "odo_noise_std": odometer.noise_std,
              "odo_resolution": odometer.resolution, "odo_seed": 11}
    slave = Slave(fmu, "odo")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        assert slave.fmu.getInteger([slave.vr["odo_valid"]]) == [0]
        got, flags, speeds, again = [], [], [], []
        for k in range(len(rows)):
            if k == 153:
                state = slave.fmu.getFMUstate()
            slave.fmu.doStep(k * STEP, STEP)
            got.append(slave.get(*OUT))
            flags.append(slave.fmu.getInteger([slave.vr["odo_valid"]])[0])
            speeds.append(slave.get("odo_speed")[0])
        slave.fmu.setFMUstate(state)
        for k in range(153, len(rows)):
            slave.fmu.doStep(k * STEP, STEP)
            again.append(slave.get("odo_speed")[0])
    finally:
        slave.free()
    np.testing.assert_array_equal(got, rows)
    flags, speeds = np.array(flags), np.array(speeds)
    np.testing.assert_array_equal(flags, aid[:, 4])
    assert flags.sum() == len(rows) // round(1 / (rate_hz * STEP)) > 10
    np.testing.assert_array_equal(speeds[flags == 1], aid[flags == 1, 5])
    np.testing.assert_array_equal(again, speeds[153:])
    last = 0.0
    for flag, speed in zip(flags, speeds):  # between readings odo_speed holds the last one
        last = speed if flag else last
        assert speed == last


AID_OUT = ["zupt_v_e", "zupt_v_n", "zupt_v_u", "nhc_v_x", "nhc_v_z"]


def _run_aid(fmu, params, n, state_at):
    """Every step's (zupt, nhc) flags and (zupt_v_e .. nhc_v_z), the other outputs, and the values again after
    setting the state taken before step ``state_at``."""
    slave = Slave(fmu, "aid")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        assert slave.fmu.getInteger([slave.vr["zupt"], slave.vr["nhc"]]) == [0, 0]
        assert slave.get(*AID_OUT) == [0.0] * 5
        flags, values, rest, again = [], [], [], []
        for k in range(n):
            if k == state_at:
                state = slave.fmu.getFMUstate()
            slave.fmu.doStep(k * STEP, STEP)
            flags.append(slave.fmu.getInteger([slave.vr["zupt"], slave.vr["nhc"]]))
            values.append(slave.get(*AID_OUT))
            rest.append(slave.get(*OUT))
        slave.fmu.setFMUstate(state)
        for k in range(state_at, n):
            slave.fmu.doStep(k * STEP, STEP)
            again.append(slave.get(*AID_OUT))
        return np.array(flags), np.array(values), np.array(rest), np.array(again)
    finally:
        slave.free()


@pytest.mark.parametrize("zupt, nhc", [(1, 1), (1, 0), (0, 1)])
def test_zupt_and_nhc_rows_equal_navigates_core_rows_bit_for_bit(fmu, expected, zupt, nhc):
    """zupt / nhc and their velocities after each step are aided.per_step_aiding(..., stream='core')'s rows
    (seed jitter_seed, FilterSettings' stds or others), the rest of the outputs unchanged; a state taken in the
    stop repeats the rest."""
    trajectory = tr.Trajectory(START, SEGMENTS)
    truth = tr.generate(trajectory, STEP)
    settings = aided.FilterSettings(zupt_std=0.02, nhc_std=0.07)
    aiding = ("zupt",) * zupt + ("nhc",) * nhc
    aid = aided.per_step_aiding(truth, aiding, settings, None, None, 13, stream="core")
    params, rows = expected
    params = {**params, "zupt_enable": zupt, "nhc_enable": nhc, "zupt_std": 0.02, "nhc_std": 0.07,
              "jitter_seed": 13}
    flags, values, rest, again = _run_aid(fmu, params, len(rows), state_at=60)
    np.testing.assert_array_equal(rest, rows)
    np.testing.assert_array_equal(flags, aid[:, [0, 6]])
    np.testing.assert_array_equal(values, aid[:, [1, 2, 3, 7, 8]])
    np.testing.assert_array_equal(again, values[60:])
    still = truth.stationary()
    assert flags[:, 0].sum() == zupt * still.sum() == zupt * 100 and flags[:, 1].sum() == nhc * (~still).sum()
    on = np.column_stack([flags[:, 0]] * 3 + [flags[:, 1]] * 2) == 1
    assert np.all(values[~on] == 0.0) and np.all(values[on] != 0.0)


def test_state_of_the_previous_version_is_refused(fmu, expected):
    """A serialized state of state version 3 (no vibration) is refused naming why."""
    from fmpy.fmi1 import FMICallException

    params, _ = expected
    slave = Slave(fmu, "old_state")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        assert int.from_bytes(blob[12:16], "little") == 4
        blob[12:16] = (3).to_bytes(4, "little")
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.deSerializeFMUstate(bytes(blob))
        assert any("state version differs" in m for status, _, m in slave.log if status == 3), slave.log
    finally:
        slave.free()


def test_fmi3_variant_outputs_the_same_zupt_and_nhc_rows(tmp_path, expected):
    """The FMI 3.0 TrajectoryIMU (validated by FMPy) gives the increments and the ZUPT / NHC rows of
    per_step_aiding(..., stream='core') bit for bit."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave
    from fmpy.validation import validate_fmu

    path = build_native_fmu("TrajectoryIMU", "trajectory_imu_slave.py", tmp_path, fmi=3, win64=False, aarch64=False)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    truth = tr.generate(tr.Trajectory(START, SEGMENTS), STEP)
    aid = aided.per_step_aiding(truth, ("zupt", "nhc"), aided.FilterSettings(), None, None, 5, stream="core")
    params, rows = expected
    params = {**params, "zupt_enable": 1, "nhc_enable": 1, "jitter_seed": 5}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier="TrajectoryIMU",
                    instanceName="ti3")
    fmu.instantiate()
    try:
        for name, value in params.items():
            if isinstance(value, str):
                fmu.setString([vr[name]], [value])
            elif isinstance(value, int):
                fmu.setInt32([vr[name]], [value])
            else:
                fmu.setFloat64([vr[name]], [value])
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        got, flags, values = [], [], []
        for k in range(len(rows)):
            fmu.doStep(k * STEP, STEP)
            got.append(fmu.getFloat64([vr[n] for n in OUT]))
            flags.append(fmu.getInt32([vr["zupt"], vr["nhc"]]))
            values.append(fmu.getFloat64([vr[n] for n in AID_OUT]))
        fmu.terminate()
    finally:
        fmu.freeInstance()
    np.testing.assert_array_equal(got, rows)
    np.testing.assert_array_equal(flags, aid[:, [0, 6]])
    np.testing.assert_array_equal(values, aid[:, [1, 2, 3, 7, 8]])


def test_vibration_and_every_step_jitter_equal_navigates_core_draws_bit_for_bit(fmu, expected):
    """vib_accel_rms / vib_rate_rms add zero_velocity.vibrate(..., stream='core') (vibration.h, stream 34 of seed) to
    the increments, and zupt_enable = 2 outputs the ZUPT jitter of every step (per_step_aiding's rows with every
    step a stop): bit for bit, a state taken mid-run repeats the rest; the truth and the flags are unchanged."""
    from sarins_fmu import zero_velocity as zv

    truth = tr.generate(tr.Trajectory(START, SEGMENTS), STEP)
    vib = zv.Vibration(accel_rms=0.3, rate_rms=0.01)
    vt, vv = zv.vibrate(truth, vib, SEED, stream="core")
    params, rows = expected
    want = rows.copy()
    want[:, 13:16] = rows[:, 13:16] + vt
    want[:, 16:19] = rows[:, 16:19] + vv
    still = truth.stationary()
    assert np.all(vt[still] == 0.0) and np.all(vv[still] == 0.0) and np.all(vv[~still][1:] != 0.0)
    aid = aided.per_step_aiding(truth, ("zupt", "nhc"), aided.FilterSettings(), None, None, 5, stops=np.ones(len(rows)),
                                stream="core")
    params = {**params, "vib_accel_rms": 0.3, "vib_rate_rms": 0.01, "zupt_enable": 2, "nhc_enable": 1,
              "jitter_seed": 5}
    flags, values, rest, again = _run_aid(fmu, params, len(rows), state_at=150)
    np.testing.assert_array_equal(rest, want)
    np.testing.assert_array_equal(values, aid[:, [1, 2, 3, 7, 8]])
    np.testing.assert_array_equal(again, values[150:])
    np.testing.assert_array_equal(flags[:, 0], still)  # the truth's stops all the same
    assert np.all(values[:, :3] != 0.0)
    # the sample specific force the vibration adds while moving has the stated rms per axis (3 x ~500 samples)
    moving = ~still
    rms = np.sqrt(np.mean((vv[moving][1:] / STEP) ** 2))
    assert abs(rms / 0.3 - 1.0) < 0.1, rms
