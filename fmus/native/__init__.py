"""The sarins FMI 2.0 native layer: our own binaries for pythonfmu slaves.

pythonfmu 0.7's prebuilt ``libpythonfmu-export.so`` cannot load in a host
without Python (unresolved ``_Py_NoneStruct``), finalises the interpreter
(use-after-free at exit) and frees objects twice after a Python exception.
The FMUs built here keep pythonfmu's slave classes and model-description
writer, and replace the binaries by two objects compiled with the system C
compiler when the FMUs are built (see ``docs/native-layer.md``):

* ``binaries/linux64/<model>.so``: a loader shim exporting the FMI 2.0
  functions, with no Python symbol; it finds a CPython runtime (search order
  in :data:`HOST_REQUIREMENTS`) and loads
* ``binaries/linux64/<model>_pycore.so``: the core, compiled against the
  build interpreter's headers, which hosts the slave through
  ``resources/_fmi_bridge.py`` and keeps the FMI 2.0 contract.

This module compiles the binaries, records the build interpreter and gives
the shipped Python library a unique package name (an alias) so the FMU runs
its own copy whatever the host imported.
"""

from __future__ import annotations

import functools
import hashlib
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
BRIDGE = HERE / "bridge.py"
LAYER = "sarins-fmi 1.0"
PY_VERSION = f"{sys.version_info[0]}.{sys.version_info[1]}"
HOST_REQUIREMENTS = (
    f"Host requirement: Linux x86-64 and CPython {PY_VERSION} (the version these FMUs were built with) with numpy "
    "(scipy too for DriftModelUpdater; the physics runs in the C core shipped inside). "
    "A Python host (e.g. FMPy) runs the FMU in its own interpreter. A native host needs no set-up: on the first "
    "fmi2Instantiate the FMU looks for the runtime in this order: (1) the environment variable "
    "SARINS_FMU_PYTHON (a python executable or a libpython .so), (2) the interpreter recorded at build time "
    "(resources/sarins_fmi_runtime.txt), (3) python3.X, then python3, on PATH with the build's version, "
    "(4) libpython3.X.so.1.0 on the system library path; if none fits, fmi2Instantiate logs the reason and "
    "returns NULL. The FMU's Python library is imported from a per-user cache (SARINS_FMU_CACHE, else "
    "XDG_CACHE_HOME/sarins-fmu, else ~/.cache/sarins-fmu), so a second start finds it unpacked. "
    "A Python-hosted FMU ships binaries/linux64 only.")

_ALIASED = ("sarins_fmu", "fmus", "pythonfmu")
SOURCES = ("shim.c", "core.c", "sarins_fmi.h", "sarins_uri.h")
# warnings are errors: the layer must compile clean with every compiler that builds the FMUs
WARNINGS = ("-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror")
_FROM = re.compile(r"^(\s*)from\s+(" + "|".join(_ALIASED) + r")(\.|\s)", re.M)
_IMPORT = re.compile(r"^(\s*)import\s+(" + "|".join(_ALIASED) + r")((?:\.\w+)*)(\s+as\s+\w+)?\s*$", re.M)


def compiler() -> str:
    """Path of the C compiler (``cc`` or ``gcc``); RuntimeError when there is none."""
    for name in ("cc", "gcc"):
        found = shutil.which(name)
        if found:
            return found
    raise RuntimeError("building FMUs needs a C compiler (cc or gcc) on PATH for the native FMI layer")


def _fmi_headers() -> Path:
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not (path / "fmi2FunctionTypes.h").is_file():
        raise RuntimeError(f"FMI 2.0 headers not found in {path}")
    return path


def _sources_digest() -> str:
    h = hashlib.sha256()
    for name in SOURCES:
        h.update((HERE / name).read_bytes())
    h.update(sysconfig.get_paths()["include"].encode())
    return h.hexdigest()


@functools.lru_cache(maxsize=4)
def _compiled(digest: str) -> tuple[bytes, bytes]:
    cc = compiler()
    flags = ["-O2", *WARNINGS, "-shared", "-fPIC", "-fvisibility=hidden", "-Wl,-Bsymbolic", f"-I{_fmi_headers()}", f"-I{HERE}"]
    with tempfile.TemporaryDirectory(prefix="sarins_fmi_cc_") as tmp:
        shim, core = Path(tmp) / "shim.so", Path(tmp) / "core.so"
        runs = [[cc, *flags, "-o", str(shim), str(HERE / "shim.c"), "-ldl", "-lpthread"],
                [cc, *flags, f"-I{sysconfig.get_paths()['include']}", "-o", str(core), str(HERE / "core.c"),
                 "-lpthread", "-lm"]]
        for cmd in runs:
            proc = subprocess.run(cmd, capture_output=True, text=True)
            if proc.returncode != 0:
                raise RuntimeError(f"compiling the native FMI layer failed:\n{' '.join(cmd)}\n{proc.stderr}")
        return shim.read_bytes(), core.read_bytes()


def binaries(model_identifier: str) -> dict[str, bytes]:
    """{archive name: content} of the FMU's binaries for ``model_identifier``."""
    shim, core = _compiled(_sources_digest())
    return {f"binaries/linux64/{model_identifier}.so": shim,
            f"binaries/linux64/{model_identifier}_pycore.so": core}


def runtime_record() -> str:
    """``resources/sarins_fmi_runtime.txt``: the interpreter that built the FMU."""
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    lib = ""
    for name in (sysconfig.get_config_var("INSTSONAME"), sysconfig.get_config_var("LDLIBRARY")):
        if name and ".so" in name and (Path(libdir) / name).is_file():
            lib = str(Path(libdir) / name)
            break
    return (f"version={PY_VERSION}\nexecutable={sys.executable}\nprefix={sys.prefix}\n"
            f"exec_prefix={sys.exec_prefix}\nlibpython={lib}\n")


def rewrite_imports(source: str, alias: str) -> str:
    """Point absolute imports of the shipped packages at ``alias.<package>``."""
    def from_(m):
        return f"{m.group(1)}from {alias}.{m.group(2)}{m.group(3)}"

    def import_(m):
        indent, pkg, sub, as_ = m.group(1), m.group(2), m.group(3), m.group(4)
        if as_:
            return f"{indent}import {alias}.{pkg}{sub}{as_}"
        if sub:
            raise ValueError(f"cannot alias 'import {pkg}{sub}' (write 'from {pkg} import ...' instead)")
        return f"{indent}import {alias}.{pkg} as {pkg}"

    return _IMPORT.sub(import_, _FROM.sub(from_, source))


def library_alias(files: dict[str, bytes]) -> str:
    """Alias package name from the content of the shipped library ({relative path: bytes})."""
    h = hashlib.sha256(LAYER.encode())
    for name in sorted(files):
        h.update(name.encode() + b"\0" + files[name] + b"\0")
    return f"_sarins_lib_{h.hexdigest()[:16]}"
