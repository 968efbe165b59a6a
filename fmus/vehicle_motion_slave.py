"""VehicleMotion FMU: a land vehicle's drives, turns and stops (seed 002) as moving-base motion.

The declaration of the native VehicleMotion FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/vehicle_motion/model.c`` computes it (the C core's vehicle, ``sarins_fmu/core/vehicle.h``, which
:mod:`sarins_fmu.vehicle` runs in process).
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import OUTPUT, PARAMETER, declare, default_experiment
from sarins_fmu import vehicle
from sarins_fmu.site import SITE_LAT_DEG
from sarins_fmu.units import DEG_TO_RAD


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
        "but the trajectory's state is held (FMU state: get, set and serialize).")
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

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the VehicleMotion FMU is native: fmus/c/vehicle_motion/model.c computes it (this "
                                  "class only declares its variables)")
