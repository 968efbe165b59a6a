"""TrajectoryIMU FMU: a vehicle trajectory from segments, the aided runs' IMU, optionally a wheel odometer and
the zero-velocity (ZUPT) and non-holonomic (NHC) aiding rows along it (the C core's traj.h + aided_imu.h + odo.h +
aid_noise.h).

The declaration of the native TrajectoryIMU FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/trajectory_imu/model.c`` computes it (the kernels :func:`sarins_fmu.trajectory.generate` and
:func:`sarins_fmu.aided.corrupt` run in process, one step at a time, and the odometer readings and the ZUPT
and NHC rows of :func:`sarins_fmu.aided.per_step_aiding` with ``stream='core'``).
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import OUTPUT, PARAMETER, declare, default_experiment
from sarins_fmu.aided import FilterSettings, OdometerConfig

NAV = (("lat", "rad; deg", "latitude"), ("lon", "rad; deg", "longitude"), ("height", "m", "height"),
       ("v_e", "m/s", "east velocity"), ("v_n", "m/s", "north velocity"), ("v_u", "m/s", "up velocity"),
       ("yaw", "rad; deg", "yaw (CCW from north)"), ("pitch", "rad; deg", "pitch"), ("roll", "rad; deg", "roll"))
NOISE = (("arw", "rad/s0.5", "angle random walk"), ("vrw", "m/s/s0.5", "velocity random walk"),
         ("gyro_bias_std", "rad/s", "std of the per-seed constant gyro bias"),
         ("accel_bias_std", "m/s2", "std of the per-seed constant accelerometer bias"),
         ("gyro_rw", "rad/s/s0.5", "gyro bias random walk"), ("accel_rw", "m/s2/s0.5", "accelerometer bias random walk"))


class TrajectoryIMU(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "A vehicle's truth motion from segments (sarins_fmu.trajectory, the C core's traj.h: speed, heading and "
        "pitch rates constant per segment, roll 0, navigation frame ENU, body right-front-up) and the aided "
        "runs' IMU along it (sarins_fmu.aided.corrupt, the core's aided_imu.h: white angle and velocity random "
        "walks, per-seed constant biases, bias random walks, seeded). segments: 'steps accel yaw_rate "
        "pitch_rate; ...' (a whole number of steps of `step` s, m/s2, rad/s, rad/s; "
        "sarins_fmu.trajectory.Trajectory.table). Contract (standard FMI timing, time-tagged): after "
        "doStep(t, h) (h = step) the outputs are the truth at t + h (truth_time = t + h) and the measured "
        "increments of [t, t + h] (increment_end_time = t + h) with the true biases over it; at initialisation "
        "the truth at the start time and no increments (both tags = the start time). With odo_rate_hz > 0 a wheel "
        "odometer (the core's odo.h: scale-factor error, white noise, quantisation, seeded by odo_seed) reads the "
        "forward (body y) speed at t + h after every (1 / (odo_rate_hz h))-th step (a whole number): odo_valid = 1 "
        "and odo_speed for that step, odo_valid = 0 otherwise (odo_speed holds), tagged by increment_end_time "
        "like the increments. With zupt_enable = 1, zupt = 1 for a step over which the vehicle stands still (speed "
        "below 1e-9 m/s at both ends: the core's aid_noise.h, Truth.stationary) and zupt_v_e/n/u the velocity "
        "measured there (zupt_std times a normal); with nhc_enable = 1, nhc = 1 for a step that is not still and "
        "nhc_v_x/z the body velocity measured (nhc_std times a normal); five normals per step from stream 33 of "
        "jitter_seed whatever the flags (navigate(..., imu_stream='core')'s rows), tagged by increment_end_time "
        "like the increments; a value under a flag 0 is zero; zupt_enable = 2 outputs the ZUPT jitter on every "
        "step (zupt still the truth's flag) for a stillness detector downstream (AidedINS zupt_source = 1). With "
        "vib_accel_rms or vib_rate_rms > 0 the vehicle's vibration while moving (the core's vibration.h, stream 34 "
        "of seed: white velocity and attitude jitter at the moving points, seen as a sample specific force and "
        "rate of those rms per axis) is added to the increments (navigate(..., imu_stream='core', "
        "vibration=Vibration(vib_accel_rms, vib_rate_rms))). A step past the last "
        "segment is an error. State outputs only (no direct feedthrough). FMU state: get, set and serialize; "
        "no allocation after initialisation.")
    default_experiment = default_experiment(0.01)  # HOST_DEFAULT_STEPS steps, the default segments as long: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "segments", PARAMETER,
                "segment rows 'steps accel yaw_rate pitch_rate' ';'-separated [1]", "1000 0 0 0")
        declare(self, "real", "step", PARAMETER, "IMU step = communication step [s]", 0.01)
        declare(self, "integer", "substeps", PARAMETER, "Runge-Kutta sub-intervals per step [1]", 8)
        for name, unit, text in (("lat0", "rad; deg", "start latitude"), ("lon0", "rad; deg", "start longitude"),
                                 ("height0", "m", "start height"), ("speed0", "m/s", "start speed"),
                                 ("yaw0", "rad; deg", "start heading, CCW from north"),
                                 ("pitch0", "rad; deg", "start pitch")):
            declare(self, "real", name, PARAMETER, f"{text} [{unit}]", 0.0)
        for name, unit, text in NOISE:
            declare(self, "real", name, PARAMETER, f"IMU {text} [{unit}]", 0.0)
        declare(self, "integer", "seed", PARAMETER, "seed of the IMU errors [1]", 0)
        odo = OdometerConfig()
        declare(self, "real", "odo_rate_hz", PARAMETER,
                "odometer reading rate; 0: no odometer; 1 / (odo_rate_hz step) must be a whole number [Hz]", 0.0)
        declare(self, "real", "odo_scale_factor", PARAMETER, "odometer scale-factor error, |value| < 0.5 [1]",
                odo.scale_factor)
        declare(self, "real", "odo_noise_std", PARAMETER, "odometer white-noise std [m/s]", odo.noise_std)
        declare(self, "real", "odo_resolution", PARAMETER, "odometer speed resolution; 0: none [m/s]", odo.resolution)
        declare(self, "integer", "odo_seed", PARAMETER, "seed of the odometer's errors [1]", 0)
        fs = FilterSettings()
        declare(self, "integer", "zupt_enable", PARAMETER,
                "1: output zupt = 1 over the steps the vehicle stands still, 0: zupt = 0 always; 2: as 1 with "
                "zupt_v_e/n/u the jitter on every step (for a detector downstream) [1]", 0)
        declare(self, "integer", "nhc_enable", PARAMETER,
                "1: output nhc = 1 over the steps the vehicle moves, 0: nhc = 0 always [1]", 0)
        declare(self, "real", "zupt_std", PARAMETER, "std of the stop's velocity jitter, per ENU axis [m/s]",
                fs.zupt_std)
        declare(self, "real", "nhc_std", PARAMETER, "std of the wheels' body x and z velocity jitter [m/s]",
                fs.nhc_std)
        declare(self, "integer", "jitter_seed", PARAMETER, "seed of the ZUPT and NHC jitter (stream 33) [1]", 0)
        declare(self, "real", "vib_accel_rms", PARAMETER,
                "vehicle vibration while moving: rms sample specific force per axis (stream 34 of seed); 0: none "
                "[m/s2]", 0.0)
        declare(self, "real", "vib_rate_rms", PARAMETER,
                "vehicle vibration while moving: rms sample angular rate per axis; 0: none [rad/s]", 0.0)
        for name, unit, text in NAV:
            declare(self, "real", name, OUTPUT, f"true {text} at truth_time [{unit}]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"omega_ib_{ax}", OUTPUT,
                    f"true body rate wrt inertial space at truth_time, {ax} axis [rad/s]", 0.0)
        declare(self, "real", "truth_time", OUTPUT, "time tag of the truth outputs [s]", 0.0)
        for q, unit in (("dtheta", "rad"), ("dv", "m/s")):
            for ax in "xyz":
                declare(self, "real", f"{q}_{ax}", OUTPUT,
                        f"measured {q} increment of the interval ending at increment_end_time, body {ax} [{unit}]",
                        0.0)
        declare(self, "real", "increment_end_time", OUTPUT, "time tag: end of the increments' interval [s]", 0.0)
        for q, unit in (("bias_g", "rad/s"), ("bias_a", "m/s2")):
            for ax in "xyz":
                declare(self, "real", f"true_{q}_{ax}", OUTPUT,
                        f"true {q.replace('_', ' ')} over the increments' interval, body {ax} [{unit}]", 0.0)
        declare(self, "integer", "odo_valid", OUTPUT,
                "1: odo_speed is a new odometer reading at increment_end_time, 0: none this step [1]", 0)
        declare(self, "real", "odo_speed", OUTPUT, "odometer speed, forward along body y, at its reading [m/s]", 0.0)
        declare(self, "integer", "zupt", OUTPUT,
                "1: the vehicle stands still over the increments' interval (zero-velocity update) [1]", 0)
        for ax in ("e", "n", "u"):
            declare(self, "real", f"zupt_v_{ax}", OUTPUT,
                    f"velocity measured at the stop over the increments' interval, {ax.upper()} (0 when zupt is 0 "
                    "and zupt_enable is not 2) [m/s]", 0.0)
        declare(self, "integer", "nhc", OUTPUT,
                "1: the vehicle moves on its wheels over the increments' interval (non-holonomic constraint) [1]", 0)
        for ax in "xz":
            declare(self, "real", f"nhc_v_{ax}", OUTPUT,
                    f"body {ax} velocity measured over the increments' interval (0 when nhc is 0) [m/s]", 0.0)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the TrajectoryIMU FMU is native: fmus/c/trajectory_imu/model.c computes it (this "
                                  "class only declares its variables)")
