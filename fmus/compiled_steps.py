"""Compiled ``doStep`` of the IMUThermal (C core), StrapdownINS and Turntable (numba) slaves.

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
* a C function (IMUThermal: ``sarins_imu_fmu_step`` of the C core,
  ``sarins_fmu/core/imu.c``; the others: a ``numba.cfunc``, cached on
  disk) that the native FMI layer
  (``fmus/native/core.c``) calls from ``fmi2DoStep`` without entering
  Python, through ``slave._fmi_fast_step = (function address, table address,
  table rows)``; on a non-zero return it calls the Python ``do_step``.

The state reaches compiled code as an array table
(:func:`sarins_fmu._jit.array_table`): the library object's arrays, then an
``io`` row of slots and settings, then the slave's own state rows.  The
Python objects own the arrays and update them in place only.

Without numba (``SARINS_NO_NUMBA=1`` or not installed) the StrapdownINS and
Turntable contexts are None; with ``SARINS_FMU_NO_COMPILED_STEP=1`` every
context is None.  The Python ``do_step`` then runs every step, with the same
results bit for bit.
"""

from __future__ import annotations

import math
import os

import numpy as np

from fmus.slave_support import TAG_TOL, real_slots
from sarins_fmu.core import imu as core_imu
from sarins_fmu.ins_kernel import align_steps, held_row, nav_steps
from sarins_fmu.turntable.schedule import state_into
from sarins_fmu._jit import HAVE_NUMBA, array_table, c_buffer, c_table, fast_step_cfunc, jit, table_view1, table_view2



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
_IMU_IO = _IMU_VEHICLE + 17  # as IO_SIZE in sarins_fmu/core/imu.c


def imu_context(slave, step: float):
    """The IMUThermal slave's compiled step (the C core's ``sarins_imu_fmu_step``), or None with
    ``SARINS_FMU_NO_COMPILED_STEP=1``."""
    if not _allowed():
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
    return FastStep(core_imu.fmu_step, core_imu.FMU_STEP_ADDRESS, arrays)


@jit
def _read(buf, slots, out):
    """out[i] = buf[slots[i]]; False if a value is not finite."""
    for i in range(out.shape[0]):
        out[i] = buf[int(slots[i])]
        if not math.isfinite(out[i]):
            return False
    return True


# ---------------------------------------------------------------- StrapdownINS

# io row: expected step, start time, align time, steps of the alignment; slots of the inputs (dtheta/dv (6),
# increment_end_time, temp_gyro_z, the correction c, b, a, axial_drift_apply_from), the 9 navigation
# outputs, the 5 error outputs, the 4 estimates, the time and temperature outputs (nav_time, temp_azimuth_gyro,
# temp_align_start, temp_align_end, temp_change_align, solution_time); lat0, lon0, (r_m + h0), (r_n + h0),
# cos(lat0); steps of the coarse alignment, the filter's velocity measurement variance
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
_INS_IO = _INS_FILTER + 2


def ins_context(slave):
    """The StrapdownINS slave's compiled step (fine alignment, navigation with a constant or temperature-model
    drift correction), or None (see :func:`enabled`)."""
    if not enabled():
        return None
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
    io[_INS_FILTER:] = slave._ins._n_coarse, config.filter.velocity_meas_std ** 2
    q, v, pos, gyro_comp, accel_comp, steps, x, p, q_diag, p_history = slave._ins.state_arrays()
    if p_history.shape[0] == 0:
        p_history = np.zeros((1, 9))  # no fine alignment: never written
    arrays = (q, v, pos, gyro_comp, accel_comp, steps, io, slave._compensation.state, x, p, q_diag, p_history)
    return FastStep(_ins_step, _ins_c_step, arrays)


@jit
def _compensation_unchanged(comp, value, apply_from, nav_start, tol):
    """True if the drift compensation inputs (value (c, b, a), apply_from) leave the value in force of the
    slave's Compensation ``state`` (``comp``) for the interval starting at ``nav_start``: the pair seen
    last, or its value again with an apply_from after every queued pair's (not queued), and no queued
    pair takes over.  Otherwise the Python step queues the pair, lets a queued one take over, or refuses
    a late one."""
    for i in range(3):
        if value[i] != comp[i]:
            return False  # a new value
    if apply_from != comp[3] and (apply_from < nav_start - tol or not comp[8] < apply_from - tol):
        return False  # too late, or it replaces queued pairs
    return nav_start < comp[7] - tol


@jit
def _ins_step(table, buf, t, h):
    """One StrapdownINS step of fine alignment or navigation: see the slave's do_step for the contract.

    The azimuth drift correction is the set (c, b, a) in force (``comp[4:7]``, see the slave's
    Compensation) evaluated at the interval's temp_gyro_z T: (a T + b) T + c, as
    :func:`sarins_fmu.drift_model.drift_model_value`.
    """
    q, v, pos = table_view1(table, 0), table_view1(table, 1), table_view1(table, 2)
    gyro_comp, accel_comp, count = table_view1(table, 3), table_view1(table, 4), table_view1(table, 5)
    io, comp = table_view1(table, 6), table_view1(table, 7)
    step = io[0]
    if not abs(h - step) <= 1e-9 * step:
        return 1
    steps = count[0]
    n_coarse, n_align = io[_INS_FILTER], io[3]
    if steps < n_coarse or steps == 0 or steps == n_align - 1:  # coarse alignment, the end of the fine one
        return 1
    n_in = _INS_NAV - _INS_IN
    inputs = np.empty(n_in)
    if not _read(buf, io[_INS_IN:_INS_NAV], inputs):
        return 1
    tag, temp_z, apply_from = inputs[6], inputs[7], inputs[n_in - 1]
    if not _same_time(tag, io[1] + steps * h + h, h):  # the interval after the last one integrated
        return 1
    nav_start = steps * h - io[2]  # nav time of the interval's start
    if not _compensation_unchanged(comp, inputs[8:11], apply_from, nav_start, TAG_TOL * h):
        return 1
    correction = np.full(1, (comp[6] * temp_z + comp[5]) * temp_z + comp[4])
    if not math.isfinite(correction[0]):
        return 1  # the Python step refuses it
    # every check passed: from here on the step happens
    comp[3] = apply_from  # the seen pair: the same value, possibly with a later apply_from
    inc = np.empty((2, 3))
    for i in range(6):
        inc[i // 3, i % 3] = inputs[i]
    if steps < n_align:  # fine alignment (the phase stays the same)
        hist = align_steps(q, v, pos, inc[0:1], inc[1:2], step, gyro_comp, accel_comp, table_view1(table, 8),
                           table_view2(table, 9), table_view1(table, 10), io[_INS_FILTER + 1])
        table_view2(table, 11)[int(steps - n_coarse)] = hist[0]
        row = held_row(q, pos)
    else:
        row = nav_steps(q, v, pos, inc[0:1], inc[1:2], step, gyro_comp, accel_comp, correction)[0]
    count[0] = steps + 1
    for i in range(9):
        buf[int(io[_INS_NAV + i])] = row[i]
    dlat = row[0] - io[_INS_SITE]
    dlon = row[1] - io[_INS_SITE + 1]
    north = dlat * io[_INS_SITE + 2]
    east = dlon * io[_INS_SITE + 3] * io[_INS_SITE + 4]
    err = (dlat, dlon, north, east, math.hypot(north, east))
    for i in range(5):
        buf[int(io[_INS_ERR + i])] = err[i]
    est = (gyro_comp[0], gyro_comp[1], accel_comp[0], accel_comp[1])
    for i in range(4):
        buf[int(io[_INS_EST + i])] = est[i]
    nav_time = (steps + 1) * step - io[2]
    buf[int(io[_INS_TEMP])] = nav_time
    buf[int(io[_INS_TEMP + 1])] = temp_z
    if steps + 1 < n_align or abs(nav_time) < 0.5 * step:
        buf[int(io[_INS_TEMP + 3])] = temp_z
        buf[int(io[_INS_TEMP + 4])] = temp_z - buf[int(io[_INS_TEMP + 2])]
    buf[int(io[_INS_TEMP + 5])] = io[1] + (steps + 1) * step  # solution_time
    return 0


def _ins_c_step(table, rows, buffer, n, t, h):
    return _ins_step(c_table(table, rows), c_buffer(buffer, n), t, h)


# ------------------------------------------------------------------- Turntable

# io row: expected step, gimbals A, constant ambient (1/0), its value, slots of angle_1..3,
# rate_1..3, accel_1..3, ambient_temp, ambient_temp_rate, motion_time
_TT_IO = 16


def turntable_context(slave):
    """The Turntable slave's compiled step (constant ambient), or None (see :func:`enabled`)."""
    ambient = slave._ambient
    if not enabled() or ambient.profile is not None or ambient.amplitude != 0.0 or ambient.slope != 0.0:
        return None
    io = np.zeros(_TT_IO)
    io[0:4] = slave._step, slave._schedule.n_axes, 1.0, float(ambient.mean)
    io[4:13] = slave._out_slots
    io[13:16] = real_slots(slave, ["ambient_temp", "ambient_temp_rate", "motion_time"])
    times, angle_bp, rate_bp, accel, angle0, rate0 = slave._schedule.tables()
    arrays = (np.ascontiguousarray(times), angle_bp, rate_bp, accel, angle0, rate0, io)
    if any(not a.flags.c_contiguous for a in arrays):
        return None
    return FastStep(_turntable_step, _turntable_c_step, arrays)


@jit
def _turntable_step(table, buf, t, h):
    """One Turntable step: the gimbal state and the (constant) ambient at t + h."""
    io = table_view1(table, 6)
    if not abs(h - io[0]) <= 1e-9 * io[0] or io[2] == 0.0:
        return 1
    time = np.full(1, t + h)
    if not math.isfinite(time[0]):
        return 1
    n = int(io[1])
    angle, rate, acc = np.empty((1, n)), np.empty((1, n)), np.zeros((1, n))
    state_into(time, table_view1(table, 0), table_view2(table, 1), table_view2(table, 2), table_view2(table, 3),
               table_view1(table, 4), table_view1(table, 5), angle, rate, acc)
    for j in range(n):
        buf[int(io[4 + j])] = angle[0, j]
        buf[int(io[7 + j])] = rate[0, j]
        buf[int(io[10 + j])] = acc[0, j]
    buf[int(io[13])] = io[3]
    buf[int(io[14])] = (io[3] - io[3]) / h
    buf[int(io[15])] = time[0]
    return 0


def _turntable_c_step(table, rows, buffer, n, t, h):
    return _turntable_step(c_table(table, rows), c_buffer(buffer, n), t, h)
