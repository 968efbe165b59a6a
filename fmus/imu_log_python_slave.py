"""The Python-hosted IMULog (pythonfmu), kept only for the tests of the pythonfmu bridge (``fmus/native/``).

Not shipped: ``sarins build-fmus`` builds the native IMULog (``fmus/c/imu_log/model.c``, declared in
``fmus/imu_log_slave.py``).  The tests build this one with :func:`fmus.build.build_fmu` (the ``bridge_fmu``
fixture of tests/conftest.py) to exercise the bridge: a Python-hosted FMU, its runtime lookup and its checks.
"""

import math

from pythonfmu import Fmi2Slave

from fmus.slave_support import check_step, declare, default_experiment, discard_on_error, guarded, OUTPUT, PARAMETER, ParameterError
from sarins_fmu.imu_log import LogError, read_log
from sarins_fmu.thermal import SENSORS


class IMULog(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Plays a recorded IMU log (CSV or NPZ, sarins-imu-log format 1: timestamped angle and velocity "
        "increments or rates in SI units, optional temperatures; checked when loaded). Contract: FMU time 0 "
        "is the start of the log's first interval (first time_s minus the log's interval h); the "
        "communication step must equal h; after doStep(t, h) the outputs are the log's increments over "
        "(t, t + h] in body axes, tagged increment_end_time = t + h as StrapdownINS expects, and the six "
        "temperatures at t + h (20 degC when the log has none). "
        "lat_deg, lon_deg and height_m of the log are outputs, to set the INS start from. A missing or bad "
        "log fails fmi2ExitInitializationMode naming the line; stepping past the end of the log fails "
        "the step. Held between steps: the sample index.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "log_file", PARAMETER, "path of the IMU log (.csv or .npz)", "")
        for ax in "xyz":
            declare(self, "real", f"dtheta_{ax}", OUTPUT, f"angle increment about body {ax} over the step [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"dv_{ax}", OUTPUT, f"velocity increment along body {ax} over the step [m/s]", 0.0)
        for sensor in SENSORS:
            declare(self, "real", f"temp_{sensor}", OUTPUT, f"temperature of the {sensor} sensor [degC]", 20.0)
        declare(self, "real", "log_time", OUTPUT, "log timestamp of the current outputs [s]", 0.0)
        declare(self, "real", "increment_end_time", OUTPUT,
                "time tag: FMU time at the end of the increments' interval (0: none yet) [s]", 0.0)
        declare(self, "real", "log_step", OUTPUT, "sample interval of the log [s]", 0.0)
        declare(self, "real", "lat_deg", OUTPUT, "static start latitude of the log [deg]", 0.0)
        declare(self, "real", "lon_deg", OUTPUT, "static start longitude of the log [deg]", 0.0)
        declare(self, "real", "height_m", OUTPUT, "static start height of the log [m]", 0.0)
        self._log = None
        self._step = None

    @guarded
    def exit_initialization_mode(self):
        if not self.log_file:
            raise ParameterError("parameter log_file is empty: give the path of an IMU log")
        try:
            self._log = read_log(self.log_file)
        except LogError as exc:
            raise ParameterError(f"parameter log_file: {exc}") from None
        log = self._log
        self.log_step = log.step
        self.log_time = float(log.time[0] - log.step)
        self.lat_deg, self.lon_deg, self.height_m = math.degrees(log.lat), math.degrees(log.lon), log.height
        if log.temps is not None:
            self._set_temps(log.temps[0])

    def _set_temps(self, temps):
        for j, sensor in enumerate(SENSORS):
            setattr(self, f"temp_{sensor}", float(temps[j]))

    @guarded
    def do_step(self, current_time, step_size):
        log = self._log
        try:
            self._step = check_step(self, step_size, self._step)
            if abs(step_size - log.step) > 1e-9 * log.step:
                raise ValueError(f"communication step {step_size} s differs from the log's interval {log.step} s")
            k = round(current_time / step_size)
            if abs(k * step_size - current_time) > 1e-6 * step_size:
                raise ValueError(f"time {current_time} s is not on the log's {log.step} s grid")
            if k >= len(log.time):
                raise ValueError(f"the log ends at FMU time {len(log.time) * log.step:.9g} s")
        except ValueError as exc:
            return discard_on_error(self, exc)
        for i, ax in enumerate("xyz"):
            setattr(self, f"dtheta_{ax}", float(log.dtheta[k, i]))
            setattr(self, f"dv_{ax}", float(log.dv[k, i]))
        if log.temps is not None:
            self._set_temps(log.temps[k])
        self.log_time = float(log.time[k])
        self.increment_end_time = (k + 1) * step_size
        return True
