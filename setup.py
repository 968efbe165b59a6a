"""Build step of the C physics core (``sarins_fmu/core/*.c``) and of the master's compiled loop
(``orchestration/steploop.c``).

pyproject.toml holds the project's metadata; this file only declares the
core as one shared library, built by ``pip install`` (regular or editable).
Both are plain C11 libraries with no libm (the core's math functions are its own, smath.c), loaded
with ctypes (:mod:`sarins_fmu.core._lib`, :mod:`orchestration.steploop`), so they export no Python module
init function.
"""

import runpy
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.errors import CCompilerError, CompileError, ExecError, LinkError, PlatformError

CORE = Path("sarins_fmu") / "core"
UNIX_FLAGS = ["-std=c11", "-O2", "-fPIC", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fno-fast-math", "-ffp-contract=off"]


class BuildCore(build_ext):
    """build_ext for a ctypes library: strict C flags, no PyInit export, a clear message without a compiler."""

    def build_extension(self, ext):
        if self.compiler.compiler_type == "msvc":
            ext.extra_compile_args = ["/std:c11", "/O2", "/W4", "/WX", "/fp:precise"]
        else:
            ext.extra_compile_args = list(UNIX_FLAGS)
        try:
            super().build_extension(ext)
        except (CCompilerError, CompileError, ExecError, LinkError, PlatformError) as exc:
            sys.exit(f"sarins-fmu: cannot build the C physics core ({exc}). "
                     "It needs a C11 compiler: install gcc or clang (Debian: apt-get install build-essential; "
                     "Windows: the MSVC build tools) and run pip install again.")

    def get_export_symbols(self, ext):
        # a plain C library: no PyInit_ function. GNU ld exports every public function by itself; MSVC's
        # linker only the names it is given
        if self.compiler.compiler_type == "msvc":
            if ext.name.startswith("orchestration."):
                return ["sl_abi", "sl_run"]
            return runpy.run_path(str(CORE / "exports.py"))["public_functions"](CORE)
        return []


setup(
    ext_modules=[Extension("sarins_fmu.core._sarins_core", sources=sorted(str(p) for p in CORE.glob("*.c")),
                           include_dirs=[str(CORE)], depends=sorted(str(p) for p in CORE.glob("*.h"))),
                 # the co-simulation master's compiled inner loop (orchestration/steploop.py)
                 Extension("orchestration._steploop", sources=["orchestration/steploop.c"])],
    cmdclass={"build_ext": BuildCore},
)
