"""The native VehicleMotion FMU (fmus/c/vehicle_motion/model.c over the C core's vehicle.h).

Every output after initialisation and after each step equals the row of the in-process
sarins_fmu.vehicle.VehicleTrajectory (the same C stream through ctypes) bit for bit, through FMPy, through
the C host with an empty environment and through the FMI 3.0 variant; after the last leg the vehicle stays
parked; an FMU state taken mid-drive repeats the run, in the same instance and deserialized into another;
bad parameters and legs are refused at fmi2ExitInitializationMode naming them (the core's checks); nothing
allocates after initialisation.  The generic checks of every native FMU (validate, no Python symbol,
exports) are tests/test_native_fmus.py's.
"""

from __future__ import annotations

import math
import os
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from fmus.cbuild import build_line
from fmus.native_fmu import build_native_fmu
from sarins_fmu.core.vehicle import COLUMNS
from sarins_fmu.vehicle import BodyMotion, VehicleTrajectory, parse_legs

LEGS = "drive 60 10; turn 90; drive 40 12; turn -45; stop 30; drive 20 5; stop 10"
PARAMS = {"legs": LEGS, "lat0": math.radians(32.0), "lon0": 0.2, "heading0": 0.4, "lead_time": 20.0,
          "body_seed": 7, "sway_pitch": math.radians(0.7)}
# the FMU's outputs in the order of the core's row columns
OUT = ([f"vehicle_{a}{q}" for q in ("", "_rate", "_accel") for a in ("yaw", "pitch", "roll")]
       + [f"base_rate_{a}" for a in "enu"] + [f"base_force_{a}" for a in "enu"] + ["lat", "lon", "v_e", "v_n", "speed"])
EXTRA = 15  # steps run after the drive (parked)


def _trajectory(params=PARAMS):
    body = BodyMotion(sway_pitch=params["sway_pitch"], seed=params["body_seed"])
    return VehicleTrajectory(parse_legs(params["legs"]), params["lat0"], params["lon0"], params["heading0"],
                             rotation="none", lead_time=params["lead_time"], body=body)


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    return build_native_fmu("VehicleMotion", "vehicle_motion_slave.py", tmp_path_factory.mktemp("vm"))


def _run(fmu, steps, state_at=None):
    """Rows of OUTPUTS + (stopped, base_motion_time) after initialisation and after each step; with
    ``state_at`` also the rows after restoring the state taken there (same instance, new instance)."""
    slave = Slave(fmu, "vm")

    def outputs(s):
        return s.get(*OUT, "base_motion_time") + s.fmu.getInteger([s.vr["stopped"]])

    try:
        slave.set(**PARAMS)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        out, state, blob = [outputs(slave)], None, None
        for k in range(steps):
            if k == state_at:
                state = slave.fmu.getFMUstate()
                blob = slave.fmu.serializeFMUstate(state)
            slave.fmu.doStep(float(k), 1.0)
            out.append(outputs(slave))
        if state is None:
            return out
        slave.fmu.setFMUstate(state)
        slave.fmu.freeFMUstate(state)
        again = []
        for k in range(state_at, steps):
            slave.fmu.doStep(float(k), 1.0)
            again.append(outputs(slave))
        other = Slave(fmu, "vm2")
        try:
            other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
            there = []
            for k in range(state_at, steps):
                other.fmu.doStep(float(k), 1.0)
                there.append(outputs(other))
        finally:
            other.free()
        return out, again, there
    finally:
        slave.free()


def test_fmu_equals_the_in_process_trajectory_bit_for_bit_and_parks(fmu):
    tr = _trajectory()
    assert list(COLUMNS) == [c.replace("vehicle_", "") for c in (
        "yaw", "pitch", "roll", "yaw_rate", "pitch_rate", "roll_rate", "yaw_accel", "pitch_accel", "roll_accel",
        "w_e", "w_n", "w_u", "f_e", "f_n", "f_u", "lat", "lon", "v_e", "v_n", "speed")]
    got = np.array(_run(fmu, tr.n_steps + EXTRA))
    rows = got[:tr.n_steps + 1, :len(OUT)]
    assert np.array_equal(rows, tr.rows)
    assert np.array_equal(got[:, len(OUT)], np.arange(tr.n_steps + EXTRA + 1.0))  # base_motion_time
    assert np.array_equal(got[:tr.n_steps + 1, -1], (tr.speed <= 1e-6).astype(float))
    assert np.max(np.abs(rows[:, 1])) > 0.2 * PARAMS["sway_pitch"]  # it swayed
    parked = got[tr.n_steps:, :len(OUT)]
    assert np.all(parked == parked[0]) and parked[0, OUT.index("speed")] == 0.0
    assert np.all(parked[:, 3:9] == 0.0)  # no rate or acceleration once parked


def test_a_long_legs_string_runs_as_in_process(fmu):
    """A drive of 200 legs (1.3 kB: the campaigns' schedules are longer than 255 bytes) runs bit for bit."""
    legs = "; ".join(f"drive {3 + k % 5} {4 + k % 7}; turn {15 * (1 + k % 3)}" for k in range(100))
    assert len(legs) > 1000
    params = {**PARAMS, "legs": legs, "lead_time": 0.0}
    tr = _trajectory(params)
    slave = Slave(fmu, "vm-long")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        rows = [slave.get(*OUT)]
        for k in range(tr.n_steps):
            slave.fmu.doStep(float(k), 1.0)
            rows.append(slave.get(*OUT))
    finally:
        slave.free()
    assert np.array_equal(np.array(rows), tr.rows)


def test_state_round_trip_mid_drive_repeats_the_run(fmu):
    tr = _trajectory()
    k = 85  # in the first turn (lead 20 s, drive 60 s)
    out, again, there = _run(fmu, tr.n_steps + 5, state_at=k)
    assert out[k][OUT.index("vehicle_yaw_rate")] != 0.0
    assert again == out[k + 1:] and there == out[k + 1:]


@pytest.mark.parametrize("segment, in_segment", [(-3, 0), (10**6, 0), (0, -1), (0, 10**9)])
def test_a_crafted_state_is_refused_with_the_reason_not_run(fmu, segment, in_segment):
    """A serialized state whose segment index or step in it is out of range (the glue's checksum recomputed,
    so its checks pass): refused at deserialisation when outside the state's buffers (check_state), else at the
    next doStep against the parameters' segments; fmi2Error naming the field, no out-of-bounds read."""
    from test_native_drift_model_updater import _fnv1a

    slave = Slave(fmu, "crafted")
    try:
        slave.set(**PARAMS)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        for k in range(30):
            slave.fmu.doStep(float(k), 1.0)
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        at = blob.index(struct.pack("<dq", 1.0, 31)) + 16  # the stream's step and grid point, then its segment
        assert blob.count(struct.pack("<dq", 1.0, 31)) == 1
        struct.pack_into("<qq", blob, at, segment, in_segment)
        head = next(h for h in range(40, 400) if struct.unpack_from("<Q", blob, h - 16)[0] == len(blob) - h)
        struct.pack_into("<Q", blob, head - 8, _fnv1a(bytes(blob[head:])))
        if segment < 0 or segment > 3 * 128 + 2 or in_segment < 0:  # outside the state's buffers: model.c's
            with pytest.raises(FMICallException, match="status 3"):  # check_state refuses the blob itself
                slave.fmu.deSerializeFMUstate(bytes(blob))
            assert any("the state's vehicle." in m for s, _, m in slave.log if s == 3), slave.log[-3:]
            return
        slave.fmu.setFMUstate(slave.fmu.deSerializeFMUstate(bytes(blob)))
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(30.0, 1.0)
        assert any("vehicle state" in m and "out of range" in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()


@pytest.mark.parametrize("params, text", [
    ({"legs": "drive 10 5; fly 3"}, "legs"),
    ({"legs": "turn 90"}, "a turn needs a moving vehicle"),
    ({"legs": "drive -4 3"}, "leg duration must be positive"),
    ({"legs": ""}, "legs is empty"),
    ({"lat0": math.radians(90.0)}, "89.9"),
    ({"grid": 0.0}, "step must be positive"),
    ({"sway_period": 0.0}, "sway_period"),
    ({"vibration": -1e-3}, "vibration"),
    ({"lead_time": math.nan}, "lead_time"),
    ({"body_seed": -1}, "body_seed"),
])
def test_bad_parameters_are_refused_at_exit_initialization(fmu, params, text):
    check_parameter_error(fmu, params, text)


def test_a_step_other_than_the_grid_and_driving_past_an_open_end_are_errors(fmu):
    slave = Slave(fmu, "grid")
    try:
        slave.set(legs="drive 5 3")
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(0.0, 0.5)
        assert any("differs from the vehicle grid" in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()
    slave = Slave(fmu, "open")
    try:
        slave.set(legs="drive 5 3", lead_time=0.0)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        n = _trajectory({**PARAMS, "legs": "drive 5 3", "lead_time": 0.0}).n_steps
        for k in range(n):
            slave.fmu.doStep(float(k), 1.0)
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(float(n), 1.0)
        assert any("do not end with a stop" in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()


# ------------------------------------------------------------------------------------- the C hosts
@pytest.fixture(scope="module")
def host(tmp_path_factory):
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    out = tmp_path_factory.mktemp("vm_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def _host_args(md):
    vr = {v.name: v.valueReference for v in md.modelVariables}
    ops = [f"s{vr['legs']}={PARAMS['legs']}", f"i{vr['body_seed']}={PARAMS['body_seed']}"]
    ops += [f"r{vr[k]}={v!r}" for k, v in PARAMS.items() if k not in ("legs", "body_seed")]
    return ops + ["out=" + ",".join(str(vr[n]) for n in OUT)]


def test_c_hosts_with_empty_environment_fmi2_and_fmi3_equal_in_process(fmu, host, tmp_path):
    """The C host started with no environment (no Python anywhere), FMI 2.0 and the FMI 3.0 variant
    (fmpy validate clean): every output equals the in-process row bit for bit; an FMU state round trip
    repeats the rest; no heap allocation after initialisation."""
    from fmpy.validation import validate_fmu

    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import COUNTER_SRC, _cc, bits, run_host, table

    folder = tmp_path / "f2"
    zipfile.ZipFile(fmu).extractall(folder)
    md = read_model_description(str(fmu))
    tr = _trajectory()
    n = tr.n_steps
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    so = folder / "binaries" / "linux64" / "VehicleMotion.so"
    allocs = run_host(host, so, md, n, *_host_args(md), "allocs", env={"LD_PRELOAD": str(counter)})
    assert "ALLOCS 0" in allocs.stdout.splitlines(), allocs.stdout[-2000:]
    two = run_host(host, so, md, n, *_host_args(md), "roundtrip=50", env={})
    assert "STATUS" not in two.stdout, two.stdout[-2000:]
    out, again = table(two), table(two, "AGAIN")
    assert [out[k] for k in range(n + 1)] == [[bits(x) for x in row] for row in tr.rows]
    assert len(again) == n - 50 and all(again[k] == out[k] for k in again)
    fmu3 = build_native_fmu("VehicleMotion", "vehicle_motion_slave.py", tmp_path / "fmu3", fmi=3, win64=False)
    assert validate_fmu(str(fmu3)) == []
    folder3 = tmp_path / "f3"
    zipfile.ZipFile(fmu3).extractall(folder3)
    host3 = tmp_path / "host3"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir(3)}",
                    str(Path(__file__).parent / "native_host" / "native_fmu3_host.c"), "-ldl", "-o", str(host3)])
    md3 = read_model_description(str(fmu3))
    three = run_host(host3, folder3 / "binaries" / "x86_64-linux" / "VehicleMotion.so", md3, n, *_host_args(md3),
                     f"nout={len(OUT)}", "nin=0", env={})
    assert "STATUS" not in three.stdout, three.stdout[-2000:]
    assert table(three) == {k: out[k] for k in range(n + 1)}
    assert os.path.getsize(folder / "binaries" / "linux64" / "VehicleMotion.so") > 0
