"""Compiled ``doStep`` of the IMUThermal, StrapdownINS and Turntable slaves (C core).

A slave's step in its usual case is one compiled call on preallocated
state: it reads the inputs from the slave's float64 Real buffer
(:mod:`fmus.slave_support`), checks the communication point and the time
tags, runs the core's kernels (the same ones the in-process runs use) and
writes the outputs back to the buffer.  It returns 0 when it did the step,
and 1 *without having changed any state* when it cannot (the first step,
alignment phase changes, a new drift compensation value or a queued one
taking over, any input or tag the Python ``do_step`` would refuse): the Python ``do_step`` then runs as before and
stays the one place that raises the error messages.

Two ways in, both into the same C function of the core
(``sarins_imu_fmu_step`` in ``sarins_fmu/core/imu.c``, ``sarins_ins_fmu_step``
in ``ins_fmu_step.c``, ``sarins_turntable_fmu_step`` in
``turntable_fmu_step.c``):

* :meth:`FastStep.step`, called first by the slave's Python ``do_step``;
* the native FMI layer (``fmus/native/core.c``) calls it from ``fmi2DoStep``
  without entering Python, through ``slave._fmi_fast_step = (function
  address, table address, table rows)``; on a non-zero return it calls the
  Python ``do_step``.

The state reaches the C as an array table
(:func:`sarins_fmu.core._lib.array_table`): the library object's arrays, then
an ``io`` row of slots and settings, then the slave's own state rows.  The
Python objects own the arrays and update them in place only.

With ``SARINS_FMU_NO_COMPILED_STEP=1`` every context is None and the Python
``do_step`` runs every step, with the same results bit for bit.
"""

from __future__ import annotations

import math
import os

import numpy as np

from fmus.slave_support import TAG_TOL, real_slots
from sarins_fmu.core import imu as core_imu
from sarins_fmu.core import ins as core_ins
from sarins_fmu.core import turntable as core_turntable
from sarins_fmu.core._lib import array_table


def enabled() -> bool:
    """True when the slaves may use their compiled steps (``SARINS_FMU_NO_COMPILED_STEP`` unset)."""
    return os.environ.get("SARINS_FMU_NO_COMPILED_STEP", "") not in ("1", "true", "yes")


class FastStep:
    """A slave's compiled step: the array table, the arrays it points to, the core's C function.

    ``step(table, buffer, t, h)`` runs it from Python (the ctypes binding);
    ``address`` is the same C function's address, for the native layer.
    """

    def __init__(self, step, address: int, arrays):
        self.arrays = tuple(arrays)  # keeps every array the table points to alive
        self.table = array_table(self.arrays)
        self._step = step
        self._address = int(address)

    def step(self, buffer, time: float, step: float) -> bool:
        """Run the compiled step from Python; True when it did the step."""
        return self._step(self.table, buffer, time, step) == 0

    @property
    def address(self):
        """(C function address, table address, table rows) for the native FMI layer."""
        return (self._address, self.table.ctypes.data, self.table.shape[0])


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
    return FastStep(core_imu.fmu_step, core_imu.FMU_STEP_ADDRESS, arrays)


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
    if not enabled():
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
    return FastStep(core_turntable.fmu_step, core_turntable.FMU_STEP_ADDRESS, arrays)
