"""AidedINS FMU: a strapdown INS with a 15-state error-state Kalman filter aided by GNSS fixes, zero-velocity
and zero-angular-rate updates at stops, a wheel odometer and the non-holonomic constraint (the C core's
nav3.h + eskf.h).

The declaration of the native AidedINS FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/aided_ins/model.c`` computes it (``sarins_eskf_predict``, ``sarins_eskf_aid`` and ``sarins_eskf_gnss``, the
kernels :func:`sarins_fmu.aided.navigate` runs in process).
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import INPUT, NO_TAG, OUTPUT, PARAMETER, declare, default_experiment
from sarins_fmu import aided, zero_velocity
from sarins_fmu.aided import FilterSettings
from sarins_fmu.gnss import GNSSConfig

# the filter settings in the core's order (eskf.h SARINS_ESKF_*), after the step: name, unit, text
SETTINGS = (("arw", "rad/s0.5", "angle random walk"), ("vrw", "m/s/s0.5", "velocity random walk"),
            ("gyro_rw", "rad/s/s0.5", "gyro bias random walk"), ("accel_rw", "m/s2/s0.5", "accel bias random walk"),
            ("pos0_std", "m", "initial position std"), ("vel0_std", "m/s", "initial velocity std"),
            ("tilt0_std", "rad", "initial tilt std"), ("heading0_std", "rad", "initial heading std"),
            ("gyro_bias0_std", "rad/s", "initial gyro bias std"), ("accel_bias0_std", "m/s2", "initial accel bias std"),
            ("lever_x", "m", "GNSS antenna lever arm, body right"), ("lever_y", "m", "lever arm, body front"),
            ("lever_z", "m", "lever arm, body up"),
            ("latency", "s", "age of a fix when it is applied (the co-simulation delay plus the receiver's)"),
            ("zupt_std", "m/s", "zero-velocity update std per axis"),
            ("cov_every", "1", "steps per covariance propagation"),
            ("nhc_std", "m/s", "non-holonomic constraint std, body x and z"), ("odo_std", "m/s", "odometer std"),
            ("zaru_std", "rad/s", "zero-angular-rate update std per step (the gyro's white rate noise arw / sqrt(step); "
                                  "navigate's default)"))
# the optional filter states (eskf.h SARINS_ESKF_OPT; navigate's filter_states): switches, then priors
STATE_SWITCHES = (("state_scale_factors", "gyro and accelerometer scale-factor errors (6 states, 'sf')"),
                  ("state_lever_arm", "GNSS antenna lever-arm error, body (3 states, 'lever')"),
                  ("state_gnss_pos_gm", "the receiver's Gauss-Markov position error, ENU (3 states, 'gnss-gm')"),
                  ("state_gnss_vel_gm", "the receiver's Gauss-Markov velocity error, ENU (3 states, 'gnss-gm' with "
                                        "use_velocity)"))
STATE_SETTINGS = (("gyro_sf0_std", "1", "prior std of the gyro scale-factor errors"),
                  ("accel_sf0_std", "1", "prior std of the accelerometer scale-factor errors"),
                  ("sf_tau", "s", "scale-factor correlation time; 0: random constants"),
                  ("lever0_std", "m", "prior std of the lever-arm error"),
                  ("gnss_pos_gm_std_e", "m", "receiver Gauss-Markov position std, east"),
                  ("gnss_pos_gm_std_n", "m", "receiver Gauss-Markov position std, north"),
                  ("gnss_pos_gm_std_u", "m", "receiver Gauss-Markov position std, up"),
                  ("gnss_pos_gm_tau", "s", "receiver Gauss-Markov position correlation time"),
                  ("gnss_vel_gm_std_e", "m/s", "receiver Gauss-Markov velocity std, east"),
                  ("gnss_vel_gm_std_n", "m/s", "receiver Gauss-Markov velocity std, north"),
                  ("gnss_vel_gm_std_u", "m/s", "receiver Gauss-Markov velocity std, up"),
                  ("gnss_vel_gm_tau", "s", "receiver Gauss-Markov velocity correlation time"))
STATE_OUTPUTS = (("scale_g", "xyz", "1", "estimated gyro scale-factor error"),
                 ("scale_a", "xyz", "1", "estimated accelerometer scale-factor error"),
                 ("lever_est", "xyz", "m", "estimated antenna lever arm"),
                 ("gnss_pos_gm", "enu", "m", "estimated receiver Gauss-Markov position error"),
                 ("gnss_vel_gm", "enu", "m/s", "estimated receiver Gauss-Markov velocity error"))
NAV = (("lat", "rad; deg", "latitude"), ("lon", "rad; deg", "longitude"), ("height", "m", "height"),
       ("v_e", "m/s", "east velocity"), ("v_n", "m/s", "north velocity"), ("v_u", "m/s", "up velocity"),
       ("yaw", "rad; deg", "yaw (CCW from north)"), ("pitch", "rad; deg", "pitch"), ("roll", "rad; deg", "roll"))


class AidedINS(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "A strapdown INS (nav3.h, ENU, body right-front-up) with a closed-loop 15-state error-state Kalman filter "
        "(eskf.h: position, velocity, attitude errors, gyro and accel biases) aided by GNSS position and velocity "
        "fixes, zero-velocity (ZUPT) and zero-angular-rate (ZARU) updates at stops, a wheel odometer and the "
        "non-holonomic constraint (NHC); optional states (parameters state_*: scale factors, lever arm, the "
        "receiver's Gauss-Markov position and velocity errors; eskf.h). Contract: doStep(t, h) integrates the increments "
        "dtheta_*/dv_* (body rad, m/s) of [t, t + h] "
        "(h = step, fixed), then applies the interval's aiding in this order: when zupt is 1 a ZUPT against "
        "zupt_v_* (std zupt_std); when zaru is 1 a ZARU (the step's compensated rate against the Earth rate, std "
        "zaru_std); when odo_valid and / or nhc is 1 one body-velocity update, forward (body y) against odo_speed "
        "(std odo_std) and / or body x, z against nhc_v_x, nhc_v_z (std nhc_std); a flag other than 0 or 1, or a "
        "non-finite value read under a set flag, is an error. With zupt_source = 1 the stops are detected from the "
        "increments (the core's zvd.h, sarins_fmu.zero_velocity.detect: a chi-square test of standing still over "
        "the zvd_window samples ending at the interval, causal, threshold zvd_gamma, the IMU's noise densities "
        "zvd_vrw, zvd_arw): the ZUPT (against zupt_v_*) and ZARU are applied where the input zupt / zaru is 1 and "
        "the detector says still (navigate(..., zupt_detect='imu')). Then, when "
        "the input fix_count grew since the last step and fix_valid is 1, it applies the fix (fix_lat .. fix_v_u) "
        "taken back by latency s; the outputs describe t + h: navigation, the "
        "bias estimates and the filter's standard deviations (sqrt of P's diagonal). Time-tagged (increment_end_time "
        "connected, e.g. from TrajectoryIMU, with fix_time and fix_horizon from GNSSReceiver): the increments are "
        "those of the interval ending at increment_end_time (the aiding inputs with them), each taken once and in "
        "order (a "
        "repeated tag waits); "
        "an interval ending at T is integrated once every fix valid up to T - latency is in (fix_horizon), "
        "then the fixes navigate applies after it (available time fix_time + latency within the interval) are "
        "applied in order; nav_time tags the outputs. So Gauss-Seidel and Jacobi give the same rows at the same "
        "nav_time (Jacobi later). At most 4 intervals and 8 fixes wait. State outputs only (no "
        "direct feedthrough). FMU state: get, set and serialize; no allocation after initialisation.")
    default_experiment = default_experiment(0.01)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        fs, g = FilterSettings(), GNSSConfig()
        starts = {"pos0_std": fs.pos0_std, "vel0_std": fs.vel0_std, "tilt0_std": fs.tilt0_std,
                  "heading0_std": fs.heading0_std, "zupt_std": fs.zupt_std, "cov_every": float(fs.cov_every),
                  "nhc_std": fs.nhc_std, "odo_std": 1.0, "gyro_bias0_std": 1e-12, "accel_bias0_std": 1e-12,
                  "zaru_std": aided.ZARU_STD_FLOOR}  # arw 0 (the start): navigate's default for an ideal gyro
        declare(self, "real", "step", PARAMETER, "IMU step = communication step [s]", 0.01)
        for name, unit, text in SETTINGS:
            declare(self, "real", name, PARAMETER, f"{text} [{unit}]", starts.get(name, 0.0))
        for name, unit, text in NAV:
            declare(self, "real", f"{name}0", PARAMETER, f"initial {text} [{unit}]", 0.0)
        for kind, values, unit in (("pos", g.pos_std(), "m"), ("vel", g.vel_std(), "m/s")):
            for i, ax in enumerate("enu"):
                declare(self, "real", f"gnss_{kind}_std_{ax}", PARAMETER,
                        f"GNSS {kind}ition std assumed by the filter, {ax} axis [{unit}]".replace("velition",
                                                                                                  "velocity"),
                        float(values[i]))
        declare(self, "integer", "use_velocity", PARAMETER, "1: apply the fixes' velocity too, 0: position only [1]",
                1)
        declare(self, "integer", "zupt_source", PARAMETER,
                "0: ZUPT / ZARU where the inputs zupt / zaru are 1; 1: where they are 1 and the stillness detector "
                "declares the interval still (zvd_*) [1]", 0)
        det = zero_velocity.DetectorSettings()
        declare(self, "integer", "zvd_window", PARAMETER,
                "stillness detector: window of samples ending at the interval (zupt_source 1) [1]", det.samples(0.01))
        declare(self, "real", "zvd_gamma", PARAMETER,
                "stillness detector: chi-square threshold (zero_velocity.threshold(zvd_window, alpha); the default "
                f"that of {det.samples(0.01)} samples and alpha {det.alpha}) [1]",
                zero_velocity.threshold(det.samples(0.01), det.alpha))
        declare(self, "real", "zvd_vrw", PARAMETER,
                "stillness detector: the IMU's velocity random walk (positive with zupt_source 1) [m/s/s0.5]", 0.0)
        declare(self, "real", "zvd_arw", PARAMETER,
                "stillness detector: the IMU's angle random walk (positive with zupt_source 1) [rad/s0.5]", 0.0)
        for name, text in STATE_SWITCHES:
            declare(self, "integer", name, PARAMETER, f"1: estimate the {text}; 0: not (the 15-state filter) [1]", 0)
        state_starts = {"gyro_sf0_std": fs.gyro_sf0_std, "accel_sf0_std": fs.accel_sf0_std, "sf_tau": fs.sf_tau,
                        "lever0_std": fs.lever0_std, "gnss_pos_gm_tau": g.pos_gm_tau, "gnss_vel_gm_tau": g.vel_gm_tau,
                        **{f"gnss_pos_gm_std_{a}": v for a, v in zip("enu", g.pos_gm_std)},
                        **{f"gnss_vel_gm_std_{a}": v for a, v in zip("enu", g.vel_gm_std)}}
        for name, unit, text in STATE_SETTINGS:
            declare(self, "real", name, PARAMETER, f"{text} (the optional states) [{unit}]", float(state_starts[name]))
        for q, unit in (("dtheta", "rad"), ("dv", "m/s")):
            for ax in "xyz":
                declare(self, "real", f"{q}_{ax}", INPUT, f"{q} increment over [t, t + h], body {ax} [{unit}]", 0.0)
        declare(self, "integer", "fix_valid", INPUT, "1: the fix is valid [1]", 0)
        for name, unit, text in NAV[:6]:
            declare(self, "real", f"fix_{name}", INPUT, f"GNSS fix {text} (antenna) [{unit}]", 0.0)
        declare(self, "integer", "fix_count", INPUT, "fixes given so far: a new fix when it grew [1]", 0)
        declare(self, "integer", "zaru", INPUT,
                "1: the vehicle stood still over the increments' interval: apply a zero-angular-rate update [1]", 0)
        declare(self, "integer", "zupt", INPUT,
                "1: the vehicle stood still over the increments' interval: apply a zero-velocity update with the "
                "measured velocity zupt_v_* (std zupt_std) [1]", 0)
        for ax, text in zip("enu", ("east", "north", "up")):
            declare(self, "real", f"zupt_v_{ax}", INPUT,
                    f"velocity measured at the stop, {text} (zero plus the stop's jitter; read when zupt is 1) [m/s]",
                    0.0)
        declare(self, "integer", "odo_valid", INPUT,
                "1: odo_speed is a new odometer reading at the interval's end: apply it (std odo_std) [1]", 0)
        declare(self, "real", "odo_speed", INPUT,
                "odometer speed, forward along body y (read when odo_valid is 1) [m/s]", 0.0)
        declare(self, "integer", "nhc", INPUT,
                "1: the vehicle moves on its wheels: apply the non-holonomic constraint with nhc_v_x, nhc_v_z "
                "(std nhc_std) [1]", 0)
        for ax, text in (("x", "right"), ("z", "up")):
            declare(self, "real", f"nhc_v_{ax}", INPUT,
                    f"body {ax} ({text}) velocity the constraint measures (zero plus the vehicle's jitter; read when "
                    f"nhc is 1) [m/s]", 0.0)
        declare(self, "real", "increment_end_time", INPUT,
                "time tag: end of the increments' interval; -1e9: the increments are of [t, t + h] [s]", NO_TAG)
        declare(self, "real", "fix_time", INPUT, "validity time of the fix (time-tagged mode) [s]", 0.0)
        declare(self, "real", "fix_horizon", INPUT,
                "every fix valid up to this time has been given (time-tagged mode) [s]", NO_TAG)
        for name, unit, text in NAV:
            declare(self, "real", name, OUTPUT, f"computed {text} at t + h [{unit}]", 0.0)
        for q, unit in (("bias_g", "rad/s"), ("bias_a", "m/s2")):
            for ax in "xyz":
                declare(self, "real", f"{q}_{ax}", OUTPUT, f"estimated {q.replace('_', ' ')}, body {ax} [{unit}]",
                        0.0)
        for q, unit in (("pos", "m"), ("vel", "m/s"), ("att", "rad")):
            for ax in "enu":
                declare(self, "real", f"sigma_{q}_{ax}", OUTPUT, f"filter std of the {q} error, {ax} axis [{unit}]",
                        0.0)
        for q, axes, unit, text in STATE_OUTPUTS:
            for ax in axes:
                declare(self, "real", f"{q}_{ax}", OUTPUT, f"{text}, {ax} (0 when its state is off) [{unit}]", 0.0)
        declare(self, "integer", "fixes_used", OUTPUT, "valid fixes applied so far [1]", 0)
        declare(self, "real", "nav_time", OUTPUT, "time of the navigation outputs [s]", 0.0)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the AidedINS FMU is native: fmus/c/aided_ins/model.c computes it (this class only "
                                  "declares its variables)")
