"""IMUCompensator FMU: a trained seed 003 compensator between IMUThermal and the INS.

The declaration of the native IMUCompensator FMU: its variables, descriptions, start values and the
timing contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it;
``fmus/c/imu_compensator/model.c`` computes it (``sarins_comp_run`` of the C core, the function the
library's compensators call in process).  The trained model travels in resources as a binary model file
(:func:`fmus.compensator_export.export_compensator`).
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import declare, default_experiment, INPUT, NO_TAG, OUTPUT, PARAMETER
from sarins_fmu.identify import compensators
from sarins_fmu.thermal import SENSORS

MODEL_IN_RESOURCES = "compensator.bin"


class IMUCompensator(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Compensates the increments of an increment-output IMU with a trained seed 003 model (traditional "
        "eqs (1)-(2), RBFNN, GRNN, LSTM or GRU; binary model file, evaluated in C in float64). Contract (standard FMI "
        "timing, time-tagged, any master scheme): inputs are the IMU's raw angle and velocity increments of the "
        "interval ending at raw_increment_end_time (connect the IMU's increment_end_time) and its six sensor "
        "temperatures there. Each doStep compensates that interval once, in order: a repeated tag (Jacobi's "
        "first step) or the start time (no increments yet) waits, a skipped interval is an error; the outputs "
        "carry the interval's tag increment_end_time and its z gyro temperature temp_azimuth_gyro (connect both "
        "to the INS). If raw_increment_end_time is not connected, the inputs are taken as the current step's "
        "(Gauss-Seidel, IMU stepped first). The model sees the mean rate dtheta/h (rad/s), "
        "the mean specific force dv/h (m/s2) and the mean of the six temperatures (degC) and the outputs are "
        "the compensated rate and specific force times h. Recurrent models carry their hidden state from "
        "step to step (zero at initialisation); use the communication step the model was trained with. "
        "The model is read at the end of initialisation from model_file or resources/compensator.bin; a "
        "missing or bad file is an error there naming the file and the reason. Held between steps (and in "
        "the FMU state): the recurrent state and the last time tag.")
    default_experiment = default_experiment(0.05)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "model_file", PARAMETER,
                f"compensator binary model file (Compensator.export_binary); empty: the one shipped in resources "
                f"({MODEL_IN_RESOURCES})", "")
        for ax in "xyz":
            declare(self, "real", f"raw_dtheta_{ax}", INPUT, f"raw angle increment about body {ax} [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"raw_dv_{ax}", INPUT, f"raw velocity increment along body {ax} [m/s]", 0.0)
        for sensor in SENSORS:
            declare(self, "real", f"temp_{sensor}", INPUT, f"temperature of the {sensor} sensor [degC]", 20.0)
        for ax in "xyz":
            declare(self, "real", f"dtheta_{ax}", OUTPUT, f"compensated angle increment about body {ax} [rad]", 0.0)
        for ax in "xyz":
            declare(self, "real", f"dv_{ax}", OUTPUT, f"compensated velocity increment along body {ax} [m/s]", 0.0)
        declare(self, "real", "temperature", OUTPUT, "mean sensor temperature the model sees [degC]", 20.0)
        declare(self, "integer", "model_kind", OUTPUT,
                "loaded model: " + ", ".join(f"{i} {k}" for i, k in enumerate(compensators.KINDS)) + " [1]", -1)
        declare(self, "real", "raw_increment_end_time", INPUT, "time tag: end of the raw increments' interval [s]",
                NO_TAG)
        declare(self, "real", "increment_end_time", OUTPUT,
                "time tag: end of the interval of the compensated increments [s]", 0.0)
        declare(self, "real", "temp_azimuth_gyro", OUTPUT, "z gyro temperature at increment_end_time [degC]", 20.0)

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the IMUCompensator FMU is native: fmus/c/imu_compensator/model.c computes it "
                                  "(this class only declares its variables)")
