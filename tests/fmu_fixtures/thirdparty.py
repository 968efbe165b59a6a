"""Third-party FMUs and engines for the master's cross-checks.

FMUs: the FMI 2.0 co-simulation FMUs built by the OpenModelica compiler
(1.20/1.21) that the PyPI package ``gemseo-fmu`` ships for Linux in
``gemseo_fmu/problems/fmu_files/linux``: ``ramp.fmu``, ``add.fmu``,
``MassSpringSubSystem1.fmu``, ``MassSpringSubSystem2.fmu`` and the
monolithic ``MassSpringSystem.fmu``.  They are taken from an installed
``gemseo_fmu`` if there is one, else from its wheel in
:data:`THIRDPARTY_DIR` (``$SARINS_THIRDPARTY_DIR``, default
``.cache/thirdparty`` in the repository), which ``.ci/run``'s set-up fills
with ``pip download --no-deps gemseo-fmu==3.1.1`` (gemseo itself is not
installed).  Tests never download: without the wheel they skip and say so.

Engines: ecospy needs the Debian library ``libtbb12``, which ``.ci/run``'s
set-up installs; without it the Ecos tests skip and say so.
"""
from __future__ import annotations

import ctypes
import importlib.util
import os
import platform
import shutil
import sys
import zipfile
from pathlib import Path

GEMSEO_FMU_WHEEL = "gemseo-fmu==3.1.1"
THIRDPARTY_DIR = Path(os.environ.get("SARINS_THIRDPARTY_DIR",
                                     Path(__file__).resolve().parents[2] / ".cache" / "thirdparty"))
OPENMODELICA_FMUS = ("ramp", "add", "MassSpringSubSystem1", "MassSpringSubSystem2",
                     "MassSpringSystem")
_INSIDE = "gemseo_fmu/problems/fmu_files/linux/"


def openmodelica_fmus(cache: Path) -> dict[str, Path] | str:
    """Return ``{name: path}`` of the OpenModelica FMUs, or the reason they are missing."""
    if sys.platform != "linux" or platform.machine() != "x86_64":
        return "the OpenModelica FMUs shipped by gemseo-fmu have linux64 binaries only"
    cache.mkdir(parents=True, exist_ok=True)
    wanted = {name: cache / f"{name}.fmu" for name in OPENMODELICA_FMUS}
    if all(p.is_file() for p in wanted.values()):
        return wanted
    spec = importlib.util.find_spec("gemseo_fmu")
    if spec is not None and spec.origin:
        folder = Path(spec.origin).parent / "problems" / "fmu_files" / "linux"
        for name, target in wanted.items():
            shutil.copyfile(folder / f"{name}.fmu", target)
        return wanted
    wheels = sorted(THIRDPARTY_DIR.glob("gemseo_fmu-*.whl"))
    if not wheels:
        return (f"no {GEMSEO_FMU_WHEEL} wheel in {THIRDPARTY_DIR} (.ci/run fetches it: "
                f"pip download --no-deps --only-binary=:all: -d {THIRDPARTY_DIR} {GEMSEO_FMU_WHEEL})")
    with zipfile.ZipFile(wheels[-1]) as wheel:
        for name, target in wanted.items():
            target.write_bytes(wheel.read(f"{_INSIDE}{name}.fmu"))
    return wanted


def ensure_libtbb() -> str | None:
    """Return why ecospy's ``libtbb.so.12`` cannot be loaded, or None when it can."""
    if sys.platform != "linux":
        return None
    try:
        ctypes.CDLL("libtbb.so.12")
        return None
    except OSError:
        return "libtbb.so.12 is missing (.ci/run installs the Debian package libtbb12)"


def has_module(name: str) -> bool:
    """True when ``name`` can be imported (without importing it)."""
    return importlib.util.find_spec(name) is not None

