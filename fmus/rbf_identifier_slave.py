"""RBFIdentifier FMU: seed 000's axial-drift identification from the latitude error."""

import math

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment

from fmus.slave_support import (INPUT, OUTPUT, PARAMETER, ParameterError, check_finite, check_step, declare,
                                discard_on_error, guarded, same_time)
from sarins_fmu.identify.axial import APPLY_LATENCY, DriftIdentifier, default_model_path
from sarins_fmu.identify.modelfile import ModelFileError


class RBFIdentifier(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Axial (azimuth) gyro drift identifier of seed 000: an RBF network (model file, JSON) maps the "
        "INS latitude error, and for the cold-start model the azimuth gyro temperature and its change over "
        "the alignment, to the drift. Contract (standard FMI timing, time-tagged): the inputs are the INS "
        "outputs tagged nav_time. The network is evaluated once, on the inputs whose nav_time equals "
        "trigger_time exactly (to 1e-6 of a step); a nav_time that passes the trigger without meeting it is an "
        "error. It then outputs axial_drift (0 before), held, with apply_from = trigger_time + latency: the "
        "INS subtracts it from the navigation interval starting at apply_from on. latency (a few steps) "
        "covers the delay of any co-simulation scheme, so every scheme gives the same navigation solution. "
        "All outputs are state outputs (no direct feedthrough). Shipped models: model_kind 'hot' or 'cold' "
        "(resources); model_file overrides them. Held between steps: the identified drift.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=88 * 3600.0, step_size=1.0)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "model_kind", PARAMETER, "shipped model: hot or cold", "hot")
        declare(self, "string", "model_file", PARAMETER, "model file path (empty: the shipped model)", "")
        declare(self, "real", "trigger_time", PARAMETER, "navigation time of the identification [s]",
                12 * 3600.0)
        declare(self, "real", "latency", PARAMETER,
                "delay from trigger_time to the first compensated navigation interval [s]", APPLY_LATENCY)
        declare(self, "real", "lat_error", INPUT, "INS latitude error at nav_time [rad; deg]", 0.0)
        declare(self, "real", "temperature", INPUT, "azimuth gyro temperature at nav_time [degC]", 20.0)
        declare(self, "real", "temp_change", INPUT, "azimuth gyro temperature change over the alignment [degC]",
                0.0)
        declare(self, "real", "nav_time", INPUT, "time tag of the inputs: time since navigation started [s]", -1.0)
        declare(self, "real", "axial_drift", OUTPUT, "identified axial drift, held [rad/s; deg/h]", 0.0)
        declare(self, "real", "apply_from", OUTPUT,
                "navigation time from which the INS subtracts axial_drift [s]", 0.0)
        declare(self, "integer", "identified", OUTPUT, "1 once the drift is identified [1]", 0)
        self._identifier = None
        self._step = None

    @guarded
    def exit_initialization_mode(self):
        check_finite(self, ["trigger_time", "latency"], non_negative=["trigger_time", "latency"])
        name = "model_file" if self.model_file.strip() else "model_kind"
        try:
            path = self.model_file.strip() or default_model_path(self.model_kind)
            self._identifier = DriftIdentifier(path)
        except (ModelFileError, ValueError, OSError) as exc:
            raise ParameterError(f"parameter {name} = {getattr(self, name)!r}: cannot load the identifier model: "
                                 f"{exc}") from None
        self.axial_drift, self.identified, self.apply_from = 0.0, 0, 0.0

    @guarded
    def do_step(self, current_time, step_size):
        try:
            self._step = check_step(self, step_size, self._step)
            if not self.identified and same_time(self.nav_time, self.trigger_time, step_size):
                drift = self._identifier.drift(self.lat_error, self.temperature, self.temp_change)
                if not math.isfinite(drift):
                    raise ValueError("the identified drift is not finite")
                self.axial_drift, self.identified = drift, 1
                self.apply_from = self.trigger_time + self.latency
            elif not self.identified and self.nav_time > self.trigger_time:
                raise ValueError(f"nav_time {self.nav_time:.9g} s passed trigger_time {self.trigger_time:.9g} s "
                                 "without meeting it (put the trigger on the communication grid)")
        except ValueError as exc:
            return discard_on_error(self, exc)
        return True
