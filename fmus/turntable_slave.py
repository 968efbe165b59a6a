"""Turntable FMU: gimbal angles, rates and accelerations of a rotation scheme."""


import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus import compiled_steps
from fmus.slave_support import (OUTPUT, PARAMETER, ParameterError, check_finite, check_integer, check_step,
                                declare, discard_on_error, guarded, real_slots)
from sarins_fmu import thermal, turntable
from sarins_fmu.thermal import Ambient
from sarins_fmu.units import DEG_TO_RAD



class Turntable(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Turntable of a rotating INS or a rate table (truth motion). Gimbal chains: single-axis schemes 'z'; "
        "dual-axis 'y,z'; rate-table-3axis, tumble-24 and rate-test 'z,x,y' (set the IMU's 'gimbals' to match). "
        "Contract (standard FMI timing, any master scheme): the outputs describe the motion segment that "
        "STARTS at motion_time: gimbal angles and rates at motion_time and the angular acceleration that holds "
        "from there to the next communication point (accelerations change only on the 'grid', a multiple of "
        "the communication step), plus the ambient (chamber) temperature at motion_time and its slope "
        "ambient_temp_rate over [motion_time, motion_time + h], h the communication step (the IMU takes the "
        "ambient linear over each step; at initialisation, before h is known, the slope is over [start, start + "
        "grid]: start a chamber profile with a hold, as its warm-up does). At initialisation motion_time is "
        "the start time; after doStep(t, h) it is t + h. All outputs "
        "are state outputs (no direct feedthrough). A connected IMU rebuilds the motion over its step [t, t+h] "
        "exactly from the set tagged t: under Jacobi it receives that set, under Gauss-Seidel (turntable "
        "stepped first) it receives the set tagged t + h and uses the one it kept from its previous step. "
        "Angles are not wrapped. Nothing but the schedule and the time is held between steps.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=16 * 3600.0, step_size=1.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "scheme", PARAMETER,
                "rotation scheme: " + ", ".join(turntable.SCHEMES), "forward-reverse")
        declare(self, "real", "rate", PARAMETER, "peak rotation rate [rad/s; deg/s]", 6.0 * DEG_TO_RAD)
        declare(self, "real", "accel", PARAMETER, "angular acceleration of the moves [rad/s2; deg/s2]", 6.0 * DEG_TO_RAD)
        declare(self, "real", "dwell", PARAMETER, "stop at each position or reversal [s]", 0.0)
        declare(self, "integer", "revolutions", PARAMETER, "turns each way (forward-reverse) [1]", 1)
        declare(self, "real", "align_time", PARAMETER,
                "initial four-position indexing for the alignment (0: none) [s]", 4 * 3600.0)
        declare(self, "real", "align_dwell", PARAMETER, "stop at each alignment position [s]", 300.0)
        declare(self, "real", "grid", PARAMETER, "time grid of acceleration changes [s]", 1.0)
        declare(self, "real", "duration", PARAMETER, "length of the generated pattern [s]", 100 * 3600.0)
        declare(self, "real", "outer_rate", PARAMETER, "dual-axis: outer flip rate [rad/s; deg/s]", 6.0 * DEG_TO_RAD)
        declare(self, "real", "outer_accel", PARAMETER, "dual-axis: outer flip acceleration [rad/s2; deg/s2]",
                6.0 * DEG_TO_RAD)
        for name, rate, acc in (("inner", 1.0, 0.01), ("middle", 10.0, 0.1), ("outer", 100.0, 1.0)):
            declare(self, "real", f"table_{name}_rate", PARAMETER,
                    f"rate-table-3axis: {name} gimbal peak rate [rad/s; deg/s]", rate * DEG_TO_RAD)
            declare(self, "real", f"table_{name}_accel", PARAMETER,
                    f"rate-table-3axis: {name} gimbal acceleration [rad/s2; deg/s2]", acc * DEG_TO_RAD)
        declare(self, "real", "warmup", PARAMETER, "rate-table-3axis: static warm-up [s]", 600.0)
        declare(self, "string", "ambient_mode", PARAMETER,
                "ambient: 'sinusoid' (mean, amplitude, period) or 'chamber' (ramp/hold cycle)", "sinusoid")
        declare(self, "real", "chamber_low", PARAMETER, "chamber low temperature [degC]", -25.0)
        declare(self, "real", "chamber_high", PARAMETER, "chamber high temperature [degC]", 40.0)
        declare(self, "real", "chamber_ramp", PARAMETER, "chamber ramp rate [degC/s]", 1.0 / 60.0)
        declare(self, "real", "chamber_hold", PARAMETER, "chamber hold at each end [s]", 1800.0)
        declare(self, "string", "chamber_first", PARAMETER, "chamber: end of the first ramp, 'low' or 'high'", "low")
        declare(self, "real", "chamber_step", PARAMETER,
                "chamber: intermediate stop every this much on the ramps between the ends (0: none) [degC]", 0.0)
        declare(self, "real", "chamber_step_hold", PARAMETER, "chamber: length of each intermediate stop [s]", 0.0)
        declare(self, "real", "ambient_mean", PARAMETER, "ambient temperature mean (chamber start) [degC]", 20.0)
        declare(self, "real", "ambient_amplitude", PARAMETER, "ambient daily amplitude [degC]", 0.0)
        declare(self, "real", "ambient_period", PARAMETER, "ambient period [s]", 86400.0)
        for j in (1, 2, 3):
            declare(self, "real", f"angle_{j}", OUTPUT, f"angle of gimbal {j} (outer = 1) at motion_time [rad; deg]",
                    0.0)
            declare(self, "real", f"rate_{j}", OUTPUT, f"angular rate of gimbal {j} at motion_time [rad/s; deg/s]",
                    0.0)
            declare(self, "real", f"accel_{j}", OUTPUT,
                    f"angular acceleration of gimbal {j} from motion_time on [rad/s2; deg/s2]", 0.0)
        declare(self, "real", "ambient_temp", OUTPUT, "ambient / chamber temperature at motion_time [degC]", 20.0)
        declare(self, "real", "ambient_temp_rate", OUTPUT,
                "slope of the ambient over the step from motion_time [degC/s]", 0.0)
        declare(self, "real", "motion_time", OUTPUT, "time tag: start of the segment the outputs describe [s]", 0.0)
        declare(self, "integer", "n_gimbals", OUTPUT, "number of gimbals in use [1]", 1)
        self._schedule = None
        self._ambient = None
        self._step = None
        self._out = np.zeros(9)
        self._out_slots = real_slots(self, [f"{q}_{j}" for q in ("angle", "rate", "accel") for j in (1, 2, 3)])
        self._start_time = 0.0
        self._fast = None  # the compiled step's context (fmus.compiled_steps)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def enter_initialization_mode(self):
        try:  # outputs during initialisation; a bad parameter is reported at exit_initialization_mode
            self._build()
        except ParameterError:
            self._schedule = None

    @guarded
    def exit_initialization_mode(self):
        self._build()

    def _build(self):
        check_finite(self, ["rate", "accel", "dwell", "align_time", "align_dwell", "grid", "duration",
                            "ambient_mean", "ambient_amplitude", "ambient_period", "outer_rate", "outer_accel",
                            "warmup", "chamber_low", "chamber_high", "chamber_ramp", "chamber_hold", "chamber_step",
                            "chamber_step_hold"]
                     + [f"table_{n}_{q}" for n in ("inner", "middle", "outer") for q in ("rate", "accel")],
                     positive=["grid", "duration", "ambient_period"],
                     non_negative=["rate", "accel", "dwell", "align_time", "align_dwell", "outer_rate", "outer_accel",
                                   "warmup", "chamber_hold", "chamber_step", "chamber_step_hold",
                                   "ambient_amplitude"])
        if not self.chamber_ramp > 0:
            raise ParameterError(f"parameter chamber_ramp = {self.chamber_ramp} degC/s must be positive")
        if self.chamber_first not in ("low", "high"):
            raise ParameterError(f"parameter chamber_first must be 'low' or 'high', got {self.chamber_first!r}")
        revolutions = check_integer(self, "revolutions", 1)
        try:
            self._schedule = turntable.schedule_for(
                self.scheme, self.duration, rate_dps=self.rate / DEG_TO_RAD, accel_dps2=self.accel / DEG_TO_RAD,
                dwell=self.dwell, grid=self.grid, revolutions=revolutions,
                align_time=self.align_time, align_dwell=self.align_dwell,
                outer_rate_dps=self.outer_rate / DEG_TO_RAD, outer_accel_dps2=self.outer_accel / DEG_TO_RAD,
                table_rates_dps=[getattr(self, f"table_{n}_rate") / DEG_TO_RAD for n in ("inner", "middle", "outer")],
                table_accels_dps2=[getattr(self, f"table_{n}_accel") / DEG_TO_RAD for n in ("inner", "middle", "outer")],
                warmup=self.warmup)
        except ValueError as exc:
            raise ParameterError(f"parameter scheme = {self.scheme!r} with its motion parameters: {exc}") from None
        try:
            if self.ambient_mode == "chamber":
                profile = thermal.chamber_profile(
                    self.duration, low_c=self.chamber_low, high_c=self.chamber_high,
                    ramp_c_per_min=self.chamber_ramp * 60.0, hold_min=self.chamber_hold / 60.0,
                    start_c=self.ambient_mean, first=self.chamber_first, step_c=self.chamber_step,
                    step_hold_min=self.chamber_step_hold / 60.0)
                self._ambient = Ambient(profile=profile)
            elif self.ambient_mode == "sinusoid":
                self._ambient = Ambient(mean=self.ambient_mean, amplitude=self.ambient_amplitude,
                                        period=self.ambient_period)
            else:
                raise ValueError("ambient_mode must be 'sinusoid' or 'chamber'")
        except ValueError as exc:
            raise ParameterError(f"parameter ambient_mode = {self.ambient_mode!r}: {exc}") from None
        self.n_gimbals = self._schedule.n_axes
        self._publish(self._start_time)

    def _publish(self, time):
        angle, rate, acc = (x[0] for x in self._schedule.state(time))
        n = len(angle)
        out = self._out  # angle_1..3, rate_1..3, accel_1..3 (0 beyond the gimbals in use)
        out[0:n], out[3:3 + n], out[6:6 + n] = angle, rate, acc
        self._fmi_buffer[self._out_slots] = out
        span = self.grid if self._step is None else self._step
        self.ambient_temp, self.ambient_temp_rate = thermal.ambient_segment(self._ambient, time, span)
        self.motion_time = float(time)

    @guarded
    def do_step(self, current_time, step_size):
        if self._fast is not None and self._fast.step(self._fmi_buffer, current_time, step_size):
            return True
        try:
            if self._step is None:
                self._schedule.check_grid(step_size)
            self._step = check_step(self, step_size, self._step)
            self._publish(current_time + step_size)
        except ValueError as exc:
            return discard_on_error(self, exc)
        if self._fast is None:
            self._fast = compiled_steps.turntable_context(self)
            self._fmi_fast_step = None if self._fast is None else self._fast.address
        return True
