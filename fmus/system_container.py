"""The system container: a whole system of FMI 2.0 FMUs as one native FMI 2.0 FMU, no Python, no JSON.

The container is a model behind the shared glue (``fmus/c/system_container/model.c``, interface
``fmus/c/model.h``) whose variable table is the system's: :func:`write_container_fmu` (called by
:func:`orchestration.container.build_container_fmu` with ``engine=write_container_fmu``) writes

* ``modelDescription.xml`` (FMI 2.0 co-simulation, ``modelIdentifier`` ``SystemContainer``, no FMU state)
  and ``variables.h`` from the same rows: every exposed ``component.variable``, value references 0, 1, ...;
* ``resources/<folder>/``: each component FMU unzipped (folder: the FMU's file stem, unique);
* ``resources/container_plan.txt``: the plain-text plan the binary reads when initialisation ends
  (components with folder, model identifier and GUID; container variable -> component variable; the
  connections), format in model.c; the parts, exposed variables and links it takes are
  ``orchestration.container``'s ``Part``, ``Exposed`` and ``Link`` (read by attribute);
* ``binaries/linux64`` (glibc 2.17 or later: the dl* functions are bound to their oldest versions),
  ``binaries/win64`` and ``binaries/aarch64-linux`` when their cross compilers are on PATH, ``sources/``
  and ``documentation/index.html`` with the compile lines.

The binary couples like FMPy's container (Jacobi; at the end of initialisation every connection is copied
while the components are still in Initialization Mode), so its results equal FMPy's container and the
master's Jacobi run bit for bit.
"""
from __future__ import annotations

import html
import re
import tempfile
import uuid
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from xml.etree import ElementTree as ET

from . import native_fmu as nf

IDENTIFIER = "SystemContainer"
PLAN = "container_plan.txt"
MODEL = nf.NativeModel("system_container")
_PLAIN = re.compile(r"[A-Za-z0-9_.-]+")
_TYPE_LETTER = {"Real": "R", "Integer": "I", "Enumeration": "I", "Boolean": "B", "String": "S"}
_TABLE_TYPE = {"Real": 0, "Integer": 1, "Enumeration": 1, "Boolean": 2, "String": 3}
LOG_CATEGORIES = ("logStatusWarning", "logStatusDiscard", "logStatusError", "logStatusFatal", "logAll")


MAX_COMPONENT_BYTES = 1 << 30  # uncompressed bytes of one component FMU copied into the container


def _copy_members(part, out: zipfile.ZipFile, prefix: str) -> None:
    """Every file of the component FMU ``part.fmu`` into ``out`` under ``prefix``, member by member (nothing
    written to disk); ValueError naming the component for a member that would leave its folder (absolute,
    ``..``, a drive or a backslash) or an archive over MAX_COMPONENT_BYTES."""
    try:
        archive = zipfile.ZipFile(part.fmu)
    except (zipfile.BadZipFile, OSError) as error:
        raise ValueError(f"component {part.name}: {part.fmu} is not a readable FMU ({error})") from None
    with archive:
        members = [m for m in archive.infolist() if not m.is_dir()]
        if sum(m.file_size for m in members) > MAX_COMPONENT_BYTES:
            raise ValueError(f"component {part.name}: {part.fmu} unpacks to more than {MAX_COMPONENT_BYTES} bytes")
        for member in sorted(members, key=lambda m: m.filename):
            name = member.filename
            parts = name.split("/")
            if name.startswith("/") or "\\" in name or ":" in parts[0] or ".." in parts or "" in parts:
                raise ValueError(f"component {part.name}: member {name!r} of {part.fmu} leaves its folder")
            info = zipfile.ZipInfo(prefix + name)
            info.external_attr = (0o755 if name.startswith("binaries/") else 0o644) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            out.writestr(info, archive.read(member))


def _check_plain(text: str, what: str, name: str) -> None:
    if not _PLAIN.fullmatch(text) or text.startswith("."):
        raise ValueError(f"{what} {text!r} of component {name}: the container's plan needs a plain name "
                         "([A-Za-z0-9_.-], not starting with '.')")


def plan_text(parts: list, folders: list[str], exposed: list, links: list) -> str:
    """The plan (resources/container_plan.txt), format in fmus/c/system_container/model.c."""
    lines = ["sarins-container-plan 1"]
    for part, folder in zip(parts, folders):
        md = part.description
        guid = md.guid
        for text, what in ((part.name, "name"), (folder, "folder"), (md.coSimulation.modelIdentifier, "identifier")):
            _check_plain(text, what, part.name)
        if not guid or any(ord(ch) <= 32 or ord(ch) >= 127 for ch in guid) or len(guid) >= 256:
            raise ValueError(f"GUID {guid!r} of component {part.name}: printable ASCII without spaces expected")
        lines.append(f"component {part.name} {folder} {md.coSimulation.modelIdentifier} {guid}")
    for k, e in enumerate(exposed):
        push = int(e.start is not None and e.causality != "output")
        lines.append(f"variable {k} {e.part} {e.vr} {push}")
    for link in links:
        lines.append(f"connection {_TYPE_LETTER[link.type]} {link.src} {link.src_vr} {link.dst} {link.dst_vr}")
    lines.append("end")
    return "\n".join(lines) + "\n"


def _row_start(e: object) -> tuple[str, str, str]:
    """(Real, Integer/Boolean, String) start constants of a table row."""
    real, integer, string = "0.0", "0", "NULL"
    if e.start is not None:
        if e.type == "Real":
            real = nf._c_double(float(e.start))
        elif e.type in ("Integer", "Enumeration", "Boolean"):
            integer = str(int(e.start))
        else:
            string = nf._c_string(str(e.start))
    return real, integer, string


def variables_header(exposed: list, guid: str) -> str:
    """``variables.h`` of the container (the table the glue checks every call against)."""
    counts = [0, 0, 0, 0]
    rows = []
    for k, e in enumerate(exposed):
        kind = _TABLE_TYPE[e.type]
        slot = counts[kind]
        counts[kind] += 1
        real, integer, string = _row_start(e)
        rows.append(f"    {{{nf._c_string(e.name)}, {k}u, {kind}, {nf.CAUSALITIES.index(e.causality)}, "
                    f"{nf.VARIABILITIES.index(e.variability)}, {slot}u, {real}, {integer}, {string}, -1}},")
    categories = ", ".join(nf._c_string(c) for c in LOG_CATEGORIES)
    return "\n".join([
        "/* Variables of the system container: generated by fmus/system_container.py from the system (the same",
        " * rows wrote modelDescription.xml).  Do not edit. */",
        "#ifndef SARINS_VARIABLES_H", "#define SARINS_VARIABLES_H", "", '#include "model.h"', "",
        f"static const char *const SARINS_CATEGORIES[] = {{{categories}}};", "",
        "static const sarins_var SARINS_VARIABLES[] = {", *(rows or ["    {NULL, 0u, 0, 0, 0, 0u, 0.0, 0, NULL, -1},"]),
        "};", "",
        "static const sarins_table SARINS_TABLE = {",
        f"    {nf._c_string(IDENTIFIER)}, {nf._c_string(guid)}, SARINS_VARIABLES, {len(rows)},",
        f"    {counts[0]}, {counts[1]}, {counts[2]}, {counts[3]},",
        f"    SARINS_CATEGORIES, {len(LOG_CATEGORIES)}, 0, 1}};", "", "#endif", ""])


def _literal(e: object) -> str:
    if e.type == "Boolean":
        return "true" if e.start else "false"
    if e.type == "Real":
        return repr(float(e.start))
    return str(e.start)


def model_description(name: str, guid: str, exposed: list, step: float, start_time: float,
                      stop_time: float | None, source_files: list[str]) -> bytes:
    """The container's FMI 2.0 co-simulation model description."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": name, "guid": guid,
        "generationTool": "sarins-fmu system container (fmus/c/system_container)",
        "variableNamingConvention": "flat", "numberOfEventIndicators": "0"})
    cosim = ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": IDENTIFIER, "needsExecutionTool": "false",
        "canHandleVariableCommunicationStepSize": "true", "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "true", "canGetAndSetFMUstate": "false",
        "canSerializeFMUstate": "false", "providesDirectionalDerivative": "false"})
    files = ET.SubElement(cosim, "SourceFiles")
    for f in source_files:
        ET.SubElement(files, "File", name=f)
    cats = ET.SubElement(root, "LogCategories")
    for c in LOG_CATEGORIES:
        ET.SubElement(cats, "Category", name=c)
    experiment = {"startTime": repr(float(start_time)), "stepSize": repr(float(step))}
    if stop_time is not None:
        experiment["stopTime"] = repr(float(stop_time))
    ET.SubElement(root, "DefaultExperiment", experiment)
    variables = ET.SubElement(root, "ModelVariables")
    for k, e in enumerate(exposed):
        attrs = {"name": e.name, "valueReference": str(k), "causality": e.causality, "variability": e.variability}
        if e.description:
            attrs["description"] = e.description
        if e.causality == "parameter":
            attrs["initial"] = "exact"
        sv = ET.SubElement(variables, "ScalarVariable", attrs)
        typed = {}
        if e.start is not None and e.causality != "output":
            typed["start"] = _literal(e)
        ET.SubElement(sv, "Integer" if e.type == "Enumeration" else e.type, typed)
    structure = ET.SubElement(root, "ModelStructure")
    outputs = [k + 1 for k, e in enumerate(exposed) if e.causality == "output"]
    if outputs:
        node = ET.SubElement(structure, "Outputs")
        for index in outputs:
            ET.SubElement(node, "Unknown", index=str(index))
        node = ET.SubElement(structure, "InitialUnknowns")
        for index in outputs:
            ET.SubElement(node, "Unknown", index=str(index))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


# libdl.so.2 stays a dependency: on glibc before 2.34 dlopen is there, not in libc (from 2.34 on it is a stub;
# named by file since a new glibc has no libdl.so for -ldl, only an empty libdl.a)
LINUX_LIBS = ("-Wl,--no-as-needed", "-l:libdl.so.2")


def linux_compile_line(cc: str = "cc") -> list[str]:
    """The container's Linux compile line: the components' plus libdl (dlopen)."""
    return [*nf.compile_line(IDENTIFIER, cc), *LINUX_LIBS]


def _compile(sources: Path, out: Path, cc: str, win64: bool) -> Path:
    """Compile ``sources/`` (each .c to an object, the glue's and the core's from the build cache when one is
    set: :mod:`fmus.cbuild`; only model.c holds the system) into ``out``; the binary's path."""
    from .cbuild import build

    flags = [*nf.CFLAGS, "-I."] if win64 else [*nf.CFLAGS, "-fPIC", "-I."]
    link = ["-shared", "-static"] if win64 else ["-shared", *LINUX_LIBS]
    target = out / (f"{IDENTIFIER}.dll" if win64 else f"{IDENTIFIER}.so")
    return build(cc, sorted(p.name for p in sources.glob("*.c")), target, flags, link, cwd=sources)


def _documentation(name: str, win64: bool, aarch64: bool) -> str:
    built = ["binaries/linux64 (x86-64 Linux, glibc 2.17 or later)"]
    if win64:
        built.append("binaries/win64 (x86-64 Windows, built with mingw-w64)")
    if aarch64:
        built.append(f"binaries/{nf.ARM_PLATFORM} (64-bit ARM Linux, glibc 2.17 or later)")
    line = " ".join(linux_compile_line())
    wline = " ".join([nf.MINGW, *nf.CFLAGS, "-shared", "-static", "-I.", "*.c", "-o", f"{IDENTIFIER}.dll"])
    return (f"<html><head><title>{html.escape(name)}</title></head><body><h1>{html.escape(name)}</h1>"
            "<p>A system of FMI 2.0 co-simulation FMUs as one FMU: the components are unzipped in resources/, "
            f"resources/{PLAN} says how they are coupled (Jacobi: every component steps, then every connection "
            "is copied; at the end of initialisation the connections are copied while the components are still "
            "in Initialization Mode). The binary loads each component's binary for the running platform.</p>"
            f"<h2>Platforms</h2><p>{html.escape('; '.join(built))}. Each component must carry a binary for the "
            "platform it runs on.</p>"
            f"<h2>Building from sources/</h2><pre>{html.escape(line)}</pre><p>Windows (mingw-w64):</p>"
            f"<pre>{html.escape(wline)}</pre><h2>Contract</h2><p>FMI 2.0 co-simulation; calls out of order, unknown "
            "value references and type mismatches return fmi2Error with a logged message; a bad plan or a "
            "component that fails to load or answers with an error is fmi2Error at fmi2ExitInitializationMode "
            "naming the plan's line or the component. FMU state is not supported. Nothing allocates after "
            "fmi2ExitInitializationMode.</p></body></html>")


def write_container_fmu(out_path: Path, *, name: str, parts: list, exposed: list, links: list,
                        step: float, start_time: float, stop_time: float | None, win64: bool | None = None,
                        aarch64: bool | None = None) -> Path:
    """Write the container FMU (see the module docstring); returns ``out_path``."""
    nf.compiler()
    win64 = nf.win64_compiler() is not None if win64 is None else win64
    aarch64 = nf.aarch64_compiler() is not None if aarch64 is None else aarch64
    guid = "{" + str(uuid.uuid4()) + "}"
    folders, seen = [], set()
    for part in parts:
        folder = re.sub(r"[^A-Za-z0-9_.-]", "_", part.fmu.stem).lstrip(".") or "component"
        base, k = folder, 1
        while folder in seen:
            folder, k = f"{base}_{k}", k + 1
        seen.add(folder)
        folders.append(folder)
    plan = plan_text(parts, folders, exposed, links)
    with tempfile.TemporaryDirectory(prefix="sarins_container_") as tmp:
        tmp = Path(tmp)
        sources = tmp / "sources"
        c_files = nf.write_sources(IDENTIFIER, sources, variables_header(exposed, guid), 2, MODEL)
        md = model_description(name, guid, exposed, step, start_time, stop_time, c_files)
        jobs = {f"binaries/linux64/{IDENTIFIER}.so": (tmp / "linux64", nf.compiler(), False)}
        if win64:
            jobs[f"binaries/win64/{IDENTIFIER}.dll"] = (tmp / "win64", nf.win64_compiler() or nf.MINGW, True)
        if aarch64:
            jobs[f"binaries/{nf.ARM_PLATFORM}/{IDENTIFIER}.so"] = (tmp / "aarch64", nf.aarch64_compiler() or nf.AARCH64,
                                                                   False)
        with ThreadPoolExecutor(max_workers=len(jobs)) as pool:  # the compilers run side by side
            futures = {}
            for arc, (folder, cc, windows) in jobs.items():
                folder.mkdir()
                futures[arc] = pool.submit(_compile, sources, folder, cc, windows)
            binaries = {arc: future.result() for arc, future in futures.items()}
        out_path = Path(out_path)
        out_path.parent.mkdir(parents=True, exist_ok=True)
        partial = out_path.with_name(out_path.name + ".partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", md)
            nf.write_binaries_and_sources(z, binaries, sources)
            z.writestr(f"resources/{PLAN}", plan)
            for part, folder in zip(parts, folders):
                _copy_members(part, z, f"resources/{folder}/")
            z.writestr("documentation/index.html", _documentation(name, win64, aarch64))
        partial.replace(out_path)
    return out_path
