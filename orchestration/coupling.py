"""Connection checks and the Gauss-Seidel stepping order.

Connections are checked against the FMUs' model descriptions, then grouped
into :class:`Link` s: all connections of one value type from one source
component to one destination component, so that one ``fmi2Get*`` and one
``fmi2Set*`` call (``fmi3Get*``/``fmi3Set*``) move them per step.

A connection joins an output and an input of one family (float, integer,
boolean; :func:`orchestration.fmitypes.can_carry`), scalar to scalar or an
FMI 3.0 array to an array of the same shape.
"""
from __future__ import annotations

import difflib
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from .errors import (AlgebraicLoopWarning, IncompatibleConnectionError,
                     UnconnectedInputWarning, UnknownComponentError, UnknownVariableError)
from .fmitypes import VALUE_TYPES, can_carry, family, size_of, value_type
from .system import Connection

__all__ = ["Link", "VALUE_TYPES", "value_type", "find_variable", "check_connections",
           "check_connector_types",
           "group_links", "gauss_seidel_order", "warn_unconnected", "output_dependencies",
           "algebraic_loops"]


@dataclass(frozen=True)
class Link:
    """Connections of one type from component ``source`` to component ``target``.

    Attributes
    ----------
    source, target : int
        Component indices in the system's declaration order.
    kind : str
        Get kind of the sources (``'Real'``, ``'Integer'``, ``'Boolean'``,
        ``'Float64'``, ``'Int32'``, ...; :mod:`orchestration.fmitypes`).
    source_vrs, target_vrs : tuple of int
        Value references, element ``i`` of one feeds element ``i`` of the other.
    connections : tuple of Connection
        The connections grouped here.
    maps : tuple of (float, float), optional
        ``(factor, offset)`` per connection (unit conversion and linear
        transformation: ``target = factor * source + offset``); ``None`` when
        every value is passed unchanged.
    target_kind : str, optional
        Set kind of the targets when it differs from ``kind`` (the values are
        cast, e.g. FMI 2.0 ``Boolean`` to FMI 3.0 ``Boolean``); ``None``: ``kind``.
    sizes : tuple of int, optional
        Values per connection (an FMI 3.0 array carries all its elements);
        ``None``: one each.
    """

    source: int
    target: int
    kind: str
    source_vrs: tuple[int, ...]
    target_vrs: tuple[int, ...]
    connections: tuple[Connection, ...]
    maps: tuple[tuple[float, float], ...] | None = None
    target_kind: str | None = None
    sizes: tuple[int, ...] | None = None

    @property
    def values(self) -> int:
        """Number of values the link moves per transfer."""
        return len(self.source_vrs) if self.sizes is None else sum(self.sizes)


def find_variable(variables: Mapping, name: str, *, component: str, file: str | None,
                  role: str = "variable"):
    """Return the model variable ``name`` or raise UnknownVariableError with hints."""
    try:
        return variables[name]
    except KeyError:
        close = difflib.get_close_matches(name, list(variables), n=3)
        hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
        raise UnknownVariableError(f"the FMU has no {role} of this name{hint}", file=file,
                                   component=component, variable=name) from None


def _endpoint(component: str, variable: str, index: Mapping[str, int],
              variables: Sequence[Mapping], files: Sequence[str], system_file: str | None,
              role: str):
    if component not in index:
        raise UnknownComponentError(f"connection {role} names an unknown component "
                                    f"(known: {', '.join(index)})", file=system_file,
                                    component=component, variable=variable)
    i = index[component]
    return i, find_variable(variables[i], variable, component=component, file=files[i])


def _connector_matches(declared: str, var) -> bool:
    """An SSP 1.0 connector type against an FMU variable type (FMI 3.0 types by family)."""
    if var.type in ("Real", "Integer", "Enumeration", "Boolean", "String", "Binary"):
        return var.type == declared  # FMI 2.0 (and types both versions share)
    return {"Real": "float", "Integer": "integer", "Enumeration": "integer",
            "Boolean": "boolean", "String": "string"}.get(declared) == family(value_type(var))


def check_connector_types(components: Sequence, variables: Sequence[Mapping],
                          files: Sequence[str], file: str | None) -> None:
    """Refuse an SSD connector whose declared type differs from its FMU variable's type.

    An FMI 3.0 variable matches the SSP 1.0 type of its family (``Real`` for
    ``Float32``/``Float64``, ``Integer`` for the integer types).

    Parameters
    ----------
    components : sequence of Component
        With ``connector_types`` as read from the SSD.
    variables : sequence of dict
        ``{name: ModelVariable}`` per component.
    files : sequence of str
        FMU file per component.
    file : str or None
        System file, for the message.

    Raises
    ------
    IncompatibleConnectionError
        Naming the component, the connector, the declared and the FMU's type.
    """
    for component, known, fmu_file in zip(components, variables, files):
        for connector, declared in getattr(component, "connector_types", {}).items():
            var = known.get(connector)
            if var is not None and not _connector_matches(declared, var):
                raise IncompatibleConnectionError(
                    f"connector '{connector}' is declared {declared} in the system file, but "
                    f"the FMU's variable is {var.type} (FMU '{fmu_file}')", file=file,
                    component=component.name, variable=connector)


def check_connections(connections: Sequence[Connection], names: Sequence[str],
                      variables: Sequence[Mapping], files: Sequence[str],
                      system_file: str | None = None,
                      shapes: Sequence[Mapping[str, tuple]] | None = None) -> list[tuple]:
    """Check every connection; return ``(src index, src var, dst index, dst var, c)``.

    ``shapes`` gives, per component, ``{name: shape}`` of its FMI 3.0 array
    variables (from :func:`orchestration.fmitypes.variable_shape`); a variable
    not in it is a scalar.

    Raises
    ------
    UnknownComponentError, UnknownVariableError
        For names not in the system / the FMU.
    IncompatibleConnectionError
        For a start that is not an output, an end that is not an input, types
        that cannot carry each other's values, a String, Binary or Clock
        connection, an array joined to a scalar or to an array of another
        shape, or an input fed twice.
    """
    index = {name: i for i, name in enumerate(names)}
    checked = []
    fed: dict[tuple[int, str], Connection] = {}
    for c in connections:
        i, start = _endpoint(c.start_component, c.start_variable, index, variables, files,
                             system_file, "start")
        j, end = _endpoint(c.end_component, c.end_variable, index, variables, files,
                           system_file, "end")
        _check_pair(c, start, end, files[j])
        if shapes is not None:
            _check_shapes(c, shapes[i].get(start.name, ()), shapes[j].get(end.name, ()), files[j])
        if (j, end.name) in fed:
            raise IncompatibleConnectionError(
                f"input is fed by two connections ({fed[(j, end.name)]} and {c})",
                file=files[j], component=c.end_component, variable=c.end_variable)
        fed[(j, end.name)] = c
        checked.append((i, start, j, end, c))
    return checked


def _check_pair(c: Connection, start, end, end_file: str) -> None:
    def fail(message: str) -> None:
        raise IncompatibleConnectionError(f"connection {c}: {message}", file=end_file,
                                          component=c.end_component, variable=c.end_variable)

    if start.causality != "output":
        fail(f"start variable '{c.start}' has causality '{start.causality}'; only outputs "
             "can drive a connection")
    if end.causality != "input":
        extra = "; give it a start value instead" if end.causality == "parameter" else ""
        fail(f"end variable '{c.end}' has causality '{end.causality}'; only inputs can be "
             f"driven by a connection{extra}")
    kinds = value_type(start), value_type(end)
    if family(kinds[0]) in ("string", "binary", "clock") or \
            family(kinds[1]) in ("string", "binary", "clock"):
        fail(f"{start.type if family(kinds[0]) in ('string', 'binary', 'clock') else end.type} "
             "connections are not supported")
    if not can_carry(*kinds):
        fail(f"type mismatch: {start.type} output to {end.type} input")


def _check_shapes(c: Connection, start_shape: tuple, end_shape: tuple, end_file: str) -> None:
    if start_shape == end_shape:
        return

    def describe(shape: tuple) -> str:
        return "a scalar" if not shape else f"an array of shape {list(shape)}"

    raise IncompatibleConnectionError(
        f"connection {c}: dimension mismatch: {c.start} is {describe(start_shape)}, "
        f"{c.end} is {describe(end_shape)}", file=end_file, component=c.end_component,
        variable=c.end_variable)


def group_links(checked, maps: Sequence[tuple[float, float]] | None = None,
                shapes: Sequence[Mapping[str, tuple]] | None = None) -> list[Link]:
    """Group checked connections by (source, target, source type, target type), in first-seen order.

    ``maps`` gives ``(factor, offset)`` per checked connection (see
    :mod:`orchestration.unit_links`); a link keeps them only if one differs
    from the identity.  ``shapes`` as in :func:`check_connections`.
    """
    groups: dict[tuple[int, int, str, str], list] = {}
    for k, (i, start, j, end, c) in enumerate(checked):
        mapping = (1.0, 0.0) if maps is None else maps[k]
        size = 1 if shapes is None else size_of(shapes[i].get(start.name, ()))
        groups.setdefault((i, j, value_type(start), value_type(end)), []).append(
            (start, end, c, mapping, size))
    links = []
    for (i, j, kind, target_kind), members in groups.items():
        mapped = tuple(m[3] for m in members)
        sizes = tuple(m[4] for m in members)
        links.append(Link(i, j, kind, tuple(m[0].valueReference for m in members),
                          tuple(m[1].valueReference for m in members),
                          tuple(m[2] for m in members),
                          None if all(m == (1.0, 0.0) for m in mapped) else mapped,
                          None if target_kind == kind else target_kind,
                          None if all(s == 1 for s in sizes) else sizes))
    return links


def output_dependencies(description) -> dict[str, frozenset[str] | None]:
    """Inputs each output depends on, from ``ModelStructure/Outputs``.

    Returns
    -------
    dict
        ``{output name: frozenset of input names}``; an empty set for an
        output declared with ``dependencies=""`` (a state output, no direct
        feedthrough); ``None`` where nothing is declared (FMI 2.0: it may
        depend on every input).
    """
    inputs = {v.name for v in description.modelVariables if v.causality == "input"}
    result: dict[str, frozenset[str] | None] = {}
    for unknown in description.outputs:
        if unknown.dependencies is None:
            result[unknown.variable.name] = None
        else:
            result[unknown.variable.name] = frozenset(
                v.name for v in unknown.dependencies if v.name in inputs)
    return result


def _feeds_through(dependencies, component: int, output: str, input_name: str | None) -> bool:
    if dependencies is None:
        return True
    declared = dependencies[component].get(output)
    if declared is None:
        return True
    return bool(declared) if input_name is None else input_name in declared


def algebraic_loops(links: Sequence[Link], dependencies=None) -> list[Connection]:
    """Connections on (or between) cycles through direct-feedthrough dependencies.

    The graph has a node per connected variable: a connection goes from an
    output to an input, and inside a component an input leads to every
    output that depends on it (all outputs when nothing is declared).  A
    cycle in it is an algebraic loop; a cycle of components that passes
    through a state output (``dependencies=""``) is not.

    Returns
    -------
    list of Connection
        The connections left after trimming every node without a predecessor
        or successor; empty when there is no algebraic loop.
    """
    edges: dict[tuple, set] = {}
    by_component_inputs: dict[int, set[str]] = {}
    by_component_outputs: dict[int, set[str]] = {}
    owner: dict[tuple, Connection] = {}
    for link in links:
        for c in link.connections:
            a, b = (link.source, "o", c.start_variable), (link.target, "i", c.end_variable)
            edges.setdefault(a, set()).add(b)
            edges.setdefault(b, set())
            owner[(a, b)] = c
            by_component_inputs.setdefault(link.target, set()).add(c.end_variable)
            by_component_outputs.setdefault(link.source, set()).add(c.start_variable)
    for j, inputs in by_component_inputs.items():
        for u in inputs:
            for y in by_component_outputs.get(j, ()):
                if _feeds_through(dependencies, j, y, u):
                    edges[(j, "i", u)].add((j, "o", y))
    alive = set(edges)
    changed = True
    while changed:
        changed = False
        has_pred = {b for a in alive for b in edges[a] if b in alive}
        for node in list(alive):
            if node not in has_pred or not (edges[node] & alive):
                alive.discard(node)
                changed = True
    return [c for (a, b), c in owner.items() if a in alive and b in alive]


def gauss_seidel_order(names: Sequence[str], links: Sequence[Link], dependencies=None
                       ) -> tuple[list[int], list[tuple[int, int]]]:
    """Order components so each one is stepped after the ones it reads from.

    Kahn's topological sort, taking the earliest-declared ready component
    first.  When only components on cycles remain, the next one stepped is
    the earliest-declared component whose outputs to the remaining ones are
    all state outputs (declared ``dependencies=""``; the cycle is then cut
    where a step does not depend on its inputs at the same instant), else the
    earliest-declared one; its incoming edges from the remaining ones are
    *broken*: over those edges it reads values from the start of the step.
    An :class:`AlgebraicLoopWarning` lists the broken connections, only when
    a cycle runs through direct-feedthrough dependencies
    (:func:`algebraic_loops`).

    Parameters
    ----------
    names : sequence of str
        Component names.
    links : sequence of Link
        Checked, grouped connections.
    dependencies : sequence of dict, optional
        Per component, :func:`output_dependencies`; ``None``: every output
        depends on every input.

    Returns
    -------
    order : list of int
        Component indices in stepping order.
    broken : list of (int, int)
        ``(source, target)`` component pairs whose edges were broken.
    """
    n = len(names)
    preds = [set() for _ in range(n)]
    state_only = [[True] * n for _ in range(n)]
    for link in links:
        if link.source != link.target:
            preds[link.target].add(link.source)
            if any(_feeds_through(dependencies, link.source, c.start_variable, None)
                   for c in link.connections):
                state_only[link.source][link.target] = False
    remaining = set(range(n))
    order, broken = [], []
    while remaining:
        ready = [i for i in sorted(remaining) if not (preds[i] & remaining)]
        if ready:
            chosen = ready[0]
        else:
            cutting = [i for i in sorted(remaining)
                       if all(state_only[i][j] for j in remaining if i in preds[j])]
            chosen = cutting[0] if cutting else min(remaining)
            broken += [(p, chosen) for p in sorted(preds[chosen] & remaining)]
        order.append(chosen)
        remaining.remove(chosen)
    loops = algebraic_loops(links, dependencies) if broken else []
    if loops:
        pairs = ", ".join(f"{names[a]} -> {names[b]}" for a, b in broken)
        warnings.warn(f"algebraic loop in the connections ({', '.join(map(str, loops))}): "
                      f"Gauss-Seidel order {' -> '.join(names[i] for i in order)} reads "
                      f"{pairs} from the start of each step", AlgebraicLoopWarning,
                      stacklevel=4)
    return order, broken


def warn_unconnected(names: Sequence[str], variables: Sequence[Mapping], checked,
                     start_values: Sequence[Mapping]) -> list[str]:
    """Warn about inputs with neither a connection nor a start value; return them."""
    fed = {(j, end.name) for _, _, j, end, _ in checked}
    missing = []
    for i, name in enumerate(names):
        for var in variables[i].values():
            if var.causality == "input" and (i, var.name) not in fed \
                    and var.name not in start_values[i]:
                missing.append(f"{name}.{var.name}")
    if missing:
        warnings.warn(f"inputs left unconnected (they keep their start values): "
                      f"{', '.join(missing)}", UnconnectedInputWarning, stacklevel=4)
    return missing
