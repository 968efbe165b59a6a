"""Build the FMUs: every FMU is native (:data:`fmus.native_fmu.NATIVE`: every FMI call in C, no Python),
built by :func:`fmus.native_fmu.build_native_fmu` from its slave declaration.

Model descriptions (:func:`fix_model_description`): ``unit`` / ``displayUnit`` attributes from the
``[unit; display]`` suffix of each variable's description, with ``<UnitDefinitions>`` (SI base-unit
exponents, display-unit factors); ``ModelStructure/Outputs`` with each output's ``dependencies`` as the
slave declared them (:func:`fmus.slave_support.declare`; empty for a state output, so FMI tools see no
direct feedthrough and no algebraic loop); ``<InitialUnknowns>`` (FMI 2.0 requires every output with
initial = approx/calculated there, which ``fmpy validate`` checks).
"""

from __future__ import annotations

import math
import re
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET


from . import SLAVES

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

    from .cbuild import shared_cache
    from .native_fmu import NATIVE, build_native_fmu

    refuse_links([Path(out_dir) / f"{n}.fmu" for n in names], "FMU")
    platforms = {} if cross is None else {"win64": cross, "aarch64": cross}
    missing = [n for n in names if n not in NATIVE]
    if missing:
        raise ValueError(f"{', '.join(missing)}: no native model (fmus.native_fmu.NATIVE)")
    with shared_cache():  # the core's files compiled once for all the FMUs
        return [build_native_fmu(n, SLAVES[n], Path(out_dir), **platforms) for n in names]


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
