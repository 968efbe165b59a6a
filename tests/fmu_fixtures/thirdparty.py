"""Third-party FMUs and engines for the master's cross-checks.

FMUs: the FMI 2.0 co-simulation FMUs built by the OpenModelica compiler
(1.20/1.21) that the PyPI package ``gemseo-fmu`` ships for Linux in
``gemseo_fmu/problems/fmu_files/linux``: ``ramp.fmu``, ``add.fmu``,
``MassSpringSubSystem1.fmu``, ``MassSpringSubSystem2.fmu`` and the
monolithic ``MassSpringSystem.fmu``.  They are taken from an installed
``gemseo_fmu`` if there is one, else from its wheel fetched with
``pip download --no-deps`` (gemseo itself is not installed).

Engines: ecospy needs the Debian library ``libtbb12``; :func:`ensure_libtbb`
installs it with apt-get when it is missing and we are root.
"""
from __future__ import annotations

import ctypes
import importlib.util
import os
import platform
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

GEMSEO_FMU_WHEEL = "gemseo-fmu==3.1.1"
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
    done = subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps",
                           "--only-binary=:all:", "-d", str(cache), GEMSEO_FMU_WHEEL],
                          capture_output=True, text=True, timeout=600)
    wheels = sorted(cache.glob("gemseo_fmu-*.whl"))
    if done.returncode != 0 or not wheels:
        return f"could not fetch {GEMSEO_FMU_WHEEL} with pip: {done.stderr.strip()[-300:]}"
    with zipfile.ZipFile(wheels[-1]) as wheel:
        for name, target in wanted.items():
            target.write_bytes(wheel.read(f"{_INSIDE}{name}.fmu"))
    for wheel_file in wheels:
        wheel_file.unlink()
    return wanted


def ensure_libtbb() -> str | None:
    """Make ``libtbb.so.12`` loadable for ecospy; return why not, or None when it is."""
    if sys.platform != "linux":
        return None
    try:
        ctypes.CDLL("libtbb.so.12")
        return None
    except OSError:
        pass
    if os.geteuid() != 0 or shutil.which("apt-get") is None:
        return "libtbb.so.12 is missing (apt-get install libtbb12 needs root and apt)"
    for command in (["apt-get", "install", "-y", "-qq", "libtbb12"],
                    ["apt-get", "update", "-qq"],
                    ["apt-get", "install", "-y", "-qq", "libtbb12"]):
        subprocess.run(command, capture_output=True, timeout=600,
                       env={**os.environ, "DEBIAN_FRONTEND": "noninteractive"})
        try:
            ctypes.CDLL("libtbb.so.12")
            return None
        except OSError:
            continue
    return "apt-get could not install libtbb12"


def has_module(name: str) -> bool:
    """True when ``name`` can be imported (without importing it)."""
    return importlib.util.find_spec(name) is not None

