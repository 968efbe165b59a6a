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
``x86_64-w64-mingw32-gcc`` is on PATH, ``sources/`` (every .c and .h, the FMI 2.0 headers included) and
``documentation/index.html`` with the one compile line that builds ``sources/``.

To make a model native: write ``fmus/c/<folder>/model.c`` against model.h and add one row to
:data:`NATIVE` (FMU name: its folder; the core .c files are found from the includes).
"""

from __future__ import annotations

import html
import importlib
import re
import shutil
import subprocess
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
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


# FMU name -> its native model (one row per native FMU)
NATIVE = {
    "Turntable": NativeModel("turntable"),
}

# setup.py's flags (sarins_fmu core) plus hidden visibility: only the fmi2* functions are exported
CFLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-fno-fast-math", "-ffp-contract=off",
          "-fvisibility=hidden")
MINGW = "x86_64-w64-mingw32-gcc"
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
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


def platform_note() -> str:
    """One line for the build output: which binaries the native FMUs carry."""
    names = ", ".join(NATIVE)
    if win64_compiler():
        return f"native FMUs ({names}): binaries/linux64, binaries/win64 and sources/"
    return (f"native FMUs ({names}): binaries/linux64 and sources/; binaries/win64 not built: {MINGW} is not on "
            "PATH (Debian: apt-get install gcc-mingw-w64-x86-64)")


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


def variables_header(slave, guid: str, identifier: str) -> str:
    """``variables.h``: the model's variable table from the declared slave (start values as declared)."""
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
        rows.append(f"    {{{_c_string(var.name)}, {vr}u, {TYPES[kind]}, {CAUSALITIES.index(var.causality.name)}, "
                    f"{VARIABILITIES.index(var.variability.name)}, {slot}u, {real}, {integer}, {string}}},")
        defines.append(f"#define SARINS_{letter[kind]}_{var.name} {slot}")
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
        f"    SARINS_CATEGORIES, {len(slave.log_categories)}}};", "", "#endif", ""])


def _needed_headers(files: list[Path]) -> list[Path]:
    """Every header the files include by quoted name, found in fmus/c or the core, transitively."""
    seen: dict[str, Path] = {}
    todo = list(files)
    while todo:
        for name in _INCLUDE.findall(todo.pop().read_text()):
            if name in seen or name == "variables.h" or name in FMI_HEADERS:
                continue
            for folder in (C_DIR, CORE_DIR):
                if (folder / name).is_file():
                    seen[name] = folder / name
                    todo.append(folder / name)
                    break
            else:
                raise RuntimeError(f"header {name} not found in {C_DIR} or {CORE_DIR}")
    return sorted(seen.values())


def fmi_headers_dir() -> Path:
    """The FMI 2.0 headers (the standard's, as FMPy ships them)."""
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not all((path / h).is_file() for h in FMI_HEADERS):
        raise RuntimeError(f"FMI 2.0 headers not found in {path}")
    return path


def write_sources(name: str, folder: Path, variables_h: str) -> list[str]:
    """Write the FMU's ``sources/`` into ``folder``; returns the .c file names (for ``<SourceFiles>``)."""
    model = NATIVE[name]
    c_files = [C_DIR / "fmi2_glue.c", C_DIR / "glue_core.c", C_DIR / model.folder / "model.c",
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
    for header in FMI_HEADERS:
        shutil.copy2(fmi_headers_dir() / header, folder / header)
    (folder / "variables.h").write_text(variables_h)
    return [p.name for p in c_files]


def compile_line(identifier: str, cc: str = "cc", win64: bool = False) -> list[str]:
    """The one command (run in ``sources/``) that builds the binary from the sources."""
    if win64:
        return [cc, *CFLAGS, "-shared", "-static", "-I.", "*.c", "-o", f"{identifier}.dll"]
    return [cc, *CFLAGS, "-fPIC", "-shared", "-I.", "*.c", "-lm", "-o", f"{identifier}.so"]


def compile_sources(sources: Path, identifier: str, out: Path, win64: bool = False) -> Path:
    """Compile ``sources/`` with :func:`compile_line` into ``out``; RuntimeError with the compiler's message."""
    cc = win64_compiler() if win64 else compiler()
    cmd = compile_line(identifier, cc, win64)
    files = sorted(p.name for p in sources.glob("*.c"))
    cmd = [a for a in cmd if a != "*.c"]
    cmd[cmd.index("-I.") + 1:cmd.index("-I.") + 1] = files
    target = out / cmd[-1]
    cmd[-1] = str(target)
    proc = subprocess.run(cmd, cwd=sources, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"compiling {identifier} failed:\n{' '.join(cmd)}\n{proc.stderr}")
    return target


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


def _documentation(name: str, description: str, identifier: str, win64: bool) -> str:
    line = " ".join(compile_line(identifier))
    wline = " ".join(compile_line(identifier, MINGW, win64=True))
    platforms = ("binaries/linux64 (x86-64 Linux) and binaries/win64 (x86-64 Windows, built with mingw-w64)"
                 if win64 else f"binaries/linux64 (x86-64 Linux) only: {MINGW} was not on PATH when this FMU was "
                 "built; compile sources/ for other platforms")
    return (f"<html><head><title>{html.escape(name)}</title></head><body><h1>{html.escape(name)}</h1>"
            f"<p>{html.escape(description)}</p><p>Units: each variable's description ends in [unit; display unit].</p>"
            "<h2>Requirements</h2><p>None: a native FMU. Every FMI 2.0 call is answered in C (C11 + libm); the "
            "binary loads no interpreter and needs no Python.</p>"
            f"<h2>Platforms</h2><p>{html.escape(platforms)}.</p>"
            "<h2>Building from sources/</h2><p>In the sources folder, with any C11 compiler:</p>"
            f"<pre>{html.escape(line)}</pre><p>Windows (mingw-w64):</p><pre>{html.escape(wline)}</pre>"
            "<h2>FMI 2.0 contract</h2><p>Calls out of the order of FMI 2.0 section 4.2.4, unknown value references "
            "and type mismatches return fmi2Error with a logged message (never fmi2Fatal); parameters are checked "
            "at fmi2ExitInitializationMode; non-finite Real outputs are never returned with fmi2OK; the first step "
            "starts at the start time; messages with status Discard or worse always reach the logger, others when "
            "debug logging is on for their category. Co-simulation only, no derivatives. FMU state: "
            "fmi2GetFMUstate/SetFMUstate and serialisation are supported; a serialized state carries a header "
            "(magic, format version, GUID, payload size, checksum) and a wrong, truncated or foreign one is refused "
            "with fmi2Error. Nothing allocates after fmi2ExitInitializationMode except the FMU-state calls."
            "</p></body></html>")


def build_native_fmu(name: str, slave_file: str, out_dir: Path) -> Path:
    """Build the native FMU ``name`` (declared by ``fmus/<slave_file>``) into ``out_dir``; returns its path."""
    compiler()  # fail early, with the reason, without a C compiler
    slave = slave_instance(slave_file)
    identifier = slave.modelName
    dependencies = dict(getattr(slave, "_output_dependencies", {}))
    win64 = win64_compiler() is not None
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="sarins_native_fmu_") as tmp:
        tmp = Path(tmp)
        sources = tmp / "sources"
        md = model_description(slave, dependencies, [])  # the GUID, before the sources name it
        guid = ET.fromstring(md).get("guid")
        c_files = write_sources(name, sources, variables_header(slave, guid, identifier))
        md = model_description(slave, dependencies, c_files)
        if ET.fromstring(md).get("guid") != guid:
            raise RuntimeError(f"{name}: the GUID changed between two writes of the model description")
        binaries = {f"binaries/linux64/{identifier}.so": compile_sources(sources, identifier, tmp)}
        if win64:
            binaries[f"binaries/win64/{identifier}.dll"] = compile_sources(sources, identifier, tmp, win64=True)
        target = out_dir / f"{identifier}.fmu"
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", md)
            for arc, path in binaries.items():
                info = zipfile.ZipInfo(arc)
                info.external_attr = 0o755 << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                z.writestr(info, path.read_bytes())
            for path in sorted(sources.iterdir()):
                z.write(path, f"sources/{path.name}")
            root = ET.fromstring(md)
            z.writestr("documentation/index.html",
                       _documentation(root.get("modelName"), root.get("description", ""), identifier, win64))
    return target
