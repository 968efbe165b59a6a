"""StrapdownINS FMU: alignment and navigation from IMU increments, static start.

The declaration of the FMU's variables (the native build, fmus/native_fmu.py,
writes the model description and fmus/c/strapdown_ins/model.c's variable
table from it) and the same FMU run in process: the whole step (time tags,
the drift compensation queue, the INS) is the C core's
``sarins_ins_fmu_do_step`` on one state struct
(``sarins_fmu/core/ins_fmu_step.h``), which model.c calls too.
"""

import math

import numpy as np
from pythonfmu import Fmi2Slave

from fmus.native_fmu import ArrayVariable
from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_latitude, check_range,
                                default_experiment,
                                declare, discard_on_error, guarded, real_slots)
from sarins_fmu import ins
from sarins_fmu.core import ins as core_ins
from sarins_fmu.site import SITE_LAT

FILTER_UNITS = {"arw": "rad/sqrt(s)", "vrw": "m/s/sqrt(s)", "drift_rw": "rad/s/sqrt(s)", "bias_rw": "m/s2/sqrt(s)",
                "velocity_meas_std": "m/s", "tilt0_std": "rad", "heading0_std": "rad", "velocity0_std": "m/s",
                "drift0_std": "rad/s", "bias0_std": "m/s2"}


class StrapdownINS(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Two-speed strapdown INS (ENU) on a known static start (align_time > 0), or started navigating at once "
        "from a given attitude yaw0, pitch0, roll0 at rest (align_time = 0). Contract (standard FMI timing, explicit "
        "time-tagged latency): the inputs are the IMU's increments of the interval ending at "
        "increment_end_time with the azimuth gyro temperature there. Each doStep integrates the interval the "
        "tag names, exactly once and in order: the next interval of the grid (one major-loop update); a tag "
        "equal to the start time (no increments yet, Jacobi's first step) waits; a repeated or skipped interval "
        "is an error (fmi2Error logged, step discarded). Under Gauss-Seidel (IMU stepped first) the solution "
        "after doStep(t, h) is at t + h; under Jacobi it lags one step: compare at the same nav_time, the tag of "
        "every output (time since navigation started, negative while aligning), or at the same solution_time "
        "(the simulation time the outputs refer to: the end of the last interval integrated, the start time "
        "before the first). Phases: coarse alignment "
        "(coarse_time), Kalman fine alignment with a zero-velocity measurement until align_time, then free "
        "navigation from the known start with the alignment's horizontal drift and accelerometer-bias "
        "estimates compensated. The azimuth drift compensation (rad/s) c + (a T + b) T, c = "
        "axial_drift_correction, b = axial_drift_correction_b, a = axial_drift_correction_a (a temperature "
        "model; a = b = 0: a constant), T = temp_gyro_z of the interval, is subtracted from the z gyro in every "
        "navigation interval starting at nav time >= axial_drift_apply_from (the previous set before); a new "
        "set that arrives after its apply_from was passed is an error. "
        "The step must stay constant. All outputs are state outputs (no direct feedthrough). Held between "
        "steps: attitude, velocity, position, filter state, estimates, the compensation in force.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults
    # FMI 3.0 only (fmus/native_fmu.py): the IMU's sub-interval arrays, read when sub_inputs = 1
    fmi3_arrays = tuple(
        ArrayVariable(f"{q}_{a}_sub", "n_sub", "input", f"{what} {a} of each of the n_sub sub-intervals of the "
                      f"interval ending at increment_end_time, in time order [{unit}]")
        for q, what, unit in (("dtheta", "angle increment about body", "rad"),
                              ("dv", "velocity increment along body", "m/s"))
        for a in "xyz") + (
        ArrayVariable("temp_gyro_z_sub", "n_sub", "input",
                      "azimuth gyro temperature at the end of each sub-interval [degC]"),)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "real", "lat0", PARAMETER, "latitude of the static start [rad; deg]", SITE_LAT)
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
        declare(self, "real", "temp_gyro_z", INPUT, "azimuth gyro temperature at increment_end_time [degC]", 20.0)
        declare(self, "real", "increment_end_time", INPUT, "time tag: end of the increments' interval [s]", 0.0)
        declare(self, "real", "axial_drift_correction", INPUT,
                "azimuth drift subtracted during navigation from axial_drift_apply_from on [rad/s; deg/h]", 0.0)
        declare(self, "real", "axial_drift_apply_from", INPUT,
                "navigation time from which axial_drift_correction applies [s]", 0.0)
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
                                 ("temp_change_align", "degC", "its change over the alignment"),
                                 ("temp_azimuth_gyro", "degC", "azimuth gyro temperature at nav_time")):
            declare(self, "real", name, OUTPUT, f"{text} [{unit}]", 0.0)
        declare(self, "integer", "phase", OUTPUT, "0 coarse alignment, 1 fine alignment, 2 navigation [1]", 0)
        for name, text in (("yaw0", "yaw, CCW from north"), ("pitch0", "pitch"), ("roll0", "roll")):
            declare(self, "real", name, PARAMETER, f"align_time = 0: initial {text} [rad; deg]", 0.0)
        declare(self, "real", "axial_drift_correction_b", INPUT,
                "linear temperature coefficient b of the azimuth drift correction [rad/s/degC]", 0.0)
        declare(self, "real", "axial_drift_correction_a", INPUT,
                "quadratic temperature coefficient a of the azimuth drift correction [rad/s/degC2]", 0.0)
        declare(self, "real", "solution_time", OUTPUT,
                "time tag: simulation time the navigation outputs refer to [s]", 0.0)
        # last, so that the value references of the variables above stay those of the earlier builds
        declare(self, "integer", "n_sub", PARAMETER,
                "sub-intervals per communication step [1]: the length of the *_sub array inputs (FMI 3.0: a "
                "structural parameter); with sub_inputs = 1 each step integrates them one by one", 1)
        declare(self, "integer", "sub_inputs", PARAMETER,
                "0: integrate the scalar increments, one interval per step; 1 (FMI 3.0 only): integrate the "
                "n_sub sub-intervals of the *_sub array inputs in order, each with its gyro_z temperature, as "
                "if stepped at h / n_sub (the scalar increments and temp_gyro_z are then unused) [1]", 0)
        self._core = core_ins.FmuState()
        self._start_time = 0.0
        self._in_slots = real_slots(self, core_ins.FMU_INPUTS)
        self._out_slots = real_slots(self, core_ins.FMU_OUTPUTS)

    @property
    def phase(self) -> int:
        """The Integer output phase: the core's (0 coarse, 1 fine alignment, 2 navigation)."""
        return self._core.phase

    @phase.setter
    def phase(self, value) -> None:
        core = self.__dict__.get("_core")  # None while the variables are declared (start value 0)
        if core is not None and int(value) != core.phase:
            raise AttributeError("phase is an output of the INS core")

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def _config(self) -> np.ndarray:
        """The core's settings array from the parameters (the step is the first doStep's)."""
        filt = {n: float(getattr(self, f"kf_{n}")) for n in FILTER_UNITS}
        values = {"lat": self.lat0, "lon": self.lon0, "height": self.height0, "align_time": self.align_time,
                  "coarse_time": self.coarse_time, "step": 1.0, **filt}
        return np.array([float(values[n]) for n in core_ins.CONFIG_FIELDS + core_ins.FILTER_FIELDS])

    def _setup(self) -> None:
        self._core.setup(self._config(), [self.yaw0, self.pitch0, self.roll0], self._start_time)
        self._fmi_buffer[self._out_slots] = self._core.out

    def enter_initialization_mode(self):
        self._setup()  # the initial outputs, for a host that reads them in Initialization Mode

    @guarded
    def exit_initialization_mode(self):
        check_finite(self, ["yaw0", "pitch0", "roll0"])
        check_range(self, "pitch0", -0.5 * math.pi, 0.5 * math.pi, unit="deg", scale=math.pi / 180.0)
        names = ["lat0", "lon0", "height0", "align_time", "coarse_time"] + [f"kf_{n}" for n in FILTER_UNITS]
        check_finite(self, names, non_negative=["align_time", "coarse_time"],
                     positive=[f"kf_{n}" for n in FILTER_UNITS])
        check_latitude(self, "lat0")
        if self.sub_inputs != 0:
            raise ParameterError(f"parameter sub_inputs = {self.sub_inputs}: this in-process INS has no array "
                                 "inputs; only 0 (the scalar increments); 1 needs the native FMI 3.0 FMU")
        self._setup()
        try:
            self._core.start(self._fmi_buffer[self._in_slots])
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self._fmi_buffer[self._out_slots] = self._core.out

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._core.do_step(self._fmi_buffer[self._in_slots], current_time, step_size)
        except ValueError as exc:
            return discard_on_error(self, exc)
        self._fmi_buffer[self._out_slots] = self._core.out
        return True
