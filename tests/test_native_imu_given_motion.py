"""FMI 3.0 IMUThermal with ``sub_inputs = 1``: the motion of every sub-interval of a step from arrays.

A step of K s with ``n_sub = K`` reads K start-of-second motion sets (a Turntable's ``*_sub`` arrays) and must
give, bit for bit, what the FMI 2.0 IMU stepped at 1 s gives when it reads the same sets one by one, whatever
its ``threads`` (the sub-intervals' minor loops run side by side on the FMU's own threads).  Also: the held
set under Gauss-Seidel, the FMU state, and the refusals (FMI 2.0, a moving base, bad thread counts, NaN).
"""

from __future__ import annotations

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from test_native_fmus3_sub import Fmu3

pytestmark = pytest.mark.integration

K, STEPS = 8, 4  # sub-intervals of a step, steps of K s
INCREMENTS = [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"]
OUTPUTS = INCREMENTS + [f"temp_{s}_{a}" for s in ("gyro", "accel") for a in "xyz"] + ["increment_end_time"]
SUB_OUT = [f"{name}_sub" for name in INCREMENTS + ["temp_gyro_z"]]
MOTION = [f"{q}_{j}" for q in ("angle", "rate", "accel") for j in (1, 2, 3)] + ["ambient_temp", "ambient_temp_rate"]
PARAMS = {"gimbals": "x,z"}  # two gimbals, noise and drifts on (nav-rlg)


def motion_at(second: int) -> dict:
    """A turning two-gimbal table whose acceleration changes every few seconds, and a warming chamber: the
    set at the start of ``second`` (each value different, so a set read for the wrong second shows)."""
    accel = (0.05, 0.0, -0.03)[second // 3 % 3]
    return {"angle_1": 0.01 * second, "rate_1": 0.02 + 0.001 * second, "accel_1": accel,
            "angle_2": -0.2 + 0.003 * second ** 2, "rate_2": 0.006 * second, "accel_2": 0.006,
            "angle_3": 0.0, "rate_3": 0.0, "accel_3": 0.0,
            "ambient_temp": 20.0 + 0.01 * second, "ambient_temp_rate": 0.01 + 0.0001 * (second % 5)}


def arrays_of(step: int) -> dict:
    """The K sets of the step starting at step * K s as arrays (the Turntable's *_sub outputs)."""
    sets = [motion_at(step * K + k) for k in range(K)]
    return {f"{name}_sub": [s[name] for s in sets] for name in MOTION}


class GivenImu(Fmu3):
    """The FMI 3.0 IMUThermal with n_sub = K and sub_inputs = 1."""

    def __init__(self, path, threads: int = 1, name: str = "imu3"):
        super().__init__(path, K, name)
        self.s.setString([self.vr["gimbals"]], [PARAMS["gimbals"]])
        self.set(sub_inputs=1, threads=threads)

    def set_arrays(self, values: dict, tag: float) -> None:
        for name, array in values.items():
            self.s.setFloat64([self.vr[name]], array)
        self.set(motion_time=tag)


def reference(fmu_dir) -> tuple[list, list]:
    """The FMI 2.0 IMU stepped at 1 s reading the sets one by one (Jacobi: the set tagged t at t): per second
    the increments and gyro_z temperature, and per K s the scalar outputs."""
    imu = Slave(fmu_dir / "IMUThermal.fmu", "imu2")
    try:
        imu.set(**PARAMS, **motion_at(0), motion_time=0.0)
        imu.fmu.enterInitializationMode()
        imu.fmu.exitInitializationMode()
        rows, ends = [], []
        for second in range(K * STEPS):
            imu.set(**motion_at(second), motion_time=float(second))
            imu.fmu.doStep(float(second), 1.0)
            rows.append(imu.get(*INCREMENTS, "temp_gyro_z"))
            if second % K == K - 1:
                ends.append(imu.get(*OUTPUTS))
        return rows, ends
    finally:
        imu.free()


def run_given(path, threads: int, gauss_seidel: bool = False) -> tuple[list, list]:
    """The FMI 3.0 IMU with K s steps; Gauss-Seidel: the arrays of the next step are set before each step
    (the upstream turntable stepped first), so the IMU must use the set it kept."""
    imu = GivenImu(path, threads)
    try:
        imu.set_arrays(arrays_of(0), 0.0)
        imu.s.enterInitializationMode()
        imu.s.exitInitializationMode()
        rows, ends = [], []
        for step in range(STEPS):
            ahead = step + 1 if gauss_seidel else step
            imu.set_arrays(arrays_of(ahead), float(ahead * K))
            imu.s.doStep(float(step * K), float(K))
            rows += np.array(imu.get(SUB_OUT, 7 * K)).reshape(7, K).T.tolist()
            ends.append(imu.get(OUTPUTS))
        return rows, ends
    finally:
        imu.s.freeInstance()


def sums(rows, step):
    total = [0.0] * 6
    for row in rows[step * K:(step + 1) * K]:
        total = [a + b for a, b in zip(total, row[:6])]
    return total


@pytest.mark.parametrize("threads,gauss_seidel", [(1, False), (2, False), (3, True)])
def test_a_step_of_k_sub_intervals_is_k_steps_of_one(fmu_dir, fmu3_dir, threads, gauss_seidel):
    ref_rows, ref_ends = reference(fmu_dir)
    rows, ends = run_given(fmu3_dir / "IMUThermal.fmu", threads, gauss_seidel)
    assert np.array(rows).tobytes() == np.array(ref_rows).tobytes()  # every second, bit for bit
    for step, (end, ref) in enumerate(zip(ends, ref_ends)):
        assert end[:6] == sums(rows, step)  # the scalars: the sums of the step's sub-intervals, in order
        assert end[6:] == ref[6:]  # temperatures and the end tag of the last second
    assert len({tuple(r[:3]) for r in rows}) == len(rows)  # the table turns: every second differs


def test_the_fmu_state_carries_the_kept_set(fmu3_dir):
    imu = GivenImu(fmu3_dir / "IMUThermal.fmu", threads=2)
    try:
        imu.set_arrays(arrays_of(0), 0.0)
        imu.s.enterInitializationMode()
        imu.s.exitInitializationMode()
        imu.set_arrays(arrays_of(1), float(K))  # Gauss-Seidel: the step reads the set kept at initialisation
        state = imu.s.getFMUState()
        imu.s.doStep(0.0, float(K))
        first = imu.get(SUB_OUT, 7 * K)
        imu.s.doStep(float(K), float(K))
        imu.s.setFMUState(state)
        imu.s.doStep(0.0, float(K))
        assert imu.get(SUB_OUT, 7 * K) == first
        imu.s.freeFMUState(state)
    finally:
        imu.s.freeInstance()


def test_a_set_tagged_for_no_step_and_nan_are_refused(fmu3_dir):
    imu = GivenImu(fmu3_dir / "IMUThermal.fmu")
    try:
        imu.set_arrays(arrays_of(0), 0.0)
        imu.s.enterInitializationMode()
        imu.s.exitInitializationMode()
        imu.set_arrays(arrays_of(3), 3.0 * K)
        imu.s.doStep(0.0, float(K))  # the set kept at initialisation is tagged 0; the one of 3 K is kept now
        with pytest.raises(FMICallException):
            imu.s.doStep(float(K), float(K))  # neither the current nor the kept set is tagged K
        assert "no turntable motion for the step starting at t=8" in "\n".join(imu.messages)
    finally:
        imu.s.freeInstance()
    imu = GivenImu(fmu3_dir / "IMUThermal.fmu")
    try:
        values = arrays_of(0)
        values["rate_2_sub"][5] = float("nan")
        imu.set_arrays(values, 0.0)
        imu.s.enterInitializationMode()
        with pytest.raises(FMICallException):
            imu.s.exitInitializationMode()
        assert "the *_sub motion inputs contain NaN or infinity" in "\n".join(imu.messages)
    finally:
        imu.s.freeInstance()


@pytest.mark.parametrize("params,text", [
    ({"sub_inputs": 2}, "parameter sub_inputs = 2 must be 0"),
    ({"sub_inputs": 1, "base": "input"}, "sub_inputs = 1 needs base = static"),
    ({"threads": 0}, "parameter threads = 0 must be an integer in [1, 64]"),
    ({"threads": 65}, "parameter threads = 65 must be an integer in [1, 64]"),
])
def test_bad_settings_are_refused_with_the_reason(fmu3_dir, params, text):
    imu = Fmu3(fmu3_dir / "IMUThermal.fmu", K)
    try:
        for name, value in params.items():
            if isinstance(value, str):
                imu.s.setString([imu.vr[name]], [value])
            else:
                imu.set(**{name: value})
        imu.s.enterInitializationMode()
        with pytest.raises(FMICallException):
            imu.s.exitInitializationMode()
        assert text in "\n".join(imu.messages)
    finally:
        imu.s.freeInstance()


def test_the_fmi2_imu_has_no_arrays_to_read(fmu_dir):
    check_parameter_error(fmu_dir / "IMUThermal.fmu", {"sub_inputs": 1}, "only the FMI 3.0 variant")
