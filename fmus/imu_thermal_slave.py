"""IMUThermal FMU: increment-output IMU with its error and thermal models."""

import math

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_step, declare,
                                discard_on_error, guarded, real_slots)
from sarins_fmu import imu, imu_params
from sarins_fmu.thermal import SENSORS, ThermalModel

DEG = math.pi / 180.0
GIMBAL_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
UNIT_DISPLAY = {"rad/s": "deg/h", "rad": "deg"}


class IMUThermal(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Increment-output IMU on a turntable, static base. Contract: inputs are the turntable's gimbal "
        "angles and rates at the END of the current communication step (Gauss-Seidel: the turntable is "
        "stepped first) and the ambient temperature there; the IMU holds the state it received at the "
        "start of the step, rebuilds the motion over the step with constant angular acceleration "
        "(rate difference / step; the end angle is checked), integrates true motion and sensor errors at "
        "internal_rate, and outputs the compensated angle and velocity increments of the step (coning and "
        "sculling applied, body axes at the start of the step) and the six sensor temperatures at its end. "
        "Held between steps: thermal state, bias-instability state, noise generator, last gimbal state. "
        "IMU parameters: 'preset' chooses the model; any coefficient parameter that is set overrides it.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=16 * 3600.0, step_size=1.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._overridden = set()
        declare(self, "string", "preset", PARAMETER, "IMU model: ideal, nav-rlg or mems", "nav-rlg")
        declare(self, "real", "lat", PARAMETER, "latitude of the static base [rad; deg]", 28.222 * DEG)
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
            declare(self, "real", f"angle_{j}", INPUT, f"gimbal {j} angle at the step end [rad; deg]", 0.0)
            declare(self, "real", f"rate_{j}", INPUT, f"gimbal {j} rate at the step end [rad/s; deg/s]", 0.0)
        declare(self, "real", "ambient_temp", INPUT, "ambient temperature at the step end [degC]", 20.0)
        for ax in "xyz":
            declare(self, "real", f"dtheta_{ax}", OUTPUT, f"angle increment about body {ax} over the step [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"dv_{ax}", OUTPUT, f"velocity increment along body {ax} over the step [m/s]", 0.0)
        for sensor in SENSORS:
            declare(self, "real", f"temp_{sensor}", OUTPUT, f"temperature of the {sensor} sensor [degC]", 20.0)
        self._sensor = None
        self._model = None
        self._step = None
        self._state = None
        # buffer slots for vectorised I/O (see fmus.slave_support)
        self._angle_slots = real_slots(self, ["angle_1", "angle_2", "angle_3"])
        self._rate_slots = real_slots(self, ["rate_1", "rate_2", "rate_3"])
        self._out_slots = real_slots(self, [f"dtheta_{ax}" for ax in "xyz"] + [f"dv_{ax}" for ax in "xyz"]
                                     + [f"temp_{sensor}" for sensor in SENSORS])

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
        if abs(self.lat) > 89.9 * DEG:
            raise ParameterError(f"parameter lat = {math.degrees(self.lat):.6g} deg is outside +-89.9 deg")
        if self.thermal_start not in ("hot", "cold"):
            raise ParameterError(f"thermal_start must be 'hot' or 'cold', got {self.thermal_start!r}")
        names = [g.strip() for g in self.gimbals.split(",")]
        if not 1 <= len(names) <= 3 or any(g not in GIMBAL_AXES for g in names):
            raise ParameterError(f"gimbals must list 1 to 3 of x, y, z, got {self.gimbals!r}")
        try:
            base_model = imu.preset(self.preset)
            overrides = {name: getattr(self, name) for name in self._overridden}
            self._model = imu_params.apply_overrides(base_model, overrides)
            self._base = imu.StaticBase(self.lat, 0.0, self.height, self.base_yaw)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self._axes = np.array([GIMBAL_AXES[g] for g in names])
        self._state = self._read_gimbals()
        self._ambient0 = float(self.ambient_temp)
        initial = ThermalModel(self._model.thermal, start=self.thermal_start)
        initial.reset(0.0, self._ambient0)
        for j, sensor in enumerate(SENSORS):
            setattr(self, f"temp_{sensor}", float(initial.temperature[j]))

    def _read_gimbals(self):
        n = len(self._axes)
        angle = self._fmi_buffer[self._angle_slots[:n]][None, :]
        rate = self._fmi_buffer[self._rate_slots[:n]][None, :]
        if not (np.isfinite(angle).all() and np.isfinite(rate).all()):
            raise ValueError("gimbal inputs contain NaN or infinity")
        return angle, rate

    def _start(self, step_size):
        try:
            self._sensor = imu.IMU(self._model, self._base, self._axes, output_interval=step_size,
                                   internal_rate=self.internal_rate, seed=int(self.seed),
                                   thermal_start=self.thermal_start, aging_days=self.aging_days)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self._sensor.reset(ambient0=self._ambient0)

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            if self._sensor is None:
                self._start(step_size)
            angle0, rate0 = self._state
            angle1, rate1 = self._read_gimbals()
            accel = (rate1 - rate0) / step_size
            predicted = angle0 + rate0 * step_size + 0.5 * accel * step_size**2
            if np.any(np.abs(predicted - angle1) > 1e-7 * (1.0 + np.abs(angle1))):
                raise ValueError(f"turntable motion at t={current_time:.9g} s is not constant-acceleration "
                                 "within the step (accelerations must change on the communication grid)")
            dtheta, dv, temps = self._sensor.step(angle0, rate0, accel, ambient=[self.ambient_temp])
        except ValueError as exc:
            return discard_on_error(self, exc)
        self._state = (angle1, rate1)
        self._fmi_buffer[self._out_slots] = np.concatenate((dtheta[0], dv[0], temps[0]))
        return True
