"""RBFIdentifier FMU: seed 000's axial-drift identification from the latitude error."""

import math

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_step, declare,
                                discard_on_error, guarded)
from sarins_fmu.identify.axial import DriftIdentifier, default_model_path
from sarins_fmu.identify.modelfile import ModelFileError


class RBFIdentifier(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Axial (azimuth) gyro drift identifier of seed 000: an RBF network (model file, JSON) maps the "
        "INS latitude error, and for the cold-start model the azimuth gyro temperature and its change over "
        "the alignment, to the drift. Contract: each doStep(t, h) reads the inputs at t + h (Gauss-Seidel: "
        "the INS is stepped first); at the first step whose nav_time reaches trigger_time (within half a "
        "step) the network is evaluated once and axial_drift is held from then on (0 before). Shipped "
        "models: model_kind 'hot' or 'cold' (resources); model_file overrides them. Held between steps: "
        "the identified drift.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=88 * 3600.0, step_size=1.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "model_kind", PARAMETER, "shipped model: hot or cold", "hot")
        declare(self, "string", "model_file", PARAMETER, "model file path (empty: the shipped model)", "")
        declare(self, "real", "trigger_time", PARAMETER, "navigation time of the identification [s]",
                12 * 3600.0)
        declare(self, "real", "lat_error", INPUT, "INS latitude error [rad; deg]", 0.0)
        declare(self, "real", "temperature", INPUT, "azimuth gyro temperature [degC]", 20.0)
        declare(self, "real", "temp_change", INPUT, "azimuth gyro temperature change over the alignment [degC]",
                0.0)
        declare(self, "real", "nav_time", INPUT, "time since navigation started [s]", -1.0)
        declare(self, "real", "axial_drift", OUTPUT, "identified axial drift, held [rad/s; deg/h]", 0.0)
        declare(self, "integer", "identified", OUTPUT, "1 once the drift is identified [1]", 0)
        self._identifier = None
        self._step = None

    @guarded
    def exit_initialization_mode(self):
        check_finite(self, ["trigger_time"], non_negative=["trigger_time"])
        try:
            path = self.model_file.strip() or default_model_path(self.model_kind)
            self._identifier = DriftIdentifier(path)
        except (ModelFileError, ValueError, OSError) as exc:
            raise ParameterError(f"cannot load the identifier model: {exc}") from None
        self.axial_drift, self.identified = 0.0, 0

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            if not self.identified and self.nav_time >= self.trigger_time - 0.5 * step_size:
                drift = self._identifier.drift(self.lat_error, self.temperature, self.temp_change)
                if not math.isfinite(drift):
                    raise ValueError("the identified drift is not finite")
                self.axial_drift, self.identified = drift, 1
        except ValueError as exc:
            return discard_on_error(self, exc)
        return True
