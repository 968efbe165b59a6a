"""StrapdownINS FMU: alignment and navigation from IMU increments, static start."""

import math

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_step, declare,
                                discard_on_error, guarded, real_slots)
from sarins_fmu import ins

DEG = math.pi / 180.0
PHASES = {"coarse": 0, "fine": 1, "navigate": 2}
FILTER_UNITS = {"arw": "rad/sqrt(s)", "vrw": "m/s/sqrt(s)", "drift_rw": "rad/s/sqrt(s)", "bias_rw": "m/s2/sqrt(s)",
                "velocity_meas_std": "m/s", "tilt0_std": "rad", "heading0_std": "rad", "velocity0_std": "m/s",
                "drift0_std": "rad/s", "bias0_std": "m/s2"}


class StrapdownINS(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Two-speed strapdown INS (ENU) on a known static start. Contract: each doStep(t, h) is one "
        "major-loop update from the IMU increments of [t, t+h] (inputs; Gauss-Seidel: the IMU is stepped "
        "first); the step must stay constant. Phases: coarse alignment (coarse_time), Kalman fine "
        "alignment with a zero-velocity measurement until align_time, then free navigation from the known "
        "start with the alignment's horizontal drift and accelerometer-bias estimates compensated. "
        "The input axial_drift_correction (rad/s) is subtracted from the z gyro during navigation. "
        "Outputs after doStep(t, h) are the navigation state at t + h and its errors with respect to the "
        "known static start. Held between steps: attitude, velocity, position, filter state, estimates.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=16 * 3600.0, step_size=1.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "real", "lat0", PARAMETER, "latitude of the static start [rad; deg]", 28.222 * DEG)
        declare(self, "real", "lon0", PARAMETER, "longitude of the static start [rad; deg]", 0.0)
        declare(self, "real", "height0", PARAMETER, "height of the static start [m]", 0.0)
        declare(self, "real", "align_time", PARAMETER, "alignment duration [s]", 4 * 3600.0)
        declare(self, "real", "coarse_time", PARAMETER, "coarse alignment duration [s]", 300.0)
        defaults = ins.AlignmentFilter()
        for name, unit in FILTER_UNITS.items():
            declare(self, "real", f"kf_{name}", PARAMETER, f"alignment filter {name} [{unit}]",
                    float(getattr(defaults, name)))
        for ax in "xyz":
            declare(self, "real", f"dtheta_{ax}", INPUT, f"angle increment about body {ax} [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"dv_{ax}", INPUT, f"velocity increment along body {ax} [m/s]", 0.0)
        declare(self, "real", "temp_gyro_z", INPUT, "azimuth gyro temperature [degC]", 20.0)
        declare(self, "real", "axial_drift_correction", INPUT,
                "azimuth drift subtracted during navigation [rad/s; deg/h]", 0.0)
        for name, unit, text in (("lat", "rad; deg", "latitude"), ("lon", "rad; deg", "longitude"),
                                 ("height", "m", "height"), ("v_e", "m/s", "east velocity"),
                                 ("v_n", "m/s", "north velocity"), ("v_u", "m/s", "up velocity"),
                                 ("yaw", "rad; deg", "yaw, CCW from north"), ("pitch", "rad; deg", "pitch"),
                                 ("roll", "rad; deg", "roll")):
            declare(self, "real", name, OUTPUT, f"{text} [{unit}]", 0.0)
        for name, unit, text in (("lat_error", "rad; deg", "latitude error wrt the static start"),
                                 ("lon_error", "rad; deg", "longitude error wrt the static start"),
                                 ("north_error", "m", "north position error"),
                                 ("east_error", "m", "east position error"),
                                 ("position_error", "m; nmi", "horizontal position error"),
                                 ("nav_time", "s", "time since navigation started (negative while aligning)"),
                                 ("gyro_drift_est_x", "rad/s; deg/h", "x gyro drift estimated in alignment"),
                                 ("gyro_drift_est_y", "rad/s; deg/h", "y gyro drift estimated in alignment"),
                                 ("accel_bias_est_x", "m/s2", "x accelerometer bias estimated in alignment"),
                                 ("accel_bias_est_y", "m/s2", "y accelerometer bias estimated in alignment"),
                                 ("temp_align_start", "degC", "azimuth gyro temperature at the alignment start"),
                                 ("temp_align_end", "degC", "azimuth gyro temperature at the alignment end"),
                                 ("temp_change_align", "degC", "its change over the alignment")):
            declare(self, "real", name, OUTPUT, f"{text} [{unit}]", 0.0)
        declare(self, "integer", "phase", OUTPUT, "0 coarse alignment, 1 fine alignment, 2 navigation [1]", 0)
        self._ins = None
        self._step = None
        self._config = None
        # buffer slots for vectorised I/O (see fmus.slave_support)
        self._in_slots = real_slots(self, [f"dtheta_{a}" for a in "xyz"] + [f"dv_{a}" for a in "xyz"])
        self._nav_slots = real_slots(self, ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"])
        self._err_slots = real_slots(self, ["lat_error", "lon_error", "north_error", "east_error", "position_error"])
        self._est_slots = real_slots(self, ["gyro_drift_est_x", "gyro_drift_est_y", "accel_bias_est_x",
                                            "accel_bias_est_y"])
        self._err = np.zeros(5)
        self._est = np.zeros(4)

    def _make_config(self, step):
        names = ["lat0", "lon0", "height0", "align_time", "coarse_time"] + [f"kf_{n}" for n in FILTER_UNITS]
        check_finite(self, names, non_negative=["align_time", "coarse_time"],
                     positive=[f"kf_{n}" for n in FILTER_UNITS])
        try:
            filt = ins.AlignmentFilter(**{n: float(getattr(self, f"kf_{n}")) for n in FILTER_UNITS})
            return ins.InsConfig(lat=self.lat0, lon=self.lon0, height=self.height0, align_time=self.align_time,
                                 coarse_time=self.coarse_time, step=step, filter=filt)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None

    @guarded
    def exit_initialization_mode(self):
        if self.align_time <= 0:
            raise ParameterError("align_time must be positive (the FMU aligns on its static start)")
        self._make_config(1.0)  # validate parameters before the first step
        self.lat, self.lon, self.height = self.lat0, self.lon0, self.height0
        self.nav_time = -self.align_time
        self.temp_align_start = self.temp_gyro_z

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            if self._ins is None:
                self._config = self._make_config(step_size)
                self._ins = ins.StrapdownINS(self._config)
                self.temp_align_start = float(self.temp_gyro_z)
            increments = self._fmi_buffer[self._in_slots][None, :]
            correction = float(self.axial_drift_correction)
            if not math.isfinite(correction):
                raise ValueError("axial_drift_correction is not finite")
            out = self._ins.step(increments[:, :3], increments[:, 3:], correction)
        except ValueError as exc:
            return discard_on_error(self, exc)
        self._publish(out[0])
        return True

    def _publish(self, row):
        state = self._ins
        buffer = self._fmi_buffer
        buffer[self._nav_slots] = row
        err = self._err
        err[:4] = state.position_error(row[None, :])[0]
        err[4] = math.hypot(err[2], err[3])
        buffer[self._err_slots] = err
        self.phase = PHASES[state.phase]
        self.nav_time = state.time - self._config.align_time
        est = self._est
        est[:2] = state.gyro_comp[:2]
        est[2:] = state.accel_comp[:2]
        buffer[self._est_slots] = est
        if state.phase != "navigate" or abs(self.nav_time) < 0.5 * self._step:
            self.temp_align_end = float(self.temp_gyro_z)
            self.temp_change_align = self.temp_align_end - self.temp_align_start
