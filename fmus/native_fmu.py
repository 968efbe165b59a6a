"""Native FMUs: every FMI 2.0 call answered in C, no Python in the binary (issue 18 item 3, issue 19 items 1-2).

A native FMU is the shared glue ``fmus/c/fmi2_glue.c`` + ``fmus/c/glue_core.c`` (interface ``fmus/c/model.h``), the model's
``fmus/c/<folder>/model.c`` and the C core files it needs (``sarins_fmu/core``), compiled by the build
with setup.py's flags.  The declaration stays in one place, the slave class (``fmus/<x>_slave.py``): the
build instantiates it and writes from the same objects

* ``modelDescription.xml`` with pythonfmu's writer and :func:`fmus.build.fix_model_description`, then
  the native capabilities (no execution tool, FMU state, serialisable state) and ``<SourceFiles>``;
* ``variables.h``, the C variable table (value references, types, causalities, variabilities, start
  values, the GUID and the log categories) that model.c and the glue read.

The FMU holds ``binaries/linux64/<id>.so``, ``binaries/win64/<id>.dll`` when
``x86_64-w64-mingw32-gcc`` is on PATH, ``binaries/aarch64-linux/<id>.so`` when ``aarch64-linux-gnu-gcc`` is
(64-bit ARM Linux: FMI 3.0's platform tuple, which FMI 2.0.4 and later name for every platform beyond
x86 Windows, Linux and macOS), ``sources/`` (every .c and .h, the FMI 2.0 headers included) and
``documentation/index.html`` with the one compile line that builds ``sources/``.  The C uses no libm (the
core's smath.h) and fixes its floating-point contract itself, so every binary and every compile line of
``sources/`` gives the same numbers.

To make a model native: write ``fmus/c/<folder>/model.c`` against model.h and add one row to
:data:`NATIVE` (FMU name: its folder; the core .c files are found from the includes).
"""

from __future__ import annotations

import html
import importlib
import re
import shutil
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable
from xml.etree import ElementTree as ET

HERE = Path(__file__).resolve().parent
C_DIR = HERE / "c"
CORE_DIR = HERE.parent / "sarins_fmu" / "core"


@dataclass(frozen=True)
class NativeModel:
    """Where a native model's C lives: ``fmus/c/<folder>/model.c``.  The core files it compiles are found
    from its includes (``x.c`` beside every core header ``x.h`` included, transitively); ``extra_core``
    names any other core .c file it needs."""

    folder: str
    extra_core: tuple[str, ...] = ()
    resources: Callable[[], dict[str, bytes]] | None = None  # files shipped in resources/ ({name: bytes})


@dataclass(frozen=True)
class ArrayVariable:
    """A Float64 array of the FMI 3.0 variant (FMI 2.0 has none): ``dimension`` names the Integer parameter
    that gives its length (it becomes a structural parameter); ``depends_on`` the inputs an output depends on
    (``()``: none, a state output; ``None``: unknown).  Declared by a slave class in ``fmi3_arrays``."""

    name: str
    dimension: str
    causality: str  # "output" or "input"
    description: str
    depends_on: tuple[str, ...] | None = ()


MAX_DIM = 100_000  # largest length of an array (a structural parameter's upper bound)


def identifier_resources() -> dict[str, bytes]:
    """RBFIdentifier's resources: the shipped hot and cold models as binary model files
    (``axial_rbf_<kind>.bin``, :meth:`sarins_fmu.identify.axial.DriftIdentifier.binary`)."""
    from sarins_fmu.identify.axial import DEFAULT_MODELS, DriftIdentifier

    return {f"axial_rbf_{kind}.bin": DriftIdentifier(path).binary() for kind, path in DEFAULT_MODELS.items()}


# FMU name -> its native model (one row per native FMU)
NATIVE = {
    "Turntable": NativeModel("turntable"),
    "StrapdownINS": NativeModel("strapdown_ins"),
    "IMUThermal": NativeModel("imu_thermal"),
    "RBFIdentifier": NativeModel("rbf_identifier", resources=identifier_resources),
    "IMUCompensator": NativeModel("imu_compensator"),  # its model: fmus.compensator_export
    "DriftModelUpdater": NativeModel("drift_model_updater"),
    "VehicleMotion": NativeModel("vehicle_motion"),
    "IMULog": NativeModel("imu_log"),
    "GNSSReceiver": NativeModel("gnss_receiver"),
    "AidedINS": NativeModel("aided_ins"),
    "TrajectoryIMU": NativeModel("trajectory_imu"),
}

# setup.py's flags (sarins_fmu core) plus hidden visibility: only the fmi2* functions are exported.  No
# floating-point flags and no -lm: the sources fix their contract themselves and call no libm (smath.h).
CFLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fvisibility=hidden")
MINGW = "x86_64-w64-mingw32-gcc"
AARCH64 = "aarch64-linux-gnu-gcc"
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
FMI3_HEADERS = ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")
# FMI version -> (glue file, headers, platform folders linux/windows, default output folder)
GLUE = {2: "fmi2_glue.c", 3: "fmi3_glue.c"}
HEADERS = {2: FMI_HEADERS, 3: FMI3_HEADERS}
PLATFORMS = {2: ("linux64", "win64"), 3: ("x86_64-linux", "x86_64-windows")}
ARM_PLATFORM = "aarch64-linux"  # FMI 3.0's platform tuple, also FMI 2.0.4's name for platforms it does not list
DEFAULT_OUT3 = Path("build") / "fmus3"
TYPES = {"Real": 0, "Integer": 1, "Boolean": 2, "String": 3}
CAUSALITIES = ("parameter", "calculatedParameter", "input", "output", "local", "independent")
VARIABILITIES = ("constant", "fixed", "tunable", "discrete", "continuous")
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def compiler() -> str:
    """The C compiler (``cc`` or ``gcc``); RuntimeError naming what to install when there is none."""
    for name in ("cc", "gcc"):
        found = shutil.which(name)
        if found:
            return found
    raise RuntimeError("building the native FMUs needs a C compiler (cc or gcc) on PATH "
                       "(Debian: apt-get install build-essential)")


def win64_compiler() -> str | None:
    """The mingw-w64 cross compiler, or None."""
    return shutil.which(MINGW)


def aarch64_compiler() -> str | None:
    """The aarch64 Linux cross compiler, or None."""
    return shutil.which(AARCH64)


def platform_note() -> str:
    """One line for the build output: which binaries the native FMUs carry."""
    names = ", ".join(NATIVE)
    built = ["binaries/linux64"] + (["binaries/win64"] if win64_compiler() else []) + (
        [f"binaries/{ARM_PLATFORM}"] if aarch64_compiler() else [])
    missing = ([f"binaries/win64 ({MINGW} not on PATH; Debian: apt-get install gcc-mingw-w64-x86-64)"]
               if not win64_compiler() else []) + (
        [f"binaries/{ARM_PLATFORM} ({AARCH64} not on PATH; Debian: apt-get install gcc-aarch64-linux-gnu)"]
        if not aarch64_compiler() else [])
    note = f"native FMUs ({names}): {', '.join(built)} and sources/"
    return note + (f"; not built: {'; '.join(missing)}" if missing else "")


def slave_instance(slave_file: str, resources: str = "."):
    """An instance of the slave class declared in ``fmus/<slave_file>`` (its variables, start values)."""
    from pythonfmu import Fmi2Slave

    module = importlib.import_module(f"fmus.{Path(slave_file).stem}")
    classes = [c for c in vars(module).values() if isinstance(c, type) and issubclass(c, Fmi2Slave)
               and c.__module__ == module.__name__]
    if len(classes) != 1:
        raise RuntimeError(f"{slave_file} must define exactly one slave class, found {len(classes)}")
    return classes[0](instance_name="build", resources=str(resources))


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _c_double(value: float) -> str:
    text = repr(float(value))
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"start value {text} cannot be a C constant")
    return text if any(c in text for c in ".e") else text + ".0"


def fmi3_arrays(slave) -> tuple[ArrayVariable, ...]:
    """The slave's FMI 3.0 arrays (``fmi3_arrays``), checked against its variables."""
    arrays = tuple(getattr(slave, "fmi3_arrays", ()))
    by_name = {v.name: v for v in slave.vars.values()}
    for a in arrays:
        dim = by_name.get(a.dimension)
        if dim is None or type(dim).__name__ != "Integer" or dim.causality.name != "parameter":
            raise ValueError(f"array {a.name}: its dimension {a.dimension} must be an Integer parameter")
        if a.causality not in ("output", "input") or a.name in by_name:
            raise ValueError(f"array {a.name}: causality output/input and a name of its own")
        if not 1 <= int(dim.getter()) <= MAX_DIM:
            raise ValueError(f"array {a.name}: the start value of {a.dimension} must be in 1 .. {MAX_DIM}")
    return arrays


def variables_header(slave, guid: str, identifier: str) -> str:
    """``variables.h``: the model's variable table from the declared slave (start values as declared) and,
    after its variables, the FMI 3.0 arrays it declares (``fmi3_arrays``)."""
    arrays = fmi3_arrays(slave)
    structural = {a.dimension for a in arrays}
    int_slot = {}
    rows, defines, counts = [], [], dict.fromkeys(TYPES, 0)
    letter = {"Real": "R", "Integer": "I", "Boolean": "B", "String": "S"}
    for vr, var in slave.vars.items():
        kind = type(var).__name__
        if kind not in TYPES:
            raise ValueError(f"{var.name}: unsupported variable type {kind}")
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", var.name):
            raise ValueError(f"{var.name}: not a C identifier (the table names slots after variables)")
        slot = counts[kind]
        counts[kind] += 1
        start = var.getter()
        real, integer, string = "0.0", "0", "NULL"
        if kind == "Real":
            real = _c_double(start)
        elif kind in ("Integer", "Boolean"):
            integer = str(int(start))
        else:
            string = _c_string(str(start))
        causality = 6 if var.name in structural else CAUSALITIES.index(var.causality.name)
        rows.append(f"    {{{_c_string(var.name)}, {vr}u, {TYPES[kind]}, {causality}, "
                    f"{VARIABILITIES.index(var.variability.name)}, {slot}u, {real}, {integer}, {string}, -1}},")
        defines.append(f"#define SARINS_{letter[kind]}_{var.name} {slot}")
        if kind == "Integer":
            int_slot[var.name] = slot
    for k, a in enumerate(arrays):
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", a.name):
            raise ValueError(f"{a.name}: not a C identifier")
        rows.append(f"    {{{_c_string(a.name)}, {len(slave.vars) + k}u, 0, {CAUSALITIES.index(a.causality)}, "
                    f"{VARIABILITIES.index('continuous')}, {k}u, 0.0, 0, NULL, {int_slot[a.dimension]}}},")
        defines.append(f"#define SARINS_A_{a.name} {k}")
    if [var.value_reference for var in slave.vars.values()] != list(range(len(slave.vars))):
        raise ValueError("value references must be 0, 1, ... in declaration order")
    categories = ", ".join(_c_string(c) for c in slave.log_categories)
    return "\n".join([
        f"/* Variables of {identifier}: generated by fmus/native_fmu.py from the slave class that declares them",
        " * (the same objects wrote modelDescription.xml).  Do not edit. */",
        "#ifndef SARINS_VARIABLES_H", "#define SARINS_VARIABLES_H", "", '#include "model.h"', "",
        *defines, "",
        f"static const char *const SARINS_CATEGORIES[] = {{{categories}}};", "",
        "static const sarins_var SARINS_VARIABLES[] = {", *rows, "};", "",
        "static const sarins_table SARINS_TABLE = {",
        f"    {_c_string(identifier)}, {_c_string(guid)}, SARINS_VARIABLES, {len(rows)},",
        f"    {counts['Real']}, {counts['Integer']}, {counts['Boolean']}, {counts['String']},",
        f"    SARINS_CATEGORIES, {len(slave.log_categories)}, {len(arrays)}, {MAX_DIM}}};", "", "#endif", ""])


def _needed_headers(files: list[Path]) -> list[Path]:
    """Every header the files include by quoted name, found in fmus/c or the core, transitively."""
    seen: dict[str, Path] = {}
    todo = list(files)
    while todo:
        for name in _INCLUDE.findall(todo.pop().read_text()):
            if name in seen or name == "variables.h" or name in FMI_HEADERS or name in FMI3_HEADERS:
                continue
            for folder in (C_DIR, CORE_DIR):
                if (folder / name).is_file():
                    seen[name] = folder / name
                    todo.append(folder / name)
                    break
            else:
                raise RuntimeError(f"header {name} not found in {C_DIR} or {CORE_DIR}")
    return sorted(seen.values())


def fmi_headers_dir(fmi: int = 2) -> Path:
    """The FMI 2.0 or 3.0 headers (the standard's, as FMPy ships them in fmpy/c-code)."""
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not all((path / h).is_file() for h in HEADERS[fmi]):
        raise RuntimeError(f"FMI {fmi}.0 headers not found in {path}")
    return path


def write_sources(name: str, folder: Path, variables_h: str, fmi: int = 2, model: NativeModel | None = None
                  ) -> list[str]:
    """Write the FMU's ``sources/`` into ``folder`` (the glue and headers of FMI ``fmi``.0); returns the .c
    file names (for ``<SourceFiles>`` / buildDescription.xml)."""
    model = model or NATIVE[name]
    c_files = [C_DIR / GLUE[fmi], C_DIR / "glue_core.c", C_DIR / model.folder / "model.c",
               *(CORE_DIR / f for f in model.extra_core)]
    missing = [str(p) for p in c_files if not p.is_file()]
    if missing:
        raise RuntimeError(f"{name}: sources missing: {', '.join(missing)}")
    while True:  # the core's x.c beside each core header x.h the files include
        more = [h.with_suffix(".c") for h in _needed_headers(c_files)
                if h.parent == CORE_DIR and h.with_suffix(".c").is_file() and h.with_suffix(".c") not in c_files]
        if not more:
            break
        c_files += sorted(set(more))
    folder.mkdir(parents=True, exist_ok=True)
    for path in c_files + _needed_headers(c_files):
        shutil.copy2(path, folder / path.name)
    for header in HEADERS[fmi]:
        shutil.copy2(fmi_headers_dir(fmi) / header, folder / header)
    (folder / "variables.h").write_text(variables_h)
    return [p.name for p in c_files]


def compile_line(identifier: str, cc: str = "cc", win64: bool = False) -> list[str]:
    """The one command (run in ``sources/``) that builds the binary from the sources."""
    if win64:
        return [cc, *CFLAGS, "-shared", "-static", "-I.", "*.c", "-o", f"{identifier}.dll"]
    return [cc, *CFLAGS, "-fPIC", "-shared", "-I.", "*.c", "-o", f"{identifier}.so"]


def compile_sources(sources: Path, identifier: str, out: Path, win64: bool = False, cc: str | None = None) -> Path:
    """Build ``sources/`` into ``out`` as :func:`compile_line` does (``cc``: another compiler, e.g. the aarch64
    cross compiler), one object per file through :func:`fmus.cbuild.build` (side by side, cached when
    ``$SARINS_CC_CACHE`` names a folder); RuntimeError with the compiler's message."""
    from .cbuild import build

    cc = cc or (win64_compiler() if win64 else compiler())
    line = compile_line(identifier, cc, win64)
    link = [a for a in ("-shared", "-static") if a in line]
    flags = [a for a in line[1:line.index("*.c")] if a not in link]
    files = sorted(p.name for p in sources.glob("*.c"))
    return build(cc, files, out / line[-1], flags, link, cwd=sources)


def model_description(slave, dependencies: dict, source_files: list[str]) -> bytes:
    """pythonfmu's writer + fmus.build's fixes + the native capabilities and source files."""
    from pythonfmu import __version__ as pythonfmu_version

    from .build import fix_model_description

    options = {"needsExecutionTool": False, "canHandleVariableCommunicationStepSize": False,
               "canGetAndSetFMUstate": True, "canSerializeFMUstate": True}
    xml = ET.tostring(slave.to_xml(options), encoding="UTF-8", xml_declaration=True)
    root = ET.fromstring(fix_model_description(xml, dependencies=dependencies))
    root.set("generationTool", f"sarins-fmu native FMI 2.0 glue (fmus/c) over a PythonFMU {pythonfmu_version} "
                               "declaration")
    cosim = root.find("CoSimulation")
    node = ET.SubElement(cosim, "SourceFiles")
    for name in source_files:
        ET.SubElement(node, "File", name=name)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


# FMI 2.0 type element -> FMI 3.0 variable element
FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}


def model_description3(md2: bytes, arrays: tuple[ArrayVariable, ...] = ()) -> bytes:
    """The FMI 3.0 co-simulation model description of the same model, from its FMI 2.0 one (so both come from
    the one declaration): Real -> Float64, Integer -> Int32; causality, variability, initial, start, unit and
    description kept; the independent variable ``time`` added with the value reference one past the last
    (the FMI 3.0 glue answers it); ModelStructure by value reference; FMU state as in FMI 2.0; no Event Mode,
    no intermediate update.  The source files are listed in ``sources/buildDescription.xml`` instead.
    ``arrays`` (the slave's ``fmi3_arrays``) are added after the variables as Float64 arrays whose
    ``<Dimension>`` is their structural parameter (UInt64 here, an Integer parameter in FMI 2.0)."""
    from pythonfmu import __version__ as pythonfmu_version

    old = ET.fromstring(md2)
    cosim = old.find("CoSimulation")
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": old.get("modelName"), "instantiationToken": old.get("guid"),
        "description": old.get("description", ""), "author": old.get("author", ""),
        "generationTool": f"sarins-fmu native FMI 3.0 glue (fmus/c) over a PythonFMU {pythonfmu_version} declaration",
        "generationDateAndTime": old.get("generationDateAndTime", ""),
        "variableNamingConvention": old.get("variableNamingConvention", "flat")})
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": cosim.get("modelIdentifier"), "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
        "providesDirectionalDerivatives": "false", "providesAdjointDerivatives": "false",
        "providesPerElementDependencies": "false",
        "canHandleVariableCommunicationStepSize": cosim.get("canHandleVariableCommunicationStepSize", "false"),
        "maxOutputDerivativeOrder": "0", "providesIntermediateUpdate": "false",
        "mightReturnEarlyFromDoStep": "false", "canReturnEarlyAfterIntermediateUpdate": "false",
        "hasEventMode": "false", "providesEvaluateDiscreteStates": "false"})
    for tag in ("UnitDefinitions", "LogCategories", "DefaultExperiment"):
        node = old.find(tag)
        if node is not None:
            root.append(node)
    variables = ET.SubElement(root, "ModelVariables")
    structural = {a.dimension for a in arrays}
    vrs = []
    vr_of = {}
    for sv in old.find("ModelVariables"):
        typed = sv[0]
        attrs = {k: sv.get(k) for k in ("name", "valueReference", "description", "causality", "variability",
                                          "initial") if sv.get(k) is not None}
        attrs.update({k: v for k, v in typed.attrib.items() if k in ("unit", "displayUnit", "min", "max", "nominal")})
        start = typed.get("start")
        if start is not None and typed.tag != "String":
            attrs["start"] = start
        kind = FMI3_TYPES[typed.tag]
        if sv.get("name") in structural:
            kind, attrs["causality"] = "UInt64", "structuralParameter"
            attrs["min"], attrs["max"] = "1", str(MAX_DIM)
        node = ET.SubElement(variables, kind, attrs)
        if start is not None and typed.tag == "String":
            ET.SubElement(node, "Start", value=start)
        vrs.append(sv.get("valueReference"))
        vr_of[sv.get("name")] = sv.get("valueReference")
    for k, a in enumerate(arrays):
        vr_of[a.name] = str(len(vrs) + k)
        attrs = {"name": a.name, "valueReference": vr_of[a.name], "description": a.description,
                 "causality": a.causality, "variability": "continuous"}
        if a.causality == "input":
            attrs["start"] = "0"
        node = ET.SubElement(variables, "Float64", attrs)
        ET.SubElement(node, "Dimension", valueReference=vr_of[a.dimension])
    time_vr = str(len(vrs) + len(arrays))
    time = ET.SubElement(variables, "Float64", name="time", valueReference=time_vr, causality="independent",
                         variability="continuous", description="simulation time [s]")
    if root.find("UnitDefinitions/Unit[@name='s']") is not None:
        time.set("unit", "s")
    structure = ET.SubElement(root, "ModelStructure")
    old_structure = old.find("ModelStructure")

    def vr_list(text):
        return " ".join(vrs[int(i) - 1] for i in text.split())

    for section, tag in (("Outputs", "Output"), ("InitialUnknowns", "InitialUnknown")):
        for unknown in old_structure.findall(f"{section}/Unknown"):
            attrs = {"valueReference": vrs[int(unknown.get("index")) - 1]}
            if unknown.get("dependencies") is not None:
                attrs["dependencies"] = vr_list(unknown.get("dependencies"))
                if unknown.get("dependenciesKind") is not None:
                    attrs["dependenciesKind"] = unknown.get("dependenciesKind")
            ET.SubElement(structure, tag, attrs)
        for a in arrays:
            if a.causality == "output":
                attrs = {"valueReference": vr_of[a.name]}
                if a.depends_on is not None and tag == "Output":
                    attrs["dependencies"] = " ".join(vr_of[n] for n in a.depends_on)
                ET.SubElement(structure, tag, attrs)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def build_description(identifier: str, c_files: list[str]) -> bytes:
    """``sources/buildDescription.xml`` of an FMI 3.0 FMU: the C files and the include folder."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ET.SubElement(root, "BuildConfiguration", modelIdentifier=identifier)
    files = ET.SubElement(config, "SourceFileSet", language="C11")
    for name in c_files:
        ET.SubElement(files, "SourceFile", name=name)
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


_CONTRACT2 = ("<h2>FMI 2.0 contract</h2><p>Calls out of the order of FMI 2.0 section 4.2.4, unknown value "
              "references and type mismatches return fmi2Error with a logged message (never fmi2Fatal); parameters "
              "are checked at fmi2ExitInitializationMode; non-finite Real outputs are never returned with fmi2OK; "
              "the first step starts at the start time; messages with status Discard or worse always reach the "
              "logger, others when debug logging is on for their category. Co-simulation only, no derivatives. FMU "
              "state: fmi2GetFMUstate/SetFMUstate and serialisation are supported; a serialized state carries a "
              "header (magic, format version, GUID, payload size, checksum) and a wrong, truncated or foreign one is "
              "refused with fmi2Error. Nothing allocates after fmi2ExitInitializationMode except the FMU-state calls.")
_CONTRACT3 = ("<h2>FMI 3.0 contract</h2><p>Co-simulation only, no Event Mode, no clocks, no intermediate update. "
              "Calls out of the order of the FMI 3.0 co-simulation state machine, unknown value references, type "
              "mismatches and wrong value counts return fmi3Error with a logged message (never fmi3Fatal); "
              "parameters are checked at fmi3ExitInitializationMode; non-finite Float64 outputs are never returned "
              "with fmi3OK; the first step starts at the start time of fmi3EnterInitializationMode; Real variables are "
              "Float64, Integer ones Int32; the independent variable time is readable with fmi3GetFloat64. Getters "
              "and setters of the other FMI 3.0 types, derivatives, clocks and Model Exchange return fmi3Error with "
              "the reason. FMU state: fmi3GetFMUState/SetFMUState and serialisation are supported (the blob of the "
              "FMI 2.0 variant: magic, format version, GUID, payload size, checksum); a wrong, truncated or foreign "
              "one is refused with fmi3Error. Nothing allocates after fmi3ExitInitializationMode except the "
              "FMU-state calls. sources/buildDescription.xml lists the sources.")


def _documentation(name: str, description: str, identifier: str, win64: bool, fmi: int = 2,
                   aarch64: bool = False) -> str:
    line = " ".join(compile_line(identifier))
    wline = " ".join(compile_line(identifier, MINGW, win64=True))
    linux, windows = PLATFORMS[fmi]
    built = [f"binaries/{linux} (x86-64 Linux, glibc 2.17 or later)"]
    if win64:
        built.append(f"binaries/{windows} (x86-64 Windows, built with mingw-w64)")
    if aarch64:
        built.append(f"binaries/{ARM_PLATFORM} (64-bit ARM Linux, glibc 2.17 or later; FMPy 0.3.32 looks for FMI 2.0 "
                     "binaries in binaries/linux64 on ARM too: load this one by its path)")
    platforms = "; ".join(built) + ". Every binary gives the same numbers, bit for bit; for another platform "\
        "compile sources/"
    contract = _CONTRACT3 if fmi == 3 else _CONTRACT2
    return (f"<html><head><title>{html.escape(name)}</title></head><body><h1>{html.escape(name)}</h1>"
            f"<p>{html.escape(description)}</p><p>Units: each variable's description ends in [unit; display unit].</p>"
            "<h2>Requirements</h2><p>None: a native FMU. Every FMI call is answered in C (C11, no libm: its "
            "math functions are its own, in smath.c); the binary loads no interpreter and needs no Python.</p>"
            f"<h2>Platforms</h2><p>{html.escape(platforms)}.</p>"
            "<h2>Building from sources/</h2><p>In the sources folder, with any C11 compiler (gcc, clang, "
            "mingw-w64, at any optimisation level, with or without -march=native; not -ffast-math): the sources "
            "fix their floating-point contract themselves, so the numbers are those of the shipped binaries:</p>"
            f"<pre>{html.escape(line)}</pre><p>Windows (mingw-w64):</p><pre>{html.escape(wline)}</pre>"
            f"{contract}</p></body></html>")


def write_binaries_and_sources(z: zipfile.ZipFile, binaries: dict[str, Path], sources: Path) -> None:
    """Into the FMU archive ``z``: each binary (archive name -> built file, executable) and every file of
    ``sources`` under ``sources/``."""
    for arc, path in binaries.items():
        info = zipfile.ZipInfo(arc)
        info.external_attr = 0o755 << 16
        info.compress_type = zipfile.ZIP_DEFLATED
        z.writestr(info, path.read_bytes())
    for path in sorted(sources.iterdir()):
        z.write(path, f"sources/{path.name}")


def build_native_fmu(name: str, slave_file: str | None, out_dir: Path, fmi: int = 2, win64: bool | None = None,
                     model: NativeModel | None = None, slave=None, resources: dict[str, bytes] | None = None,
                     aarch64: bool | None = None) -> Path:
    """Build the native FMU ``name`` (declared by ``fmus/<slave_file>``) for FMI ``fmi``.0 (2 or 3) into
    ``out_dir``; returns its path.  Both versions come from the same declaration and the same model.c.
    ``win64``: also the Windows binary (default: when mingw-w64 is on PATH); ``aarch64``: also the 64-bit ARM
    Linux one (default: when its cross compiler is on PATH).  ``model`` and ``slave`` (an
    instance of the declaring class) replace ``NATIVE[name]`` and ``slave_file`` (tests build models that
    are not shipped).  ``resources`` ({file name: bytes}) go into ``resources/`` beside the model's own
    (:attr:`NativeModel.resources`)."""
    if fmi not in GLUE:
        raise ValueError(f"fmi = {fmi}: the native FMUs are built for FMI 2 or 3")
    compiler()  # fail early, with the reason, without a C compiler
    slave = slave if slave is not None else slave_instance(slave_file)
    identifier = slave.modelName
    dependencies = dict(getattr(slave, "_output_dependencies", {}))
    win64 = win64_compiler() is not None if win64 is None else win64
    aarch64 = aarch64_compiler() is not None if aarch64 is None else aarch64
    linux, windows = PLATFORMS[fmi]
    native = model or NATIVE[name]
    files = (native.resources() if native.resources else {}) | dict(resources or {})
    for arc in files:
        if not re.fullmatch(r"[A-Za-z0-9_.-]+", arc) or arc.startswith("."):
            raise ValueError(f"resource file name {arc!r}: a plain file name expected")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="sarins_native_fmu_") as tmp:
        tmp = Path(tmp)
        sources = tmp / "sources"
        md = model_description(slave, dependencies, [])  # the GUID, before the sources name it
        guid = ET.fromstring(md).get("guid")
        c_files = write_sources(name, sources, variables_header(slave, guid, identifier), fmi, model)
        md = model_description(slave, dependencies, c_files)
        if ET.fromstring(md).get("guid") != guid:
            raise RuntimeError(f"{name}: the GUID changed between two writes of the model description")
        if fmi == 3:
            md = model_description3(md, fmi3_arrays(slave))
            (sources / "buildDescription.xml").write_bytes(build_description(identifier, c_files))
        binaries = {f"binaries/{linux}/{identifier}.so": compile_sources(sources, identifier, tmp)}
        if win64:
            binaries[f"binaries/{windows}/{identifier}.dll"] = compile_sources(sources, identifier, tmp, win64=True)
        if aarch64:
            arm = tmp / "aarch64"
            arm.mkdir()
            binaries[f"binaries/{ARM_PLATFORM}/{identifier}.so"] = compile_sources(sources, identifier, arm,
                                                                                   cc=aarch64_compiler() or AARCH64)
        target = out_dir / f"{identifier}.fmu"
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", md)
            write_binaries_and_sources(z, binaries, sources)
            for arc, data in sorted(files.items()):
                z.writestr(f"resources/{arc}", data)
            root = ET.fromstring(md)
            z.writestr("documentation/index.html",
                       _documentation(root.get("modelName"), root.get("description", ""), identifier, win64, fmi,
                                      aarch64))
    return target


def build_native_fmus3(out_dir: Path | str = DEFAULT_OUT3, names=None) -> list[Path]:
    """The FMI 3.0 variants of the native FMUs (default: all of :data:`NATIVE`) into ``out_dir``."""
    from . import SLAVES

    from .build import NEEDS_MODEL

    names = [n for n in NATIVE if n not in NEEDS_MODEL] if names is None else list(names)
    unknown = [n for n in names if n not in NATIVE]
    if unknown:
        raise ValueError(f"no native FMI 3.0 variant of {unknown}; native FMUs: {', '.join(NATIVE)}")
    from sarins_fmu.files import refuse_links

    from .cbuild import shared_cache

    refuse_links([Path(out_dir) / f"{n}.fmu" for n in names], "FMU")
    with shared_cache():
        return [build_native_fmu(n, SLAVES[n], Path(out_dir), fmi=3) for n in names]
