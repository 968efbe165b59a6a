"""One process-wide FMI 2.0 logger, dispatching messages by instance name.

FMPy formats an FMU's variadic log messages through a native proxy
(``fmpy.logging.addLoggerProxy``) that keeps the Python callback in a single
static pointer: every call replaces it.  With one callback per FMU instance,
all instances would log into the most recently registered callback, and once
that callback's object is garbage collected the next message jumps into freed
memory (seen here as heap corruption at interpreter exit).  So the process
gets exactly one callback structure, proxied once and never freed, and the
messages are routed to per-instance sinks by the instance name the FMU
reports.
"""
from __future__ import annotations

import threading
from ctypes import byref

__all__ = ["callbacks", "register", "unregister"]

_LOCK = threading.Lock()
_SINKS: dict[str, object] = {}
_STATE: dict[str, object] = {}


def _dispatch(environment, instance_name, status, category, message) -> None:
    name = instance_name.decode("utf-8", "replace") if instance_name else ""
    sink = _SINKS.get(name)
    if sink is not None:
        sink(status, category.decode("utf-8", "replace") if category else "",
             message.decode("utf-8", "replace") if message else "")


def callbacks():
    """A ``fmi2CallbackFunctions`` routed through the process-wide dispatcher.

    Each call builds a new structure (an FMU may keep a pointer to it, so all
    are kept alive) and re-installs the one Python logger in FMPy's proxy, in
    case other code (``fmpy.simulate_fmu`` installs its own, short-lived
    callback) replaced it in the meantime.
    """
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
    from fmpy.logging import addLoggerProxy

    with _LOCK:
        if "logger" not in _STATE:
            _STATE["logger"] = fmi2CallbackLoggerTYPE(_dispatch)  # lives as long as the process
            _STATE["alloc"] = fmi2CallbackAllocateMemoryTYPE(calloc)
            _STATE["free"] = fmi2CallbackFreeMemoryTYPE(free)
            _STATE["structures"] = []
        cb = fmi2CallbackFunctions()
        cb.logger = _STATE["logger"]
        cb.allocateMemory = _STATE["alloc"]
        cb.freeMemory = _STATE["free"]
        addLoggerProxy(byref(cb))
        _STATE["structures"].append(cb)
        return cb


def register(name: str, sink) -> str:
    """Route messages of instance ``name`` to ``sink(status, category, text)``.

    Returns the name to instantiate with: ``name`` itself, or ``name#k`` when
    another live instance already uses it (names must be unique to route).
    """
    with _LOCK:
        unique, k = name, 1
        while unique in _SINKS:
            k += 1
            unique = f"{name}#{k}"
        _SINKS[unique] = sink
        return unique


def unregister(name: str) -> None:
    """Stop routing messages of instance ``name`` (after fmi2FreeInstance)."""
    with _LOCK:
        _SINKS.pop(name, None)
