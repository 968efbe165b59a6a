"""FMI 2.0 and 3.0 variable types: get/set families, kinds, C and numpy types, array sizes.

A variable's *kind* names the ``fmi2Get*/fmi3Get*`` family that moves it:
``Real``, ``Integer`` (also FMI 2.0 enumerations), ``Boolean``, ``String`` for
FMI 2.0; the type name itself for FMI 3.0 (``Float64``, ``Int32``, ``UInt64``,
``Boolean``, ...; FMI 3.0 enumerations are read as ``Int64``, see
:func:`normalize_fmi3`).  Kinds of one *family* (``float``, ``integer``,
``boolean``) can be connected: a value crosses through a cast when the C types
differ (``fmi2Boolean`` is an ``int``, ``fmi3Boolean`` a ``bool``).

FMI 3.0 arrays (variables with ``<Dimension>``) are flattened in row-major
order; their shape comes from each dimension's ``start`` or from the value of
the structural parameter it references (its start value in the system, else
its start in the model description).
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from ctypes import c_bool, c_double, c_float, c_int, c_int8, c_int16, c_int32, c_int64, \
    c_uint8, c_uint16, c_uint32, c_uint64

import numpy as np

__all__ = ["VALUE_TYPES", "FAMILIES", "NUMPY_TYPES", "RECORDABLE", "value_type", "family",
           "c_type", "is_fmi3", "normalize_fmi3", "variable_shape", "element_names",
           "can_carry", "size_of"]

_FMI3_NUMBERS = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32",
                 "Int64", "UInt64")
# model-description type -> the getter/setter family used for it
VALUE_TYPES = {"Real": "Real", "Integer": "Integer", "Enumeration": "Integer",
               "Boolean": "Boolean", "String": "String", "Binary": "Binary", "Clock": "Clock",
               **{name: name for name in _FMI3_NUMBERS}}
FAMILIES = {"Real": "float", "Float32": "float", "Float64": "float", "Integer": "integer",
            **{name: "integer" for name in _FMI3_NUMBERS if name.startswith(("Int", "UInt"))},
            "Boolean": "boolean", "String": "string", "Binary": "binary", "Clock": "clock"}
NUMPY_TYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.bool_,
               "Float32": np.float32, "Float64": np.float64, "Int8": np.int8, "UInt8": np.uint8,
               "Int16": np.int16, "UInt16": np.uint16, "Int32": np.int32, "UInt32": np.uint32,
               "Int64": np.int64, "UInt64": np.uint64}
RECORDABLE = frozenset(NUMPY_TYPES)  # kinds the recorder stores (not String, Binary, Clock)
_C_TYPES = {"Real": c_double, "Integer": c_int, "Float32": c_float, "Float64": c_double,
            "Int8": c_int8, "UInt8": c_uint8, "Int16": c_int16, "UInt16": c_uint16,
            "Int32": c_int32, "UInt32": c_uint32, "Int64": c_int64, "UInt64": c_uint64}


def value_type(variable) -> str:
    """The get/set kind of an FMPy model variable (``Real``, ``Float64``, ``Boolean``, ...)."""
    return VALUE_TYPES[variable.type]


def family(kind: str) -> str:
    """``'float'``, ``'integer'``, ``'boolean'``, ``'string'``, ``'binary'`` or ``'clock'``."""
    return FAMILIES[kind]


def c_type(kind: str, fmi3: bool):
    """The ctypes type of one value of ``kind`` (``fmi2Boolean`` is int, ``fmi3Boolean`` bool)."""
    if kind == "Boolean":
        return c_bool if fmi3 else c_int
    return _C_TYPES[kind]


def is_fmi3(description) -> bool:
    """True for an FMI 3.0 model description."""
    return str(description.fmiVersion).startswith("3.")


def normalize_fmi3(description) -> None:
    """Give FMI 3.0 enumeration variables their value type, ``Int64`` (in place)."""
    for variable in description.modelVariables:
        if variable.type == "Enumeration":
            variable.type = "Int64"


def can_carry(source_kind: str, target_kind: str) -> bool:
    """Whether a connection may move values of ``source_kind`` into ``target_kind``.

    Same family; integers only when every source value fits the target type
    (``Int64`` to ``Int32`` is refused); floats of any width (``Float64`` to
    ``Float32`` rounds).
    """
    a, b = family(source_kind), family(target_kind)
    if a != b or a not in ("float", "integer", "boolean"):
        return False
    return a != "integer" or np.can_cast(NUMPY_TYPES[source_kind], NUMPY_TYPES[target_kind], "safe")


def variable_shape(variable, starts: Mapping[str, object] | None = None) -> tuple[int, ...]:
    """Shape of an FMI 3.0 array variable (``()`` for a scalar).

    Parameters
    ----------
    variable : fmpy ModelVariable
        With ``dimensions`` (FMPy resolves each dimension's structural parameter).
    starts : mapping, optional
        ``{variable name: start value}`` of the component: a structural
        parameter given a start value there sets the dimension.

    Raises
    ------
    ValueError
        If a dimension is not a non-negative integer.
    """
    shape = []
    for dimension in getattr(variable, "dimensions", None) or ():
        if dimension.start is not None:
            size = dimension.start
        else:
            parameter = dimension.variable
            size = (starts or {}).get(parameter.name, parameter.start)
        try:
            size = int(size)
        except (TypeError, ValueError):
            raise ValueError(f"dimension {size!r} of '{variable.name}' is not an integer") from None
        if size < 0:
            raise ValueError(f"dimension {size} of '{variable.name}' is negative")
        shape.append(size)
    return tuple(shape)


def element_names(name: str, shape: tuple[int, ...]) -> list[str]:
    """Column names of a variable's elements: ``[name]``, or ``name[1]``..``name[n]``
    (``name[i,j]`` for more dimensions, 1-based, row-major)."""
    if not shape:
        return [name]
    return [f"{name}[{','.join(str(i + 1) for i in index)}]" for index in np.ndindex(*shape)]


def size_of(shape: tuple[int, ...]) -> int:
    """Number of elements of a variable of this shape (1 for a scalar)."""
    return math.prod(shape)
