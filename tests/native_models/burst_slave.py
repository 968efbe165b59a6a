"""Declaration of the test model Burst (tests/native_models/burst/model.c): FMI 3.0 arrays sized by a
structural parameter, the mechanism IMUThermal's increments and the INS's array inputs use.

Over a step [t, t + h] split into n_sub equal intervals, ``samples[k] = slope * (t + (k + 1) h / n_sub) + u``
(the value at the end of interval k + 1); ``y`` is the last of them; ``wsum`` is the sum of the array input
``w`` as it was during the step, ``steps`` the number of steps done.  In FMI 2.0 there are no arrays and
n_sub is a fixed Integer parameter.
"""

from pythonfmu import Fmi2Slave

from fmus.native_fmu import ArrayVariable
from fmus.slave_support import INPUT, OUTPUT, PARAMETER, declare


class Burst(Fmi2Slave):

    author = "sarins-fmu tests"
    description = "test model of the native glue's FMI 3.0 arrays (not shipped)"
    fmi3_arrays = (
        ArrayVariable("samples", "n_sub", "output", "value at the end of each interval of the last step [1]",
                      depends_on=("u",)),
        ArrayVariable("w", "n_sub", "input", "values summed into wsum at the next step [1]"),
    )

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        declare(self, "integer", "n_sub", PARAMETER, "intervals per communication step [1]", 4)
        declare(self, "real", "slope", PARAMETER, "slope of the ramp [1/s]", 2.0)
        declare(self, "real", "u", INPUT, "offset added to every sample [1]", 0.0)
        declare(self, "real", "y", OUTPUT, "the last sample [1]", 0.0, depends_on=("u",))
        declare(self, "real", "wsum", OUTPUT, "sum of w during the last step [1]", 0.0, depends_on=())
        declare(self, "integer", "steps", OUTPUT, "steps done [1]", 0, depends_on=())

    def do_step(self, current_time, step_size):
        raise NotImplementedError("native only: tests/native_models/burst/model.c")
