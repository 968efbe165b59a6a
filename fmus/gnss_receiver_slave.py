"""GNSSReceiver FMU: GNSS position/velocity fixes of a moving antenna (the C core's gnss.h).

The declaration of the native GNSSReceiver FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/gnss_receiver/model.c`` computes it (the C core's receiver, ``sarins_fmu/core/gnss.h``, which
:func:`sarins_fmu.gnss.simulate` runs in process).
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import INPUT, NO_TAG, OUTPUT, PARAMETER, declare, default_experiment
from sarins_fmu.gnss import GNSSConfig


class GNSSReceiver(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "A GNSS receiver (sarins_fmu.gnss, the C core's gnss.h): position and velocity fixes with white and "
        "first-order Gauss-Markov errors per ENU axis, an antenna lever arm (body right-front-up) and outage "
        "windows, seeded (seed). Inputs: the truth at the communication point t (lat, lon rad, height m, v_e v_n "
        "v_u m/s, yaw pitch roll rad as mat_nb = Rz(yaw) Rx(pitch) Ry(roll), omega_ib body rad/s). Fix epochs are "
        "the communication points t_k = start + k h, k = m every (m = 1, 2, ...; every = 1 / (rate_hz h), a whole "
        "number: the step is fixed). Contract: doStep(t_k, h) at an epoch computes the fix valid at t_k from "
        "the inputs set for t_k and publishes it after the step: fix_time = t_k, fix_count + 1, fix_valid 0 "
        "inside an outage window [start, end) ('start:end;start:end' s, at most 16; the error processes keep "
        "running). Between epochs the outputs hold the last fix. Latency is the consumer's (fix_time tags the "
        "fix). Time-tagged truth (truth_time connected, e.g. from TrajectoryIMU): the inputs are the truth at "
        "truth_time, a communication point; each point's truth is taken once, in order (a repeated tag waits: "
        "Jacobi's one-step delay), an epoch's fix is computed when its truth arrives, and fix_horizon says up to "
        "which time every fix has been published, so a consumer gets the same fixes under Gauss-Seidel and "
        "Jacobi. Unconnected (truth_time = -1e9), the inputs are the truth at t. Outputs are state outputs (no "
        "direct feedthrough). FMU state: get, set and serialize.")
    default_experiment = default_experiment(0.01)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        cfg = GNSSConfig()
        declare(self, "real", "rate_hz", PARAMETER, "fix rate, 1 .. 20 Hz, a whole number of steps per fix [Hz]",
                cfg.rate_hz)
        declare(self, "integer", "seed", PARAMETER, "seed of the receiver errors [1]", 0)
        for i, ax in enumerate("xyz"):
            declare(self, "real", f"lever_{ax}", PARAMETER,
                    f"antenna lever arm, body {'right front up'.split()[i]} axis [m]", cfg.lever_arm[i])
        for name, values, unit, text in (("pos_white", cfg.pos_white_std, "m", "white position error std"),
                                         ("pos_gm", cfg.pos_gm_std, "m", "Gauss-Markov position error std"),
                                         ("vel_white", cfg.vel_white_std, "m/s", "white velocity error std"),
                                         ("vel_gm", cfg.vel_gm_std, "m/s", "Gauss-Markov velocity error std")):
            for i, ax in enumerate("enu"):
                declare(self, "real", f"{name}_{ax}", PARAMETER, f"{text}, {ax} axis [{unit}]", values[i])
            if name.endswith("gm"):
                declare(self, "real", f"{name}_tau", PARAMETER, f"{text[:-4]} correlation time [s]",
                        cfg.pos_gm_tau if name == "pos_gm" else cfg.vel_gm_tau)
        declare(self, "string", "outages", PARAMETER, "outage windows 'start:end;start:end' [s], at most 16", "")
        for name, unit, text in (("lat", "rad; deg", "latitude"), ("lon", "rad; deg", "longitude"),
                                 ("height", "m", "height"), ("v_e", "m/s", "east velocity"),
                                 ("v_n", "m/s", "north velocity"), ("v_u", "m/s", "up velocity"),
                                 ("yaw", "rad; deg", "yaw (CCW from north)"), ("pitch", "rad; deg", "pitch"),
                                 ("roll", "rad; deg", "roll")):
            declare(self, "real", name, INPUT, f"true {text} of the body at t [{unit}]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"omega_ib_{ax}", INPUT, f"true body rate wrt inertial space, {ax} axis [rad/s]",
                    0.0)
        declare(self, "real", "truth_time", INPUT, "time tag of the truth inputs; -1e9: the truth is at t [s]", NO_TAG)
        declare(self, "integer", "fix_valid", OUTPUT, "1: the last fix is valid, 0: outage or no fix yet [1]", 0)
        for name, unit, text in (("fix_lat", "rad; deg", "latitude"), ("fix_lon", "rad; deg", "longitude"),
                                 ("fix_height", "m", "height"), ("fix_v_e", "m/s", "east velocity"),
                                 ("fix_v_n", "m/s", "north velocity"), ("fix_v_u", "m/s", "up velocity")):
            declare(self, "real", name, OUTPUT, f"antenna {text} of the last fix [{unit}]", 0.0)
        declare(self, "real", "fix_time", OUTPUT, "validity time of the last fix (start time before the first) [s]",
                0.0)
        declare(self, "integer", "fix_count", OUTPUT, "fixes given so far (a new fix: it grew) [1]", 0)
        declare(self, "real", "fix_horizon", OUTPUT,
                "time of the truth last taken: every fix valid up to it is published (-1e9 before the first) [s]",
                NO_TAG)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the GNSSReceiver FMU is native: fmus/c/gnss_receiver/model.c computes it (this "
                                  "class only declares its variables)")
