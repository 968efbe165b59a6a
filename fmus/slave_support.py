"""Helpers shared by the slaves: variable declaration and error handling.

Unit convention: every variable's ``description`` ends with its unit in
square brackets, optionally followed by a display unit after a semicolon,
e.g. ``"angular rate of gimbal 1 [rad/s; deg/s]"``.  The build step turns
that into FMI ``unit``/``displayUnit`` attributes and ``<UnitDefinitions>``.

Error handling (pythonfmu 0.7): a Python exception raised from a slave
method becomes ``fmi2Fatal`` with the exception logged; ``do_step`` returning
False becomes ``fmi2Discard``.  pythonfmu has no path to ``fmi2Error``.  So
invalid parameters raise :class:`ParameterError` from
``exit_initialization_mode`` (the host gets a fatal status and the message,
the instance must be freed), and invalid inputs during a step are logged as
errors and the step is discarded (outputs keep their previous values).
"""

from __future__ import annotations

import math

from pythonfmu import Fmi2Causality, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

PARAMETER = Fmi2Causality.parameter
INPUT = Fmi2Causality.input
OUTPUT = Fmi2Causality.output
FIXED = Fmi2Variability.fixed
TUNABLE = Fmi2Variability.tunable
DISCRETE = Fmi2Variability.discrete
CONTINUOUS = Fmi2Variability.continuous


class ParameterError(ValueError):
    """A parameter value the FMU cannot run with."""


def declare(slave, kind: str, name: str, causality, description: str, start, *, variability=None):
    """Set ``slave.<name> = start`` and register it (kind: 'real', 'integer', 'string')."""
    setattr(slave, name, start)
    if variability is None:
        variability = FIXED if causality == PARAMETER else (CONTINUOUS if kind == "real" else DISCRETE)
    cls = {"real": Real, "integer": Integer, "string": String}[kind]
    slave.register_variable(cls(name, causality=causality, variability=variability, description=description))


def check_finite(slave, names, *, positive=(), non_negative=()):
    """Raise ParameterError naming the first non-finite / non-positive parameter."""
    for name in names:
        value = getattr(slave, name)
        if not math.isfinite(value):
            raise ParameterError(f"parameter {name} = {value} is not a finite number")
    for name in positive:
        if not getattr(slave, name) > 0:
            raise ParameterError(f"parameter {name} = {getattr(slave, name)} must be positive")
    for name in non_negative:
        if not getattr(slave, name) >= 0:
            raise ParameterError(f"parameter {name} = {getattr(slave, name)} must not be negative")


def check_step(slave, step_size: float, expected: float | None) -> float:
    """The communication step must be positive, finite and, once set, constant."""
    if not (step_size > 0 and math.isfinite(step_size)):
        raise ValueError(f"communication step {step_size} must be positive and finite")
    if expected is not None and abs(step_size - expected) > 1e-9 * expected:
        raise ValueError(f"communication step changed from {expected} s to {step_size} s; "
                         "this FMU needs a fixed step")
    return step_size


def discard_on_error(slave, exc: Exception) -> bool:
    """Log ``exc`` as an error and tell the host the step was discarded."""
    slave.log(f"{type(exc).__name__}: {exc}", Fmi2Status.error)
    return False
