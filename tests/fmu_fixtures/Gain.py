"""Test slave: gain with direct feedthrough, an integrator, and pass-throughs.

``y = k * u`` (direct feedthrough, evaluated after the step with the input
held over the step), ``x`` integrates ``u`` with forward Euler, ``n_out``
and ``flag_out`` copy the Integer and Boolean inputs.
"""
from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real


class Gain(Fmi2Slave):

    author = "sarins-fmu tests"
    description = "Gain, integrator and pass-through"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k = 1.0
        self.u = 0.0
        self.n_in = 0
        self.flag_in = False
        self.y = 0.0
        self.x = 0.0
        self.n_out = 0
        self.flag_out = False
        self.register_variable(Real("k", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Integer("n_in", causality=Fmi2Causality.input,
                                         variability=Fmi2Variability.discrete))
        self.register_variable(Boolean("flag_in", causality=Fmi2Causality.input,
                                         variability=Fmi2Variability.discrete))
        self.register_variable(Real("y", causality=Fmi2Causality.output))
        self.register_variable(Real("x", causality=Fmi2Causality.output))
        self.register_variable(Integer("n_out", causality=Fmi2Causality.output,
                                         variability=Fmi2Variability.discrete))
        self.register_variable(Boolean("flag_out", causality=Fmi2Causality.output,
                                         variability=Fmi2Variability.discrete))

    def do_step(self, current_time, step_size):
        self.x += self.u * step_size
        self.y = self.k * self.u
        self.n_out = self.n_in
        self.flag_out = self.flag_in
        return True
