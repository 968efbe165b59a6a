"""Exceptions and warnings raised by the co-simulation master.

Every error a user can make with a system description derives from
:class:`SystemDescriptionError`; every failure reported by an FMU derives
from :class:`FMUCallError`.  Both derive from :class:`OrchestrationError`, so
``except OrchestrationError`` catches everything the master raises on
purpose.
"""
from __future__ import annotations

from collections.abc import Sequence

__all__ = [
    "OrchestrationError",
    "SystemDescriptionError",
    "SystemFileError",
    "UnknownComponentError",
    "UnknownVariableError",
    "IncompatibleConnectionError",
    "StartValueError",
    "ScheduleError",
    "FMUCallError",
    "FMUFatalError",
    "ImporterUnavailableError",
    "OrchestrationWarning",
    "UnconnectedInputWarning",
    "AlgebraicLoopWarning",
    "RealTimeLagWarning",
    "DefaultStepWarning",
]

STATUS_LABELS = ("OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING")


def status_label(status: int) -> str:
    """Return the FMI 2.0 name of a status code (``3 -> 'ERROR'``)."""
    if 0 <= status < len(STATUS_LABELS):
        return STATUS_LABELS[status]
    return f"illegal status {status}"


class OrchestrationError(Exception):
    """Base class of every error raised on purpose by ``orchestration``."""


class SystemDescriptionError(OrchestrationError, ValueError):
    """A system description (SSP/SSD or python description) is wrong.

    Parameters
    ----------
    message : str
        What is wrong.
    file : str, optional
        System file or FMU file concerned.
    component : str, optional
        Component (FMU instance) name concerned.
    variable : str, optional
        Variable name concerned.
    """

    def __init__(self, message: str, *, file: str | None = None,
                 component: str | None = None, variable: str | None = None):
        self.file = file
        self.component = component
        self.variable = variable
        where = []
        if file is not None:
            where.append(f"file '{file}'")
        if component is not None:
            where.append(f"component '{component}'")
        if variable is not None:
            where.append(f"variable '{variable}'")
        prefix = ", ".join(where)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class SystemFileError(SystemDescriptionError):
    """A system or FMU file is missing, unreadable or of the wrong kind."""


class UnknownComponentError(SystemDescriptionError):
    """A connection or parameter names a component that is not in the system."""


class UnknownVariableError(SystemDescriptionError):
    """A connection, parameter or recorder names a variable the FMU lacks."""


class IncompatibleConnectionError(SystemDescriptionError):
    """A connection joins variables that cannot be connected."""


class StartValueError(SystemDescriptionError):
    """A start value cannot be applied (wrong causality or bad literal)."""


class ScheduleError(OrchestrationError, ValueError):
    """Start/stop time or communication step (schedule) is invalid.

    Parameters
    ----------
    message : str
        What is wrong.
    names : tuple of str
        The arguments of :meth:`orchestration.Master.simulate` at fault
        (``'start_time'``, ``'stop_time'``, ``'step_size'``,
        ``'output_every'``), so that a front end can name its own options.
    """

    def __init__(self, message: str, *, names: tuple[str, ...] = ()):
        self.names = tuple(names)
        super().__init__(message)


class FMUCallError(OrchestrationError, RuntimeError):
    """An FMU returned an error status (discard, error, fatal) from a call.

    Parameters
    ----------
    component : str
        Name of the component (FMU instance).
    call : str
        FMI function that failed, e.g. ``'fmi2DoStep'``.
    status : int
        FMI status code returned.
    time : float or None
        Simulated time at which the call was made (start of the step for
        ``fmi2DoStep``), ``None`` before the simulation loop.
    messages : sequence of str
        Log messages the FMU sent to the logger callback (latest last).
    fmu_file : str, optional
        FMU file of the component.
    """

    def __init__(self, component: str, call: str, status: int, time: float | None,
                 messages: Sequence[str] = (), fmu_file: str | None = None):
        self.component = component
        self.call = call
        self.status = status
        self.time = time
        self.messages = list(messages)
        self.fmu_file = fmu_file
        when = "before the simulation loop" if time is None else f"at t = {time:.9g} s"
        text = (f"component '{component}'"
                + (f" (FMU '{fmu_file}')" if fmu_file else "")
                + f": {call} returned {status_label(status)} {when}")
        if self.messages:
            text += "\nFMU log:\n" + "\n".join(f"  {m}" for m in self.messages)
        else:
            text += " (the FMU logged no message)"
        super().__init__(text)



class FMUInstantiateError(FMUCallError, ValueError):
    """The FMU refused to be instantiated (``fmi2Instantiate`` / ``fmi3InstantiateCoSimulation``
    returned NULL): its files do not fit together (e.g. a model description whose GUID is not the
    binary's) or its resources are missing; a fault of the FMU file, not of the run."""

class FMUFatalError(FMUCallError):
    """An FMU returned ``fmi2Fatal``: its instance must not be called again."""


class ImporterUnavailableError(OrchestrationError, RuntimeError):
    """A third-party importer (ecospy, libcosimpy) is not installed or fails to load."""


class OrchestrationWarning(UserWarning):
    """Base class of the master's warnings."""


class UnconnectedInputWarning(OrchestrationWarning):
    """An FMU input has no incoming connection (it keeps its start value)."""


class AlgebraicLoopWarning(OrchestrationWarning):
    """The connection graph has a cycle; Gauss-Seidel order broke it."""


class RealTimeLagWarning(OrchestrationWarning):
    """Real-time pacing fell behind the wall clock."""


class DefaultStepWarning(OrchestrationWarning):
    """No step was given: the FMUs' DefaultExperiment stepSize is used (says which)."""
