"""Helpers shared by the slaves: variable declaration and error handling.

Unit convention: every variable's ``description`` ends with its unit in
square brackets, optionally followed by a display unit after a semicolon,
e.g. ``"angular rate of gimbal 1 [rad/s; deg/s]"``.  The build step turns
that into FMI ``unit``/``displayUnit`` attributes and ``<UnitDefinitions>``.

Error handling (pythonfmu 0.7).  A Python exception escaping a slave method
becomes ``fmi2Fatal``, but pythonfmu's wrapper then releases the Python
objects twice (once in its exception handler, again in ``fmi2FreeInstance``),
which corrupts the host's heap: the host crashes later, at some garbage
collection.  So no exception may leave a slave method.  :func:`guarded`
catches them: the message is logged with status ``fmi2Error`` (category
``logStatusError``), a failed initialisation is remembered, and every
``doStep`` after it, or any step that fails itself, returns ``False``, which
pythonfmu reports as ``fmi2Discard`` (the outputs keep their last values).
pythonfmu has no way to return ``fmi2Error`` itself.
"""

from __future__ import annotations

import functools
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


def declare(slave, kind: str, name: str, causality, description: str, start, *, variability=None,
            depends_on=()):
    """Set ``slave.<name> = start`` and register it (kind: 'real', 'integer', 'string').

    ``depends_on`` (outputs only): the inputs this output depends on directly
    within a step (direct feedthrough).  The default, none, declares a state
    output: it changes only in ``doStep`` (every output of a pythonfmu slave
    that computes in ``do_step`` is one).  The build writes it to
    ``ModelStructure/Outputs`` as the ``dependencies`` attribute.
    """
    setattr(slave, name, start)
    if causality == OUTPUT:
        slave.__dict__.setdefault("_output_dependencies", {})[name] = tuple(depends_on)
    elif depends_on:
        raise ValueError(f"depends_on is for outputs only ({name} is not one)")
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


def guarded(method):
    """Wrap a slave method so that no exception reaches pythonfmu (see module
    docstring).  ``do_step`` returns False on any failure, including a failed
    initialisation; other methods log and record the failure."""
    name = method.__name__

    @functools.wraps(method)
    def wrapper(self, *args):
        failure = getattr(self, "_failure", None)
        if name == "do_step" and failure is not None:
            self.log(f"cannot step: {failure}", Fmi2Status.error)
            return False
        try:
            result = method(self, *args)
        except Exception as exc:  # noqa: BLE001 - nothing may escape to the C++ wrapper
            message = f"{name}: {type(exc).__name__}: {exc}"
            self.log(message, Fmi2Status.error)
            if name != "do_step":
                self._failure = message
            return False if name == "do_step" else None
        return True if name == "do_step" and result is None else result

    return wrapper


def same_time(a: float, b: float, step: float) -> bool:
    """True if two time tags name the same communication point (to 1e-6 of a step)."""
    return abs(a - b) <= 1e-6 * step


class StartOfStepInputs:
    """Chooses, at ``doStep(t, h)``, the input set that describes the step's start.

    A time-tagged upstream output set (tag = the time it describes) arrives
    with tag t under Jacobi (every FMU reads the others' outputs from the
    start of the step) and with tag t + h under Gauss-Seidel (the upstream
    FMU was stepped first).  The slave keeps the set it read at its previous
    step (or at initialisation) and uses whichever of the two is tagged t;
    any other tag is an error, never a silent shift of the motion.
    """

    def __init__(self, what: str, tag_name: str):
        self.what, self.tag_name = what, tag_name
        self._held = None

    def prime(self, tag: float, values) -> None:
        """Keep the set read at initialisation."""
        self._held = (float(tag), values)

    def select(self, time: float, step: float, tag: float, values):
        """The set tagged ``time`` among the current one and the held one."""
        tag = float(tag)
        held = self._held
        if not math.isfinite(tag):
            raise ValueError(f"{self.tag_name} is not finite")
        if same_time(tag, time, step):
            chosen = values
        elif held is not None and same_time(held[0], time, step):
            chosen = held[1]
        else:
            before = "none" if held is None else f"{held[0]:.9g} s"
            raise ValueError(
                f"no {self.what} for the step starting at t={time:.9g} s: the input {self.tag_name} is "
                f"{tag:.9g} s and the previous set was tagged {before}; the inputs must be the values at t "
                "(Jacobi) or at t + h (Gauss-Seidel, upstream stepped first)")
        self._held = (tag, values)
        return chosen
