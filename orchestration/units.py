"""Units of connected variables: definitions, compatibility and conversion.

A unit is defined as in SSP 1.0 (``ssc:Unit/ssc:BaseUnit``) and FMI 2.0 / 3.0
(``UnitDefinitions/Unit/BaseUnit``; an FMI 3.0 ``Float32``/``Float64`` variable
names its unit in its own ``unit`` attribute or its type definition's): exponents of the SI base units
(kg, m, s, A, K, mol, cd) and of the derived unit rad, plus a ``factor`` and
an ``offset`` so that ``value_SI = factor * value + offset``.  Two units are
compatible when all eight exponents are equal; a value then converts from
unit ``a`` to unit ``b`` as ``b = (a.factor * v + a.offset - b.offset) / b.factor``
(deg -> rad: factor pi/180; degC -> K: offset 273.15).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["Unit", "EXPONENTS", "unit_from_attributes", "units_of_description",
           "variable_unit", "conversion", "compose", "IDENTITY"]

EXPONENTS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
IDENTITY = (1.0, 0.0)


@dataclass(frozen=True)
class Unit:
    """A unit definition.

    Attributes
    ----------
    name : str
        Unit name as written in the files (``'deg'``, ``'degC'``).
    exponents : tuple of int, optional
        Exponents of kg, m, s, A, K, mol, cd, rad; ``None`` when the
        definition has no base unit (only equal names then match).
    factor, offset : float
        ``value_SI = factor * value + offset``.
    """

    name: str
    exponents: tuple[int, ...] | None = None
    factor: float = 1.0
    offset: float = 0.0

    def describe(self) -> str:
        """Base-unit form, e.g. ``'rad'``, ``'K'``, ``'m.s-2'``, ``'1'``."""
        if self.exponents is None:
            return "no base unit"
        parts = [name if e == 1 else f"{name}{e}"
                 for name, e in zip(EXPONENTS, self.exponents) if e]
        return ".".join(parts) or "1"


def unit_from_attributes(name: str, attributes: Mapping[str, str] | None) -> Unit:
    """Build a :class:`Unit` from the attributes of an SSP/FMI ``BaseUnit`` element.

    Raises
    ------
    ValueError
        If an exponent is not an integer or factor/offset not a finite number.
    """
    if attributes is None:
        return Unit(name)
    exponents = tuple(int(attributes.get(key, 0)) for key in EXPONENTS)
    factor = float(attributes.get("factor", 1.0))
    offset = float(attributes.get("offset", 0.0))
    if not (factor == factor and offset == offset) or factor == 0.0 \
            or abs(factor) == float("inf") or abs(offset) == float("inf"):
        raise ValueError(f"unit '{name}': factor and offset must be finite, factor non-zero")
    return Unit(name, exponents, factor, offset)


def units_of_description(description) -> dict[str, Unit]:
    """``{name: Unit}`` from an FMPy model description's ``UnitDefinitions``."""
    units = {}
    for unit in description.unitDefinitions:
        base = unit.baseUnit
        if base is None:
            units[unit.name] = Unit(unit.name)
        else:
            units[unit.name] = Unit(unit.name, tuple(int(getattr(base, k)) for k in EXPONENTS),
                                    float(base.factor), float(base.offset))
    return units


def variable_unit(variable) -> str | None:
    """Unit name of an FMPy model variable (its own, else its declared type's), or None."""
    unit = getattr(variable, "unit", None)
    if not unit and getattr(variable, "declaredType", None) is not None:
        unit = variable.declaredType.unit
    return unit or None


def conversion(source: Unit, target: Unit) -> tuple[float, float] | None:
    """``(factor, offset)`` turning a value in ``source`` into ``target``, or None.

    None means the units are incompatible (different base-unit exponents, or
    a definition without base unit and different names).
    """
    if source.name == target.name:
        return IDENTITY
    if source.exponents is None or target.exponents is None \
            or source.exponents != target.exponents:
        return None
    if source.factor == target.factor and source.offset == target.offset:
        return IDENTITY
    return source.factor / target.factor, (source.offset - target.offset) / target.factor


def compose(first: tuple[float, float], then: tuple[float, float]) -> tuple[float, float]:
    """Affine map ``then(first(v))`` as ``(factor, offset)``."""
    if first == IDENTITY:
        return then
    if then == IDENTITY:
        return first
    return then[0] * first[0], then[0] * first[1] + then[1]
