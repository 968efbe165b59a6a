"""Direct ctypes access to the FMI 2.0 / 3.0 C functions of a loaded FMU.

The master's inner loop calls ``fmi2DoStep``, ``fmi2Get*`` and ``fmi2Set*``
(``fmi3DoStep``, ``fmi3Get*``, ``fmi3Set*``) through function pointers
prepared here, with value-reference and value arrays allocated once, and
checks the returned status itself.  Only the standard C API of the FMU's
shared library is used (the library handle comes from FMPy's
``FMU2Slave.dll`` / ``FMU3Slave.dll``).  The FMI 3.0 getters and setters take
one more argument than FMI 2.0's, ``nValues`` (the number of values, array
elements included): :func:`value_args` builds either argument list.

Speed: the pointers have no ``argtypes``, so ctypes converts nothing per
call (half the cost of a call with ``argtypes``; docs/native-layer.md,
Speed); every argument must therefore already be
a ctypes object of the C type: :func:`handle` for the instance,
:func:`count` for array lengths, ``c_double`` for times, the arrays of
:func:`vr_array` / :func:`value_buffer` or a ``c_void_p`` address for values.
A plain Python int would be passed as a C ``int`` and truncate a pointer.
"""
from __future__ import annotations

from ctypes import Array, byref, c_bool, c_double, c_int, c_size_t, c_uint, c_void_p

from .fmitypes import c_type

__all__ = ["C_TYPES", "raw_function", "getter", "setter", "do_step", "vr_array", "value_buffer", "handle",
           "count", "FMI_WARNING", "NO_SET_PRIOR", "is_fmi3_slave", "value_args", "DoStep3Flags",
           "step_args"]

FMI_WARNING = 1  # largest status that lets the simulation go on
C_TYPES = {"Real": c_double, "Integer": c_int, "Boolean": c_int}  # fmi2Boolean is an int
NO_SET_PRIOR = c_int(1)  # fmi2DoStep's noSetFMUStatePriorToCurrentPoint
NO_SET_PRIOR3 = c_bool(True)  # fmi3DoStep's (an fmi3Boolean)


def is_fmi3_slave(slave) -> bool:
    """True for an FMPy FMI 3.0 slave (``FMU3Slave``)."""
    return type(slave).__name__.startswith("FMU3")


def _prefix(slave) -> str:
    return "fmi3" if is_fmi3_slave(slave) else "fmi2"


def raw_function(slave, name: str):
    """A fresh ctypes pointer to the C function ``name`` of the slave's library (no argtypes)."""
    function = slave.dll[name]
    function.restype = c_int
    return function


def getter(slave, kind: str):
    """``fmi2Get<kind>`` / ``fmi3Get<kind>`` of the slave's library (arguments: :func:`value_args`).

    ``values`` is a :func:`value_buffer` or a ``c_void_p`` holding an address
    (to write straight into a slice of a larger array).
    """
    return raw_function(slave, f"{_prefix(slave)}Get{kind}")


def setter(slave, kind: str):
    """``fmi2Set<kind>`` / ``fmi3Set<kind>`` of the slave's library (arguments: :func:`value_args`)."""
    return raw_function(slave, f"{_prefix(slave)}Set{kind}")


def value_args(slave, component: c_void_p, vrs: Array, values, n_values: int) -> tuple:
    """Arguments of a getter/setter: ``(handle, vrs, nvr, values)``, FMI 3.0 adding ``nValues``."""
    nvr = count(len(vrs))
    return (component, vrs, nvr, values, count(n_values)) if is_fmi3_slave(slave) else \
        (component, vrs, nvr, values)


class DoStep3Flags:
    """The output arguments of ``fmi3DoStep``, allocated once per instance."""

    def __init__(self):
        self.event = c_bool()
        self.terminate = c_bool()
        self.early = c_bool()
        self.last_time = c_double()
        self.pointers = (byref(self.event), byref(self.terminate), byref(self.early),
                         byref(self.last_time))


def do_step(slave):
    """``fmi2DoStep(handle, c_double(t), c_double(h), NO_SET_PRIOR)``, or ``fmi3DoStep`` with
    its arguments from :func:`step_args`."""
    return raw_function(slave, f"{_prefix(slave)}DoStep")


def step_args(slave, component: c_void_p, t: c_double, h: c_double,
              flags: DoStep3Flags | None) -> tuple:
    """``fmi2DoStep``'s or ``fmi3DoStep``'s argument tuple (t and h are updated in place)."""
    if flags is None:
        return (component, t, h, NO_SET_PRIOR)
    return (component, t, h, NO_SET_PRIOR3, *flags.pointers)


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


def value_buffer(kind: str, n: int, fmi3: bool = False) -> Array:
    """A C array for ``n`` values of the given kind (of an FMI 3.0 FMU when ``fmi3``)."""
    return (c_type(kind, fmi3) * n)()
