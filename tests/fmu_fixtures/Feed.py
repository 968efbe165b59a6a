"""Test slave: direct feedthrough at get time, a state output, a unit and a default step.

``y = k * u + b`` is computed whenever it is read, from the input as last
set (true direct feedthrough: setting ``u`` changes ``y`` at once, as in an
FMU generated from equations); its ModelStructure declares
``dependencies`` = ``u``.  ``x`` integrates ``u`` over each step (forward
Euler) and is a state output (``dependencies=""``).  ``angle`` is an input
in rad (UnitDefinitions: rad), recorded to check unit conversions.  The
DefaultExperiment declares stepSize 0.125 s.
"""
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.default_experiment import DefaultExperiment
from xml.etree.ElementTree import Element, SubElement


class Feed(Fmi2Slave):

    author = "sarins-fmu tests"
    description = "Direct feedthrough y = k u + b, state x, angle input in rad"
    default_experiment = DefaultExperiment(start_time=0.0, step_size=0.125)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k = 1.0
        self.b = 0.0
        self.u = 0.0
        self.angle = 0.0
        self.x = 0.0
        self.register_variable(Real("k", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("b", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("angle", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output,
                                    getter=lambda: self.k * self.u + self.b))
        self.register_variable(Real("x", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.x += self.u * step_size
        return True

    def to_xml(self, model_options=None):
        """pythonfmu's description plus units and declared output dependencies."""
        root = super().to_xml(model_options or {})
        units = Element("UnitDefinitions")
        unit = SubElement(units, "Unit", name="rad")
        SubElement(unit, "BaseUnit", rad="1")
        children = list(root)
        position = next(i for i, c in enumerate(children) if c.tag == "CoSimulation") + 1
        root.insert(position, units)
        variables = list(root.find("ModelVariables"))
        index = {v.get("name"): i + 1 for i, v in enumerate(variables)}
        variables[index["angle"] - 1].find("Real").set("unit", "rad")
        for unknown in root.find("ModelStructure/Outputs"):
            name = variables[int(unknown.get("index")) - 1].get("name")
            unknown.set("dependencies", str(index["u"]) if name == "y" else "")
            if name == "y":
                unknown.set("dependenciesKind", "dependent")
        return root
