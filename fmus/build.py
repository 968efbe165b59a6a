"""Build the slaves into self-contained FMI 2.0 co-simulation FMUs.

The native FMUs (:data:`fmus.native_fmu.NATIVE`: every FMI call in C, no Python) are built by
:func:`fmus.native_fmu.build_native_fmu` from the same slave declarations; the others as follows.
``build_fmus(out_dir)`` runs pythonfmu's builder on every slave with the
``sarins_fmu`` and ``fmus`` packages as resources (so a host Python with
numpy and scipy, without this project installed, runs them; the built C
physics core and its sources ride along,
:func:`core_files`), then rewrites each modelDescription.xml:

* ``unit`` / ``displayUnit`` attributes from the ``[unit; display]`` suffix
  of each variable's description, with ``<UnitDefinitions>`` (SI base-unit
  exponents, display-unit factors);
* ``ModelStructure/Outputs`` with each output's ``dependencies`` as the
  slave declared them (:func:`fmus.slave_support.declare`; empty for a state
  output, so FMI tools see no direct feedthrough and no algebraic loop);
* ``<InitialUnknowns>`` (pythonfmu leaves it out; FMI 2.0 requires every
  output with initial = approx/calculated there, which ``fmpy validate``
  checks);
* a ``documentation/index.html`` with the slave's contract.
"""

from __future__ import annotations

import html
import json
import math
import re
import shutil
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import sarins_fmu

from . import SLAVES, native

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent  # the folder holding the packages sarins_fmu and fmus
SHIPPED_PACKAGES = ("sarins_fmu", "fmus")
DEFAULT_OUT = Path("build") / "fmus"

# unit -> SI base-unit exponents (FMI 2.0 BaseUnit attributes) and factor/offset
BASE_UNITS = {
    "rad": {"rad": 1}, "rad/s": {"rad": 1, "s": -1}, "rad/s2": {"rad": 1, "s": -2},
    "m": {"m": 1}, "m/s": {"m": 1, "s": -1}, "m/s2": {"m": 1, "s": -2}, "s": {"s": 1},
    "s2/m": {"s": 2, "m": -1}, "s/rad": {"s": 1, "rad": -1}, "Hz": {"s": -1},
    "degC": {"K": 1, "offset": 273.15}, "d": {"s": 1, "factor": 86400.0},
    "1/degC": {"K": -1}, "1/degC2": {"K": -2}, "1/degC3": {"K": -3}, "1/degC4": {"K": -4},
    "rad/degC": {"rad": 1, "K": -1},
    "rad/s/degC": {"rad": 1, "s": -1, "K": -1}, "rad/s/degC2": {"rad": 1, "s": -1, "K": -2},
    "m/s2/degC": {"m": 1, "s": -2, "K": -1}, "m/s2/degC2": {"m": 1, "s": -2, "K": -2},
    "rad/s/(m/s2)": {"rad": 1, "s": 1, "m": -1},
}
# display unit -> (unit it displays, factor); display = factor * value
DISPLAY_UNITS = {
    "deg": ("rad", 180.0 / math.pi), "deg/s": ("rad/s", 180.0 / math.pi),
    "deg/s2": ("rad/s2", 180.0 / math.pi), "deg/h": ("rad/s", 180.0 / math.pi * 3600.0),
    "nmi": ("m", 1.0 / 1852.0),
}
_UNIT_RE = re.compile(r"\[([^\[\];]+)(?:;\s*([^\[\]]+))?\]\s*$")


def parse_unit(description: str):
    """(unit, display unit or None) from a description ending in [unit; display]."""
    m = _UNIT_RE.search(description or "")
    if not m:
        return None, None
    return m.group(1).strip(), (m.group(2).strip() if m.group(2) else None)


def _unit_definitions(root, used):
    defs = ET.Element("UnitDefinitions")
    for unit in sorted(used):
        node = ET.SubElement(defs, "Unit", name=unit)
        base = dict(BASE_UNITS.get(unit, {}))
        if base:
            attrs = {k: (repr(float(v)) if k in ("factor", "offset") else str(v)) for k, v in base.items()}
            ET.SubElement(node, "BaseUnit", attrs)
        for display in sorted(used[unit]):
            _, factor = DISPLAY_UNITS[display]
            ET.SubElement(node, "DisplayUnit", name=display, factor=repr(factor))
    return defs


def fix_model_description(xml_bytes: bytes, descriptions: dict | None = None,
                          dependencies: dict | None = None) -> bytes:
    """Add units, display units, UnitDefinitions, Outputs and InitialUnknowns.

    ``descriptions`` ({variable name: description}) fills in missing
    descriptions first (used for container FMUs, whose variables are the
    components' ``component.variable``).  ``dependencies`` ({output name:
    input names}) is written as each output's ``dependencies`` attribute in
    ``ModelStructure/Outputs``; an output missing from it gets none (a state
    output).  Without ``dependencies`` the attribute is left out (FMI: the
    output may depend on every input).
    """
    root = ET.fromstring(xml_bytes)
    variables = root.find("ModelVariables")
    used: dict[str, set] = {}
    initial_unknowns = []
    outputs = []
    index_of = {v.get("name"): i for i, v in enumerate(variables.findall("ScalarVariable"), start=1)}
    for index, var in enumerate(variables.findall("ScalarVariable"), start=1):
        if descriptions and not var.get("description") and var.get("name") in descriptions:
            var.set("description", descriptions[var.get("name")])
        if var.get("causality") == "output":
            outputs.append(index)
        unit, display = parse_unit(var.get("description"))
        real = var.find("Real")
        if real is not None and unit and unit != "1":
            real.set("unit", unit)
            used.setdefault(unit, set())
            if display:
                if DISPLAY_UNITS.get(display, (None,))[0] != unit:
                    raise ValueError(f"display unit {display!r} does not fit unit {unit!r} of {var.get('name')}")
                real.set("displayUnit", display)
                used[unit].add(display)
        if var.get("causality") == "output" and var.get("initial", "calculated") in ("approx", "calculated"):
            initial_unknowns.append(index)
    old = root.find("UnitDefinitions")
    if old is not None:
        root.remove(old)
    if used:
        # FMI 2.0 element order: CoSimulation, UnitDefinitions, TypeDefinitions, LogCategories, ...
        position = list(root).index(root.find("CoSimulation")) + 1
        root.insert(position, _unit_definitions(root, used))
    structure = root.find("ModelStructure")
    derivatives = structure.find("Derivatives")
    for node in list(structure):
        structure.remove(node)
    if outputs:
        node = ET.SubElement(structure, "Outputs")
        names = {i: n for n, i in index_of.items()}
        for index in outputs:
            attrs = {"index": str(index)}
            if dependencies is not None:
                inputs = dependencies.get(names[index], ())
                unknown = [n for n in inputs if n not in index_of]
                if unknown:
                    raise ValueError(f"output {names[index]} depends on unknown variables {unknown}")
                attrs["dependencies"] = " ".join(str(index_of[n]) for n in inputs)
            ET.SubElement(node, "Unknown", attrs)
    if derivatives is not None:
        structure.append(derivatives)
    if initial_unknowns:
        node = ET.SubElement(structure, "InitialUnknowns")
        for index in initial_unknowns:
            ET.SubElement(node, "Unknown", index=str(index))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _documentation(model_name: str, description: str) -> str:
    name, text = html.escape(model_name), html.escape(description)
    return (f"<html><head><title>{name}</title></head><body><h1>{name}</h1>"
            f"<p>{text}</p><p>Units: each variable's description ends in [unit; display unit].</p>"
            f"<h2>Requirements</h2><p>{html.escape(native.HOST_REQUIREMENTS)}</p>"
            "<h2>FMI 2.0 contract</h2><p>Calls out of the order of FMI 2.0 section 4.2.4, unknown value references, "
            "type mismatches and Python exceptions return fmi2Error with a logged message (never fmi2Fatal); "
            "parameters are checked at fmi2ExitInitializationMode; non-finite Real outputs are never returned "
            "with fmi2OK; messages with status Discard or worse always reach the logger, others when debug "
            "logging is on for their category (loggingOn at instantiation, or fmi2SetDebugLogging). "
            "Co-simulation only, no FMU state, no derivatives.</p></body></html>")


def _fmu_builder():
    """pythonfmu's ``FmuBuilder`` (only its model-description writing and resource copying are used:
    the binaries come from :mod:`fmus.native`).

    The builder embeds the Python sources of the ``pythonfmu`` it was imported
    from.  After a plain pythonfmu FMU was loaded in this process, ``pythonfmu``
    may be that FMU's copy in an extracted folder that is gone by now, and the
    builder would silently embed nothing; so the sources are always taken from
    the installed distribution.
    """
    from importlib.metadata import PackageNotFoundError, distribution

    from pythonfmu import builder

    try:
        installed = Path(distribution("pythonfmu").locate_file("pythonfmu"))
    except PackageNotFoundError:
        installed = builder.HERE
    if not (installed / "fmi2slave.py").is_file():
        raise RuntimeError(f"pythonfmu's sources are missing in {installed} (reinstall pythonfmu)")
    builder.HERE = installed
    return builder.FmuBuilder


def shipped_modules(slave_path: Path) -> list[str]:
    """The modules an FMU runs: the import closure of its slave within
    :data:`SHIPPED_PACKAGES`, with every package ``__init__.py`` on the way,
    as paths relative to :data:`ROOT` (imports inside functions count too).
    The library's CLI, campaigns and reports live in other packages and are
    never shipped."""
    import ast

    def module_file(name: str) -> Path | None:
        base = ROOT.joinpath(*name.split("."))
        for candidate in (base.with_suffix(".py"), base / "__init__.py"):
            if candidate.is_file():
                return candidate
        return None

    def package_of(path: Path) -> str:
        rel = path.relative_to(ROOT).with_suffix("")
        parts = list(rel.parts)
        return ".".join(parts[:-1]) if parts[-1] != "__init__" else ".".join(parts[:-1])

    seen: set[Path] = set()
    todo = [Path(slave_path).resolve()]
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        seen.add(path)
        in_tree = ROOT in path.parents
        package = package_of(path) if in_tree else ""
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[:len(package.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                names = [module] + [f"{module}.{a.name}" for a in node.names]
            for name in names:
                if name.split(".")[0] not in SHIPPED_PACKAGES:
                    continue
                parts = name.split(".")
                for k in range(1, len(parts) + 1):  # the packages on the way and the module itself
                    found = module_file(".".join(parts[:k]))
                    if found is not None and found not in seen:
                        todo.append(found)
    return sorted(str(p.relative_to(ROOT)) for p in seen if ROOT in p.parents)


def core_files() -> list[Path]:
    """The built C physics core and its sources (``sarins_fmu/core``), shipped beside the
    binding in an FMU whose library uses it, so that the FMU's copy loads its own core."""
    import importlib.machinery

    from sarins_fmu.core import _lib

    core = ROOT / "sarins_fmu" / "core"
    built = [core / (_lib.NAME + s) for s in importlib.machinery.EXTENSION_SUFFIXES if (core / (_lib.NAME + s)).is_file()]
    if not built:
        raise RuntimeError(f"the C physics core is not built in {core}: run 'python3 -m pip install -e .' first")
    return built[:1] + sorted(core.glob("*.c")) + sorted(core.glob("*.h"))


def build_fmu(slave_file: str, out_dir: Path, extra_files=()) -> Path:
    """Build one slave into ``out_dir`` and fix its model description.

    ``extra_files``: more files or folders copied into the FMU's ``resources/``
    (e.g. a trained model the slave loads from ``self.resources``).
    """
    native.compiler()  # fail early, before pythonfmu's builder runs, without a C compiler
    FmuBuilder = _fmu_builder()

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="sarins_fmu_build_") as tmp:
        tmp = Path(tmp)
        # clean copies of the packages (no caches, no build products)
        for rel in shipped_modules(HERE / slave_file):
            target = tmp / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / rel, target)
        shutil.copytree(Path(sarins_fmu.__file__).parent / "data", tmp / "sarins_fmu" / "data")
        if any(rel.startswith(str(Path("sarins_fmu") / "core")) for rel in shipped_modules(HERE / slave_file)):
            for path in core_files():
                shutil.copy2(path, tmp / "sarins_fmu" / "core" / path.name)
        script = tmp / slave_file
        shutil.copy2(HERE / slave_file, script)
        project_files = [tmp / "sarins_fmu", tmp / "fmus", *(Path(p) for p in extra_files)]
        fmu = FmuBuilder.build_FMU(script, dest=tmp / "out", project_files=project_files,
                                   needsExecutionTool=False, canHandleVariableCommunicationStepSize=False)
        if "resources/pythonfmu/fmi2slave.py" not in zipfile.ZipFile(fmu).namelist():
            raise RuntimeError(f"pythonfmu wrote {fmu.name} without its slave base class in resources/")
        target = out_dir / fmu.name
        _rewrite(fmu, target, declared_dependencies(slave_file, tmp))
    return target


def declared_dependencies(slave_file: str, resources) -> dict:
    """{output name: inputs it depends on} as the slave declares them
    (:func:`fmus.slave_support.declare`), read from an instance of the slave."""
    import importlib

    from pythonfmu import Fmi2Slave

    module = importlib.import_module(f"fmus.{Path(slave_file).stem}")
    classes = [c for c in vars(module).values() if isinstance(c, type) and issubclass(c, Fmi2Slave)
               and c.__module__ == module.__name__]
    if len(classes) != 1:
        raise RuntimeError(f"{slave_file} must define exactly one slave class, found {len(classes)}")
    slave = classes[0](instance_name="build", resources=str(resources))
    return dict(getattr(slave, "_output_dependencies", {}))


def _native_model_description(xml_bytes: bytes) -> bytes:
    """State what the FMU needs: ``needsExecutionTool`` (a CPython runtime), the generation tool."""
    from pythonfmu import __version__ as pythonfmu_version

    root = ET.fromstring(xml_bytes)
    root.set("generationTool", f"{native.LAYER} native FMI 2.0 layer (sarins-fmu) over PythonFMU {pythonfmu_version} "
                               "slave classes")
    root.find("CoSimulation").set("needsExecutionTool", "true")
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _rewrite(src: Path, dst: Path, dependencies: dict | None = None) -> None:
    """pythonfmu's FMU -> ours: native binaries, aliased library, bridge, records, documentation."""
    with zipfile.ZipFile(src) as zin:
        md = zin.read("modelDescription.xml")
        root = ET.fromstring(md)
        model_id = root.find("CoSimulation").get("modelIdentifier")
        slave_module = zin.read("resources/slavemodule.txt").decode().strip()
        library, kept = {}, []
        for item in zin.infolist():
            name = item.filename
            if name.endswith("/") or name.startswith("binaries/") or name == "modelDescription.xml":
                continue  # pythonfmu's binaries are replaced by ours (Linux x86-64 only)
            parts = name.split("/")
            data = zin.read(name)
            if parts[0] == "resources" and len(parts) > 2 and parts[1] in native._ALIASED:
                library["/".join(parts[1:])] = data
            else:
                kept.append((name, data))
    alias = native.library_alias(library)
    package = {"__init__.py": (f'"""The library shipped in this FMU, under its own name ({alias})."""\n').encode()}
    for rel, data in library.items():
        package[rel] = native.rewrite_imports(data.decode(), alias).encode() if rel.endswith(".py") else data
    config = {"guid": root.get("guid"), "alias": alias, "slave_module": slave_module,
              "slave_class": root.get("modelName"), "layer": native.LAYER,
              "manifest": {rel: len(data) for rel, data in package.items()}}
    with zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        zout.writestr("modelDescription.xml",
                      _native_model_description(fix_model_description(md, dependencies=dependencies)))
        for name, data in kept:
            if name == f"resources/{slave_module}.py":
                data = native.rewrite_imports(data.decode(), alias).encode()
            zout.writestr(name, data)
        for rel, data in package.items():
            zout.writestr(f"resources/{alias}/{rel}", data)
        zout.writestr("resources/_fmi_bridge.py", native.BRIDGE.read_bytes())
        zout.writestr("resources/sarins_fmi.json", json.dumps(config, indent=1))
        zout.writestr("resources/sarins_fmi_runtime.txt", native.runtime_record())
        for name, data in native.binaries(model_id).items():
            info = zipfile.ZipInfo(name)
            info.external_attr = 0o755 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            zout.writestr(info, data)
        zout.writestr("documentation/index.html",
                      _documentation(root.get("modelName"), root.get("description", "")))


# IMUCompensator runs only with a trained model inside: it is built by
# fmus.compensator_export.export_compensator (``sarins build-fmus --compensator MODEL``), never empty.
NEEDS_MODEL = {"IMUCompensator": "sarins build-fmus --compensator MODEL_FILE (or fmus.compensator_export)"}
DEFAULT_NAMES = [n for n in SLAVES if n not in NEEDS_MODEL]


def build_fmus(out_dir: Path | str = DEFAULT_OUT, names=None, cross: bool | None = None) -> list[Path]:
    """Build the named FMUs (default: every FMU that runs without a trained model) into
    ``out_dir``; returns their paths.  ``cross``: also the native FMUs' win64 and aarch64-linux
    binaries (default: for each, when its cross compiler is on PATH); ``False``: linux64 only."""
    names = list(DEFAULT_NAMES) if names is None else list(names)
    unknown = [n for n in names if n not in SLAVES]
    if unknown:
        raise ValueError(f"unknown FMU(s) {unknown}; known: {', '.join(SLAVES)}")
    for name in names:
        if name in NEEDS_MODEL:
            raise ValueError(f"{name} needs a trained model to run; build it with {NEEDS_MODEL[name]}")
    from sarins_fmu.files import refuse_links

    from .native_fmu import NATIVE, build_native_fmu

    refuse_links([Path(out_dir) / f"{n}.fmu" for n in names], "FMU")
    platforms = {} if cross is None else {"win64": cross, "aarch64": cross}
    return [build_native_fmu(n, SLAVES[n], Path(out_dir), **platforms) if n in NATIVE
            else build_fmu(SLAVES[n], Path(out_dir))
            for n in names]


def fix_fmu_description(path: Path, components=()) -> None:
    """Rewrite an existing FMU's model description in place with
    :func:`fix_model_description`; ``components`` [(name, fmu path)] provide
    descriptions (and so units) for container variables ``name.variable``."""
    from fmpy import read_model_description

    descriptions = {}
    for name, source in components:
        for v in read_model_description(str(source)).modelVariables:
            if v.description:
                descriptions[f"{name}.{v.name}"] = v.description
    path = Path(path)
    tmp = path.with_suffix(".tmp.fmu")
    with zipfile.ZipFile(path) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = fix_model_description(data, descriptions)
            zout.writestr(item, data)
    tmp.replace(path)
