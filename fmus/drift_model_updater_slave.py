"""DriftModelUpdater FMU: seed 002's online update of the azimuth-drift model (Fig. 2)."""

import math

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, NO_TAG, OUTPUT, PARAMETER, ParameterError, TaggedHistory, check_finite,
                                check_step, declare, discard_on_error, guarded, same_time)
from sarins_fmu.identify.axial import APPLY_LATENCY
from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings
from sarins_fmu.kalman import StopFilterSettings
from sarins_fmu.units import DAY, DEG_TO_RAD, DPH_TO_RPS

NAVIGATE = 2  # StrapdownINS 'phase' output value in navigation
P_UNITS = {"p_aa": "1/degC4", "p_ab": "1/degC3", "p_ac": "1/degC2", "p_bb": "1/degC2", "p_bc": "1/degC", "p_cc": "1"}
P_INDEX = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]


class DriftModelUpdater(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Online update of the azimuth gyro drift model eps(T) = a T^2 + b T + c (seed 002, Fig. 2). "
        "Contract (standard FMI timing, time-tagged, any master scheme): the INS inputs are one row of the INS's "
        "outputs, tagged solution_time (the simulation time they refer to; if solution_time is not connected, "
        "nav_time orders the rows); each doStep processes the row whose tag follows the last one processed by "
        "one step (a repeated tag, e.g. Jacobi's first steps, or the INS's initial outputs at the start time are "
        "skipped; a skipped row is an error). vehicle_speed tagged speed_time (the vehicle's time tag) is paired "
        "with the INS row of the same time: the updater keeps the last 8 speeds, so a speed that arrives before "
        "the row (Jacobi: two links ahead) is found; a row without its speed is an error (fmi2Error with the "
        "tags). If speed_time is not connected, vehicle_speed is taken as it is at each doStep. The updater's "
        "clock is start_day + nav_time of the row. The vehicle is stopped while vehicle_speed < speed_threshold "
        "and the INS navigates (ins_phase = 2 and nav_time >= 0: the phase input may be held at 2, the row's "
        "nav_time tells); at the start of a stop a static Kalman filter (velocity = 0 measurement, states "
        "attitude, velocity, gyro drifts incl. the azimuth drift, accelerometer biases, north position) is "
        "reset and a timer starts; when the vehicle moves off, a stop of at least time_threshold updates the "
        "model by forgetting-factor RLS (lambda^(dt/m)) with the pair (mean gyro temperature, estimated "
        "drift); a shorter stop is discarded. Outputs: the current model drift_a, drift_b, drift_c (connect to "
        "StrapdownINS axial_drift_correction_a, _b and axial_drift_correction: the INS evaluates it at each "
        "interval's temperature) and compensation_drift = the model at temp_gyro_z of the row (for an INS "
        "taking a constant), both to be applied from nav time apply_from = row nav_time + latency on "
        "(axial_drift_apply_from; at initialisation -1e9 s: the initial model applies from the start). One step "
        "of latency is enough for any scheme (under Jacobi the INS reads the updater's output of the row before "
        "the interval it integrates). All outputs are state outputs (no direct feedthrough). The initial model "
        "is a0, b0, c0 with prior_points equivalent calibration points spread over prior_t_min..prior_t_max, or "
        "the RLS state in model_file (JSON/npz of sarins_fmu.identify.rls.ForgettingRLS.save; its forgetting "
        "settings must equal forgetting_factor and forgetting_time_scale); the outputs p_aa..p_cc (its inverse "
        "information) and model_time (the time of its last update) with drift_a/b/c give the state back, so a "
        "next run can continue from it. last_stop_* describe the last finished stop (last_stop_used 1: it "
        "updated the model). Held between steps: the model and its RLS information, the filter, the stop "
        "timer, the last speeds.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=6 * 3600.0, step_size=1.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "real", "a0", PARAMETER, "initial model a [rad/s/degC2]", 1.0e-6 * DPH_TO_RPS)
        declare(self, "real", "b0", PARAMETER, "initial model b [rad/s/degC]", -4.0e-5 * DPH_TO_RPS)
        declare(self, "real", "c0", PARAMETER, "initial model c [rad/s; deg/h]", 0.0025 * DPH_TO_RPS)
        declare(self, "real", "prior_points", PARAMETER,
                "weight of the initial model as a number of calibration points [1]", 11.0)
        declare(self, "real", "prior_t_min", PARAMETER, "lowest calibration temperature [degC]", 0.0)
        declare(self, "real", "prior_t_max", PARAMETER, "highest calibration temperature [degC]", 50.0)
        declare(self, "real", "start_day", PARAMETER, "time of nav_time = 0 since the calibration [d]", 0.0)
        declare(self, "real", "latency", PARAMETER,
                "delay from a row's nav_time to the first navigation interval compensated with it [s]",
                APPLY_LATENCY)
        declare(self, "real", "forgetting_factor", PARAMETER, "forgetting factor lambda per time scale [1]", 0.8)
        declare(self, "real", "forgetting_time_scale", PARAMETER, "forgetting time scale m (one month) [s]",
                30.0 * DAY)
        declare(self, "real", "time_threshold", PARAMETER, "shortest stop used for an update [s]", 1800.0)
        declare(self, "real", "speed_threshold", PARAMETER, "speed below which the vehicle is stopped [m/s]", 0.01)
        defaults = StopFilterSettings()
        declare(self, "real", "kf_arw", PARAMETER, "stop filter gyro angle random walk [rad/sqrt(s)]", defaults.arw)
        declare(self, "real", "kf_vrw", PARAMETER, "stop filter velocity random walk [m/s/sqrt(s)]", defaults.vrw)
        declare(self, "real", "kf_velocity_meas_std", PARAMETER, "stop filter velocity noise [m/s]",
                defaults.velocity_meas_std)
        declare(self, "real", "kf_heading0_std", PARAMETER, "stop filter initial heading error [rad; deg]",
                defaults.heading0_std)
        declare(self, "real", "v_e", INPUT, "INS east velocity [m/s]", 0.0)
        declare(self, "real", "v_n", INPUT, "INS north velocity [m/s]", 0.0)
        declare(self, "real", "yaw", INPUT, "INS yaw, CCW from north [rad; deg]", 0.0)
        declare(self, "real", "pitch", INPUT, "INS pitch [rad; deg]", 0.0)
        declare(self, "real", "roll", INPUT, "INS roll [rad; deg]", 0.0)
        declare(self, "real", "lat", INPUT, "INS latitude [rad; deg]", 40.0 * DEG_TO_RAD)
        declare(self, "real", "temp_gyro_z", INPUT, "azimuth gyro temperature [degC]", 20.0)
        declare(self, "real", "nav_time", INPUT, "time tag of the INS inputs: INS nav_time [s]", 0.0)
        declare(self, "real", "vehicle_speed", INPUT, "vehicle speed (odometer) [m/s]", 0.0)
        declare(self, "integer", "ins_phase", INPUT, "INS phase; stops count only in navigation (2) [1]", NAVIGATE)
        for name, unit, text in (("drift_a", "rad/s/degC2", "current model a"),
                                 ("drift_b", "rad/s/degC", "current model b"),
                                 ("drift_c", "rad/s; deg/h", "current model c"),
                                 ("compensation_drift", "rad/s; deg/h", "current model at temp_gyro_z"),
                                 ("apply_from", "s", "nav time from which the INS applies compensation_drift"),
                                 ("stop_timer", "s", "estimation time of the current stop"),
                                 ("drift_estimate", "rad/s; deg/h", "current stop's azimuth drift estimate"),
                                 ("drift_estimate_std", "rad/s; deg/h", "its filter standard deviation"),
                                 ("last_update_drift", "rad/s; deg/h", "drift of the last model update"),
                                 ("last_update_temp", "degC", "mean gyro temperature of the last update")):
            declare(self, "real", name, OUTPUT, f"{text} [{unit}]", 0.0)
        declare(self, "integer", "stopped", OUTPUT, "1 while a stop is being estimated [1]", 0)
        declare(self, "integer", "n_updates", OUTPUT, "model updates so far [1]", 0)
        declare(self, "integer", "n_resets", OUTPUT, "stops discarded as too short [1]", 0)
        declare(self, "string", "model_file", PARAMETER,
                "initial RLS state (ForgettingRLS JSON/npz); empty: a0, b0, c0 and prior_*", "")
        declare(self, "real", "solution_time", INPUT, "time tag of the INS inputs: INS solution_time [s]", NO_TAG)
        declare(self, "real", "speed_time", INPUT, "time tag of vehicle_speed [s]", NO_TAG)
        declare(self, "real", "row_time", OUTPUT, "tag (solution_time, else nav_time) of the last row processed [s]",
                NO_TAG)
        for name, unit in P_UNITS.items():
            declare(self, "real", name, OUTPUT, f"RLS inverse information {name[2:]} [{unit}]", 0.0)
        declare(self, "real", "model_time", OUTPUT, "clock time of the model's last update or initialisation [s]",
                0.0)
        for name, unit, text in (("last_stop_time", "s", "clock time at which it ended"),
                                 ("last_stop_duration", "s", "its estimation time"),
                                 ("last_stop_temp", "degC", "its mean gyro temperature"),
                                 ("last_stop_drift", "rad/s; deg/h", "its azimuth drift estimate"),
                                 ("last_stop_drift_std", "rad/s; deg/h", "its filter standard deviation")):
            declare(self, "real", name, OUTPUT, f"last finished stop: {text} [{unit}]", 0.0)
        declare(self, "integer", "last_stop_used", OUTPUT, "last finished stop updated the model (1) or not [1]", 0)
        self._core = None
        self._step = None
        self._last_tag = None
        self._speeds = TaggedHistory("vehicle_speed", "speed_time")
        self._start_time = 0.0

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def _make_core(self, dt=1.0):
        names = ["a0", "b0", "c0", "prior_points", "prior_t_min", "prior_t_max", "start_day", "forgetting_factor",
                 "forgetting_time_scale", "time_threshold", "speed_threshold", "kf_arw", "kf_vrw",
                 "kf_velocity_meas_std", "kf_heading0_std", "latency"]
        check_finite(self, names, positive=["prior_points", "forgetting_factor", "forgetting_time_scale",
                                            "time_threshold", "speed_threshold", "kf_arw", "kf_vrw",
                                            "kf_velocity_meas_std", "kf_heading0_std"],
                     non_negative=["start_day", "latency"])
        if not self.prior_t_max > self.prior_t_min:
            raise ParameterError("prior_t_max must exceed prior_t_min")
        try:
            settings = RLSSettings(self.forgetting_factor, self.forgetting_time_scale)
            rls = self._initial_model(settings)
            kf = StopFilterSettings(arw=self.kf_arw, vrw=self.kf_vrw, velocity_meas_std=self.kf_velocity_meas_std,
                                    heading0_std=self.kf_heading0_std)
            upd = UpdaterSettings(self.time_threshold, self.speed_threshold)
            return OnlineDriftUpdater(rls, self.lat, dt, kf, upd)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None

    def _initial_model(self, settings: RLSSettings) -> ForgettingRLS:
        """The RLS state of model_file, else a0, b0, c0 worth prior_points calibration points."""
        if not self.model_file:
            p0 = prior_covariance(self.prior_points, self.prior_t_min, self.prior_t_max)
            return ForgettingRLS([self.a0, self.b0, self.c0], p0, 0.0, settings)
        try:
            rls = ForgettingRLS.load(self.model_file)
        except (ValueError, OSError) as exc:
            raise ParameterError(f"parameter model_file = {self.model_file!r}: {exc}") from None
        if rls.settings != settings:
            raise ParameterError(f"model_file {self.model_file} has forgetting factor "
                                 f"{rls.settings.forgetting_factor} per {rls.settings.time_scale} s; the parameters "
                                 f"say {settings.forgetting_factor} per {settings.time_scale} s")
        return rls

    def enter_initialization_mode(self):
        try:  # the initial outputs, for a host that reads them in Initialization Mode
            self._core = self._make_core()
            self._publish(float(self._core.compensation(self.temp_gyro_z)), NO_TAG)
        except ValueError:  # a bad parameter is reported at exit_initialization_mode
            self._core = None

    @guarded
    def exit_initialization_mode(self):
        self._core = self._make_core()
        self._last_tag = None
        self._speeds = TaggedHistory("vehicle_speed", "speed_time")
        if self.speed_time != NO_TAG:
            self._speeds.push(self.speed_time, float(self.vehicle_speed))
        self._publish(float(self._core.compensation(self.temp_gyro_z)), NO_TAG)

    @guarded
    def do_step(self, current_time, step_size):
        try:
            first = self._step is None
            self._step = check_step(self, step_size, self._step)
            if first and step_size != self._core.dt:  # the filter's interval is the communication step
                self._core = self._make_core(step_size)
            inputs = [self.v_e, self.v_n, self.yaw, self.pitch, self.roll, self.temp_gyro_z, self.vehicle_speed,
                      self.lat, self.nav_time]
            if not all(math.isfinite(x) for x in inputs):
                raise ValueError("an input (velocity, attitude, temperature, speed or nav_time) is NaN or infinite")
            speed = self._vehicle_speed(step_size)
            tag = self._row_tag(step_size)
            if tag is None:
                return True  # no new INS row
            self._last_tag = tag
            speed = speed(tag)
            time = self.start_day * DAY + float(self.nav_time)
            comp = self._core.step([time], [speed], [[self.v_e, self.v_n]],
                                   [[self.yaw, self.pitch, self.roll]], [self.temp_gyro_z], [self.lat],
                                   [int(self.ins_phase) == NAVIGATE and self.nav_time >= 0.0])
        except ValueError as exc:
            return discard_on_error(self, exc)
        self.row_time = tag
        self._publish(float(comp[0]), float(self.nav_time) + self.latency)
        return True

    def _vehicle_speed(self, step):
        """Keep the speed just read; returns the speed of a row tag (tag -> m/s)."""
        if self.speed_time == NO_TAG:
            return lambda tag: float(self.vehicle_speed)
        if self.solution_time == NO_TAG:
            raise ValueError("vehicle_speed is tagged (speed_time is connected) but the INS rows are not: "
                             "connect the INS's solution_time to pair each row with the speed of its time")
        self._speeds.push(self.speed_time, float(self.vehicle_speed), step)
        return lambda tag: self._speeds.at(tag, step)

    def _row_tag(self, step):
        """Tag of the INS row to process now, or None if it is no new row."""
        tagged = self.solution_time != NO_TAG
        tag = float(self.solution_time if tagged else self.nav_time)
        last = self._last_tag
        if tagged and tag <= self._start_time + 1e-6 * step:
            return None  # the INS's initial outputs: no interval integrated yet
        if last is not None and same_time(tag, last, step):
            return None  # the same row again (Jacobi's first steps)
        expected = (self._start_time + step) if (tagged and last is None) else (None if last is None else last + step)
        if expected is not None and not same_time(tag, expected, step):
            name = "solution_time" if tagged else "nav_time"
            raise ValueError(f"INS row tagged {name}={tag:.9g} s where the row at {expected:.9g} s was due: rows "
                             "must follow each other one step apart (none skipped or repeated)")
        return tag

    def _publish(self, compensation, apply_from):
        core = self._core
        self.drift_a, self.drift_b, self.drift_c = (float(x) for x in core.rls.parameters)
        p = core.rls.covariance
        for name, (i, j) in zip(P_UNITS, P_INDEX):
            setattr(self, name, float(p[i, j]))
        self.model_time = core.rls.time
        self.compensation_drift = compensation
        self.apply_from = apply_from
        self.stopped = int(core.stopped)
        self.stop_timer = core.timer
        kf = core.filter
        self.drift_estimate = kf.drift_estimate if core.stopped else 0.0
        self.drift_estimate_std = kf.drift_std if core.stopped else 0.0
        kinds = [e[1] for e in core.events]
        self.n_updates = kinds.count("update")
        self.n_resets = kinds.count("reset")
        updates = [e for e in core.events if e[1] == "update"]
        if updates:
            self.last_update_temp, self.last_update_drift = float(updates[-1][3]), float(updates[-1][4])
        if core.events:
            time, kind, duration, temp, drift, std = core.events[-1]
            self.last_stop_time, self.last_stop_duration, self.last_stop_temp = time, duration, temp
            self.last_stop_drift, self.last_stop_drift_std = drift, std
            self.last_stop_used = int(kind == "update")
