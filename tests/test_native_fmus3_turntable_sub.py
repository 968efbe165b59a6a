"""FMI 3.0 Turntable with every sub-interval of the coming step in arrays (n_sub).

With ``n_sub`` = K the Turntable stepped at h describes the K sub-intervals of h / K of the coming step in
the arrays ``angle_1_sub`` .. ``ambient_temp_rate_sub``: element k is what a Turntable with n_sub = 1
stepped at h / K shows at motion_time + k h / K, so the schedule's breakpoints need only lie on the grid of
h / K.  Checked: the arrays against the n_sub = 1 Turntable stepped at h / K bit for bit over runs whose
steps span acceleration changes and chamber ramp corners (the scalars: element 0, the ambient's slope over
the whole step); n_sub = 1 is the Turntable of before; steps off the grid and bad n_sub refused with the
reason (the FMI 2.0 variant, which has no arrays, refuses K > 1); FMU state keeps the arrays.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

pytestmark = pytest.mark.integration

OUTPUTS = [f"{q}_{j}" for q in ("angle", "rate", "accel") for j in (1, 2, 3)] + ["ambient_temp", "ambient_temp_rate"]
SUB = [f"{name}_sub" for name in OUTPUTS]
RATE_AT = OUTPUTS.index("ambient_temp_rate")
CHAMBER = {"ambient_mode": "chamber", "chamber_low": 15.0, "chamber_high": 30.0, "chamber_ramp": 0.5,
           "chamber_hold": 7.0, "ambient_mean": 20.0, "chamber_step": 2.0, "chamber_step_hold": 3.0}
# alignment indexing (accelerations of 3 s), then forward-reverse with dwells; the chamber's ramps stop every
# 2 degC: breakpoints at 3, 30, 33, 43, ... s and ramp corners at 10, 17, 21, 24, ... s
FORWARD_REVERSE = {"scheme": "forward-reverse", "rate": math.radians(6.0), "accel": math.radians(2.0),
                   "dwell": 5.0, "align_time": 100.0, "align_dwell": 10.0, "duration": 2000.0, **CHAMBER}
CASES = {  # name: (K, h [s], start time [s], turntable parameters); grid = h / K (the initial sub-interval)
    "K=4 forward-reverse": (4, 4.0, 0.0, FORWARD_REVERSE),
    "K=5 dual-axis from t=3": (5, 5.0, 3.0, {"scheme": "dual-axis", "align_time": 60.0, "align_dwell": 7.0,
                                             "duration": 2000.0, **CHAMBER}),
    "K=10 half-second grid": (10, 5.0, 0.0, {**FORWARD_REVERSE, "grid": 0.5, "dwell": 2.5}),
}
RUN = 300.0  # s


@pytest.fixture(scope="module")
def turntable3(fmu3_dir):
    """The session's FMI 3.0 Turntable (tests/conftest.py)."""
    return fmu3_dir / "Turntable.fmu"


class Table3:
    """An FMI 3.0 Turntable, configured with n_sub (default: not configured, n_sub = 1), its log kept."""

    def __init__(self, path, n_sub: int | None = None, name: str = "tt"):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[tuple[int, str]] = []

        def log(env, status, category, message):
            self.messages.append((status, message.decode()))

        self.s = FMU3Slave(guid=self.md.guid, unzipDirectory=extract(str(path)),
                           modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate(logMessage=log)
        self.n = 1 if n_sub is None else n_sub
        if n_sub is not None:
            self.s.enterConfigurationMode()
            self.s.setUInt64([self.vr["n_sub"]], [n_sub])
            self.s.exitConfigurationMode()

    def set(self, values: dict):
        for name, value in values.items():
            if isinstance(value, str):
                self.s.setString([self.vr[name]], [value])
            else:
                self.s.setFloat64([self.vr[name]], [float(value)])

    def start(self, values: dict, start: float = 0.0):
        self.set(values)
        self.s.enterInitializationMode(startTime=start)
        self.s.exitInitializationMode()

    def scalars(self) -> np.ndarray:
        return np.array(self.s.getFloat64([self.vr[n] for n in OUTPUTS + ["motion_time"]]))

    def arrays(self) -> np.ndarray:
        """(n_sub, 11): row k = sub-interval k, columns in the order of OUTPUTS."""
        return np.array(self.s.getFloat64([self.vr[n] for n in SUB], len(SUB) * self.n)).reshape(len(SUB), self.n).T

    def errors(self) -> str:
        return "\n".join(m for status, m in self.messages if status >= 3)

    def free(self):
        self.s.freeInstance()


def reference_rows(path, values: dict, start: float, step: float, steps: int) -> np.ndarray:
    """The scalar outputs (and motion_time) of the n_sub = 1 Turntable at initialisation and after each of
    ``steps`` steps of ``step`` s, the communication points start + j step as a master computes them."""
    t = Table3(path, name="ref")
    try:
        t.start(values, start)
        rows = [t.scalars()]
        for j in range(steps):
            t.s.doStep(start + j * step, step)
            rows.append(t.scalars())
        return np.array(rows)
    finally:
        t.free()


@pytest.mark.parametrize("case", list(CASES))
def test_the_arrays_are_the_turntable_stepped_at_h_over_n_sub(turntable3, case):
    n, h, start, values = CASES[case]
    sub = h / n
    steps = round(RUN / h)
    ref = reference_rows(turntable3, {**values, "grid": sub}, start, sub, (steps + 1) * n)
    np.testing.assert_array_equal(ref[:, -1], start + np.arange(len(ref)) * sub)  # whole-grid times
    # the run spans what n_sub = 1 at h could not: accelerations and ambient slopes changing inside a step
    inside = [j for j in range(steps) for col in (6, 7, 8, RATE_AT)
              if np.ptp(ref[j * n:(j + 1) * n, col]) > 0]
    assert len({j for j in inside}) >= 10, inside
    t = Table3(turntable3, n)
    try:
        t.start({**values, "grid": sub}, start)
        assert np.array_equal(t.arrays(), ref[:n, :-1])  # before h is known: sub-intervals of grid
        assert np.array_equal(t.scalars(), ref[0])
        for i in range(steps):
            t.s.doStep(start + i * h, h)
            first = (i + 1) * n
            assert np.array_equal(t.arrays(), ref[first:first + n, :-1]), (case, i)
            scalars = t.scalars()
            # the state at motion_time and the acceleration holding from there: element 0
            assert np.array_equal(scalars[:RATE_AT], ref[first, :RATE_AT]), i
            assert scalars[-1] == ref[first, -1] == start + (i + 1) * h
            # the ambient's slope over the whole step [motion_time, motion_time + h]
            ambient = OUTPUTS.index("ambient_temp")
            assert scalars[RATE_AT] == (ref[first + n, ambient] - ref[first, ambient]) / h, i
    finally:
        t.free()
    assert np.ptp(ref[:, 0]) > 1.0  # the table turned


def test_one_sub_interval_is_the_turntable_of_before(fmu_dir, turntable3):
    from fmu_driver import Slave

    values = {**CASES["K=5 dual-axis from t=3"][3], "align_time": 0.0}
    two = Slave(fmu_dir / "Turntable.fmu", "tt2")
    three = Table3(turntable3)  # not configured: n_sub = 1, its default
    try:
        two.set(**values)
        two.fmu.enterInitializationMode()
        two.fmu.exitInitializationMode()
        three.start(values)
        assert three.s.getUInt64([three.vr["n_sub"]]) == [1]
        for k in range(60):
            if k:
                two.fmu.doStep(k - 1.0, 1.0)
                three.s.doStep(k - 1.0, 1.0)
            scalars = three.scalars()
            assert list(scalars) == two.get(*OUTPUTS, "motion_time")
            assert np.array_equal(three.arrays(), scalars[None, :-1])  # one element: the scalars
    finally:
        two.free()
        three.free()


def test_steps_off_the_sub_grid_and_bad_n_sub_are_refused_with_the_reason(fmu_dir, turntable3):
    from fmu_driver import check_parameter_error

    values = CASES["K=4 forward-reverse"][3]
    for n_sub, h, reason in ((4, 8.0, "is not on the output grid of step 8 s / n_sub 4 = 2 s"),
                             (None, 4.0, "is not on the output grid of step 4 s: the IMU cannot rebuild")):
        t = Table3(turntable3, n_sub)
        t.start(values)
        with pytest.raises(FMICallException):
            t.s.doStep(0.0, h)
        assert "turntable breakpoint at t=3 s" in t.errors() and reason in t.errors(), t.errors()
        t.free()
    t = Table3(turntable3, 2)  # breakpoints on the 0.5 s grid, but the arrays of initialisation are 1 s (grid) long
    t.start(values)
    with pytest.raises(FMICallException):
        t.s.doStep(0.0, 1.0)
    assert "step 1 s / n_sub 2 = 0.5 s must equal grid = 1 s" in t.errors(), t.errors()
    t.free()
    t = Table3(turntable3)
    for bad in (0, 100_001):
        t.s.enterConfigurationMode()
        with pytest.raises(FMICallException):
            t.s.setUInt64([t.vr["n_sub"]], [bad])
        assert f"n_sub = {bad} must be in 1 .. 100000" in t.errors(), t.errors()
        t.s.reset()
    t.free()
    # FMI 2.0: no arrays, so no sub-intervals; n_sub out of range named
    check_parameter_error(fmu_dir / "Turntable.fmu", {"n_sub": 2}, "which only the FMI 3.0 variant of this FMU has")
    check_parameter_error(fmu_dir / "Turntable.fmu", {"n_sub": 0}, "n_sub = 0")


def test_fmu_state_keeps_the_arrays(turntable3):
    n, h, start, values = CASES["K=4 forward-reverse"]
    a = Table3(turntable3, n, "a")
    a.start({**values, "grid": h / n}, start)

    def run(t, first, count):
        rows = []
        for i in range(first, first + count):
            t.s.doStep(start + i * h, h)
            rows.append((t.arrays(), t.scalars()))
        return rows

    def same(x, y):
        return len(x) == len(y) and all(np.array_equal(p[0], q[0]) and np.array_equal(p[1], q[1])
                                        for p, q in zip(x, y))

    try:
        run(a, 0, 10)
        state = a.s.getFMUState()
        blob = a.s.serializeFMUState(state)
        mark = (a.arrays(), a.scalars())
        expected = run(a, 10, 15)
        assert not np.array_equal(expected[-1][0], mark[0])
        a.s.setFMUState(state)
        assert same([(a.arrays(), a.scalars())], [mark])
        assert same(run(a, 10, 15), expected)
        # into an instance with the default n_sub = 1 that never initialised: n_sub and the arrays come too
        b = Table3(turntable3, name="b")
        restored = b.s.deserializeFMUState(blob)
        b.s.setFMUState(restored)
        b.n = n
        assert b.s.getUInt64([b.vr["n_sub"]]) == [n]
        assert same([(b.arrays(), b.scalars())], [mark])
        assert same(run(b, 10, 15), expected)
        b.s.freeFMUState(restored)
        b.free()
        a.s.freeFMUState(state)
    finally:
        a.free()
