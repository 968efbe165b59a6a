"""Helpers shared by the slaves: variable declaration and error handling.

Unit convention: every variable's ``description`` ends with its unit in
square brackets, optionally followed by a display unit after a semicolon,
e.g. ``"angular rate of gimbal 1 [rad/s; deg/s]"``.  The build step turns
that into FMI ``unit``/``displayUnit`` attributes and ``<UnitDefinitions>``.

Real variables declared with :func:`declare` live in one float64 buffer per
slave instance (``slave._fmi_buffer``; ``slave._fmi_slots`` maps value
reference -> slot).  The attribute ``slave.<name>`` reads and writes that
slot (a class-level descriptor), so slave code and pythonfmu's own
``get_real``/``set_real``/``to_xml`` work unchanged.  ``slave._fmi_real(names)``
gives the slots of named Reals for vectorised access.

Error handling (a slave run in process): parameter checks raise
(:class:`ParameterError`) in ``exit_initialization_mode``; a failed step logs
its reason with status fmi2Error and returns False.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from pythonfmu import Fmi2Causality, Fmi2Variability, Integer, Real, String
from pythonfmu.enums import Fmi2Status

PARAMETER = Fmi2Causality.parameter
INPUT = Fmi2Causality.input
OUTPUT = Fmi2Causality.output
FIXED = Fmi2Variability.fixed
TUNABLE = Fmi2Variability.tunable
DISCRETE = Fmi2Variability.discrete
CONTINUOUS = Fmi2Variability.continuous


NO_TAG = -1.0e9  # s, start value of a time-tag input: names no communication point of a run (not connected)


class ParameterError(ValueError):
    """A parameter value the FMU cannot run with."""


class _RealSlot:
    """Class-level descriptor: the Real ``name`` is slot ``index`` of the instance's buffer."""

    __slots__ = ("name", "index")

    def __init__(self, name: str, index: int):
        self.name, self.index = name, index

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        return obj._fmi_view[self.index]

    def __set__(self, obj, value):
        obj._fmi_view[self.index] = float(value)


def _bind_real(slave, name: str, start) -> int:
    """Give the Real ``name`` the next slot of the slave's buffer; returns the slot."""
    buffer = slave.__dict__.get("_fmi_buffer")
    if buffer is None:
        buffer = np.zeros(32)
        slave._fmi_slots = {}
        slave._fmi_count = 0
    index = slave._fmi_count
    if index >= buffer.shape[0]:  # grow (only while declaring, before the FMI layer holds the buffer)
        grown = np.zeros(2 * buffer.shape[0])
        grown[:index] = buffer[:index]
        buffer = grown
    slave._fmi_buffer = buffer
    slave._fmi_view = memoryview(buffer)
    slave._fmi_count = index + 1
    cls = type(slave)
    existing = cls.__dict__.get(name)
    if existing is None and not hasattr(cls, name):
        setattr(cls, name, _RealSlot(name, index))
    elif not (isinstance(existing, _RealSlot) and existing.index == index):
        raise RuntimeError(f"{cls.__name__}.{name}: a class attribute has this name, or Reals are declared in a "
                           "different order than in the first instance")
    slave.__dict__.pop(name, None)
    slave._fmi_view[index] = float(start)
    return index


def declare(slave, kind: str, name: str, causality, description: str, start, *, variability=None,
            depends_on=()):
    """Register a variable with start value ``start`` (kind: 'real', 'integer', 'string').

    A Real lives in the slave's float64 buffer (see the module docstring);
    other kinds are plain attributes.  ``depends_on`` (outputs only): the
    inputs this output depends on directly within a step (direct
    feedthrough).  The default, none, declares a state output: it changes
    only in ``doStep`` (every output of a slave that computes in ``do_step``
    is one).  The build writes it to ``ModelStructure/Outputs`` as the
    ``dependencies`` attribute.
    """
    if causality == OUTPUT:
        slave.__dict__.setdefault("_output_dependencies", {})[name] = tuple(depends_on)
    elif depends_on:
        raise ValueError(f"depends_on is for outputs only ({name} is not one)")
    if variability is None:
        variability = FIXED if causality == PARAMETER else (CONTINUOUS if kind == "real" else DISCRETE)
    cls = {"real": Real, "integer": Integer, "string": String}[kind]
    if kind == "real":
        index = _bind_real(slave, name, start)
    else:
        setattr(slave, name, start)
    var = cls(name, causality=causality, variability=variability, description=description)
    slave.register_variable(var)
    if kind == "real":
        slave._fmi_slots[var.value_reference] = index


def real_slots(slave, names) -> np.ndarray:
    """Buffer slots of the named Reals (for ``slave._fmi_buffer[slots]``)."""
    return np.array([type(slave).__dict__[n].index for n in names], dtype=np.intp)


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


INT32_MIN, INT32_MAX = -2**31, 2**31 - 1  # the range of an FMI 2.0 Integer


def check_integer(slave, name: str, low: int = INT32_MIN, high: int = INT32_MAX) -> int:
    """Raise ParameterError unless the Integer parameter ``name`` lies in [low, high]; returns it."""
    value = getattr(slave, name)
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ParameterError(f"parameter {name} = {value!r} must be an integer in [{low}, {high}]")
    return int(value)


def check_range(slave, name: str, low: float, high: float, *, unit: str = "", scale: float = 1.0) -> float:
    """Raise ParameterError unless the Real parameter ``name`` is finite and in [low, high] (SI units);
    the message shows the values divided by ``scale`` with ``unit`` (e.g. radians shown in deg)."""
    value = getattr(slave, name)
    if not (math.isfinite(value) and low <= value <= high):
        shown = f" {unit}" if unit else ""
        raise ParameterError(f"parameter {name} = {value / scale:.9g}{shown} is outside "
                             f"[{low / scale:.9g}, {high / scale:.9g}]{shown}")
    return float(value)


LAT_LIMIT = math.radians(89.9)  # rad: the navigation frame is singular at the poles


def check_latitude(slave, name: str) -> float:
    """A latitude parameter (rad) within +-89.9 deg."""
    return check_range(slave, name, -LAT_LIMIT, LAT_LIMIT, unit="deg", scale=math.pi / 180.0)


def check_step(slave, step_size: float, expected: float | None) -> float:
    """The communication step must be positive, finite and, once set, constant."""
    if not (step_size > 0 and math.isfinite(step_size)):
        raise ValueError(f"communication step {step_size} must be positive and finite")
    if expected is not None and abs(step_size - expected) > 1e-9 * expected:
        raise ValueError(f"communication step changed from {expected} s to {step_size} s; "
                         "this FMU needs a fixed step")
    return step_size


def discard_on_error(slave, exc: Exception) -> bool:
    """Log ``exc`` with status fmi2Error; the step returns False (the layer reports fmi2Error)."""
    slave.log(f"{type(exc).__name__}: {exc}", Fmi2Status.error)
    return False


def guarded(method):
    """``do_step`` may return None for success (pythonfmu expects a bool); exceptions propagate
    to the native FMI layer, which logs them and returns fmi2Error at that call."""

    @functools.wraps(method)
    def wrapper(self, *args):
        result = method(self, *args)
        return True if result is None and method.__name__ == "do_step" else result

    return wrapper


TAG_TOL = 1e-6  # of a step: two time tags closer than this name the same communication point

def same_time(a: float, b: float, step: float) -> bool:
    """True if two time tags name the same communication point (to TAG_TOL of a step)."""
    return abs(a - b) <= TAG_TOL * step


class TaggedHistory:
    """The last ``size`` sets of a time-tagged input, to pair them by tag with another input stream.

    A consumer of two upstream output sets (e.g. the INS's solution and the
    vehicle's speed) receives them with different lags under different
    schemes (Jacobi: one step per link; Gauss-Seidel: none).  It keeps the
    sets of one stream by their tag (the time they refer to) and takes the one
    whose tag equals the other stream's; a tag that was never received or
    has dropped out of the history is an error, never a silent mismatch.
    """

    def __init__(self, what: str, tag_name: str, size: int = 8):
        self.what, self.tag_name, self.size = what, tag_name, int(size)
        self._sets: list[tuple[float, object]] = []

    def push(self, tag: float, values, step: float | None = None) -> None:
        """Keep ``values`` tagged ``tag`` (a repeated tag, e.g. Jacobi's first step, is ignored)."""
        tag = float(tag)
        if not math.isfinite(tag):
            raise ValueError(f"{self.tag_name} is not finite")
        if self._sets:
            last = self._sets[-1][0]
            if same_time(tag, last, step or 1.0):
                return
            if tag < last:
                raise ValueError(f"{self.tag_name} went back from {last:.9g} s to {tag:.9g} s")
        self._sets.append((tag, values))
        del self._sets[:-self.size]

    def at(self, tag: float, step: float):
        """The set tagged ``tag``."""
        for held, values in reversed(self._sets):
            if same_time(held, tag, step):
                return values
        kept = f"{self._sets[0][0]:.9g} .. {self._sets[-1][0]:.9g} s" if self._sets else "none"
        raise ValueError(f"no {self.what} tagged {self.tag_name}={tag:.9g} s to pair with (kept: {kept}; the "
                         f"{self.what} must arrive no later than, and at most {self.size - 1} steps before, the "
                         "input it is paired with)")


#: communication steps of an FMU's DefaultExperiment: a host that runs it with its defaults takes the
#: declared stepSize (FMPy doubles the step while the run would need more than 1,000 of them, and a
#: doubled step is one the FMUs may refuse), so stopTime = HOST_DEFAULT_STEPS * stepSize
HOST_DEFAULT_STEPS = 1000


def default_experiment(step_size: float):
    """pythonfmu's DefaultExperiment from 0 s over :data:`HOST_DEFAULT_STEPS` steps of ``step_size`` (s)."""
    from pythonfmu.default_experiment import DefaultExperiment

    return DefaultExperiment(start_time=0.0, stop_time=HOST_DEFAULT_STEPS * step_size, step_size=step_size)
