"""Unit conversion and linear transformation of each connection.

For a connection (a chain of :class:`~orchestration.system.Hop` s) the unit
at its start is the one declared on the start connector, else the FMU
variable's (``unit`` or its declared type's, defined in the FMU's
``UnitDefinitions``); at its end likewise; a system connector without a unit
passes the unit through.  Each hop converts from the current unit to its end
unit (unless ``suppressUnitConversion``), then applies its
``LinearTransformation``.  The result per connection is one affine map
``target = factor * source + offset``.
"""
from __future__ import annotations

from collections.abc import Sequence

from .errors import IncompatibleConnectionError, StartValueError
from .fmitypes import VALUE_TYPES, family
from .system import Hop
from .units import IDENTITY, Unit, compose, conversion, units_of_description, variable_unit

__all__ = ["connection_maps", "refuse_conversions", "start_in_variable_unit"]

_PLAIN = (Hop(),)


def _lookup(name: str | None, *tables) -> Unit | None:
    if name is None:
        return None
    for table in tables:
        if name in table:
            return table[name]
    return Unit(name)


def connection_maps(checked, descriptions: Sequence, files: Sequence[str],
                    system_units: dict, system_file: str | None) -> list[tuple[float, float]]:
    """``(factor, offset)`` per checked connection (``IDENTITY`` for most).

    Parameters
    ----------
    checked : list
        From :func:`orchestration.coupling.check_connections`.
    descriptions : sequence
        FMPy model description per component.
    files : sequence of str
        FMU file per component.
    system_units : dict
        The system file's unit definitions.
    system_file : str, optional
        The system file, for error messages.

    Raises
    ------
    IncompatibleConnectionError
        Units with different base-unit exponents (e.g. rad to degC), an
        undefined unit that differs from the other side, or a linear
        transformation on a non-Real connection; the message names the
        file, the end component and its connector.
    """
    fmu_units: dict[int, dict] = {}

    def units_of(i: int) -> dict:
        if i not in fmu_units:
            fmu_units[i] = units_of_description(descriptions[i])
        return fmu_units[i]

    maps = []
    for i, start, j, end, c in checked:
        hops = c.hops or _PLAIN
        where = system_file if system_file is not None else files[j]

        def fail(message: str, c=c, where=where) -> None:
            raise IncompatibleConnectionError(f"connection {c}: {message}", file=where,
                                              component=c.end_component,
                                              variable=c.end_variable)

        first = hops[0].start_unit
        current = _lookup(first, system_units) if first is not None else \
            _lookup(variable_unit(start), units_of(i), system_units)
        mapping = IDENTITY
        for k, hop in enumerate(hops):
            if hop.end_unit is not None:
                target = _lookup(hop.end_unit, system_units)
            elif k == len(hops) - 1:
                target = _lookup(variable_unit(end), units_of(j), system_units)
            else:
                target = current
            if not hop.suppress_unit_conversion and current is not None \
                    and target is not None:
                step = conversion(current, target)
                if step is None:
                    inside = f" ({hop.where})" if hop.where else ""
                    fail(f"unit '{current.name}' ({current.describe()}) cannot be converted "
                         f"to '{target.name}' ({target.describe()}){inside}")
                mapping = compose(mapping, step)
            mapping = compose(mapping, (hop.factor, hop.offset))
            current = target if target is not None else current
        if mapping != IDENTITY and family(VALUE_TYPES[start.type]) != "float":
            fail(f"a linear transformation on a {start.type} connection is not supported")
        maps.append(mapping)
    return maps


def refuse_conversions(system, checked, descriptions: Sequence, files: Sequence[str],
                       tool: str) -> None:
    """Raise if a connection needs a unit conversion or transformation ``tool`` cannot do.

    Raises
    ------
    IncompatibleConnectionError
        Naming the first such connection and the tool.
    """
    file = None if system.source_file is None else str(system.source_file)
    maps = connection_maps(checked, descriptions, files, system.units, file)
    for (_, _, _, _, c), mapping in zip(checked, maps):
        if mapping != IDENTITY:
            raise IncompatibleConnectionError(
                f"connection {c} converts its values (factor {mapping[0]!r}, offset "
                f"{mapping[1]!r}: units or a linear transformation), which {tool} does not "
                "do; run it with the master", file=file, component=c.end_component,
                variable=c.end_variable)


def start_in_variable_unit(value: float, unit_name: str, variable, description, system_units: dict, *,
                           file: str | None, component: str) -> float:
    """A Real start value given in ``unit_name`` (SSP ``ssv:Real unit``), in the variable's own unit.

    ``description`` is the FMU's model description (its ``UnitDefinitions``);
    ``system_units`` the system's.  Raises StartValueError naming the file,
    component and variable if the units are incompatible.
    """
    target_name = variable_unit(variable)
    if target_name is None or family(VALUE_TYPES[variable.type]) != "float":
        return value
    source = system_units.get(unit_name, Unit(unit_name))
    target = units_of_description(description).get(target_name, system_units.get(target_name, Unit(target_name)))
    mapping = conversion(source, target)
    if mapping is None:
        raise StartValueError(f"start value in unit '{unit_name}' ({source.describe()}) cannot be converted to "
                              f"the variable's unit '{target_name}' ({target.describe()})", file=file,
                              component=component, variable=variable.name)
    return mapping[0] * value + mapping[1] if mapping != (1.0, 0.0) else value
