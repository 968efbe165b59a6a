"""IMUCompensator FMU: a trained seed 003 compensator between IMUThermal and the INS."""

import math
from pathlib import Path

import numpy as np
from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, NO_TAG, OUTPUT, PARAMETER, ParameterError, check_step, declare,
                                discard_on_error, guarded, same_time)
from sarins_fmu.identify import compensators
from sarins_fmu.thermal import SENSORS

MODEL_IN_RESOURCES = "compensator.npz"


class IMUCompensator(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Compensates the increments of an increment-output IMU with a trained seed 003 model (traditional "
        "eqs (1)-(2), RBFNN, GRNN, LSTM or GRU; plain-data model file, numpy only). Contract (standard FMI "
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
        declare(self, "real", "raw_increment_end_time", INPUT, "time tag: end of the raw increments' interval [s]",
                NO_TAG)
        declare(self, "real", "increment_end_time", OUTPUT,
                "time tag: end of the interval of the compensated increments [s]", 0.0)
        declare(self, "real", "temp_azimuth_gyro", OUTPUT, "z gyro temperature at increment_end_time [degC]", 20.0)
        self._stream = None
        self._step = None
        self._start_time = 0.0
        self._last_tag = None

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._start_time = float(start_time)

    def enter_initialization_mode(self):
        self._publish_start()

    def _publish_start(self):
        self.increment_end_time = self._start_time  # no increments yet
        self.temp_azimuth_gyro = self.temp_gyro_z

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
        self._last_tag = None
        self._publish_start()

    def _interval(self, current_time, step_size):
        """End time of the interval to compensate now, or None if no new one arrived."""
        tag = float(self.raw_increment_end_time)
        if tag == NO_TAG:
            return current_time + step_size  # untagged: the current step's increments
        if not math.isfinite(tag):
            raise ValueError("raw_increment_end_time is not finite")
        last = self._last_tag
        if tag <= self._start_time + 1e-6 * step_size or (last is not None and same_time(tag, last, step_size)):
            return None
        expected = (self._start_time if last is None else last) + step_size
        if not same_time(tag, expected, step_size):
            raise ValueError(f"raw increments tagged raw_increment_end_time={tag:.9g} s where the interval ending at "
                             f"{expected:.9g} s was due (each interval once, in order)")
        self._last_tag = tag
        return tag

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            end = self._interval(current_time, step_size)
            if end is None:
                return True
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
        self.increment_end_time = end
        self.temp_azimuth_gyro = self.temp_gyro_z
        return True
