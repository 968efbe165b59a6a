"""IMUThermal FMU: increment-output IMU with its error and thermal models."""


import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus import compiled_steps
from fmus.slave_support import (INPUT, NO_TAG, OUTPUT, PARAMETER, ParameterError, StartOfStepInputs,
                                check_finite, check_integer, check_latitude, check_range, check_step, declare,
                                discard_on_error, guarded, real_slots, same_time)
from sarins_fmu import imu, imu_params
from sarins_fmu.thermal import SENSORS, ThermalModel
from sarins_fmu.site import SITE_LAT

GIMBAL_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
UNIT_DISPLAY = {"rad/s": "deg/h", "rad": "deg"}
SELF_HEATING_LIMIT = 500.0  # degC: a sensor's rise above the ambient; beyond it no sensor runs (and the model overflows)


class IMUThermal(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Increment-output IMU on a turntable, on a static base (base = static: lat, height, base_yaw) or riding on "
        "a vehicle (base = input: the vehicle's motion from an upstream FMU, see below). Contract (standard "
        "FMI timing, any master scheme): "
        "the motion inputs are a time-tagged set from the turntable describing the segment that starts at "
        "motion_time: gimbal angles, rates and angular accelerations (constant until the next communication "
        "point), the ambient temperature and its slope. doStep(t, h) needs the set tagged t: under Jacobi it "
        "reads it; under Gauss-Seidel (turntable stepped first) it reads the set tagged t + h and uses the one "
        "kept from its previous step (or initialisation); any other tag is an error (fmi2Error logged, step "
        "discarded). It integrates true motion and sensor errors at internal_rate and outputs the compensated "
        "angle and velocity increments of [t, t + h] (coning and sculling applied, body axes at t), the six "
        "sensor temperatures at t + h and the tag increment_end_time = t + h (the start time at "
        "initialisation: no increments yet). Under Gauss-Seidel the master must pass the turntable's initial outputs "
        "before the first step (FMI initialisation; motion_time starts at -1e9 s, no valid tag). The thermal state "
        "starts at the ambient of the set tagged with the start time (so a Jacobi host that passes connections "
        "only after initialisation gives the same run). If motion_time is "
        "never set (no turntable connected), the motion inputs are constants: a fixed table. So the "
        "increments are bit-identical under every scheme. All "
        "outputs are state outputs (no direct feedthrough). Held between steps: thermal state, "
        "bias-instability state, noise generator, the previous motion set. "
        "Moving base (base = input): the vehicle motion is a second time-tagged start-of-step set, tagged "
        "base_motion_time and chosen like the turntable's: the vehicle attitude as Euler angles yaw (CCW from "
        "north), pitch, roll with mat_nv = Rz(yaw) Rx(pitch) Ry(roll) (ENU, body right-front-up), their rates "
        "and their angular accelerations, constant over the step (the turntable's gimbals ride on the vehicle: "
        "gimbal chain z, x, y, then the turntable's), and the inertial angular rate of the local-level ENU frame "
        "at the vehicle (omega_ie + omega_en) and the specific force resolved in it, both held over the step. "
        "IMU parameters: 'preset' chooses the model; any coefficient parameter that is set overrides it.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=16 * 3600.0, step_size=1.0)
    VEHICLE_INPUTS = ([f"vehicle_{a}{q}" for q in ("", "_rate", "_accel") for a in ("yaw", "pitch", "roll")]
                      + [f"base_{kind}_{ax}" for kind in ("rate", "force") for ax in "enu"])  # the flat vehicle set

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._overridden = set()
        declare(self, "string", "preset", PARAMETER, "IMU model: ideal, nav-rlg or mems", "nav-rlg")
        declare(self, "string", "base", PARAMETER, "static (lat, height, base_yaw) or input (vehicle motion inputs)",
                "static")
        declare(self, "real", "lat", PARAMETER, "latitude of the static base [rad; deg]", SITE_LAT)
        declare(self, "real", "height", PARAMETER, "height of the static base [m]", 0.0)
        declare(self, "real", "base_yaw", PARAMETER, "yaw of the turntable base, CCW from north [rad; deg]", 0.0)
        declare(self, "string", "gimbals", PARAMETER,
                "gimbal axes, outer first, each in its parent frame: e.g. z, or x,z", "z")
        declare(self, "real", "internal_rate", PARAMETER, "minor-loop rate [Hz]", 200.0)
        declare(self, "integer", "seed", PARAMETER, "seed of the noise and bias-instability streams [1]", 0)
        declare(self, "string", "thermal_start", PARAMETER, "hot or cold start", "hot")
        declare(self, "real", "aging_days", PARAMETER, "age of the drift model since calibration [d]", 0.0)
        defaults = imu_params.flatten(imu.preset("nav-rlg"))
        for name, unit, _ in imu_params.PARAMETERS:
            shown = f"{unit}; {UNIT_DISPLAY[unit]}" if unit in UNIT_DISPLAY else unit
            self._declare_coefficient(name, defaults[name], shown)
        for j in (1, 2, 3):
            declare(self, "real", f"angle_{j}", INPUT, f"gimbal {j} angle at motion_time [rad; deg]", 0.0)
            declare(self, "real", f"rate_{j}", INPUT, f"gimbal {j} rate at motion_time [rad/s; deg/s]", 0.0)
            declare(self, "real", f"accel_{j}", INPUT,
                    f"gimbal {j} angular acceleration from motion_time to the next communication point "
                    "[rad/s2; deg/s2]", 0.0)
        declare(self, "real", "ambient_temp", INPUT, "ambient temperature at motion_time [degC]", 20.0)
        declare(self, "real", "ambient_temp_rate", INPUT, "slope of the ambient from motion_time on [degC/s]", 0.0)
        # start value: no valid tag, so a motion set the master never passed is an error, not a silent zero
        declare(self, "real", "motion_time", INPUT, "time tag of the motion inputs [s]", NO_TAG)
        for q, unit, text in (("", "rad; deg", "at base_motion_time"), ("_rate", "rad/s; deg/s", "at base_motion_time"),
                              ("_accel", "rad/s2; deg/s2", "from base_motion_time to the next communication point")):
            for angle in ("yaw", "pitch", "roll"):
                declare(self, "real", f"vehicle_{angle}{q}", INPUT, f"base = input: vehicle {angle}{q.replace('_', ' ')} "
                        f"{text} [{unit}]", 0.0)
        for ax in "enu":
            declare(self, "real", f"base_rate_{ax}", INPUT,
                    f"base = input: inertial rate of the local-level frame, {ax} axis, held over the step [rad/s]", 0.0)
        for ax in "enu":
            declare(self, "real", f"base_force_{ax}", INPUT,
                    f"base = input: specific force, {ax} axis, held over the step [m/s2]", 0.0)
        declare(self, "real", "base_motion_time", INPUT, "base = input: time tag of the vehicle motion inputs [s]",
                NO_TAG)
        for ax in "xyz":
            declare(self, "real", f"dtheta_{ax}", OUTPUT, f"angle increment about body {ax} over the step [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"dv_{ax}", OUTPUT, f"velocity increment along body {ax} over the step [m/s]", 0.0)
        for sensor in SENSORS:
            declare(self, "real", f"temp_{sensor}", OUTPUT,
                    f"temperature of the {sensor} sensor at increment_end_time [degC]", 20.0)
        declare(self, "real", "increment_end_time", OUTPUT,
                "time tag: end of the interval of the increments [s]", 0.0)
        self._sensor = None
        self._motion = None  # StartOfStepInputs, made when the gimbal count is known
        self._vehicle = StartOfStepInputs("vehicle motion", "base_motion_time", 15)
        self._fast = None  # the compiled step's context (fmus.compiled_steps)
        self._start_time = 0.0
        self._model = None
        self._step = None
        self._state = None
        # buffer slots for vectorised output (see fmus.slave_support)
        self._out_slots = real_slots(self, [f"dtheta_{ax}" for ax in "xyz"] + [f"dv_{ax}" for ax in "xyz"]
                                     + [f"temp_{sensor}" for sensor in SENSORS])

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def _declare_coefficient(self, name, start, unit):
        """A model coefficient: setting it marks it as overriding the preset."""
        from pythonfmu import Real
        from fmus.slave_support import FIXED

        setattr(self, name, start)

        def setter(value, name=name):
            setattr(self, name, value)
            self._overridden.add(name)

        self.register_variable(Real(name, causality=PARAMETER, variability=FIXED,
                                    description=f"IMU coefficient, overrides the preset when set [{unit}]",
                                    getter=lambda name=name: getattr(self, name), setter=setter))

    @guarded
    def exit_initialization_mode(self):
        check_finite(self, ["lat", "height", "base_yaw", "internal_rate", "aging_days"],
                     positive=["internal_rate"], non_negative=["aging_days"])
        check_latitude(self, "lat")
        check_integer(self, "seed", 0)  # the noise streams take a non-negative seed
        for name in self._overridden:
            if name.startswith("self_heating_"):
                check_range(self, name, -SELF_HEATING_LIMIT, SELF_HEATING_LIMIT, unit="degC")
        if self.thermal_start not in ("hot", "cold"):
            raise ParameterError(f"thermal_start must be 'hot' or 'cold', got {self.thermal_start!r}")
        if self.base not in ("static", "input"):
            raise ParameterError(f"base must be 'static' or 'input', got {self.base!r}")
        names = [g.strip() for g in self.gimbals.split(",")]
        if not 1 <= len(names) <= 3 or any(g not in GIMBAL_AXES for g in names):
            raise ParameterError(f"gimbals must list 1 to 3 of x, y, z, got {self.gimbals!r}")
        try:
            base_model = imu.preset(self.preset)
        except ValueError as exc:
            raise ParameterError(f"parameter preset: {exc}") from None
        self._model = self._overridden_model(base_model)
        try:
            self._base = imu.StaticBase(self.lat, 0.0, self.height, self.base_yaw) if self.base == "static" \
                else imu.HeldBase()
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self._axes = np.array([GIMBAL_AXES[g] for g in names])
        self._motion = StartOfStepInputs("turntable motion", "motion_time", 3 * len(names) + 2)
        self._motion.prime(self.motion_time, self._read_motion())
        if self.base == "input":
            self._vehicle.prime(self.base_motion_time, self._read_vehicle())
        self.increment_end_time = self._start_time
        initial = ThermalModel(self._model.thermal, start=self.thermal_start)
        initial.reset(0.0, float(self.ambient_temp))  # the initial outputs; the state starts at the first step
        for j, sensor in enumerate(SENSORS):
            setattr(self, f"temp_{sensor}", float(initial.temperature[j]))

    def _overridden_model(self, base_model):
        """The preset with the set coefficients; a coefficient the model refuses is named."""
        overrides = {name: getattr(self, name) for name in sorted(self._overridden)}
        try:
            return imu_params.apply_overrides(base_model, overrides)
        except ValueError as exc:
            culprits = []
            for name, value in overrides.items():  # which of them (the model's message names a field, not these)
                try:
                    imu_params.apply_overrides(base_model, {name: value})
                except ValueError:
                    culprits.append(f"{name} = {value!r}")
            named = f"parameter {', '.join(culprits)}: " if culprits else f"parameters {', '.join(overrides)}: "
            raise ParameterError(named + str(exc)) from None

    def _read_motion(self):
        """The motion inputs as one flat set: angles, rates, accelerations (A each), ambient and its slope."""
        n = len(self._axes)
        values = np.array([getattr(self, f"{q}_{j + 1}") for q in ("angle", "rate", "accel") for j in range(n)]
                          + [self.ambient_temp, self.ambient_temp_rate])
        if not np.isfinite(values).all():
            raise ValueError("motion or ambient inputs contain NaN or infinity")
        return values

    def _read_vehicle(self):
        """The vehicle inputs as one flat set: attitude angles, rates, accelerations (yaw, pitch, roll each),
        base rate and specific force (e, n, u each)."""
        values = np.array([getattr(self, name) for name in self.VEHICLE_INPUTS])
        if not np.isfinite(values).all():
            raise ValueError("vehicle motion inputs contain NaN or infinity")
        return values

    def _start(self, step_size, ambient0):
        """Build the IMU at the first step; its thermal state starts at ``ambient0`` (degC), the ambient
        of the motion set tagged with the start time (a host that passes no connected inputs during
        initialisation delivers it with the first step)."""
        axes = self._axes if self.base == "static" else np.vstack([imu.VEHICLE_ATTITUDE_AXES, self._axes])
        try:
            self._sensor = imu.IMU(self._model, self._base, axes, output_interval=step_size,
                                   internal_rate=self.internal_rate, seed=int(self.seed),
                                   thermal_start=self.thermal_start, aging_days=self.aging_days)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self._sensor.reset(ambient0=ambient0)
        self._fast = compiled_steps.imu_context(self, step_size)
        self._fmi_fast_step = None if self._fast is None else self._fast.address

    @guarded
    def do_step(self, current_time, step_size):
        if self._fast is not None and self._fast.step(self._fmi_buffer, current_time, step_size):
            return True
        try:
            self._step = check_step(self, step_size, self._step)
            if self.motion_time == NO_TAG and self._motion.held_tag == NO_TAG:  # never set: fixed table
                motion = self._read_motion()
            else:
                motion = self._motion.select(current_time, step_size, self.motion_time, self._read_motion())
            n = len(self._axes)
            angle0, rate0, accel = (motion[None, i * n:(i + 1) * n] for i in range(3))
            amb0, amb_rate = motion[3 * n], motion[3 * n + 1]
            if self._sensor is None:
                self._start(step_size, amb0)
            if not same_time(self._sensor.time + self._start_time, current_time, step_size):
                raise ValueError(f"doStep at t={current_time:.9g} s but the IMU stands at "
                                 f"{self._sensor.time + self._start_time:.9g} s (steps must follow each other)")
            if self.base == "input":
                vehicle = self._vehicle.select(current_time, step_size, self.base_motion_time, self._read_vehicle())
                v_angle, v_rate, v_accel = (vehicle[None, i * 3:(i + 1) * 3] for i in range(3))
                self._base.hold(vehicle[9:12], vehicle[12:15])
                angle0, rate0, accel = (np.hstack(pair) for pair in ((v_angle, angle0), (v_rate, rate0),
                                                                       (v_accel, accel)))
            dtheta, dv, temps = self._sensor.step(angle0, rate0, accel, ambient=[amb0 + amb_rate * step_size])
        except ValueError as exc:
            return discard_on_error(self, exc)
        self._fmi_buffer[self._out_slots] = np.concatenate((dtheta[0], dv[0], temps[0]))
        self.increment_end_time = current_time + step_size
        return True
