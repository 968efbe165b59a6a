"""DriftModelUpdater FMU: seed 002's online update of the azimuth-drift model (Fig. 2)."""

import math

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_step, declare,
                                discard_on_error, guarded, same_time)
from sarins_fmu.identify.axial import APPLY_LATENCY
from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings
from sarins_fmu.kalman import StopFilterSettings
from sarins_fmu.units import DAY, DEG_TO_RAD, DPH_TO_RPS

NAVIGATE = 2  # StrapdownINS 'phase' output value in navigation


class DriftModelUpdater(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Online update of the azimuth gyro drift model eps(T) = a T^2 + b T + c (seed 002, Fig. 2). "
        "Contract (standard FMI timing, time-tagged): the INS inputs are tagged nav_time; each doStep processes "
        "the row whose tag follows the last one processed by one step (a repeated tag, e.g. Jacobi's first "
        "step, is skipped; a skipped row is an error), whatever the master's scheme. The updater's clock is "
        "start_day + nav_time. The vehicle is stopped while vehicle_speed < speed_threshold and ins_phase = 2 "
        "(navigating); at the start of a stop a static Kalman filter (velocity = 0 measurement, states "
        "attitude, velocity, gyro drifts incl. the azimuth drift, accelerometer biases, north position) is "
        "reset and a timer starts; when the vehicle moves off, a stop of at least time_threshold updates the "
        "model by forgetting-factor RLS (lambda^(dt/m)) with the pair (mean gyro temperature, estimated "
        "drift); a shorter stop is discarded. Output compensation_drift = current model at temp_gyro_z of the "
        "row, to be subtracted by the INS (axial_drift_correction) from nav time apply_from = row nav_time + "
        "latency on (axial_drift_apply_from; latency a few steps, long enough for any scheme). All outputs are "
        "state outputs (no direct feedthrough). The initial model is a0, b0, c0 with prior_points "
        "equivalent calibration points spread over prior_t_min..prior_t_max. Held between steps: the model "
        "and its RLS information, the filter, the stop timer.")
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
        self._core = None
        self._step = None
        self._last_tag = None

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
            p0 = prior_covariance(self.prior_points, self.prior_t_min, self.prior_t_max)
            settings = RLSSettings(self.forgetting_factor, self.forgetting_time_scale)
            rls = ForgettingRLS([self.a0, self.b0, self.c0], p0, 0.0, settings)
            kf = StopFilterSettings(arw=self.kf_arw, vrw=self.kf_vrw, velocity_meas_std=self.kf_velocity_meas_std,
                                    heading0_std=self.kf_heading0_std)
            upd = UpdaterSettings(self.time_threshold, self.speed_threshold)
            return OnlineDriftUpdater(rls, self.lat, dt, kf, upd)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None

    @guarded
    def exit_initialization_mode(self):
        self._core = self._make_core()
        self._last_tag = None
        self._publish(float(self._core.compensation(self.temp_gyro_z)), self.nav_time)

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
            tag = float(self.nav_time)
            if self._last_tag is not None:
                if same_time(tag, self._last_tag, step_size):
                    return True  # no new INS row (Jacobi's first step)
                if not same_time(tag, self._last_tag + step_size, step_size):
                    raise ValueError(f"INS row tagged nav_time={tag:.9g} s after {self._last_tag:.9g} s: rows "
                                     "must follow each other one step apart (none skipped or repeated)")
            self._last_tag = tag
            time = self.start_day * DAY + tag
            comp = self._core.step([time], [self.vehicle_speed], [[self.v_e, self.v_n]],
                                   [[self.yaw, self.pitch, self.roll]], [self.temp_gyro_z], [self.lat],
                                   [int(self.ins_phase) == NAVIGATE])
        except ValueError as exc:
            return discard_on_error(self, exc)
        self._publish(float(comp[0]), tag)
        return True

    def _publish(self, compensation, tag):
        core = self._core
        self.drift_a, self.drift_b, self.drift_c = (float(x) for x in core.rls.parameters)
        self.compensation_drift = compensation
        self.apply_from = float(tag) + self.latency
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
