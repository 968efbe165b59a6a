"""IMULog FMU: plays a recorded IMU log (docs/imu-log.md) as increments, e.g. into StrapdownINS.

The declaration of the native IMULog FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/imu_log/model.c`` reads the log (the project's CSV format 1, the rules of :mod:`sarins_fmu.imu_log`)
and plays it.
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import declare, default_experiment, OUTPUT, PARAMETER
from sarins_fmu.thermal import SENSORS


class IMULog(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Plays a recorded IMU log (CSV, sarins-imu-log format 1: timestamped angle and velocity "
        "increments or rates in SI units, optional temperatures; checked when loaded). Contract: FMU time 0 "
        "is the start of the log's first interval (first time_s minus the log's interval h); the "
        "communication step must equal h; after doStep(t, h) the outputs are the log's increments over "
        "(t, t + h] in body axes, tagged increment_end_time = t + h as StrapdownINS expects, and the six "
        "temperatures at t + h (20 degC when the log has none). "
        "lat_deg, lon_deg and height_m of the log are outputs, to set the INS start from. A missing or bad "
        "log fails fmi2ExitInitializationMode naming the line (an NPZ, gzip, vendor CSV, i2Nav or ROS "
        "log is refused naming the conversion: write it with sarins_fmu.imu_log.write_log as .csv); stepping "
        "past the end of the log fails the step. Held between steps: the sample index.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "log_file", PARAMETER, "path of the IMU log (CSV format 1)", "")
        for ax in "xyz":
            declare(self, "real", f"dtheta_{ax}", OUTPUT, f"angle increment about body {ax} over the step [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"dv_{ax}", OUTPUT, f"velocity increment along body {ax} over the step [m/s]", 0.0)
        for sensor in SENSORS:
            declare(self, "real", f"temp_{sensor}", OUTPUT, f"temperature of the {sensor} sensor [degC]", 20.0)
        declare(self, "real", "log_time", OUTPUT, "log timestamp of the current outputs [s]", 0.0)
        declare(self, "real", "increment_end_time", OUTPUT,
                "time tag: FMU time at the end of the increments' interval (0: none yet) [s]", 0.0)
        declare(self, "real", "log_step", OUTPUT, "sample interval of the log [s]", 0.0)
        declare(self, "real", "lat_deg", OUTPUT, "static start latitude of the log [deg]", 0.0)
        declare(self, "real", "lon_deg", OUTPUT, "static start longitude of the log [deg]", 0.0)
        declare(self, "real", "height_m", OUTPUT, "static start height of the log [m]", 0.0)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the IMULog FMU is native: fmus/c/imu_log/model.c plays the log (this "
                                  "class only declares it)")
