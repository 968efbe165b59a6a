"""The compiled physics core, loaded with ctypes.

``pip install`` builds ``sarins_fmu/core/*.c`` into one shared library beside
this file (``setup.py``).  :data:`LIB` is that library; component modules
declare the prototypes they use with :func:`function`.  The environment
variable ``SARINS_CORE_LIB`` (a path) loads another build of it instead
(e.g. one built with sanitizers).
"""

from __future__ import annotations

import ctypes
import importlib.machinery
import os
from pathlib import Path

import numpy as np

ABI = 8  # SARINS_CORE_ABI in sarins_core.h

HERE = Path(__file__).resolve().parent
NAME = "_sarins_core"

c_double_p = ctypes.POINTER(ctypes.c_double)
c_int64_p = ctypes.POINTER(ctypes.c_int64)


class CoreNotBuilt(ImportError):
    """The shared library is missing or of another ABI."""


def library_path() -> Path:
    """The built library beside this file (any of this interpreter's extension suffixes), or the
    file that ``SARINS_CORE_LIB`` names."""
    override = os.environ.get("SARINS_CORE_LIB", "")
    if override:
        if not Path(override).is_file():
            raise CoreNotBuilt(f"SARINS_CORE_LIB names {override}, which is not a file")
        return Path(override)
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        candidate = HERE / (NAME + suffix)
        if candidate.is_file():
            return candidate
    raise CoreNotBuilt(f"the C physics core is not built ({HERE / NAME}*.so missing): run "
                       "'python3 -m pip install -e .' in the project folder (it needs a C compiler)")


def _origin(path: Path) -> str:
    """How to name ``path`` in a message: the environment variable when it chose the file."""
    if os.environ.get("SARINS_CORE_LIB", ""):
        return f"SARINS_CORE_LIB names {path}, which"
    return f"the C physics core at {path}"


def _load() -> ctypes.CDLL:
    path = library_path()
    try:
        lib = ctypes.CDLL(str(path))
    except OSError as exc:  # not a shared library (a text file, a truncated or foreign binary)
        raise CoreNotBuilt(f"{_origin(path)} cannot be loaded as a shared library "
                           f"({' '.join(str(exc).split())})") from None
    try:
        abi_fn = lib.sarins_core_abi
    except AttributeError:  # another library (e.g. libm)
        raise CoreNotBuilt(f"{_origin(path)} is not the sarins C physics core (no function sarins_core_abi)") \
            from None
    abi_fn.restype = ctypes.c_int
    abi_fn.argtypes = []
    abi = abi_fn()
    if abi != ABI:
        raise CoreNotBuilt(f"{_origin(path)} has ABI {abi}, this package expects {ABI}: "
                           "rebuild it with 'python3 -m pip install -e .'")
    return lib


LIB = _load()


def function(name: str, restype, *argtypes):
    """The library's function ``name`` with its prototype set."""
    try:
        fn = getattr(LIB, name)
    except AttributeError:
        raise CoreNotBuilt(f"the C physics core at {library_path()} has no function {name} (built from older "
                           "sources): rebuild it with 'python3 -m pip install -e .'") from None
    fn.restype = restype
    fn.argtypes = list(argtypes)
    return fn


def array_table(arrays) -> np.ndarray:
    """(N, 3) int64 table (address, rows, columns) of C-contiguous 1-D or 2-D float64 arrays, the form in
    which the core's table functions take a component's state (a 1-D array has 1 column).  The caller
    keeps the arrays alive and updates them in place only."""
    rows = []
    for i, a in enumerate(arrays):
        if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.c_contiguous and a.ndim in (1, 2)):
            raise ValueError(f"array table row {i}: needs a C-contiguous 1-D or 2-D float64 array")
        rows.append((a.ctypes.data, a.shape[0], a.shape[1] if a.ndim == 2 else 1))
    return np.array(rows, dtype=np.int64).reshape(len(rows), 3)
