"""Test slave that fails on demand.

``mode = 1`` makes exit_initialization_mode raise, ``mode = 2`` makes
do_step return False once ``t >= fail_at``; both log a message first.
"""
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real
from pythonfmu.enums import Fmi2Status


class Faulty(Fmi2Slave):

    author = "sarins-fmu tests"
    description = "Fails on a bad parameter or at a given time"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.mode = 0
        self.fail_at = 1.0
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Integer("mode", causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.fixed))
        self.register_variable(Real("fail_at", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.fixed))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def exit_initialization_mode(self):
        if self.mode == 1:
            self.log("mode 1: bad parameter, refusing to initialise", Fmi2Status.error)
            raise ValueError("bad parameter mode=1")

    def do_step(self, current_time, step_size):
        if self.mode == 2 and current_time + 0.5 * step_size >= self.fail_at:
            self.log(f"mode 2: failing at t={current_time}", Fmi2Status.error)
            return False
        self.y = self.u
        return True
