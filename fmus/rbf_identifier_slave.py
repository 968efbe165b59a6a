"""RBFIdentifier FMU: seed 000's axial-drift identification from the latitude error.

The declaration of the native RBFIdentifier FMU: its variables, descriptions, start values and the timing
contract.  ``fmus/native_fmu.py`` writes the model description and the C variable table from it and ships
the hot and cold models as binary model files in resources; ``fmus/c/rbf_identifier/model.c`` computes it
(``sarins_axial_drift`` of the C core, the function :class:`sarins_fmu.identify.axial.DriftIdentifier` calls).
"""

from pythonfmu import Fmi2Slave

from fmus.slave_support import declare, default_experiment, INPUT, OUTPUT, PARAMETER
from sarins_fmu.identify.axial import APPLY_LATENCY


class RBFIdentifier(Fmi2Slave):

    author = "sarins-fmu"
    description = (
        "Axial (azimuth) gyro drift identifier of seed 000: an RBF network (binary model file) maps the "
        "INS latitude error, and for the cold-start model the azimuth gyro temperature and its change over "
        "the alignment, to the drift. Contract (standard FMI timing, time-tagged): the inputs are the INS "
        "outputs tagged nav_time. The network is evaluated once, on the inputs whose nav_time equals "
        "trigger_time exactly (to 1e-6 of a step); a nav_time that passes the trigger without meeting it is an "
        "error. It then outputs axial_drift (0 before), held, with apply_from = trigger_time + latency: the "
        "INS subtracts it from the navigation interval starting at apply_from on. latency (a few steps) "
        "covers the delay of any co-simulation scheme, so every scheme gives the same navigation solution. "
        "All outputs are state outputs (no direct feedthrough). Shipped models: model_kind 'hot' or 'cold' "
        "(resources/axial_rbf_hot.bin, axial_rbf_cold.bin); model_file overrides them: a binary model file "
        "written by 'sarins identify train --out model.bin' (or DriftIdentifier.export_binary). The model is "
        "read at the end of initialisation; a missing or bad file is an error there naming the file and the "
        "reason. Held between steps: the identified drift.")
    default_experiment = default_experiment(1.0)  # HOST_DEFAULT_STEPS steps: runs on a host's defaults

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "string", "model_kind", PARAMETER, "shipped model: hot or cold", "hot")
        declare(self, "string", "model_file", PARAMETER,
                "binary model file path (empty: the shipped model of model_kind)", "")
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

    def do_step(self, current_time, step_size):
        raise NotImplementedError("the RBFIdentifier FMU is native: fmus/c/rbf_identifier/model.c computes it (this "
                                  "class only declares its variables)")
