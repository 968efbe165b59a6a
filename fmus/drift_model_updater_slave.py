"""DriftModelUpdater FMU: seed 002's online update of the azimuth-drift model (Fig. 2).

The declaration of the native DriftModelUpdater FMU: its variables, descriptions, start values and the
timing contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/drift_model_updater/model.c`` computes it on the C core's stop filter, forgetting-factor RLS and
Fig. 2 row logic (``sarins_fmu/core/online.h``), which the library's
:class:`~sarins_fmu.identify.online.OnlineDriftUpdater` runs in process.
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import declare, default_experiment, INPUT, NO_TAG, OUTPUT, PARAMETER
from sarins_fmu.identify.axial import APPLY_LATENCY
from sarins_fmu.kalman import StopFilterSettings
from sarins_fmu.units import DAY, DEG_TO_RAD, DPH_TO_RPS

NAVIGATE = 2  # StrapdownINS 'phase' output value in navigation
P_UNITS = {"p_aa": "1/degC4", "p_ab": "1/degC3", "p_ac": "1/degC2", "p_bb": "1/degC2", "p_bc": "1/degC", "p_cc": "1"}
P_INDEX = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]


class DriftModelUpdater(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Online update of the azimuth gyro drift model eps(T) = a T^2 + b T + c (seed 002, Fig. 2). "
        "Contract (standard FMI timing, time-tagged, any master scheme): the INS inputs are one row of the INS's "
        "outputs, tagged solution_time (the simulation time they refer to; if solution_time is not connected, "
        "nav_time orders the rows); each doStep processes the row whose tag follows the last one processed by "
        "one step (a repeated tag, e.g. Jacobi's first steps, or the INS's initial outputs at the start time are "
        "skipped; a skipped row is an error). vehicle_speed tagged speed_time (the vehicle's time tag) is paired "
        "with the INS row of the same time: the updater keeps the last 8 speeds, so a speed that arrives before "
        "the row (Jacobi: two links ahead) is found; a row without its speed is an error (fmi2Error with the "
        "tags). If speed_time is not connected, vehicle_speed is taken as it is at each doStep. The updater's "
        "clock is start_day + nav_time of the row. The vehicle is stopped while vehicle_speed < speed_threshold "
        "and the INS navigates (ins_phase = 2 and nav_time >= 0: the phase input may be held at 2, the row's "
        "nav_time tells); at the start of a stop a static Kalman filter (velocity = 0 measurement, states "
        "attitude, velocity, gyro drifts incl. the azimuth drift, accelerometer biases, north position) is "
        "reset and a timer starts; when the vehicle moves off, a stop of at least time_threshold updates the "
        "model by forgetting-factor RLS (lambda^(dt/m)) with the pair (mean gyro temperature, estimated "
        "drift); a shorter stop is discarded. Outputs: the current model drift_a, drift_b, drift_c (connect to "
        "StrapdownINS axial_drift_correction_a, _b and axial_drift_correction: the INS evaluates it at each "
        "interval's temperature) and compensation_drift = the model at temp_gyro_z of the row (for an INS "
        "taking a constant), both to be applied from nav time apply_from = row nav_time + latency on "
        "(axial_drift_apply_from; at initialisation -1e9 s: the initial model applies from the start). One step "
        "of latency is enough for any scheme (under Jacobi the INS reads the updater's output of the row before "
        "the interval it integrates). All outputs are state outputs (no direct feedthrough). The initial model "
        "is a0, b0, c0 with prior_points equivalent calibration points spread over prior_t_min..prior_t_max, or "
        "the RLS state in model_file (the binary model file written by sarins_fmu.identify.rls.ForgettingRLS."
        "export_binary('name.bin'), every byte described in sources/netfile.h and rls.h, read at initialisation; its "
        "forgetting settings must equal forgetting_factor and forgetting_time_scale); the outputs p_aa..p_cc (its inverse "
        "information) and model_time (the time of its last update) with drift_a/b/c give the state back, so a "
        "next run can continue from it. last_stop_* describe the last finished stop (last_stop_used 1: it "
        "updated the model). Held between steps: the model and its RLS information, the filter, the stop "
        "timer, the last speeds (all in the FMU state). The first doStep fixes the step: the filter's interval "
        "is the communication step (a step other than 1 s rebuilds the filter and the initial model then).")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "real", "a0", PARAMETER, "initial model a [rad/s/degC2]", 1.0e-6 * DPH_TO_RPS)
        declare(self, "real", "b0", PARAMETER, "initial model b [rad/s/degC]", -4.0e-5 * DPH_TO_RPS)
        declare(self, "real", "c0", PARAMETER, "initial model c [rad/s; deg/h]", 0.0025 * DPH_TO_RPS)
        declare(self, "real", "prior_points", PARAMETER,
                "weight of the initial model as a number of calibration points [1]", 11.0)
        declare(self, "real", "prior_t_min", PARAMETER, "lowest calibration temperature [degC]", 0.0)
        declare(self, "real", "prior_t_max", PARAMETER, "highest calibration temperature [degC]", 50.0)
        declare(self, "real", "start_day", PARAMETER, "time of nav_time = 0 since the calibration [d]", 0.0)
        declare(self, "real", "latency", PARAMETER,
                "delay from a row's nav_time to the first navigation interval compensated with it [s]",
                APPLY_LATENCY)
        declare(self, "real", "forgetting_factor", PARAMETER, "forgetting factor lambda per time scale [1]", 0.8)
        declare(self, "real", "forgetting_time_scale", PARAMETER, "forgetting time scale m (one month) [s]",
                30.0 * DAY)
        declare(self, "real", "time_threshold", PARAMETER, "shortest stop used for an update [s]", 1800.0)
        declare(self, "real", "speed_threshold", PARAMETER, "speed below which the vehicle is stopped [m/s]", 0.01)
        defaults = StopFilterSettings()
        declare(self, "real", "kf_arw", PARAMETER, "stop filter gyro angle random walk [rad/sqrt(s)]", defaults.arw)
        declare(self, "real", "kf_vrw", PARAMETER, "stop filter velocity random walk [m/s/sqrt(s)]", defaults.vrw)
        declare(self, "real", "kf_velocity_meas_std", PARAMETER, "stop filter velocity noise [m/s]",
                defaults.velocity_meas_std)
        declare(self, "real", "kf_heading0_std", PARAMETER, "stop filter initial heading error [rad; deg]",
                defaults.heading0_std)
        declare(self, "real", "v_e", INPUT, "INS east velocity [m/s]", 0.0)
        declare(self, "real", "v_n", INPUT, "INS north velocity [m/s]", 0.0)
        declare(self, "real", "yaw", INPUT, "INS yaw, CCW from north [rad; deg]", 0.0)
        declare(self, "real", "pitch", INPUT, "INS pitch [rad; deg]", 0.0)
        declare(self, "real", "roll", INPUT, "INS roll [rad; deg]", 0.0)
        declare(self, "real", "lat", INPUT, "INS latitude [rad; deg]", 40.0 * DEG_TO_RAD)
        declare(self, "real", "temp_gyro_z", INPUT, "azimuth gyro temperature [degC]", 20.0)
        declare(self, "real", "nav_time", INPUT, "time tag of the INS inputs: INS nav_time [s]", 0.0)
        declare(self, "real", "vehicle_speed", INPUT, "vehicle speed (odometer) [m/s]", 0.0)
        declare(self, "integer", "ins_phase", INPUT, "INS phase; stops count only in navigation (2) [1]", NAVIGATE)
        for name, unit, text in (("drift_a", "rad/s/degC2", "current model a"),
                                 ("drift_b", "rad/s/degC", "current model b"),
                                 ("drift_c", "rad/s; deg/h", "current model c"),
                                 ("compensation_drift", "rad/s; deg/h", "current model at temp_gyro_z"),
                                 ("apply_from", "s", "nav time from which the INS applies compensation_drift"),
                                 ("stop_timer", "s", "estimation time of the current stop"),
                                 ("drift_estimate", "rad/s; deg/h", "current stop's azimuth drift estimate"),
                                 ("drift_estimate_std", "rad/s; deg/h", "its filter standard deviation"),
                                 ("last_update_drift", "rad/s; deg/h", "drift of the last model update"),
                                 ("last_update_temp", "degC", "mean gyro temperature of the last update")):
            declare(self, "real", name, OUTPUT, f"{text} [{unit}]", 0.0)
        declare(self, "integer", "stopped", OUTPUT, "1 while a stop is being estimated [1]", 0)
        declare(self, "integer", "n_updates", OUTPUT, "model updates so far [1]", 0)
        declare(self, "integer", "n_resets", OUTPUT, "stops discarded as too short [1]", 0)
        declare(self, "string", "model_file", PARAMETER,
                "initial RLS state (binary model file of ForgettingRLS.export_binary); empty: a0, b0, c0 and "
                "prior_*", "")
        declare(self, "real", "solution_time", INPUT, "time tag of the INS inputs: INS solution_time [s]", NO_TAG)
        declare(self, "real", "speed_time", INPUT, "time tag of vehicle_speed [s]", NO_TAG)
        declare(self, "real", "row_time", OUTPUT, "tag (solution_time, else nav_time) of the last row processed [s]",
                NO_TAG)
        for name, unit in P_UNITS.items():
            declare(self, "real", name, OUTPUT, f"RLS inverse information {name[2:]} [{unit}]", 0.0)
        declare(self, "real", "model_time", OUTPUT, "clock time of the model's last update or initialisation [s]",
                0.0)
        for name, unit, text in (("last_stop_time", "s", "clock time at which it ended"),
                                 ("last_stop_duration", "s", "its estimation time"),
                                 ("last_stop_temp", "degC", "its mean gyro temperature"),
                                 ("last_stop_drift", "rad/s; deg/h", "its azimuth drift estimate"),
                                 ("last_stop_drift_std", "rad/s; deg/h", "its filter standard deviation")):
            declare(self, "real", name, OUTPUT, f"last finished stop: {text} [{unit}]", 0.0)
        declare(self, "integer", "last_stop_used", OUTPUT, "last finished stop updated the model (1) or not [1]", 0)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the DriftModelUpdater FMU is native: fmus/c/drift_model_updater/model.c computes "
                                  "it (this class only declares its variables)")
