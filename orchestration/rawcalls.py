"""Direct ctypes access to the FMI 2.0 C functions of a loaded FMU.

The master's inner loop calls ``fmi2DoStep``, ``fmi2Get*`` and ``fmi2Set*``
through function pointers prepared here, with value-reference and value
arrays allocated once, and checks the returned status itself.  Only the
standard FMI 2.0 C API of the FMU's shared library is used (the library
handle comes from FMPy's ``FMU2Slave.dll``).

Speed: the pointers have no ``argtypes``, so ctypes converts nothing per
call (half the cost of a call with ``argtypes``; docs/native-layer.md,
Speed); every argument must therefore already be
a ctypes object of the C type: :func:`handle` for the instance,
:func:`count` for array lengths, ``c_double`` for times, the arrays of
:func:`vr_array` / :func:`value_buffer` or a ``c_void_p`` address for values.
A plain Python int would be passed as a C ``int`` and truncate a pointer.
"""
from __future__ import annotations

from ctypes import Array, c_double, c_int, c_size_t, c_uint, c_void_p

__all__ = ["C_TYPES", "raw_function", "getter", "setter", "do_step", "vr_array", "value_buffer", "handle",
           "count", "FMI_WARNING", "NO_SET_PRIOR"]

FMI_WARNING = 1  # largest status that lets the simulation go on
C_TYPES = {"Real": c_double, "Integer": c_int, "Boolean": c_int}  # fmi2Boolean is an int
NO_SET_PRIOR = c_int(1)  # fmi2DoStep's noSetFMUStatePriorToCurrentPoint


def raw_function(slave, name: str):
    """A fresh ctypes pointer to the C function ``name`` of the slave's library (no argtypes)."""
    function = slave.dll[name]
    function.restype = c_int
    return function


def getter(slave, kind: str):
    """``fmi2Get<kind>(handle, vr_array, count, values)`` for ``kind`` in Real/Integer/Boolean.

    ``values`` is a :func:`value_buffer` or a ``c_void_p`` holding an address
    (to write straight into a slice of a larger array).
    """
    return raw_function(slave, f"fmi2Get{kind}")


def setter(slave, kind: str):
    """``fmi2Set<kind>(handle, vr_array, count, values)`` for ``kind`` in Real/Integer/Boolean."""
    return raw_function(slave, f"fmi2Set{kind}")


def do_step(slave):
    """``fmi2DoStep(handle, c_double(t), c_double(h), NO_SET_PRIOR)``."""
    return raw_function(slave, "fmi2DoStep")


def handle(slave) -> c_void_p:
    """The instance pointer (``fmi2Component``) of an instantiated FMPy slave."""
    return c_void_p(slave.component)


def count(n: int) -> c_size_t:
    """An array length as the C ``size_t`` the FMI functions take."""
    return c_size_t(n)


def vr_array(vrs) -> Array:
    """A C array of value references."""
    vrs = list(vrs)
    return (c_uint * len(vrs))(*vrs)


def value_buffer(kind: str, n: int) -> Array:
    """A C array for ``n`` values of the given kind."""
    return (C_TYPES[kind] * n)()
