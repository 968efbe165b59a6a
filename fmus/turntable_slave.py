"""Turntable FMU: gimbal angles, rates and accelerations of a rotation scheme.

The declaration of the native Turntable FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/turntable/model.c`` computes it (the schedule and ambient builders of the C core).
"""

from pythonfmu import Fmi2Slave

from fmus.native_fmu import ArrayVariable
from fmus.slave_support import declare, default_experiment, OUTPUT, PARAMETER
from sarins_fmu import turntable
from sarins_fmu.units import DEG_TO_RAD


class Turntable(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Turntable of a rotating INS or a rate table (truth motion). Gimbal chains: single-axis schemes 'z'; "
        "dual-axis 'y,z'; rate-table-3axis, tumble-24 and rate-test 'z,x,y' (set the IMU's 'gimbals' to match). "
        "Contract (standard FMI timing, any master scheme): the outputs describe the motion segment that "
        "STARTS at motion_time: gimbal angles and rates at motion_time and the angular acceleration that holds "
        "from there to the next communication point (accelerations change only on the 'grid', a multiple of "
        "the communication step), plus the ambient (chamber) temperature at motion_time and its slope "
        "ambient_temp_rate over [motion_time, motion_time + h], h the communication step (the IMU takes the "
        "ambient linear over each step; at initialisation, before h is known, the slope is over [start, start + "
        "grid]: start a chamber profile with a hold, as its warm-up does). At initialisation motion_time is "
        "the start time; after doStep(t, h) it is t + h. All outputs "
        "are state outputs (no direct feedthrough). A connected IMU rebuilds the motion over its step [t, t+h] "
        "exactly from the set tagged t: under Jacobi it receives that set, under Gauss-Seidel (turntable "
        "stepped first) it receives the set tagged t + h and uses the one it kept from its previous step. "
        "Angles are not wrapped. Nothing but the schedule and the time is held between steps. "
        "Sub-intervals (n_sub = K, default 1; the *_sub arrays are FMI 3.0 only, and the FMI 2.0 variant refuses "
        "K > 1): element k of each *_sub array is the output of the same name that this turntable with n_sub = 1 "
        "stepped at h / K shows at motion_time + k h / K (times on the master's grid begin + j h / K), so the "
        "schedule breakpoints need only lie on the grid of h / K (a step may span them; the chamber profile's "
        "corners need not: each sub-interval's ambient is the chord of the profile, as at n_sub = 1). The "
        "scalars keep their meaning at motion_time: angle and rate there, accel the acceleration holding from "
        "there to the first sub-interval boundary (= accel_j_sub[0]; not constant over a step that spans a "
        "breakpoint: read the arrays), ambient_temp_rate the slope over the whole step [motion_time, "
        "motion_time + h] (= ambient_temp_rate_sub[0] only if K = 1 or the ambient is linear over the step). "
        "At initialisation, before h is known, the sub-intervals are taken grid long, so a first step with h / K "
        "other than grid is refused.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults
    # FMI 3.0 only (fmus/native_fmu.py): every sub-interval of the coming step, n_sub elements each
    fmi3_arrays = tuple(
        ArrayVariable(f"{name}_sub", "n_sub", "output", f"{what} at the start of each of the n_sub sub-intervals "
                      f"of the coming step, in time order [{unit}]")
        for name, what, unit in (
            *((f"angle_{j}", f"angle of gimbal {j}", "rad") for j in (1, 2, 3)),
            *((f"rate_{j}", f"angular rate of gimbal {j}", "rad/s") for j in (1, 2, 3)),
            *((f"accel_{j}", f"angular acceleration of gimbal {j} (holding over the sub-interval)", "rad/s2")
              for j in (1, 2, 3)),
            ("ambient_temp", "ambient / chamber temperature", "degC"),
            ("ambient_temp_rate", "slope of the ambient over the sub-interval", "degC/s")))

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "scheme", PARAMETER,
                "rotation scheme: " + ", ".join(turntable.SCHEMES), "forward-reverse")
        declare(self, "real", "rate", PARAMETER, "peak rotation rate [rad/s; deg/s]", 6.0 * DEG_TO_RAD)
        declare(self, "real", "accel", PARAMETER, "angular acceleration of the moves [rad/s2; deg/s2]", 6.0 * DEG_TO_RAD)
        declare(self, "real", "dwell", PARAMETER, "stop at each position or reversal [s]", 0.0)
        declare(self, "integer", "revolutions", PARAMETER, "turns each way (forward-reverse) [1]", 1)
        declare(self, "real", "align_time", PARAMETER,
                "initial four-position indexing for the alignment (0: none) [s]", 4 * 3600.0)
        declare(self, "real", "align_dwell", PARAMETER, "stop at each alignment position [s]", 300.0)
        declare(self, "real", "grid", PARAMETER, "time grid of acceleration changes [s]", 1.0)
        declare(self, "real", "duration", PARAMETER, "length of the generated pattern [s]", 100 * 3600.0)
        declare(self, "real", "outer_rate", PARAMETER, "dual-axis: outer flip rate [rad/s; deg/s]", 6.0 * DEG_TO_RAD)
        declare(self, "real", "outer_accel", PARAMETER, "dual-axis: outer flip acceleration [rad/s2; deg/s2]",
                6.0 * DEG_TO_RAD)
        for name, rate, acc in (("inner", 1.0, 0.01), ("middle", 10.0, 0.1), ("outer", 100.0, 1.0)):
            declare(self, "real", f"table_{name}_rate", PARAMETER,
                    f"rate-table-3axis: {name} gimbal peak rate [rad/s; deg/s]", rate * DEG_TO_RAD)
            declare(self, "real", f"table_{name}_accel", PARAMETER,
                    f"rate-table-3axis: {name} gimbal acceleration [rad/s2; deg/s2]", acc * DEG_TO_RAD)
        declare(self, "real", "warmup", PARAMETER, "rate-table-3axis: static warm-up [s]", 600.0)
        declare(self, "string", "ambient_mode", PARAMETER,
                "ambient: 'sinusoid' (mean, amplitude, period) or 'chamber' (ramp/hold cycle)", "sinusoid")
        declare(self, "real", "chamber_low", PARAMETER, "chamber low temperature [degC]", -25.0)
        declare(self, "real", "chamber_high", PARAMETER, "chamber high temperature [degC]", 40.0)
        declare(self, "real", "chamber_ramp", PARAMETER, "chamber ramp rate [degC/s]", 1.0 / 60.0)
        declare(self, "real", "chamber_hold", PARAMETER, "chamber hold at each end [s]", 1800.0)
        declare(self, "string", "chamber_first", PARAMETER, "chamber: end of the first ramp, 'low' or 'high'", "low")
        declare(self, "real", "chamber_step", PARAMETER,
                "chamber: intermediate stop every this much on the ramps between the ends (0: none) [degC]", 0.0)
        declare(self, "real", "chamber_step_hold", PARAMETER, "chamber: length of each intermediate stop [s]", 0.0)
        declare(self, "real", "ambient_mean", PARAMETER, "ambient temperature mean (chamber start) [degC]", 20.0)
        declare(self, "real", "ambient_amplitude", PARAMETER, "ambient daily amplitude [degC]", 0.0)
        declare(self, "real", "ambient_period", PARAMETER, "ambient period [s]", 86400.0)
        for j in (1, 2, 3):
            declare(self, "real", f"angle_{j}", OUTPUT, f"angle of gimbal {j} (outer = 1) at motion_time [rad; deg]",
                    0.0)
            declare(self, "real", f"rate_{j}", OUTPUT, f"angular rate of gimbal {j} at motion_time [rad/s; deg/s]",
                    0.0)
            declare(self, "real", f"accel_{j}", OUTPUT,
                    f"angular acceleration of gimbal {j} from motion_time on [rad/s2; deg/s2]", 0.0)
        declare(self, "real", "ambient_temp", OUTPUT, "ambient / chamber temperature at motion_time [degC]", 20.0)
        declare(self, "real", "ambient_temp_rate", OUTPUT,
                "slope of the ambient over the step from motion_time [degC/s]", 0.0)
        declare(self, "real", "motion_time", OUTPUT, "time tag: start of the segment the outputs describe [s]", 0.0)
        declare(self, "integer", "n_gimbals", OUTPUT, "number of gimbals in use [1]", 1)
        # last, so that the value references of the variables above stay those of the earlier builds
        declare(self, "integer", "n_sub", PARAMETER,
                "sub-intervals per communication step [1]: the *_sub arrays describe the K sub-intervals of "
                "h / K of the coming step, and the schedule's breakpoints need only lie on the grid of h / K. "
                "1: one interval per step. FMI 3.0: a structural parameter, the length of the *_sub arrays; "
                "FMI 2.0 (no arrays): 1 only", 1)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the Turntable FMU is native: fmus/c/turntable/model.c computes it (this class "
                                  "only declares its variables)")
