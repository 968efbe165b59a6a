"""The native AidedINS FMU (fmus/c/aided_ins/model.c over the C core's eskf.h).

Fed the increments of sarins_fmu.aided.corrupt and each GNSS fix at the step after which navigate applies
it (its own schedule, aided.fix_rows), the outputs (navigation, bias estimates, the filter's sigmas) equal
navigate(aiding=('gnss',)) at every step bit for bit, and with the input zaru set at the trajectory's stop
steps navigate(aiding=('gnss', 'zaru')), through FMPy and through the C host with an empty
environment (no allocation after initialisation); an FMU state taken mid-run repeats the rest, also
deserialized into another instance; bad parameters are refused naming them.
"""

from __future__ import annotations

import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description

from fmu_driver import Slave, check_parameter_error
from fmus.native_fmu import build_native_fmu
from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr

STEP = 0.02
SEED = 5
SEGMENTS = ({"kind": "stop", "duration": 1}, {"kind": "accelerate", "to_speed": 8, "accel": 2.0},
            {"kind": "turn", "rate_dps": 15, "angle_deg": 45}, {"kind": "cruise", "duration": 2})
GNSS = gnss.preset("sps", rate_hz=5.0, latency=2 * STEP, lever_arm=(0.2, 0.9, 1.1))
OUTAGES = [[3.0, 4.0]]
NOISE = aided.IMU_NOISE["tactical"]
SETTINGS = aided.FilterSettings(out_every=1)
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
OUT = NAV + [f"bias_{q}_{a}" for q in "ga" for a in "xyz"] + [f"sigma_{q}_{a}" for q in ("pos", "vel", "att")
                                                            for a in "enu"]
INPUTS = [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"] + [f"fix_{n}" for n in NAV[:6]]
SETTING_NAMES = ["step", "arw", "vrw", "gyro_rw", "accel_rw", "pos0_std", "vel0_std", "tilt0_std", "heading0_std",
                 "gyro_bias0_std", "accel_bias0_std", "lever_x", "lever_y", "lever_z", "latency", "zupt_std",
                 "cov_every", "nhc_std", "odo_std", "zaru_std"]


def make_case(aiding):
    """(params, per-step inputs (K, 12), per-step flags (K, 3) fix valid / fix new / zaru, expected (K, 24))."""
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=35.0, heading_deg=-30.0), SEGMENTS), STEP)
    result = aided.navigate(truth, noise=NOISE, gnss=GNSS, aiding=aiding, outages=OUTAGES, settings=SETTINGS,
                            seed=SEED)
    dtheta, dv, _, _ = aided.corrupt(truth, NOISE, SEED)
    nav0 = aided._initial_state(truth, SETTINGS, np.random.default_rng([SEED, 3018]))
    params = dict(zip(SETTING_NAMES, aided._config(NOISE, SETTINGS, GNSS, STEP).tolist()))
    params.update({f"{n}0": float(v) for n, v in zip(NAV, nav0)})
    params.update({f"gnss_{k}_std_{a}": float(v) for k, std in (("pos", GNSS.pos_std()), ("vel", GNSS.vel_std()))
                   for a, v in zip("enu", std)})
    rows = aided.fix_rows(gnss.simulate(truth, GNSS, SEED, OUTAGES), GNSS, STEP)
    k = truth.n_steps
    inputs = np.zeros((k, 12))
    inputs[:, :3], inputs[:, 3:6] = dtheta, dv
    flags = np.zeros((k, 3), int)
    if "zaru" in aiding:
        flags[:, 2] = truth.stationary()
    for row in rows:
        i = int(row[0])
        if i < k:
            inputs[i, 6:] = row[2:8]
            flags[i, :2] = (int(row[1]), 1)
    sigma = np.sqrt(np.diagonal(result.cov, axis1=1, axis2=2)[:, :9])
    expected = np.column_stack([result.nav, result.bias_g, result.bias_a, sigma])
    assert 0 < (flags[:, 1] & ~flags[:, 0]).sum() < flags[:, 1].sum()  # the outage drops some fixes
    return params, inputs, flags, expected


@pytest.fixture(scope="module")
def case():
    return make_case(("gnss",))


@pytest.fixture(scope="module")
def zaru_case():
    """GNSS and ZARU at the first second's stop (50 steps)."""
    c = make_case(("gnss", "zaru"))
    assert c[2][:, 2].sum() == 50 and not np.array_equal(c[3], make_case(("gnss",))[3])
    return c


@pytest.fixture(scope="module")
def fmu(fmu_dir):
    return fmu_dir / "AidedINS.fmu"  # the session build (tests/conftest.py)


def _run(fmu, case, state_at=None):
    params, inputs, flags, _ = case
    slave = Slave(fmu, "ai")
    counts = np.cumsum(flags[:, 1])

    def steps(s, start, end, out):
        for k in range(start, end):
            s.fmu.setReal([s.vr[n] for n in INPUTS], list(inputs[k]))
            s.fmu.setInteger([s.vr["fix_valid"], s.vr["fix_count"], s.vr["zaru"]],
                             [int(flags[k, 0]), int(counts[k]), int(flags[k, 2])])
            s.fmu.doStep(k * STEP, STEP)
            out.append(s.get(*OUT))

    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        out = []
        n = len(inputs)
        steps(slave, 0, state_at or n, out)
        if state_at is None:
            return np.array(out), slave.fmu.getInteger([slave.vr["fixes_used"]])[0]
        state = slave.fmu.getFMUstate()
        blob = slave.fmu.serializeFMUstate(state)
        steps(slave, state_at, n, out)
        slave.fmu.setFMUstate(state)
        again = []
        steps(slave, state_at, n, again)
        other = Slave(fmu, "ai2")
        try:
            other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
            there = []
            steps(other, state_at, n, there)
        finally:
            other.free()
        return out, again, there
    finally:
        slave.free()


def test_fmu_equals_navigate_bit_for_bit(fmu, case):
    got, used = _run(fmu, case)
    assert np.array_equal(got, case[3])
    assert used == case[2][:, 0].sum() > 10
    assert got[-1, OUT.index("sigma_pos_e")] < case[0]["gnss_pos_std_e"]  # the fixes bound the position


def test_state_round_trip_repeats_the_rest(fmu, case):
    out, again, there = _run(fmu, case, state_at=180)
    assert again == out[180:] and there == out[180:]


def test_fmu_with_zaru_equals_navigate_bit_for_bit(fmu, zaru_case):
    got, used = _run(fmu, zaru_case)
    assert np.array_equal(got, zaru_case[3])
    assert used == zaru_case[2][:, 0].sum() > 10


def test_state_round_trip_in_a_stop_with_zaru(fmu, zaru_case):
    out, again, there = _run(fmu, zaru_case, state_at=30)
    assert again == out[30:] and there == out[30:]


def test_bad_zaru_input_is_refused(fmu, case):
    from fmpy.fmi1 import FMICallException

    slave = Slave(fmu, "bad_zaru")
    try:
        slave.set(**case[0])
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        slave.fmu.setInteger([slave.vr["zaru"]], [2])
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(0.0, STEP)
        assert any("input zaru = 2" in m for status, _, m in slave.log if status == 3), slave.log
    finally:
        slave.free()


def test_c_host_empty_environment_no_allocation(fmu, case, tmp_path):
    """The Reals through the C host (fix_count and fix_valid stay as set once: here every step carries a
    fix only when its fix_count grows, so the host run applies none and equals a pure INS run of FMPy)."""
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import COUNTER_SRC, HOST_SRC, _cc

    params, inputs, flags, _ = case
    host = tmp_path / "host"
    subprocess.run([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(host)], check=True)
    counter = tmp_path / "alloc_counter.so"
    subprocess.run([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"], check=True)
    zipfile.ZipFile(fmu).extractall(tmp_path / "f")
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    rows_file = tmp_path / "rows.bin"
    inputs.astype("=f8").tofile(rows_file)
    ops = [f"r{vr[k]}={v!r}" for k, v in params.items()]
    ops += ["in=" + ",".join(str(vr[n]) for n in INPUTS), f"rows={rows_file}", "out=" + ",".join(str(vr[n])
                                                                                               for n in OUT)]
    cmd = [str(host), str(tmp_path / "f" / "binaries" / "linux64" / "AidedINS.so"), md.guid, str(len(inputs)),
           repr(STEP), *ops]
    proc = subprocess.run([*cmd, "allocs"], capture_output=True, text=True, timeout=120,
                          env={"LD_PRELOAD": str(counter)})
    assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]
    proc = subprocess.run([*cmd, "roundtrip=100"], capture_output=True, text=True, timeout=120, env={})
    assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:]

    def rows(tag):
        return {int(p[1]): [int(h, 16) for h in p[2:]] for p in (line.split() for line in proc.stdout.splitlines())
                if p and p[0] == tag}

    out, again = rows("OUT"), rows("AGAIN")
    no_fix = (params, inputs, np.zeros_like(flags), None)
    pure, used = _run(fmu, no_fix)
    assert used == 0
    assert [out[k] for k in range(1, len(inputs) + 1)] == pure.view(np.uint64).tolist()
    assert again and all(again[k] == out[k] for k in again)


@pytest.mark.parametrize("params, text", [
    ({"step": 0.0}, "step"),
    ({"arw": -1.0}, "arw"),
    ({"cov_every": 2.5}, "cov_every"),
    ({"gnss_pos_std_n": 0.0}, "gnss_pos_std_n"),
    ({"use_velocity": 2}, "use_velocity"),
    ({"zaru_std": -1e-4}, "zaru_std"),
    ({"zaru_std": float("nan")}, "zaru_std"),
    ({"lat0": 1.6}, "lat0"),
])
def test_bad_parameters_are_refused(fmu, params, text):
    check_parameter_error(fmu, params, text)


@pytest.mark.parametrize("name", ["case", "zaru_case"])
def test_fmi3_variant_equals_navigate(name, request, tmp_path):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave
    from fmpy.validation import validate_fmu

    params, inputs, flags, expected = request.getfixturevalue(name)
    path = build_native_fmu("AidedINS", "aided_ins_slave.py", tmp_path, fmi=3, win64=False, aarch64=False)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier="AidedINS", instanceName="ai3")
    fmu.instantiate()
    try:
        fmu.setFloat64([vr[k] for k in params], list(params.values()))
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        counts = np.cumsum(flags[:, 1])
        got = []
        for k, row in enumerate(inputs):
            fmu.setFloat64([vr[n] for n in INPUTS], list(row))
            fmu.setInt32([vr["fix_valid"], vr["fix_count"], vr["zaru"]], [int(flags[k, 0]), int(counts[k]),
                                                                        int(flags[k, 2])])
            fmu.doStep(k * STEP, STEP)
            got.append(fmu.getFloat64([vr[n] for n in OUT]))
        assert np.array_equal(np.array(got), expected)
        fmu.terminate()
    finally:
        fmu.freeInstance()


def test_receiver_into_aided_ins_equals_navigate_with_two_steps_latency(fmu, tmp_path):
    """GNSSReceiver -> AidedINS exchanged at every communication point (Jacobi): a fix valid at t_k leaves
    the receiver after doStep(t_k, h) and is applied in AidedINS's doStep(t_k + h, h), at t_k + 2h.  With
    latency = 2h in both, the chain equals navigate(aiding=('gnss',)) at every step bit for bit."""
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=35.0, heading_deg=-30.0), SEGMENTS), STEP)
    result = aided.navigate(truth, noise=NOISE, gnss=GNSS, aiding=("gnss",), outages=OUTAGES, settings=SETTINGS,
                            seed=SEED)
    assert GNSS.latency == 2 * STEP
    dtheta, dv, _, _ = aided.corrupt(truth, NOISE, SEED)
    nav0 = aided._initial_state(truth, SETTINGS, np.random.default_rng([SEED, 3018]))
    params = dict(zip(SETTING_NAMES, aided._config(NOISE, SETTINGS, GNSS, STEP).tolist()))
    params.update({f"{n}0": float(v) for n, v in zip(NAV, nav0)})
    params.update({f"gnss_{k}_std_{a}": float(v) for k, std in (("pos", GNSS.pos_std()), ("vel", GNSS.vel_std()))
                   for a, v in zip("enu", std)})
    receiver_fmu = fmu.parent / "GNSSReceiver.fmu"
    receiver = Slave(receiver_fmu, "rx")
    ins = Slave(fmu, "ins")
    truth_in = np.column_stack([truth.nav_rows(), truth.omega_ib_b])
    rx_in = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "omega_ib_x", "omega_ib_y",
             "omega_ib_z"]
    fix = [f"fix_{n}" for n in NAV[:6]]
    try:
        receiver.set(rate_hz=GNSS.rate_hz, seed=SEED, outages="3:4", **dict(zip(
            ["lever_x", "lever_y", "lever_z", "pos_white_e", "pos_white_n", "pos_white_u", "pos_gm_e", "pos_gm_n",
             "pos_gm_u", "pos_gm_tau", "vel_white_e", "vel_white_n", "vel_white_u", "vel_gm_e", "vel_gm_n",
             "vel_gm_u", "vel_gm_tau"], GNSS.array().tolist())))
        ins.set(**params)
        for s in (receiver, ins):
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        got = []
        for k in range(truth.n_steps):
            fix_values = receiver.get(*fix)
            fix_ints = receiver.fmu.getInteger([receiver.vr["fix_valid"], receiver.vr["fix_count"]])
            receiver.fmu.setReal([receiver.vr[n] for n in rx_in], list(truth_in[k]))
            ins.fmu.setReal([ins.vr[n] for n in INPUTS], [*dtheta[k], *dv[k], *fix_values])
            ins.fmu.setInteger([ins.vr["fix_valid"], ins.vr["fix_count"]], list(fix_ints))
            receiver.fmu.doStep(k * STEP, STEP)
            ins.fmu.doStep(k * STEP, STEP)
            got.append(ins.get(*NAV))
        assert np.array_equal(np.array(got), result.nav)
        rows = aided.fix_rows(gnss.simulate(truth, GNSS, SEED, OUTAGES), GNSS, STEP)
        applied = int(np.sum((rows[:, 1] > 0) & (rows[:, 0] < truth.n_steps)))  # the last fix falls after the run
        assert ins.fmu.getInteger([ins.vr["fixes_used"]])[0] == applied > 10
    finally:
        receiver.free()
        ins.free()
