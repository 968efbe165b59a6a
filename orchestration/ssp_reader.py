"""Read SSP 1.0 system files (``.ssp`` archives or ``SystemStructure.ssd``).

The XML is parsed with :mod:`fmpy.ssp.ssd`.  Supported: one flat system of
FMU components; parameter bindings with inline ``ParameterValues`` or an
``.ssv`` source, at component level (bare variable names) or at system level
(``component.variable`` names), each with an optional ``prefix`` prepended
to the names (SSP 1.0 rule); connections between component connectors; the
``DefaultExperiment`` start/stop time and the step size stored by
:mod:`orchestration.ssp_writer` in an annotation.

Not supported (a :class:`~orchestration.errors.SystemFileError` says so):
nested systems, system-level connectors, parameter mappings, signal
dictionaries, transformations on connections, non-FMU components.
"""
from __future__ import annotations

import io
import tempfile
import zipfile
from pathlib import Path

from lxml import etree

from .errors import StartValueError, SystemFileError, UnknownComponentError
from .system import Component, Connection, StartValue, System

__all__ = ["read_system", "ANNOTATION_TYPE", "parse_literal"]

ANNOTATION_TYPE = "org.sarins-fmu.master"
SSD_NAME = "SystemStructure.ssd"
FMU_MIME = "application/x-fmu-sharedlibrary"
_NS = {
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
}


def parse_literal(type_name: str, literal: str | None, *, file: str | None = None,
                  component: str | None = None, variable: str | None = None) -> StartValue:
    """Convert an SSV/XML literal to a python value of the given SSP type.

    Parameters
    ----------
    type_name : {'Real', 'Integer', 'Boolean', 'String'}
        SSP/FMI type of the value.
    literal : str
        Text of the ``value`` attribute.

    Returns
    -------
    float, int, bool or str
    """
    try:
        if type_name == "Real":
            return float(literal)
        if type_name == "Integer":
            return int(literal)
        if type_name == "Boolean":
            text = str(literal).strip().lower()
            if text in ("true", "1"):
                return True
            if text in ("false", "0"):
                return False
            raise ValueError(literal)
        if type_name == "String":
            return "" if literal is None else str(literal)
    except (TypeError, ValueError):
        raise StartValueError(f"'{literal}' is not a valid {type_name} value",
                              file=file, component=component, variable=variable) from None
    raise StartValueError(f"parameter type {type_name} is not supported",
                          file=file, component=component, variable=variable)


def read_system(path: str | Path) -> System:
    """Read a system from an ``.ssp`` archive, an ``.ssd`` file or a folder.

    Parameters
    ----------
    path : str or Path
        ``x.ssp`` (zip with ``SystemStructure.ssd`` and the FMUs), an
        ``.ssd`` file whose component sources are relative to its folder, or
        a folder holding ``SystemStructure.ssd``.

    Returns
    -------
    System
        For an ``.ssp`` the archive is extracted to a temporary folder owned
        by the returned object (removed when it is garbage collected).

    Raises
    ------
    SystemFileError
        If the file is missing, is not valid SSP or uses an unsupported feature.
    """
    path = Path(path)
    if path.is_dir():
        path = path / SSD_NAME
    if not path.is_file():
        raise SystemFileError("system file not found", file=str(path))
    workdir = None
    if zipfile.is_zipfile(path):
        workdir = tempfile.TemporaryDirectory(prefix="orchestration_ssp_")
        try:
            with zipfile.ZipFile(path) as archive:
                archive.extractall(workdir.name)
        except (zipfile.BadZipFile, OSError) as error:
            raise SystemFileError(f"cannot extract archive: {error}", file=str(path)) from None
        base_dir = Path(workdir.name)
        archive_source: str | io.BytesIO = str(path)
        if not (base_dir / SSD_NAME).is_file():
            raise SystemFileError(f"archive has no {SSD_NAME}", file=str(path))
        ssd_text = (base_dir / SSD_NAME).read_bytes()
    else:
        base_dir = path.parent
        ssd_text = path.read_bytes()
        archive_source = _pack_ssd(path, ssd_text)
    description = _read_with_fmpy(archive_source, path)
    _refuse_transformations(ssd_text, path)
    system = _convert(description, path, base_dir)
    system.start_time, system.stop_time, system.step_size = _read_experiment(ssd_text, path)
    system._workdir = workdir
    return system


def _pack_ssd(path: Path, ssd_text: bytes) -> io.BytesIO:
    """Zip an SSD and the SSV/SSM files it references, as fmpy's reader expects."""
    buffer = io.BytesIO()
    try:
        root = etree.fromstring(ssd_text)
    except etree.XMLSyntaxError as error:
        raise SystemFileError(f"not well-formed XML: {error}", file=str(path)) from None
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr(SSD_NAME, ssd_text)
        for tag in ("ParameterBinding", "ParameterMapping", "SignalDictionary"):
            for element in root.iter(f"{{{_NS['ssd']}}}{tag}"):
                source = element.get("source")
                if source:
                    referenced = path.parent / source
                    if not referenced.is_file():
                        raise SystemFileError(f"referenced file '{source}' not found",
                                              file=str(path))
                    archive.write(referenced, source)
    buffer.seek(0)
    return buffer


def _read_with_fmpy(archive_source, path: Path):
    from fmpy.ssp import ssd as fmpy_ssd

    try:
        return fmpy_ssd.read_ssd(archive_source, validate=True)
    except etree.XMLSyntaxError as error:
        raise SystemFileError(f"not well-formed XML: {error}", file=str(path)) from None
    except (KeyError, OSError, zipfile.BadZipFile) as error:
        raise SystemFileError(f"cannot read SSD: {error}", file=str(path)) from None
    except Exception as error:  # fmpy raises bare Exception on schema errors
        raise SystemFileError(str(error), file=str(path)) from None


def _convert(description, path: Path, base_dir: Path) -> System:
    from fmpy.ssp import ssd as fmpy_ssd

    file = str(path)
    root = description.system
    if any(c.kind in ("input", "output", "inout") for c in root.connectors):
        raise SystemFileError("system-level connectors are not supported; connect "
                              "component connectors directly", file=file)
    if root.signalDictionaries:
        raise SystemFileError("signal dictionaries are not supported", file=file)
    components: list[Component] = []
    for element in root.elements:
        if not isinstance(element, fmpy_ssd.Component):
            kind = "nested systems" if isinstance(element, fmpy_ssd.System) else \
                "signal dictionary references"
            raise SystemFileError(f"{kind} are not supported", file=file,
                                  component=element.name)
        if element.type not in (None, FMU_MIME):
            raise SystemFileError(f"component type '{element.type}' is not an FMU",
                                  file=file, component=element.name)
        parameters = _bound_values(element.parameterBindings, file, element.name)
        components.append(Component(element.name, element.source, parameters))
    names = {c.name for c in components}
    system_values = _bound_values(root.parameterBindings, file, None)
    for qualified, value in system_values.items():
        name, _, variable = qualified.partition(".")
        if name not in names or not variable:
            raise UnknownComponentError(
                f"system-level parameter '{qualified}' does not name a component "
                "variable", file=file, component=name)
        target = next(c for c in components if c.name == name)
        target.parameters[variable] = value
    connections = [_connection(c, file) for c in root.connections]
    return System(name=root.name or description.name or path.stem, components=components,
                  connections=connections, base_dir=base_dir, source_file=path)


def _bound_values(bindings, file: str, component: str | None) -> dict[str, StartValue]:
    values: dict[str, StartValue] = {}
    for binding in bindings:
        if any(m.mappingEntries for m in binding.parameterMapping):
            raise SystemFileError("parameter mappings are not supported", file=file,
                                  component=component)
        prefix = binding.prefix or ""
        for parameter_set in binding.parameterValues:
            for parameter in parameter_set.parameters:
                name = prefix + parameter.name
                values[name] = parse_literal(parameter.type, parameter.value, file=file,
                                             component=component, variable=name)
    return values


def _connection(connection, file: str) -> Connection:
    if connection.startElement is None or connection.endElement is None:
        raise SystemFileError("connections to system-level connectors are not supported "
                              f"({connection.startConnector} -> {connection.endConnector})",
                              file=file)
    return Connection(connection.startElement, connection.startConnector,
                      connection.endElement, connection.endConnector)


def _refuse_transformations(ssd_text: bytes, path: Path) -> None:
    """Refuse connections with a transformation (fmpy's reader does not see them)."""
    root = etree.fromstring(ssd_text)
    for connection in root.iter(f"{{{_NS['ssd']}}}Connection"):
        for child in connection:
            if isinstance(child.tag, str) and child.tag.endswith("Transformation"):
                raise SystemFileError(
                    f"transformations on connections ({etree.QName(child).localname}) are "
                    "not supported", file=str(path), component=connection.get("endElement"),
                    variable=connection.get("endConnector"))


def _read_experiment(ssd_text: bytes, path: Path) -> tuple[float | None, ...]:
    root = etree.fromstring(ssd_text)
    experiment = root.find("ssd:DefaultExperiment", _NS)
    start = stop = step = None
    if experiment is not None:
        start = _float_or_none(experiment.get("startTime"))
        stop = _float_or_none(experiment.get("stopTime"))
        for annotation in experiment.iterfind("ssd:Annotations/ssc:Annotation", _NS):
            if annotation.get("type") == ANNOTATION_TYPE:
                for child in annotation:
                    step = _float_or_none(child.get("stepSize")) or step
    return start, stop, step


def _float_or_none(text: str | None) -> float | None:
    return None if text is None else float(text)
