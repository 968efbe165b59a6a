"""Every shipped FMU runs in a host that uses its defaults: ``fmpy simulate X.fmu`` (FMPy's
``simulate_fmu`` with no options) takes the DefaultExperiment, whose stopTime is
``HOST_DEFAULT_STEPS`` communication steps of its stepSize (FMPy doubles a step that would need more
than 1,000, and the FMUs refuse a step that is not a whole number of their internal steps)."""

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from fmus.build import DEFAULT_NAMES
from fmus.slave_support import HOST_DEFAULT_STEPS

# the FMUs that need a file named before they can run: the error names it
NEEDS_A_FILE = {"IMULog": "log_file"}


@pytest.mark.parametrize("name", [n for n in DEFAULT_NAMES if n not in NEEDS_A_FILE])
def test_fmpy_simulate_with_no_options_runs_every_shipped_fmu(name, fmu_dir):
    path = str(fmu_dir / f"{name}.fmu")
    experiment = read_model_description(path).defaultExperiment
    stop, step = float(experiment.stopTime), float(experiment.stepSize)
    assert stop == HOST_DEFAULT_STEPS * step
    result = simulate_fmu(path)
    assert len(result) == HOST_DEFAULT_STEPS + 1
    assert result["time"][-1] == pytest.approx(stop)
    for field in result.dtype.names:
        if result.dtype[field].kind == "f":
            assert np.all(np.isfinite(result[field])), (name, field)
