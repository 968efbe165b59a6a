"""Python side of the sarins FMI 2.0 native layer (shipped as ``resources/_fmi_bridge.py``).

The C core (``<model>_pycore.so``) imports this file under a name derived
from its content and calls :func:`create` once per ``fmi2Instantiate``.
Only the standard library is used here.

What it does
------------
* Reads ``resources/sarins_fmi.json`` (written by the build): the GUID, the
  alias package holding the FMU's own copy of its Python library, the slave
  module and class.
* Makes the library importable under the alias name (e.g.
  ``_sarins_lib_<hash>.sarins_fmu``), whatever packages of the same plain
  names the host has imported: the build rewrote the shipped sources'
  imports to the alias.  The alias package is imported from a per-user
  cache folder keyed by its content hash (``$SARINS_FMU_CACHE`` or
  ``$XDG_CACHE_HOME/sarins-fmu`` or ``~/.cache/sarins-fmu``; a temporary
  folder when none is writable), so a second run of the FMU finds it
  there.
* Instantiates the pythonfmu slave class with pythonfmu's keyword arguments
  and describes its variables to the C core (value reference, type,
  causality, variability, name) and, when the slave offers one, the float64
  buffer that holds its Real variables (``_fmi_buffer`` and ``_fmi_slots``,
  see ``fmus.slave_support``), which the core reads and writes directly.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import sys
import tempfile
import traceback
from pathlib import Path

CONFIG = "sarins_fmi.json"
TYPES = ("Real", "Integer", "Boolean", "String")
CAUSALITIES = ("parameter", "calculatedParameter", "input", "output", "local", "independent")
VARIABILITIES = ("constant", "fixed", "tunable", "discrete", "continuous")


class FmiUsageError(Exception):
    """The host used the FMU in a way the FMI 2.0 standard does not allow."""


def describe(exc: BaseException) -> str:
    """One line naming the exception and where it was raised (file:line in function)."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = ""
    if frames:
        last = frames[-1]
        where = f" (at {Path(last.filename).name}:{last.lineno} in {last.name})"
    text = str(exc) or repr(exc)
    return f"{type(exc).__name__}: {text}{where}"


def _cache_base() -> list[Path]:
    """Candidate cache folders, most persistent first."""
    out = []
    if os.environ.get("SARINS_FMU_CACHE"):
        out.append(Path(os.environ["SARINS_FMU_CACHE"]))
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg:
        out.append(Path(xdg) / "sarins-fmu")
    try:
        out.append(Path.home() / ".cache" / "sarins-fmu")
    except RuntimeError:  # no home directory
        pass
    out.append(Path(tempfile.gettempdir()) / f"sarins-fmu-{os.getuid()}")
    return out


def _matches(folder: Path, manifest: dict) -> bool:
    """True when ``folder`` holds every file of ``manifest`` with its size."""
    try:
        return all((folder / rel).stat().st_size == size for rel, size in manifest.items())
    except OSError:
        return False


def _library_root(resources: Path, alias: str, manifest: dict) -> Path:
    """Folder whose child ``alias`` is the package to import (a cache copy when possible)."""
    source = resources / alias
    if os.environ.get("SARINS_FMU_NO_CACHE", "") in ("1", "true", "yes"):
        return resources
    for base in _cache_base():
        target = base / alias
        if _matches(target / alias, manifest):
            return target
        try:
            base.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(prefix=f".{alias}.", dir=base))
            shutil.copytree(source, tmp / alias)
            try:
                os.rename(tmp, target)  # atomic: other processes see all or nothing
            except OSError:  # another process won the race, or a stale copy is in the way
                shutil.rmtree(tmp, ignore_errors=True)
                if not _matches(target / alias, manifest):
                    stale = Path(tempfile.mkdtemp(prefix=f".{alias}.stale.", dir=base))
                    os.rename(target, stale / "old")
                    shutil.rmtree(stale, ignore_errors=True)
                    continue
            if _matches(target / alias, manifest):
                return target
        except OSError:
            continue
    return resources


def _load_alias(resources: Path, config: dict) -> None:
    alias = config["alias"]
    if alias in sys.modules:
        return
    root = _library_root(resources, alias, config.get("manifest", {}))
    package = root / alias
    spec = importlib.util.spec_from_file_location(alias, package / "__init__.py",
                                                  submodule_search_locations=[str(package)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[alias] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(alias, None)
        raise


def _slave_class(resources: Path, config: dict):
    alias, name = config["alias"], config["slave_module"]
    module_name = f"{alias}_{name}"
    module = sys.modules.get(module_name)
    if module is None:
        spec = importlib.util.spec_from_file_location(module_name, resources / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[module_name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            sys.modules.pop(module_name, None)
            raise
    return getattr(module, config["slave_class"])


def _kind(var) -> int:
    for cls in type(var).__mro__:
        if cls.__name__ in TYPES:
            return TYPES.index(cls.__name__)
    raise TypeError(f"variable {var.name!r} has an unsupported type {type(var).__name__}")


def _enum_index(value, names, default: str) -> int:
    name = default if value is None else getattr(value, "name", str(value))
    if name not in names:
        raise ValueError(f"unknown FMI attribute value {name!r}")
    return names.index(name)


class Instance:
    """One FMU instance: the slave object and what the C core needs to serve it."""

    def __init__(self, resources: str, instance_name: str, visible: bool, guid: str):
        self.resources = Path(resources)
        with open(self.resources / CONFIG, encoding="utf-8") as f:
            self.config = json.load(f)
        if guid != self.config["guid"]:
            raise FmiUsageError(f"fmi2Instantiate: GUID {guid!r} does not match this FMU's "
                                f"{self.config['guid']!r} (modelDescription.xml of another FMU?)")
        self.instance_name = instance_name
        self.visible = bool(visible)
        _load_alias(self.resources, self.config)
        self.cls = _slave_class(self.resources, self.config)
        self.reset()

    def reset(self) -> None:
        """(Re)create the slave, as at instantiation; refresh table, buffer and categories."""
        self.slave = None
        slave = self.cls(instance_name=self.instance_name, resources=str(self.resources), visible=self.visible)
        table = []
        for vr, var in slave.vars.items():
            kind = _kind(var)
            default_variability = "continuous" if kind == 0 else "discrete"
            table.append((int(vr), kind, _enum_index(var.causality, CAUSALITIES, "local"),
                          _enum_index(var.variability, VARIABILITIES, default_variability), str(var.name)))
        self.table = table
        self.categories = [str(c) for c in getattr(slave, "log_categories", {})]
        self.buffer, self.slots = self._buffer(slave, {row[0]: row[1] for row in table})
        self.log_queue = slave._get_log_queue()
        self.slave = slave

    @staticmethod
    def _buffer(slave, kinds):
        """(buffer, [(vr, slot)]) when the slave keeps its Reals in a float64 buffer, else (None, [])."""
        buffer = getattr(slave, "_fmi_buffer", None)
        slots = getattr(slave, "_fmi_slots", None)
        if buffer is None or not slots:
            return None, []
        view = memoryview(buffer)
        if view.format != "d" or view.ndim != 1 or not view.c_contiguous or view.readonly:
            return None, []
        pairs = [(int(vr), int(slot)) for vr, slot in slots.items()]
        if any(kinds.get(vr) != 0 or not 0 <= slot < view.shape[0] for vr, slot in pairs):
            return None, []
        return buffer, pairs


def create(resources: str, instance_name: str, visible: bool, guid: str) -> Instance:
    """Entry point for the C core's fmi2Instantiate."""
    return Instance(resources, instance_name, visible, guid)
