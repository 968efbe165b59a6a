"""Flatten an SSP 1.0 ``ssd:System`` tree into FMU components and direct connections.

Nested ``ssd:System`` elements are dissolved: their components are named by
path (``"sub.gain"``).  A connection that ends at a system-level connector
is continued by the connection that starts there, so every chain
``component output -> system connector(s) -> component input`` becomes one
:class:`~orchestration.system.Connection` whose :class:`~orchestration.system.Hop` s
keep the units and linear transformations of every piece.  A system input
with no source feeds nothing: the component inputs behind it keep their
start values (they are reported as unconnected by the master).  Parameter
bindings apply from the inside out, so a binding of an enclosing system
overrides one of a component or inner system.
"""
from __future__ import annotations

from collections.abc import Callable

from lxml import etree

from .errors import IncompatibleConnectionError, SystemFileError, UnknownComponentError
from .system import Component, Connection, Hop, StartValue

__all__ = ["flatten", "NS", "FMU_MIME"]

NS = {
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
}
FMU_MIME = "application/x-fmu-sharedlibrary"
_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration", "Binary")

Bindings = Callable[[etree._Element, str | None], tuple[dict[str, StartValue], dict[str, str]]]


def _local(element) -> str:
    return etree.QName(element).localname


class _Flattener:
    def __init__(self, file: str, units: dict, read_bindings: Bindings):
        self.file = file
        self.units = units
        self.read_bindings = read_bindings
        self.components: list[Component] = []
        self.by_name: dict[str, Component] = {}
        self.connector_units: dict[tuple[str, str], str | None] = {}
        self.connector_types: dict[str, dict[str, str]] = {}  # owner -> {connector: declared type}
        self.system_connectors: dict[str, dict[str, str]] = {}  # path -> {name: kind}
        self.feeds: dict[tuple[str, str], tuple[tuple[str, str], Hop]] = {}
        self.systems: set[str] = set()

    # elements -------------------------------------------------------------
    def system(self, element, path: str) -> None:
        self.systems.add(path)
        label = f"system '{element.get('name')}'"
        self.system_connectors[path] = self._connectors(element, path)
        if element.find("ssd:SignalDictionaries", NS) is not None:
            raise SystemFileError(f"{label}: signal dictionaries are not supported",
                                  file=self.file)
        for child in element.iterfind("ssd:Elements/*", NS):
            kind = _local(child)
            name = child.get("name")
            full = f"{path}.{name}" if path else name
            if kind == "Component":
                self._component(child, full)
            elif kind == "System":
                self.system(child, full)
            else:
                raise SystemFileError(f"{label}: {kind} elements are not supported (only FMU "
                                      "components and nested systems)", file=self.file,
                                      component=full)
        for connection in element.iterfind("ssd:Connections/ssd:Connection", NS):
            self._connection(connection, path, label)
        self._bind_system(element, path, label)

    def _component(self, element, name: str) -> None:
        kind = element.get("type")
        if kind not in (None, FMU_MIME):
            raise SystemFileError(f"component type '{kind}' is not an FMU ({FMU_MIME})",
                                  file=self.file, component=name)
        if element.get("implementation") == "ModelExchange":
            raise SystemFileError("implementation 'ModelExchange' is not supported "
                                  "(FMI 2.0 and 3.0 co-simulation only)", file=self.file,
                                  component=name)
        self._connectors(element, name)
        values, units = self.read_bindings(element, name)
        component = Component(name, element.get("source"), values, units,
                              self.connector_types.get(name, {}))
        self.components.append(component)
        self.by_name[name] = component

    def _connectors(self, element, owner: str) -> dict[str, str]:
        kinds = {}
        for connector in element.iterfind("ssd:Connectors/ssd:Connector", NS):
            name = connector.get("name")
            kinds[name] = connector.get("kind")
            unit = None
            for typed in connector:
                if isinstance(typed.tag, str) and _local(typed) in _TYPES:
                    self.connector_types.setdefault(owner, {})[name] = _local(typed)
                if isinstance(typed.tag, str) and _local(typed) == "Real":
                    unit = typed.get("unit")
            if unit is not None and unit not in self.units:
                raise SystemFileError(f"connector unit '{unit}' is not defined in the SSD's "
                                      "Units", file=self.file, component=owner or None,
                                      variable=name)
            self.connector_units[(owner, name)] = unit
        return kinds

    # connections ----------------------------------------------------------
    def _node(self, path: str, element: str | None, connector: str, label: str):
        if element is None:
            if connector not in self.system_connectors[path]:
                raise SystemFileError(f"{label}: a connection names system connector "
                                      f"'{connector}', which the system does not declare",
                                      file=self.file, variable=connector)
            return path, connector
        full = f"{path}.{element}" if path else element
        if full not in self.by_name and full not in self.systems:
            raise UnknownComponentError(f"{label}: a connection names an unknown element",
                                        file=self.file, component=full, variable=connector)
        if full in self.systems and connector not in self.system_connectors[full]:
            raise SystemFileError(f"{label}: a connection names connector '{connector}', "
                                  "which the nested system does not declare", file=self.file,
                                  component=full, variable=connector)
        return full, connector

    def _connection(self, element, path: str, label: str) -> None:
        start = self._node(path, element.get("startElement"), element.get("startConnector"),
                           label)
        end = self._node(path, element.get("endElement"), element.get("endConnector"), label)
        factor, offset = 1.0, 0.0
        for child in element:
            if not isinstance(child.tag, str):
                continue
            kind = _local(child)
            if kind == "LinearTransformation":
                factor = float(child.get("factor", 1.0))
                offset = float(child.get("offset", 0.0))
            elif kind.endswith("Transformation"):
                raise SystemFileError(f"{label}: {kind} on connections is not supported "
                                      "(only LinearTransformation)", file=self.file,
                                      component=end[0] or None, variable=end[1])
        suppress = element.get("suppressUnitConversion", "false").strip() in ("true", "1")
        hop = Hop(self.connector_units.get(start), self.connector_units.get(end), factor,
                  offset, suppress, label)
        if end in self.feeds:
            raise IncompatibleConnectionError(f"{label}: connector is fed by two connections",
                                              file=self.file, component=end[0] or None,
                                              variable=end[1])
        self.feeds[end] = (start, hop)

    def connections(self) -> tuple[list[Connection], list[str]]:
        """Component-to-component connections, and the inputs fed by a source-less system input."""
        result, dangling = [], []
        for end, (start, hop) in self.feeds.items():
            if end[0] not in self.by_name:
                continue  # ends at a system connector: continued (or not) elsewhere
            hops, node, seen = [hop], start, {end}
            while node[0] not in self.by_name:
                if node in seen:
                    raise SystemFileError("system connectors are connected in a cycle",
                                          file=self.file, component=node[0] or None,
                                          variable=node[1])
                seen.add(node)
                if node not in self.feeds:
                    break
                node, previous = self.feeds[node]
                hops.insert(0, previous)
            if node[0] in self.by_name:
                result.append(Connection(node[0], node[1], end[0], end[1], tuple(hops)))
            else:
                where = f"{node[0]}.{node[1]}" if node[0] else node[1]
                dangling.append(f"{end[0]}.{end[1]} (through system connector '{where}')")
        return result, dangling

    # parameters -----------------------------------------------------------
    def _bind_system(self, element, path: str, label: str) -> None:
        values, units = self.read_bindings(element, None)
        for qualified, value in values.items():
            full = f"{path}.{qualified}" if path else qualified
            owner = max((n for n in self.by_name if full.startswith(n + ".")
                         and len(full) > len(n) + 1), key=len, default=None)
            if owner is None:
                raise UnknownComponentError(f"{label}: system-level parameter '{qualified}' "
                                            "does not name a component variable "
                                            "(component.variable)", file=self.file,
                                            component=qualified.partition(".")[0])
            variable = full[len(owner) + 1:]
            self.by_name[owner].parameters[variable] = value
            if qualified in units:
                self.by_name[owner].parameter_units[variable] = units[qualified]
            else:
                self.by_name[owner].parameter_units.pop(variable, None)


def flatten(root_system, *, file: str, units: dict, read_bindings: Bindings
            ) -> tuple[list[Component], list[Connection], list[str]]:
    """Flatten the top ``ssd:System`` element.

    Parameters
    ----------
    root_system : lxml element
        The ``ssd:System`` child of ``ssd:SystemStructureDescription``.
    file : str
        SSD file, for error messages.
    units : dict
        The SSD's unit definitions ``{name: Unit}``.
    read_bindings : callable
        ``read_bindings(element, component)`` -> ``(values, units)`` of the
        element's ``ssd:ParameterBindings``.

    Returns
    -------
    components, connections, dangling
        FMU components (path names), component-to-component connections and
        the inputs behind system inputs that have no source.
    """
    flattener = _Flattener(file, units, read_bindings)
    flattener.system(root_system, "")
    connections, dangling = flattener.connections()
    return flattener.components, connections, dangling
