"""Test slave: a ramp source with Integer and Boolean outputs.

``y = offset + slope * t`` evaluated at the end of each step; ``count`` is the
number of steps taken and ``positive`` tells whether ``y > 0``.
"""
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real


class Ramp(Fmi2Slave):

    author = "sarins-fmu tests"
    description = "Ramp source with a step counter"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.slope = 1.0
        self.offset = 0.0
        self.y = 0.0
        self.count = 0
        self.positive = False
        self.register_variable(Real("slope", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("offset", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("y", causality=Fmi2Causality.output))
        self.register_variable(Integer("count", causality=Fmi2Causality.output,
                                         variability=Fmi2Variability.discrete))
        self.register_variable(Boolean("positive", causality=Fmi2Causality.output,
                                         variability=Fmi2Variability.discrete))

    def exit_initialization_mode(self):
        self.y = self.offset
        self.positive = self.y > 0.0

    def do_step(self, current_time, step_size):
        self.y = self.offset + self.slope * (current_time + step_size)
        self.count += 1
        self.positive = self.y > 0.0
        return True
