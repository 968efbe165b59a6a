"""The C physics core (``sarins_core.h``) and its ctypes binding."""

from ._lib import ABI, LIB, CoreNotBuilt, library_path

__all__ = ["ABI", "LIB", "CoreNotBuilt", "library_path"]
