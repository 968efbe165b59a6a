"""Python description of a co-simulation system.

A :class:`System` lists components (FMU instances with start values) and
connections between their variables.  It is what the SSP reader returns, what
the SSP writer takes and what the master runs.  Components of nested SSP
systems are named by their path (``"sub.gain"``); a qualified variable name
``"component.variable"`` is resolved against the longest matching component
name, and :meth:`Connection.between` splits at the first dot, so variable
names may contain dots (``"ramp.height"``).  A connection may carry unit
information and linear transformations (:class:`Hop`), which the master
turns into a conversion of the transferred values.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .errors import SystemDescriptionError, UnknownComponentError

__all__ = ["Component", "Connection", "Hop", "System", "split_name", "StartValue"]

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
    parameter_units : dict
        ``{variable: unit name}`` for Real start values given in a unit (SSP
        ``ssv:Real unit``); the master converts them to the variable's unit.
    connector_types : dict
        ``{connector: type}`` declared by an SSD (``'Real'``, ``'Integer'``,
        ``'Boolean'``, ``'String'``, ``'Enumeration'``, ``'Binary'``); the
        master checks them against the FMU's variables.
    """

    name: str
    source: str | Path
    parameters: dict[str, StartValue] = field(default_factory=dict)
    parameter_units: dict[str, str] = field(default_factory=dict)
    connector_types: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Hop:
    """One SSP connection on the way from an output to an input.

    A flattened connection through system-level connectors is a chain of
    hops; a plain connection is one hop.

    Parameters
    ----------
    start_unit, end_unit : str, optional
        Units declared on the hop's start and end connectors (names in the
        system's unit definitions); ``None``: not declared (at a component,
        the FMU variable's unit applies; at a system connector, the unit is
        passed through).
    factor, offset : float
        ``ssc:LinearTransformation``: ``end = factor * start + offset``, applied
        after the unit conversion.
    suppress_unit_conversion : bool
        SSP ``suppressUnitConversion``: no unit conversion on this hop.
    where : str
        Where the hop is declared, for error messages.
    """

    start_unit: str | None = None
    end_unit: str | None = None
    factor: float = 1.0
    offset: float = 0.0
    suppress_unit_conversion: bool = False
    where: str = ""


@dataclass(frozen=True)
class Connection:
    """A connection from an output to an input.

    Parameters
    ----------
    start_component, start_variable : str
        Source component and its output variable.
    end_component, end_variable : str
        Destination component and its input variable.
    hops : tuple of Hop
        Units and transformations along the connection (SSP); empty for a
        plain connection (the FMU variables' own units still apply).
    """

    start_component: str
    start_variable: str
    end_component: str
    end_variable: str
    hops: tuple[Hop, ...] = ()

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
    units : dict, optional
        ``{name: orchestration.units.Unit}``: the system file's unit
        definitions, referenced by the connections' hops.
    inputs_without_source : list of str, optional
        Component inputs connected only to a system-level input that has no
        source (they keep their start values).
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
    units: dict = field(default_factory=dict)
    inputs_without_source: list[str] = field(default_factory=list)
    _workdir: object | None = field(default=None, repr=False,
                                                        compare=False)

    def __post_init__(self) -> None:
        seen = set()
        for component in self.components:
            if not component.name or component.name.startswith(".") \
                    or component.name.endswith(".") or ".." in component.name:
                raise SystemDescriptionError(
                    "component names must be non-empty, without empty dot-separated parts",
                    file=self._file, component=component.name)
            if component.name in seen:
                raise SystemDescriptionError("duplicate component name",
                                             file=self._file, component=component.name)
            seen.add(component.name)
        for name in seen:
            parent = name.rpartition(".")[0]
            while parent:
                if parent in seen:
                    raise SystemDescriptionError(
                        f"component name is ambiguous: component '{parent}' is a prefix of it",
                        file=self._file, component=name)
                parent = parent.rpartition(".")[0]

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

    def split(self, qualified: str) -> tuple[str, str]:
        """Split ``component.variable`` at the longest component name that prefixes it.

        Raises
        ------
        UnknownComponentError
            If no component name prefixes it.
        """
        best = None
        for component in self.components:
            name = component.name
            if qualified.startswith(name + ".") and len(qualified) > len(name) + 1 \
                    and (best is None or len(name) > len(best)):
                best = name
        if best is None:
            component, _, _ = qualified.partition(".")
            known = ", ".join(c.name for c in self.components)
            raise UnknownComponentError(f"no component prefixes '{qualified}' (known: {known})",
                                        file=self._file, component=component)
        return best, qualified[len(best) + 1:]

    def fmu_path(self, component: Component) -> Path:
        """Absolute path of a component's FMU file."""
        path = Path(component.source)
        if not path.is_absolute() and self.base_dir is not None:
            path = Path(self.base_dir) / path
        return path.resolve()
