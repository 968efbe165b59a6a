"""IMUThermal FMU: increment-output IMU with its error and thermal models.

The declaration of the native IMUThermal FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/imu_thermal/model.c`` computes it (the C core's IMU build and FMU step, the functions
``sarins_fmu.imu.IMU`` runs in process): the parameter checks at fmi2ExitInitializationMode, the preset
with the coefficients that were set, the static or input base, the thermal start at the ambient of the
motion set tagged with the start time, the first step at the start time.
"""

from pythonfmu import Fmi2Slave

from fmus.native_fmu import ArrayVariable
from fmus.slave_support import declare, default_experiment, INPUT, NO_TAG, OUTPUT, PARAMETER
from sarins_fmu import imu, imu_params
from sarins_fmu.thermal import SENSORS
from sarins_fmu.site import SITE_LAT

UNIT_DISPLAY = {"rad/s": "deg/h", "rad": "deg"}


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
        "bias-instability state, noise generator, the periodic terms' phases (drawn from the seed), the previous "
        "motion set. "
        "Moving base (base = input): the vehicle motion is a second time-tagged start-of-step set, tagged "
        "base_motion_time and chosen like the turntable's: the vehicle attitude as Euler angles yaw (CCW from "
        "north), pitch, roll with mat_nv = Rz(yaw) Rx(pitch) Ry(roll) (ENU, body right-front-up), their rates "
        "and their angular accelerations, constant over the step (the turntable's gimbals ride on the vehicle: "
        "gimbal chain z, x, y, then the turntable's), and the inertial angular rate of the local-level ENU frame "
        "at the vehicle (omega_ie + omega_en) and the specific force resolved in it, both held over the step. "
        "IMU parameters: 'preset' chooses the model; any coefficient parameter that is set overrides it.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults
    # FMI 3.0 only (fmus/native_fmu.py): every sub-interval of the last step, n_sub elements each
    fmi3_arrays = tuple(
        ArrayVariable(f"{q}_{a}_sub", "n_sub", "output", f"{what} {a} of each of the n_sub sub-intervals of the "
                      f"last step, in time order, each in body axes at its own start [{unit}]")
        for q, what, unit in (("dtheta", "angle increment about body", "rad"),
                              ("dv", "velocity increment along body", "m/s"))
        for a in "xyz") + (
        ArrayVariable("temp_gyro_z_sub", "n_sub", "output",
                      "temperature of the gyro_z sensor at the end of each sub-interval of the last step [degC]"),
    ) + tuple(  # the motion of every sub-interval of the coming step (a Turntable's n_sub arrays), sub_inputs = 1
        ArrayVariable(f"{q}_{j}_sub", "n_sub", "input", f"sub_inputs = 1: gimbal {j} {what} at the start of each "
                      f"of the n_sub sub-intervals of the step starting at motion_time, in time order [{unit}]")
        for q, what, unit in (("angle", "angle", "rad"), ("rate", "rate", "rad/s"),
                              ("accel", "angular acceleration holding over the sub-interval", "rad/s2"))
        for j in (1, 2, 3)) + (
        ArrayVariable("ambient_temp_sub", "n_sub", "input",
                      "sub_inputs = 1: ambient temperature at the start of each sub-interval [degC]"),
        ArrayVariable("ambient_temp_rate_sub", "n_sub", "input",
                      "sub_inputs = 1: slope of the ambient temperature over each sub-interval [degC/s]"))

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
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
        units = {name: f"{unit}; {UNIT_DISPLAY[unit]}" if unit in UNIT_DISPLAY else unit
                 for name, unit, _ in imu_params.PARAMETERS}
        for name in units:
            if name not in imu_params.PERIODIC_NAMES:  # declared last (below)
                self._declare_coefficient(name, defaults[name], units[name])
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
        # last, so that the value references of the variables above stay those of the earlier builds
        declare(self, "integer", "n_sub", PARAMETER,
                "sub-intervals per communication step [1]: the IMU runs as if stepped at h / n_sub (each "
                "sub-interval its own thermal and error terms, random walk and internal_rate h / n_sub minor "
                "steps, a whole number); the scalar increments are the sums over the sub-intervals (no coning or "
                "sculling across them), the temperatures the last one's. 1: one interval per step. FMI 3.0: a "
                "structural parameter, the length of the *_sub arrays", 1)
        for name in imu_params.PERIODIC_NAMES:  # after n_sub, for the same reason
            self._declare_coefficient(name, defaults[name], units[name])
        # last, for the same reason
        declare(self, "integer", "sub_inputs", PARAMETER,
                "0: the scalar motion set, carried forward over the n_sub sub-intervals with its accelerations; "
                "1 (FMI 3.0 only, static base): the motion of each sub-interval from the *_sub array inputs (a "
                "Turntable with the same n_sub), tagged motion_time like the scalar set; the same numbers as "
                "this IMU stepped at h / n_sub with the scalar inputs [1]", 0)
        declare(self, "integer", "threads", PARAMETER,
                "threads of a step's sub-interval minor loops, this FMU's own included (1: none started; "
                "at most 64); the results do not depend on it [1]", 1)

    def _declare_coefficient(self, name, start, unit):
        """A model coefficient: setting it overrides the preset (model.c reads the glue's set flag)."""
        from pythonfmu import Real
        from fmus.slave_support import FIXED

        setattr(self, name, start)

        def setter(value, name=name):
            setattr(self, name, value)

        self.register_variable(Real(name, causality=PARAMETER, variability=FIXED,
                                    description=f"IMU coefficient, overrides the preset when set [{unit}]",
                                    getter=lambda name=name: getattr(self, name), setter=setter))

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the IMUThermal FMU is native: fmus/c/imu_thermal/model.c computes it (this "
                                  "class only declares its variables)")
