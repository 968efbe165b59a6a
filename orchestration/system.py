"""Python description of a co-simulation system.

A :class:`System` lists components (FMU instances with start values) and
connections between their variables.  It is what the SSP reader returns, what
the SSP writer takes and what the master runs.  Component names must not
contain a dot: ``"component.variable"`` is split at the first dot, so variable
names may contain dots (``"ramp.height"``).
"""
from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from .errors import SystemDescriptionError, UnknownComponentError

__all__ = ["Component", "Connection", "System", "split_name", "StartValue"]

StartValue = float | int | bool | str


def split_name(qualified: str) -> tuple[str, str]:
    """Split ``"component.variable"`` at the first dot.

    Parameters
    ----------
    qualified : str
        Qualified variable name.

    Returns
    -------
    tuple of str
        ``(component, variable)``.
    """
    component, dot, variable = qualified.partition(".")
    if not dot or not component or not variable:
        raise SystemDescriptionError(
            f"'{qualified}' is not of the form 'component.variable'")
    return component, variable


@dataclass(frozen=True)
class Component:
    """One FMU instance of a system.

    Parameters
    ----------
    name : str
        Instance name, unique in the system, without dots.
    source : str or Path
        FMU file; a relative path is resolved against ``System.base_dir``.
    parameters : dict
        Start values applied before initialisation, ``{variable: value}``.
    """

    name: str
    source: str | Path
    parameters: dict[str, StartValue] = field(default_factory=dict)


@dataclass(frozen=True)
class Connection:
    """A connection from an output to an input.

    Parameters
    ----------
    start_component, start_variable : str
        Source component and its output variable.
    end_component, end_variable : str
        Destination component and its input variable.
    """

    start_component: str
    start_variable: str
    end_component: str
    end_variable: str

    @classmethod
    def between(cls, start: str, end: str) -> Connection:
        """Make a connection from two qualified names, ``"a.y" -> "b.u"``."""
        return cls(*split_name(start), *split_name(end))

    @property
    def start(self) -> str:
        """Qualified start name ``component.variable``."""
        return f"{self.start_component}.{self.start_variable}"

    @property
    def end(self) -> str:
        """Qualified end name ``component.variable``."""
        return f"{self.end_component}.{self.end_variable}"

    def __str__(self) -> str:
        return f"{self.start} -> {self.end}"


@dataclass
class System:
    """A set of components, their start values and their connections.

    Parameters
    ----------
    name : str
        System name.
    components : list of Component
        Components in declaration order (the order breaks ties in the
        Gauss-Seidel ordering).
    connections : list of Connection
        Output-to-input connections.
    start_time, stop_time, step_size : float, optional
        Default experiment, s; ``None`` when the description has none.
    base_dir : Path, optional
        Directory against which relative component sources are resolved.
    source_file : Path, optional
        The SSP/SSD file the system was read from, for error messages.
    """

    name: str
    components: list[Component]
    connections: list[Connection] = field(default_factory=list)
    start_time: float | None = None
    stop_time: float | None = None
    step_size: float | None = None
    base_dir: Path | None = None
    source_file: Path | None = None
    _workdir: tempfile.TemporaryDirectory | None = field(default=None, repr=False,
                                                        compare=False)

    def __post_init__(self) -> None:
        seen = set()
        for component in self.components:
            if not component.name or "." in component.name:
                raise SystemDescriptionError(
                    "component names must be non-empty and contain no dot",
                    file=self._file, component=component.name)
            if component.name in seen:
                raise SystemDescriptionError("duplicate component name",
                                             file=self._file, component=component.name)
            seen.add(component.name)

    @property
    def _file(self) -> str | None:
        return None if self.source_file is None else str(self.source_file)

    def component(self, name: str) -> Component:
        """Return the component called ``name``.

        Raises
        ------
        UnknownComponentError
            If there is none.
        """
        for component in self.components:
            if component.name == name:
                return component
        known = ", ".join(c.name for c in self.components)
        raise UnknownComponentError(f"no such component (known: {known})",
                                    file=self._file, component=name)

    def fmu_path(self, component: Component) -> Path:
        """Absolute path of a component's FMU file."""
        path = Path(component.source)
        if not path.is_absolute() and self.base_dir is not None:
            path = Path(self.base_dir) / path
        return path.resolve()
