"""VehicleMotion FMU: a land vehicle's drives, turns and stops (seed 002) as moving-base motion."""


import numpy as np
from pythonfmu import Fmi2Slave

from fmus.slave_support import (OUTPUT, PARAMETER, ParameterError, check_finite, check_integer, check_latitude,
                                default_experiment,
                                check_step, declare,
                                discard_on_error, guarded, same_time)
from sarins_fmu import vehicle
from sarins_fmu.site import SITE_LAT_DEG
from sarins_fmu.units import DEG_TO_RAD



def parse_legs(text: str):
    """'drive 300 10; turn 90; stop 1800' -> [('drive', 300.0, 10.0), ('turn', 90.0), ('stop', 1800.0)]."""
    legs = []
    for part in filter(None, (p.strip() for p in text.split(";"))):
        kind, *numbers = part.split()
        try:
            legs.append((kind, *(float(x) for x in numbers)))
        except ValueError:
            raise ParameterError(f"parameter legs: leg {part!r}: numbers expected after {kind!r}") from None
        want = {"drive": 2, "turn": 1, "stop": 1}.get(kind)
        if want is None or len(numbers) != want:
            raise ParameterError(f"parameter legs: leg {part!r}: use 'drive SECONDS SPEED', 'turn DEGREES' or "
                                 "'stop SECONDS'")
    if not legs:
        raise ParameterError("parameter legs is empty")
    return legs


class VehicleMotion(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "A land vehicle's truth motion (seed 002's drives, turns and stops on a level road, with the body's "
        "pitch and roll sway and vibration while moving: sarins_fmu.vehicle.BodyMotion, amplitudes at "
        "reference_speed, phases from body_seed; set the amplitudes to 0 for a rigid body) as "
        "moving-base inputs of IMUThermal (base = input). Legs: 'drive SECONDS SPEED_M_S; turn DEGREES; stop "
        "SECONDS; ...' (turns positive to the left), after lead_time s at rest. Longitudinal and yaw "
        "accelerations change only on the grid (= the communication step). Contract (standard FMI timing): the "
        "outputs describe the step that STARTS at base_motion_time (the start time at initialisation, t + h "
        "after doStep(t, h)): attitude yaw (CCW from north), pitch, roll (mat_nv = Rz(yaw) Rx(pitch) Ry(roll), ENU, "
        "body right-front-up) with rates and angular accelerations constant over the step; the inertial rate "
        "(omega_ie + omega_en) of the local-level ENU frame at the vehicle and the specific force in it, held "
        "over the step (exact for the IMU: f = dv/h + (2 omega_ie + omega_en) x v_mean - g, v_mean the step's "
        "Simpson mean velocity); position, velocity and speed at base_motion_time and stopped (1 at rest). After "
        "the last leg the vehicle stays parked. All outputs are state outputs (no direct feedthrough). Nothing "
        "but the trajectory is held.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "legs", PARAMETER, "drive/turn/stop legs, ';'-separated",
                "drive 300 10; turn 90; drive 300 12; stop 1800; drive 180 10; stop 60")
        declare(self, "real", "lat0", PARAMETER, "start latitude [rad; deg]", SITE_LAT_DEG * DEG_TO_RAD)
        declare(self, "real", "lon0", PARAMETER, "start longitude [rad; deg]", 0.0)
        declare(self, "real", "heading0", PARAMETER, "start heading, CCW from north [rad; deg]", 0.0)
        declare(self, "real", "lead_time", PARAMETER, "time at rest before the first leg (alignment) [s]", 900.0)
        declare(self, "real", "grid", PARAMETER, "time grid of acceleration changes = communication step [s]", 1.0)
        body = vehicle.BodyMotion()
        declare(self, "real", "sway_pitch", PARAMETER, "pitch sway amplitude at reference_speed [rad; deg]",
                body.sway_pitch)
        declare(self, "real", "sway_roll", PARAMETER, "roll sway amplitude at reference_speed [rad; deg]",
                body.sway_roll)
        declare(self, "real", "sway_period", PARAMETER, "sway period [s]", body.sway_period)
        declare(self, "real", "vibration", PARAMETER,
                "pitch/roll vibration amplitude per frequency (0.13, 0.29, 0.41 Hz) at reference_speed [rad; deg]",
                body.vibration)
        declare(self, "real", "reference_speed", PARAMETER, "speed of the stated amplitudes [m/s]",
                body.reference_speed)
        declare(self, "integer", "body_seed", PARAMETER, "seed of the sway and vibration phases [1]", 0)
        for q, unit in (("", "rad; deg"), ("_rate", "rad/s; deg/s"), ("_accel", "rad/s2; deg/s2")):
            for angle in ("yaw", "pitch", "roll"):
                declare(self, "real", f"vehicle_{angle}{q}", OUTPUT,
                        f"vehicle {angle}{q.replace('_', ' ')} from base_motion_time on [{unit}]", 0.0)
        for ax in "enu":
            declare(self, "real", f"base_rate_{ax}", OUTPUT,
                    f"inertial rate of the local-level frame, {ax} axis, over the step [rad/s]", 0.0)
        for ax in "enu":
            declare(self, "real", f"base_force_{ax}", OUTPUT, f"specific force, {ax} axis, over the step [m/s2]", 0.0)
        for name, unit, text in (("lat", "rad; deg", "latitude"), ("lon", "rad; deg", "longitude"),
                                 ("v_e", "m/s", "east velocity"), ("v_n", "m/s", "north velocity"),
                                 ("speed", "m/s", "speed"), ("base_motion_time", "s", "time tag of the outputs")):
            declare(self, "real", name, OUTPUT, f"{text} at base_motion_time [{unit}]", 0.0)
        declare(self, "integer", "stopped", OUTPUT, "1 while the vehicle is at rest [1]", 1)
        self._trajectory = None
        self._step = None
        self._start_time = 0.0

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def enter_initialization_mode(self):
        try:  # outputs during initialisation (a host may read them then); a bad parameter is reported at exit
            self._build()
        except ParameterError:
            self._trajectory = None

    @guarded
    def exit_initialization_mode(self):
        self._build()

    def _build(self):
        check_finite(self, ["lat0", "lon0", "heading0", "lead_time", "grid", "sway_pitch", "sway_roll", "sway_period",
                            "vibration", "reference_speed"], positive=["grid", "sway_period", "reference_speed"],
                     non_negative=["lead_time", "sway_pitch", "sway_roll", "vibration"])
        check_latitude(self, "lat0")
        seed = check_integer(self, "body_seed", 0)
        legs = parse_legs(self.legs)
        try:
            body = vehicle.BodyMotion(self.sway_pitch, self.sway_roll, self.sway_period, self.vibration,
                                      reference_speed=self.reference_speed, seed=seed)
        except ValueError as exc:
            raise ParameterError(f"parameters sway_pitch, sway_roll, sway_period, vibration, reference_speed: "
                                 f"{exc}") from None
        try:
            self._trajectory = vehicle.VehicleTrajectory(legs, self.lat0, self.lon0, self.heading0, step=self.grid,
                                                         rotation="none", lead_time=self.lead_time, body=body)
        except ValueError as exc:
            raise ParameterError(f"parameter legs = {self.legs!r}: {exc}") from None
        self._publish(self._start_time)

    def _publish(self, time):
        tr = self._trajectory
        k = int(round((time - self._start_time) / tr.step))
        if not same_time(k * tr.step + self._start_time, time, tr.step):
            raise ValueError(f"time {time:.9g} s is not on the vehicle's grid of {tr.step} s")
        if k > tr.n_steps and tr.speed[-1] != 0.0:  # (the state at the drive's end is published, not a step after)
            raise ValueError(f"time {time:.9g} s is beyond the drive and the legs do not end with a stop")
        k_motion = min(k, tr.n_steps - 1)  # after the last leg: parked (the last step is at rest)
        angle, rate, accel = (x[0] for x in tr.schedule.state(min(k, tr.n_steps) * tr.step))
        parked = k >= tr.n_steps
        for j, name in enumerate(("yaw", "pitch", "roll")):
            setattr(self, f"vehicle_{name}", float(angle[j]))
            setattr(self, f"vehicle_{name}_rate", 0.0 if parked else float(rate[j]))
            setattr(self, f"vehicle_{name}_accel", 0.0 if parked else float(accel[j]))
        w_t, f_t = tr.base_motion(np.array([k_motion * tr.step]), tr.step)
        for i, ax in enumerate("enu"):
            setattr(self, f"base_rate_{ax}", float(w_t[0, i]))
            setattr(self, f"base_force_{ax}", float(f_t[0, i]))
        j = min(k, tr.n_steps)
        self.lat, self.lon = float(tr.lat[j]), float(tr.lon[j])
        self.v_e, self.v_n = float(tr.velocity_n[j, 0]), float(tr.velocity_n[j, 1])
        self.speed = float(tr.speed[j])
        self.stopped = int(not tr.moving()[j])
        self.base_motion_time = float(time)

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            if not same_time(step_size, self._trajectory.step, step_size):
                raise ValueError(f"communication step {step_size} s differs from the vehicle grid {self.grid} s")
            self._publish(current_time + step_size)
        except ValueError as exc:
            return discard_on_error(self, exc)
        return True
