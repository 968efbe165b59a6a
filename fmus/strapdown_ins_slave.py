"""StrapdownINS FMU: alignment and navigation from IMU increments, static start."""

import collections
import math

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus import compiled_steps
from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_latitude, check_range,
                                check_step, declare,
                                discard_on_error, guarded, real_slots, same_time)
from sarins_fmu import ins
from sarins_fmu.drift_model import drift_model_value
from sarins_fmu.rotations import euler_to_mat
from sarins_fmu.site import SITE_LAT

PHASES = {"coarse": 0, "fine": 1, "navigate": 2}
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
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=16 * 3600.0, step_size=1.0)

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
        self._start_time = 0.0
        self._compensation = None
        self._fast = None  # the compiled step's context (fmus.compiled_steps)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def _make_config(self, step):
        names = ["lat0", "lon0", "height0", "align_time", "coarse_time"] + [f"kf_{n}" for n in FILTER_UNITS]
        check_finite(self, names, non_negative=["align_time", "coarse_time"],
                     positive=[f"kf_{n}" for n in FILTER_UNITS])
        check_latitude(self, "lat0")
        try:
            filt = ins.AlignmentFilter(**{n: float(getattr(self, f"kf_{n}")) for n in FILTER_UNITS})
            return ins.InsConfig(lat=self.lat0, lon=self.lon0, height=self.height0, align_time=self.align_time,
                                 coarse_time=self.coarse_time, step=step, filter=filt)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None

    def enter_initialization_mode(self):
        self._publish_start()  # the initial outputs, for a host that reads them in Initialization Mode

    @guarded
    def exit_initialization_mode(self):
        check_finite(self, ["yaw0", "pitch0", "roll0"])
        check_range(self, "pitch0", -0.5 * math.pi, 0.5 * math.pi, unit="deg", scale=math.pi / 180.0)
        self._make_config(1.0)  # validate parameters before the first step
        self._publish_start()
        self.temp_align_start = self.temp_gyro_z
        self.temp_azimuth_gyro = self.temp_gyro_z
        self._compensation = Compensation(self._correction_inputs(), float(self.axial_drift_apply_from))

    def _publish_start(self):
        self.lat, self.lon, self.height = self.lat0, self.lon0, self.height0
        self.nav_time = -self.align_time
        self.solution_time = self._start_time
        if self.align_time == 0:  # navigating from the given attitude
            self.yaw, self.pitch, self.roll = self.yaw0, self.pitch0, self.roll0
            self.phase = PHASES["navigate"]

    def _correction_inputs(self) -> tuple:
        """The azimuth drift correction set (c, b, a) of the inputs, rad/s per degC^n."""
        return (float(self.axial_drift_correction), float(self.axial_drift_correction_b),
                float(self.axial_drift_correction_a))

    def _new_ins(self, step):
        self._config = self._make_config(step)
        if self.align_time > 0:
            return ins.StrapdownINS(self._config)
        return ins.StrapdownINS(self._config, initial_attitude=euler_to_mat(self.yaw0, self.pitch0, self.roll0))

    @guarded
    def do_step(self, current_time, step_size):
        if self._fast is not None and self._fast.step(self._fmi_buffer, current_time, step_size):
            return True
        try:
            self._step = check_step(self, step_size, self._step)
            if self._ins is None:
                self._ins = self._new_ins(step_size)
                self._fast = compiled_steps.ins_context(self)
                self._fmi_fast_step = None if self._fast is None else self._fast.address
            increments = self._fmi_buffer[self._in_slots][None, :]
            tag = float(self.increment_end_time)
            if not (np.isfinite(increments).all() and math.isfinite(tag) and math.isfinite(self.temp_gyro_z)):
                raise ValueError("increments, increment_end_time or temp_gyro_z contain NaN or infinity")
            done = self._start_time + self._ins.steps * step_size  # end of the last interval integrated
            if same_time(tag, done, step_size) and self._ins.steps == 0:
                return True  # no increments yet (Jacobi's first step): nothing to integrate
            if not same_time(tag, done + step_size, step_size):
                what = "were already integrated" if same_time(tag, done, step_size) else "would skip an interval"
                raise ValueError(f"increments tagged increment_end_time={tag:.9g} s {what}: the INS has integrated "
                                 f"up to {done:.9g} s and needs the interval ending at {done + step_size:.9g} s")
            nav_start = self._ins.steps * step_size - self._config.align_time  # nav time of the interval start
            c, b, a = self._compensation.value_at(nav_start, self._correction_inputs(),
                                                  float(self.axial_drift_apply_from), step_size)
            correction = drift_model_value((a, b, c), float(self.temp_gyro_z))
            if self._ins.steps == 0:
                self.temp_align_start = float(self.temp_gyro_z)  # at the end of the first interval
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
        err[4] = np.hypot(err[2], err[3])  # libm's, as the in-process runs and the compiled step
        buffer[self._err_slots] = err
        self.phase = PHASES[state.phase]
        self.nav_time = state.time - self._config.align_time
        self.solution_time = self._start_time + state.time
        est = self._est
        est[:2] = state.gyro_comp[:2]
        est[2:] = state.accel_comp[:2]
        buffer[self._est_slots] = est
        self.temp_azimuth_gyro = float(self.temp_gyro_z)
        if state.phase != "navigate" or abs(self.nav_time) < 0.5 * self._step:
            self.temp_align_end = float(self.temp_gyro_z)
            self.temp_change_align = self.temp_align_end - self.temp_align_start


class Compensation:
    """The azimuth drift compensation in force and the pending ones (value: a tuple of
    coefficients, rad/s per degC^n; apply_from: nav time, s).

    An input pair that differs from the last one seen is queued; it takes
    over for the intervals that start at or after its apply_from (a sender
    whose value changes every step, tagged with increasing apply_from,
    queues one pair per step; a pair replaces the queued ones that would
    start at or after its own apply_from).  A pair whose value equals the one
    it would follow (the last queued, else the one in force) is not queued:
    it would change nothing (a sender that repeats its value with a later
    apply_from every step queues nothing).  A pair whose apply_from lies
    before the interval about to be integrated arrived too late: an error,
    never a silent shift of the compensation.

    ``state`` (for the compiled step, :mod:`fmus.compiled_steps`) holds the
    seen pair (value..., apply_from), the value in force, and the apply_from
    of the first and of the last queued pair (inf and -inf: none queued).  The
    seen pair lives there only: a compiled step records a repeated value with
    a later apply_from by writing it; every other change it leaves to
    :meth:`value_at`.  The value of the last queued pair (else the one in
    force) always equals the seen value.
    """

    def __init__(self, value: tuple, apply_from: float):
        n = len(value)
        self.state = np.zeros(2 * n + 3)
        self._n = n
        self.current = tuple(0.0 for _ in value)
        self.pending = collections.deque([(value, apply_from)])
        self.seen = (value, apply_from)
        self.started = False
        self._publish()

    @property
    def seen(self) -> tuple:
        """The last input pair (value, apply_from)."""
        n = self._n
        return tuple(float(x) for x in self.state[:n]), float(self.state[n])

    @seen.setter
    def seen(self, pair) -> None:
        n = self._n
        self.state[:n] = pair[0]
        self.state[n] = pair[1]

    def _publish(self) -> None:
        n, pending = self._n, self.pending
        self.state[n + 1:2 * n + 1] = self.current
        self.state[2 * n + 1] = pending[0][1] if pending else math.inf
        self.state[2 * n + 2] = pending[-1][1] if pending else -math.inf

    def value_at(self, nav_start: float, value: tuple, apply_from: float, step: float) -> tuple:
        """Compensation for the interval starting at nav time ``nav_start`` given the current inputs."""
        if not (all(math.isfinite(v) for v in value) and math.isfinite(apply_from)):
            raise ValueError("an axial_drift_correction input or axial_drift_apply_from is not finite")
        tol = 1e-6 * step
        if (value, apply_from) != self.seen:
            if self.started and apply_from < nav_start - tol:
                raise ValueError(f"axial drift compensation {value[0]:.6g} rad/s to apply from nav time "
                                 f"{apply_from:.9g} s arrived when the INS integrates the interval starting at "
                                 f"{nav_start:.9g} s (make the sender's latency longer)")
            while self.pending and self.pending[-1][1] >= apply_from - tol:
                self.pending.pop()
            self.seen = (value, apply_from)
            if value != (self.pending[-1][0] if self.pending else self.current):
                self.pending.append((value, apply_from))
        self.started = True
        while self.pending and nav_start >= self.pending[0][1] - tol:
            self.current = self.pending.popleft()[0]
        self._publish()
        return self.current
