"""Compiled ``doStep`` of the IMUThermal (numba), StrapdownINS and Turntable (C core) slaves.

A slave's step in its usual case is one compiled call on preallocated
state: it reads the inputs from the slave's float64 Real buffer
(:mod:`fmus.slave_support`), checks the communication point and the time
tags, runs the library's kernels (the same ones the in-process runs use) and
writes the outputs back to the buffer.  It returns 0 when it did the step,
and 1 *without having changed any state* when it cannot (the first step,
alignment phase changes, a block of random numbers to draw, a new drift
compensation value or a queued one taking over, any input or tag the Python
``do_step`` would refuse): the
Python ``do_step`` then runs as before and stays the one place that raises
the error messages.

Two ways in:

* :meth:`FastStep.step`, called first by the slave's Python ``do_step``;
* a C function (StrapdownINS: ``sarins_ins_fmu_step`` of the C core,
  ``sarins_fmu/core/ins_fmu_step.c``; Turntable: ``sarins_turntable_fmu_step``,
  ``turntable_fmu_step.c``; IMUThermal: a ``numba.cfunc``, cached on disk)
  that the native FMI layer
  (``fmus/native/core.c``) calls from ``fmi2DoStep`` without entering
  Python, through ``slave._fmi_fast_step = (function address, table address,
  table rows)``; on a non-zero return it calls the Python ``do_step``.

The state reaches compiled code as an array table
(:func:`sarins_fmu._jit.array_table`): the library object's arrays, then an
``io`` row of slots and settings, then the slave's own state rows.  The
Python objects own the arrays and update them in place only.

Without numba (``SARINS_NO_NUMBA=1`` or not installed) the IMUThermal
context is None; with ``SARINS_FMU_NO_COMPILED_STEP=1`` every context is
None.  The Python ``do_step`` then runs every step, with the same results
bit for bit.
"""

from __future__ import annotations

import math
import os

import numpy as np

from fmus.slave_support import NO_TAG, TAG_TOL, real_slots
from sarins_fmu import imu_step
from sarins_fmu.core import ins as core_ins
from sarins_fmu.core import turntable as core_turntable
from sarins_fmu._jit import HAVE_NUMBA, array_table, c_buffer, c_table, fast_step_cfunc, jit, table_view1



def _allowed() -> bool:
    return os.environ.get("SARINS_FMU_NO_COMPILED_STEP", "") not in ("1", "true", "yes")


def enabled() -> bool:
    """True when the slaves may use their numba-compiled steps."""
    return HAVE_NUMBA and _allowed()


class FastStep:
    """A slave's compiled step: the array table, the arrays it points to, the C entry point.

    ``step(table, buffer, t, h)`` runs it from Python; ``body`` is the
    numba cfunc's body, or the address (int) of a C function of the core.
    """

    def __init__(self, step, body, arrays):
        self.arrays = tuple(arrays)  # keeps every array the table points to alive
        self.table = array_table(self.arrays)
        self._step = step
        self._body = body

    def step(self, buffer, time: float, step: float) -> bool:
        """Run the compiled step from Python; True when it did the step."""
        return self._step(self.table, buffer, time, step) == 0

    @property
    def address(self):
        """(C function address, table address, table rows) for the native FMI layer, or None
        when the C function cannot be made (the Python do_step then calls :meth:`step`)."""
        if isinstance(self._body, int):
            return (self._body, self.table.ctypes.data, self.table.shape[0])
        try:
            return (_cfunc(self._body).address, self.table.ctypes.data, self.table.shape[0])
        except Exception:  # pragma: no cover - numba cannot compile a cfunc here
            return None


_CFUNCS = {}


def _cfunc(body):
    """The C-callable version of a step body (compiled, or loaded from numba's cache, on first use)."""
    if body not in _CFUNCS:
        _CFUNCS[body] = fast_step_cfunc(body)
    return _CFUNCS[body]


@jit
def _same_time(a, b, step):
    return abs(a - b) <= TAG_TOL * step


# ------------------------------------------------------------------ IMUThermal

# io row: expected step, start time, gimbals A, slots of motion_time, ambient_temp,
# ambient_temp_rate, angle_1..3, rate_1..3, accel_1..3, outputs (dtheta, dv, temps: 12),
# increment_end_time; moving base (1/0), slots of base_motion_time and of the 15 vehicle inputs
# (yaw, pitch, roll; their rates; their accelerations; base rate e, n, u; base force e, n, u)
_IMU_OUT, _IMU_VEHICLE = 15, 28
_IMU_IO = _IMU_VEHICLE + 17
VEHICLE_SET = 15  # values in the vehicle input set


def imu_context(slave, step: float):
    """The IMUThermal slave's compiled step, or None (see :func:`enabled`)."""
    if not enabled():
        return None
    n = len(slave._axes)
    io = np.zeros(_IMU_IO)
    io[0], io[1], io[2] = step, slave._start_time, n
    io[3:6] = real_slots(slave, ["motion_time", "ambient_temp", "ambient_temp_rate"])
    for k, q in enumerate(("angle", "rate", "accel")):
        io[6 + 3 * k:6 + 3 * k + n] = real_slots(slave, [f"{q}_{j + 1}" for j in range(n)])
    io[_IMU_OUT:_IMU_OUT + 12] = slave._out_slots
    io[27] = real_slots(slave, ["increment_end_time"])[0]
    io[_IMU_VEHICLE] = slave.base == "input"
    io[_IMU_VEHICLE + 1:] = real_slots(slave, ["base_motion_time"] + slave.VEHICLE_INPUTS)
    arrays = slave._sensor.state_arrays() + (io, slave._motion.store, slave._vehicle.store)
    return FastStep(_imu_step, _imu_c_step, arrays)


@jit
def _read(buf, slots, out):
    """out[i] = buf[slots[i]]; False if a value is not finite."""
    for i in range(out.shape[0]):
        out[i] = buf[int(slots[i])]
        if not math.isfinite(out[i]):
            return False
    return True


@jit
def _choose(held, current, tag, t, h):
    """The set tagged t among the current one and the held one (fmus.slave_support.StartOfStepInputs),
    or an empty array when neither is."""
    if _same_time(tag, t, h):
        return current
    if held[0] != 0.0 and _same_time(held[1], t, h):
        return held[2:2 + current.shape[0]].copy()
    return current[0:0]


@jit
def _keep(held, current, tag):
    held[2:2 + current.shape[0]] = current
    held[1] = tag
    held[0] = 1.0


@jit
def _imu_step(table, buf, t, h):
    """One IMUThermal step: see the slave's do_step for the contract."""
    s = imu_step.from_table(table)
    io = table_view1(table, imu_step.N_STATE_ARRAYS)
    held = table_view1(table, imu_step.N_STATE_ARRAYS + 1)
    consts, clock = s[imu_step.CONSTS], s[imu_step.CLOCK]
    if not abs(h - io[0]) <= 1e-9 * io[0]:
        return 1
    if clock[2] >= consts[6]:  # random blocks used up: the Python step draws the next ones
        return 1
    if not _same_time(consts[0] + clock[0] * consts[1] + io[1], t, h):
        return 1
    n = int(io[2])
    current = np.empty(3 * n + 2)
    slots = np.empty(3 * n + 2)
    for k in range(3):
        slots[k * n:(k + 1) * n] = io[6 + 3 * k:6 + 3 * k + n]
    slots[3 * n:] = io[4:6]
    tag = buf[int(io[3])]
    if not (_read(buf, slots, current) and math.isfinite(tag)):
        return 1
    fixed = tag == NO_TAG and held[0] != 0.0 and held[1] == NO_TAG  # no turntable connected
    chosen = current if fixed else _choose(held, current, tag, t, h)
    if chosen.shape[0] == 0:
        return 1
    moving = io[_IMU_VEHICLE] != 0.0
    vehicle = np.empty(VEHICLE_SET)
    v_tag = buf[int(io[_IMU_VEHICLE + 1])]
    v_chosen = vehicle
    if moving:
        v_held = table_view1(table, imu_step.N_STATE_ARRAYS + 2)
        if not (_read(buf, io[_IMU_VEHICLE + 2:], vehicle) and math.isfinite(v_tag)):
            return 1
        v_chosen = _choose(v_held, vehicle, v_tag, t, h)
        if v_chosen.shape[0] == 0:
            return 1
    amb_end = np.empty(1)
    amb_end[0] = chosen[3 * n] + chosen[3 * n + 1] * h
    if not (math.isfinite(amb_end[0]) and amb_end[0] >= -273.15):
        return 1
    # every check passed: from here on the step happens
    if not fixed:
        _keep(held, current, tag)
    m = n + 3 if moving else n  # the vehicle's attitude gimbals carry the table's
    motion = np.empty((3, m))
    for k in range(3):
        if moving:
            motion[k, 0:3] = v_chosen[3 * k:3 * k + 3]
        motion[k, m - n:] = chosen[k * n:(k + 1) * n]
    if moving:
        _keep(table_view1(table, imu_step.N_STATE_ARRAYS + 2), vehicle, v_tag)
        base = s[imu_step.BASE]
        base[0] = v_chosen[9:12]
        base[1] = v_chosen[12:15]
    dtheta = np.empty((1, 3))
    dv = np.empty((1, 3))
    temps = np.empty((1, 6))
    imu_step.one_interval(s, motion[0:1], motion[1:2], motion[2:3], amb_end, dtheta, dv, temps)
    for i in range(3):
        buf[int(io[_IMU_OUT + i])] = dtheta[0, i]
        buf[int(io[_IMU_OUT + 3 + i])] = dv[0, i]
    for i in range(6):
        buf[int(io[_IMU_OUT + 6 + i])] = temps[0, i]
    buf[int(io[27])] = t + h
    return 0


def _imu_c_step(table, rows, buffer, n, t, h):
    return _imu_step(c_table(table, rows), c_buffer(buffer, n), t, h)


# ---------------------------------------------------------------- StrapdownINS

# io row: expected step, start time, align time, steps of the alignment; slots of the inputs (dtheta/dv (6),
# increment_end_time, temp_gyro_z, the correction c, b, a, axial_drift_apply_from), the 9 navigation
# outputs, the 5 error outputs, the 4 estimates, the time and temperature outputs (nav_time, temp_azimuth_gyro,
# temp_align_start, temp_align_end, temp_change_align, solution_time); lat0, lon0, (r_m + h0), (r_n + h0),
# cos(lat0); steps of the coarse alignment, the filter's velocity measurement variance; the time-tag tolerance
# (the layout of ins_fmu_step.h)
INS_INPUTS = [f"dtheta_{a}" for a in "xyz"] + [f"dv_{a}" for a in "xyz"] + [
    "increment_end_time", "temp_gyro_z", "axial_drift_correction", "axial_drift_correction_b",
    "axial_drift_correction_a", "axial_drift_apply_from"]
INS_TIME_TEMP = ["nav_time", "temp_azimuth_gyro", "temp_align_start", "temp_align_end", "temp_change_align",
                 "solution_time"]
_INS_IN = 4
_INS_NAV = _INS_IN + len(INS_INPUTS)
_INS_ERR = _INS_NAV + 9
_INS_EST = _INS_ERR + 5
_INS_TEMP = _INS_EST + 4
_INS_SITE = _INS_TEMP + len(INS_TIME_TEMP)
_INS_FILTER = _INS_SITE + 5
_INS_TAG_TOL = _INS_FILTER + 2
_INS_IO = _INS_TAG_TOL + 1


def ins_context(slave):
    """The StrapdownINS slave's compiled step (fine alignment, navigation with a constant or temperature-model
    drift correction: the C core's ``sarins_ins_fmu_step``), or None with ``SARINS_FMU_NO_COMPILED_STEP=1``."""
    if not _allowed():
        return None
    if core_ins.IO_SIZE != _INS_IO:
        raise RuntimeError(f"the C core's INS step reads an io row of {core_ins.IO_SIZE} values, this module "
                           f"writes {_INS_IO}: rebuild the core ('python3 -m pip install -e .')")
    from sarins_fmu import earth

    config = slave._config
    io = np.zeros(_INS_IO)
    io[0:4] = config.step, slave._start_time, config.align_time, round(config.align_time / config.step)
    io[_INS_IN:_INS_NAV] = real_slots(slave, INS_INPUTS)
    io[_INS_NAV:_INS_ERR] = slave._nav_slots
    io[_INS_ERR:_INS_EST] = slave._err_slots
    io[_INS_EST:_INS_TEMP] = slave._est_slots
    io[_INS_TEMP:_INS_SITE] = real_slots(slave, INS_TIME_TEMP)
    r_m, r_n = earth.radii(config.lat)
    io[_INS_SITE:_INS_FILTER] = config.lat, config.lon, r_m + config.height, r_n + config.height, math.cos(config.lat)
    io[_INS_FILTER:_INS_TAG_TOL] = slave._ins._n_coarse, config.filter.velocity_meas_std ** 2
    io[_INS_TAG_TOL] = TAG_TOL
    q, v, pos, gyro_comp, accel_comp, steps, x, p, q_diag, p_history = slave._ins.state_arrays()
    if p_history.shape[0] == 0:
        p_history = np.zeros((1, 9))  # no fine alignment: never written
    arrays = (q, v, pos, gyro_comp, accel_comp, steps, io, slave._compensation.state, x, p, q_diag, p_history)
    return FastStep(core_ins.fmu_step, core_ins.FMU_STEP_ADDRESS, arrays)


# ------------------------------------------------------------------- Turntable

# io row: expected step, gimbals A, constant ambient (1/0), its value, slots of angle_1..3,
# rate_1..3, accel_1..3, ambient_temp, ambient_temp_rate, motion_time (the layout of turntable_fmu_step.h)
_TT_IO = 16


def turntable_context(slave):
    """The Turntable slave's compiled step (constant ambient: the C core's ``sarins_turntable_fmu_step``), or None
    (a varying ambient, or ``SARINS_FMU_NO_COMPILED_STEP=1``)."""
    ambient = slave._ambient
    if not _allowed() or ambient.profile is not None or ambient.amplitude != 0.0 or ambient.slope != 0.0:
        return None
    io = np.zeros(_TT_IO)
    io[0:4] = slave._step, slave._schedule.n_axes, 1.0, float(ambient.mean)
    io[4:13] = slave._out_slots
    io[13:16] = real_slots(slave, ["ambient_temp", "ambient_temp_rate", "motion_time"])
    times, angle_bp, rate_bp, accel, angle0, rate0 = slave._schedule.tables()
    arrays = (np.ascontiguousarray(times), angle_bp, rate_bp, accel, angle0, rate0, io)
    if any(not a.flags.c_contiguous for a in arrays):
        return None
    return FastStep(core_turntable.fmu_step, core_turntable.FMU_STEP_ADDRESS, arrays)
