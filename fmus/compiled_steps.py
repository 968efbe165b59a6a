"""Compiled ``doStep`` of the IMUThermal slave (C core; the Turntable and StrapdownINS FMUs are native).

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
(``sarins_imu_fmu_step`` in ``sarins_fmu/core/imu.c``):

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

import os

import numpy as np

from fmus.slave_support import real_slots
from sarins_fmu.core import imu as core_imu
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
