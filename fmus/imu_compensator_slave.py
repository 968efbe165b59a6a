"""IMUCompensator FMU: a trained seed 003 compensator between IMUThermal and the INS."""

from pathlib import Path

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_step, declare, discard_on_error,
                                guarded)
from sarins_fmu.identify import compensators
from sarins_fmu.thermal import SENSORS

MODEL_IN_RESOURCES = "compensator.npz"


class IMUCompensator(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Compensates the increments of an increment-output IMU with a trained seed 003 model (traditional "
        "eqs (1)-(2), RBFNN, GRNN, LSTM or GRU; plain-data model file, numpy only). Contract: inputs are the "
        "IMU's raw angle and velocity increments of the current communication step and its six sensor "
        "temperatures (Gauss-Seidel: the IMU is stepped first); the model sees the mean rate dtheta/h (rad/s), "
        "the mean specific force dv/h (m/s2) and the mean of the six temperatures (degC) and the outputs are "
        "the compensated rate and specific force times h. Recurrent models carry their hidden state from "
        "step to step (zero at initialisation); use the communication step the model was trained with. "
        "Held between steps: the recurrent state only.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=3600.0, step_size=0.05)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "model_file", PARAMETER,
                f"compensator model file (JSON/npz); empty: the one shipped in resources ({MODEL_IN_RESOURCES})", "")
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
        self._stream = None
        self._step = None

    def _model_path(self) -> Path:
        if self.model_file:
            return Path(self.model_file)
        if not self.resources:
            raise ParameterError("no model_file given and the FMU has no resources folder")
        return Path(self.resources) / MODEL_IN_RESOURCES

    @guarded
    def exit_initialization_mode(self):
        try:
            model = compensators.load(self._model_path())
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self.model_kind = compensators.KINDS.index(model.kind)
        self._stream = model.stream()
        self._step = None

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            raw = np.array([getattr(self, f"raw_dtheta_{a}") for a in "xyz"] + [getattr(self, f"raw_dv_{a}")
                                                                                for a in "xyz"])
            temps = [getattr(self, f"temp_{s}") for s in SENSORS]
            x = np.concatenate([raw / step_size, [sum(temps) / len(temps)]])
            if not np.all(np.isfinite(x)):
                raise ValueError(f"non-finite IMU input at t={current_time:.9g} s")
            y = self._stream.step(x)
        except ValueError as exc:
            return discard_on_error(self, exc)
        for i, ax in enumerate("xyz"):
            setattr(self, f"dtheta_{ax}", float(y[i] * step_size))
            setattr(self, f"dv_{ax}", float(y[3 + i] * step_size))
        self.temperature = float(x[6])
        return True
