"""The native GNSSReceiver FMU (fmus/c/gnss_receiver/model.c over the C core's gnss.h).

Fed the truth of a trajectory at every communication point, its fixes (valid flag, position, velocity,
time tag) equal sarins_fmu.gnss.simulate's on the same truth, settings and seed bit for bit, through FMPy
(FMI 2.0 and the FMI 3.0 variant) and through the C host with an empty environment; an FMU state taken
mid-run repeats the rest, in the same instance and deserialized into another; bad parameters and a step
that is not a whole fraction of the fix interval are refused naming them; nothing allocates after
initialisation.
"""

from __future__ import annotations

import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from fmus.cbuild import build_line
from fmus.native_fmu import build_native_fmu
from sarins_fmu import gnss
from sarins_fmu import trajectory as tr

STEP = 0.1
SEED = 3
OUTAGES = "2.5:3.5; 5:5.4"
CONFIG = gnss.preset("sps", rate_hz=5.0, lever_arm=(0.3, 1.2, 0.8))
SEGMENTS = ({"kind": "stop", "duration": 1}, {"kind": "accelerate", "to_speed": 6, "accel": 2.0},
            {"kind": "turn", "rate_dps": 20, "angle_deg": 60}, {"kind": "climb", "to_pitch_deg": 2, "duration": 1},
            {"kind": "cruise", "duration": 1})
INPUTS = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "omega_ib_x", "omega_ib_y",
          "omega_ib_z"]
FIX = ["fix_lat", "fix_lon", "fix_height", "fix_v_e", "fix_v_n", "fix_v_u", "fix_time"]


def _params(config=CONFIG):
    values = dict(zip(["lever_x", "lever_y", "lever_z", "pos_white_e", "pos_white_n", "pos_white_u", "pos_gm_e",
                       "pos_gm_n", "pos_gm_u", "pos_gm_tau", "vel_white_e", "vel_white_n", "vel_white_u",
                       "vel_gm_e", "vel_gm_n", "vel_gm_u", "vel_gm_tau"], config.array().tolist()))
    return {**values, "rate_hz": config.rate_hz, "seed": SEED, "outages": OUTAGES}


@pytest.fixture(scope="module")
def truth():
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=30.0, heading_deg=20.0), SEGMENTS), STEP)


@pytest.fixture(scope="module")
def expected(truth):
    """In process: (m, 8) rows valid, lat, lon, h, v E N U, time."""
    f = gnss.simulate(truth, CONFIG, SEED, outages=[[2.5, 3.5], [5.0, 5.4]])
    return np.column_stack([f.valid.astype(float), f.lat, f.lon, f.height, f.velocity_n, f.time])


def _inputs(truth) -> np.ndarray:
    return np.column_stack([truth.nav_rows(), truth.omega_ib_b])


@pytest.fixture(scope="module")
def fmu(fmu_dir):
    return fmu_dir / "GNSSReceiver.fmu"  # the session build (tests/conftest.py)


def _fixes(rows: list) -> np.ndarray:
    """The rows (valid, fix..., count) where fix_count grew, without the count."""
    rows = np.array(rows)
    new = np.diff(np.concatenate([[0.0], rows[:, -1]])) > 0
    return rows[new, :-1]


def _run2(fmu, inputs, state_at=None):
    slave = Slave(fmu, "gr")

    def outputs(s):
        return [float(s.fmu.getInteger([s.vr["fix_valid"]])[0]), *s.get(*FIX[:-1]), s.get("fix_time")[0],
                float(s.fmu.getInteger([s.vr["fix_count"]])[0])]

    def steps(s, start, out, end=len(inputs)):
        for k in range(start, end):
            s.fmu.setReal([s.vr[n] for n in INPUTS], list(inputs[k]))
            s.fmu.doStep(k * STEP, STEP)
            out.append(outputs(s))

    try:
        slave.set(**_params())
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        out = [outputs(slave)]
        if state_at is None:
            steps(slave, 0, out)
            return out
        steps(slave, 0, out, state_at)
        state = slave.fmu.getFMUstate()
        blob = slave.fmu.serializeFMUstate(state)
        steps(slave, state_at, out)
        slave.fmu.setFMUstate(state)
        again = []
        steps(slave, state_at, again)
        other = Slave(fmu, "gr2")
        try:
            other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
            there = []
            steps(other, state_at, there)
        finally:
            other.free()
        return out, again, there
    finally:
        slave.free()


def test_fmi2_fixes_equal_in_process_bit_for_bit(fmu, truth, expected):
    rows = _run2(fmu, _inputs(truth))
    assert rows[0][-1] == 0.0 and rows[0][0] == 0.0  # no fix at initialisation
    got = _fixes(rows)
    assert got.shape == expected.shape == (len(truth.time) // 2, 8)
    assert np.array_equal(got, expected)
    assert 0 < (expected[:, 0] == 0).sum() < len(expected)  # the outages hit some epochs


def test_state_round_trip_repeats_the_rest(fmu, truth):
    out, again, there = _run2(fmu, _inputs(truth), state_at=23)
    assert again == out[24:] and there == out[24:]


def test_fmi3_variant_equals_in_process(tmp_path, truth, expected):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave
    from fmpy.validation import validate_fmu

    path = build_native_fmu("GNSSReceiver", "gnss_receiver_slave.py", tmp_path, fmi=3, win64=False, aarch64=False)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier="GNSSReceiver",
                    instanceName="gr3")
    fmu.instantiate()
    try:
        p = _params()
        fmu.setFloat64([vr[k] for k, v in p.items() if isinstance(v, float)], [v for v in p.values()
                                                                               if isinstance(v, float)])
        fmu.setInt32([vr["seed"]], [SEED])
        fmu.setString([vr["outages"]], [OUTAGES])
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        rows = []
        for k, row in enumerate(_inputs(truth)):
            fmu.setFloat64([vr[n] for n in INPUTS], list(row))
            fmu.doStep(k * STEP, STEP)
            rows.append([float(fmu.getInt32([vr["fix_valid"]])[0]), *fmu.getFloat64([vr[n] for n in FIX]),
                         float(fmu.getInt32([vr["fix_count"]])[0])])
        assert np.array_equal(_fixes(rows), expected)
        fmu.terminate()
    finally:
        fmu.freeInstance()


def test_c_host_empty_environment_no_allocation(fmu, truth, expected, tmp_path):
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import COUNTER_SRC, HOST_SRC, _cc

    host = tmp_path / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(host)])
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    zipfile.ZipFile(fmu).extractall(tmp_path / "f")
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    rows_file = tmp_path / "rows.bin"
    inputs = _inputs(truth)
    inputs.astype("=f8").tofile(rows_file)
    p = _params()
    ops = [f"r{vr[k]}={v!r}" for k, v in p.items() if isinstance(v, float)]
    ops += [f"i{vr['seed']}={SEED}", f"s{vr['outages']}={OUTAGES}", "in=" + ",".join(str(vr[n]) for n in INPUTS),
            f"rows={rows_file}", "out=" + ",".join(str(vr[n]) for n in FIX)]
    cmd = [str(host), str(tmp_path / "f" / "binaries" / "linux64" / "GNSSReceiver.so"), md.guid, str(len(inputs)),
           repr(STEP), *ops]
    proc = subprocess.run([*cmd, "allocs"], capture_output=True, text=True, timeout=120,
                          env={"LD_PRELOAD": str(counter)})
    assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]
    got = []
    for line in proc.stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == "OUT":
            got.append([np.array([int(h, 16)], np.uint64).view(np.float64)[0] for h in parts[2:]])
    got = np.array(got)
    new = np.diff(got[:, -1]) != 0
    assert np.array_equal(got[1:][new], expected[:, 1:])


@pytest.mark.parametrize("params, text", [
    ({"rate_hz": 25.0}, "rate_hz"),
    ({"seed": -1}, "seed"),
    ({"pos_gm_tau": 0.0}, "pos_"),
    ({"vel_white_n": -0.1}, "vel_"),
    ({"outages": "5:3"}, "outages"),
    ({"outages": "1:2;x"}, "outages"),
])
def test_bad_parameters_are_refused(fmu, params, text):
    check_parameter_error(fmu, params, text)


def test_a_step_not_dividing_the_fix_interval_or_changing_is_an_error(fmu):
    for first, second, text in ((0.15, None, "not a whole number of steps"), (0.3, None, "above the step rate"),
                                (0.1, 0.2, "fixed step")):
        slave = Slave(fmu, "step")
        try:
            slave.set(rate_hz=5.0)
            slave.fmu.enterInitializationMode()
            slave.fmu.exitInitializationMode()
            with pytest.raises(FMICallException, match="status 3"):
                slave.fmu.doStep(0.0, first)
                slave.fmu.doStep(first, second)
            assert any(text in m for s, _, m in slave.log if s == 3), slave.log[-3:]
        finally:
            slave.free()


def test_a_crafted_state_is_refused_naming_the_field(fmu, truth):
    """A serialized state whose outage count is beyond its buffer (the glue's checksum recomputed, so its
    checks pass): fmi2DeSerializeFMUstate is refused by the model's check_state naming the field."""
    import struct

    from test_native_drift_model_updater import _fnv1a

    slave = Slave(fmu, "crafted")
    try:
        slave.set(**_params())
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        for k, row in enumerate(_inputs(truth)[:7]):
            slave.fmu.setReal([slave.vr[n] for n in INPUTS], list(row))
            slave.fmu.doStep(k * STEP, STEP)
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        tail = struct.pack("<qqqd", 2, 7, 2, STEP)  # n_outages, k, every, step
        assert blob.count(tail) == 1
        struct.pack_into("<q", blob, blob.index(tail), 99)
        head = next(h for h in range(40, 400) if struct.unpack_from("<Q", blob, h - 16)[0] == len(blob) - h)
        struct.pack_into("<Q", blob, head - 8, _fnv1a(bytes(blob[head:])))
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.deSerializeFMUstate(bytes(blob))
        assert any("n_outages" in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()
