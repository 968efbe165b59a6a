"""Direct ctypes access to the FMI 2.0 C functions of a loaded FMU.

The master's inner loop calls ``fmi2DoStep``, ``fmi2Get*`` and ``fmi2Set*``
through function pointers prepared here, with value-reference and value
arrays allocated once, and checks the returned status itself.  Only the
standard FMI 2.0 C API of the FMU's shared library is used (the library
handle comes from FMPy's ``FMU2Slave.dll``).
"""
from __future__ import annotations

from ctypes import POINTER, Array, c_double, c_int, c_size_t, c_uint, c_void_p

__all__ = ["C_TYPES", "raw_function", "getter", "setter", "do_step", "vr_array",
           "value_buffer", "FMI_WARNING"]

FMI_WARNING = 1  # largest status that lets the simulation go on
C_TYPES = {"Real": c_double, "Integer": c_int, "Boolean": c_int}  # fmi2Boolean is an int


def raw_function(slave, name: str, argtypes: list):
    """Return a fresh ctypes pointer to the C function ``name`` of the slave's library."""
    function = slave.dll[name]
    function.argtypes = argtypes
    function.restype = c_int
    return function


def getter(slave, kind: str, to_address: bool = False):
    """``fmi2Get<kind>(c, vr[], nvr, value[])`` for ``kind`` in Real/Integer/Boolean.

    With ``to_address`` the value argument is a plain address (an ``int``),
    so that values can be written straight into a slice of a larger array.
    """
    values = c_void_p if to_address else POINTER(C_TYPES[kind])
    return raw_function(slave, f"fmi2Get{kind}", [c_void_p, POINTER(c_uint), c_size_t, values])


def setter(slave, kind: str):
    """``fmi2Set<kind>(c, vr[], nvr, value[])`` for ``kind`` in Real/Integer/Boolean."""
    return raw_function(slave, f"fmi2Set{kind}",
                        [c_void_p, POINTER(c_uint), c_size_t, POINTER(C_TYPES[kind])])


def do_step(slave):
    """``fmi2DoStep(c, currentCommunicationPoint, communicationStepSize, noSetPrior)``."""
    return raw_function(slave, "fmi2DoStep", [c_void_p, c_double, c_double, c_int])


def vr_array(vrs) -> Array:
    """A C array of value references."""
    vrs = list(vrs)
    return (c_uint * len(vrs))(*vrs)


def value_buffer(kind: str, n: int) -> Array:
    """A C array for ``n`` values of the given kind."""
    return (C_TYPES[kind] * n)()
