"""Read SSP 1.0 system files (``.ssp`` archives or ``SystemStructure.ssd``).

The SSD is parsed with a hardened lxml parser (no entity expansion, no DTD,
no network) and validated against the SSP 1.0 schema shipped with FMPy.
Supported:

- FMU components, nested ``ssd:System`` elements and system-level connectors
  (flattened by :mod:`orchestration.ssp_flatten` into direct connections;
  nested components are named by path, ``"sub.gain"``);
- units: the SSD's ``ssd:Units`` (``ssc:Unit``/``ssc:BaseUnit``) and the
  connectors' ``ssc:Real unit``; connections carry them (and any
  ``ssc:LinearTransformation`` and ``suppressUnitConversion``) to the master,
  which converts compatible units and refuses incompatible ones;
- parameter bindings with inline ``ParameterValues`` or an ``.ssv`` file
  inside the system's folder, at component level (bare variable names) or
  system level (``component.variable`` names, relative to that system), each
  with an optional ``prefix`` (SSP 1.0 rule); ``ssv:Real unit`` is kept for
  the master to convert;
- the ``DefaultExperiment`` start/stop time and the step size stored by
  :mod:`orchestration.ssp_writer` in an annotation.

Refused with a :class:`~orchestration.errors.SystemFileError` saying why:
parameter mappings (``.ssm``), signal dictionaries, non-FMU components,
Model Exchange implementations, Boolean/Integer/Enumeration mapping
transformations, Enumeration and Binary parameter values, binding sources
outside the system's folder.  ``.ssp`` archives are extracted with limits
(:mod:`orchestration.archive`); an SSD file on disk or a parameter file is
read only up to :data:`MAX_XML_BYTES`.

Component sources are trusted no further than the system: a source must be
a relative reference (percent-encoded, as a URI reference) or a ``file:``
URI (host empty or ``localhost``) that resolves inside the archive or, for
an SSD on disk, inside the SSD's folder.  ``..`` leading out, an absolute
path or ``file:`` URI elsewhere, a symbolic link leading out and any other
URI scheme are refused naming the component, before any file is opened (an
``.ssp`` received from someone else cannot make the master load a library
that is not in it).
"""
from __future__ import annotations

import dataclasses
import os
import shutil
import weakref
import zipfile
from pathlib import Path
from urllib.parse import unquote, urlsplit

from lxml import etree

from .archive import MAX_ARCHIVE_BYTES, MAX_ARCHIVE_MEMBERS, extract_archive
from .errors import StartValueError, SystemFileError
from .ssp_flatten import FMU_MIME, NS, flatten
from .system import StartValue, System
from .units import Unit, unit_from_attributes

__all__ = ["read_system", "ANNOTATION_TYPE", "parse_literal", "SSD_NAME", "FMU_MIME",
           "xml_parser"]

ANNOTATION_TYPE = "org.sarins-fmu.master"
SSD_NAME = "SystemStructure.ssd"
PARAMETER_SET_MIME = "application/x-ssp-parameter-set"
MAX_XML_BYTES = 64 * 2**20  # an SSD or SSV file on disk larger than this is refused before parsing


def xml_parser() -> etree.XMLParser:
    """An lxml parser that expands no entities and loads no DTD or network resource."""
    return etree.XMLParser(resolve_entities=False, load_dtd=False, no_network=True,
                           huge_tree=False, remove_comments=True)


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


class _Workdir:
    """A folder deleted by :meth:`cleanup` or when the object is garbage collected."""

    def __init__(self, folder: Path):
        self.name = str(folder)
        self._finalizer = weakref.finalize(self, shutil.rmtree, self.name, True)

    def cleanup(self) -> None:
        self._finalizer()


def read_system(path: str | Path, *, max_bytes: int = MAX_ARCHIVE_BYTES,
                max_members: int = MAX_ARCHIVE_MEMBERS) -> System:
    """Read a system from an ``.ssp`` archive, an ``.ssd`` file or a folder.

    Parameters
    ----------
    path : str or Path
        ``x.ssp`` (zip with ``SystemStructure.ssd`` and the FMUs), an
        ``.ssd`` file whose component sources are relative to its folder, or
        a folder holding ``SystemStructure.ssd``.
    max_bytes, max_members : int
        Limits on the uncompressed size and member count of an archive.

    Returns
    -------
    System
        For an ``.ssp`` the archive is extracted to a temporary folder owned
        by the returned object (removed by ``system._workdir.cleanup()`` or
        when the object is garbage collected).

    Raises
    ------
    SystemFileError
        If the file is missing, is not valid SSP, uses an unsupported feature
        or is an archive over the limits or with a member escaping its folder.
    """
    path = Path(path)
    if path.is_dir():
        path = path / SSD_NAME
    if not path.is_file():
        raise SystemFileError("system file not found", file=str(path))
    workdir = None
    if zipfile.is_zipfile(path):
        workdir = _Workdir(extract_archive(path, kind="ssp", max_bytes=max_bytes,
                                           max_members=max_members))
        base_dir = Path(workdir.name)
        ssd_path = base_dir / SSD_NAME
        if not ssd_path.is_file():
            workdir.cleanup()
            raise SystemFileError(f"archive has no {SSD_NAME}", file=str(path))
    else:
        base_dir, ssd_path = path.parent, path
    try:
        system = _read_ssd(ssd_path, path, base_dir)
    except BaseException:
        if workdir is not None:
            workdir.cleanup()
        raise
    system._workdir = workdir
    return system


def _parse(file: Path, shown: Path, schema: str):
    from fmpy.ssp.ssd import validate_tree

    try:
        size = file.stat().st_size
    except OSError as error:
        raise SystemFileError(f"cannot read: {error.strerror}", file=str(shown)) from None
    if size > MAX_XML_BYTES:
        raise SystemFileError(f"{size} bytes, more than the limit of {MAX_XML_BYTES} bytes "
                              "(MAX_XML_BYTES) for an SSP XML file; refused", file=str(shown))
    try:
        tree = etree.parse(str(file), xml_parser())
    except etree.XMLSyntaxError as error:
        raise SystemFileError(f"not well-formed XML: {error}", file=str(shown)) from None
    except OSError as error:
        raise SystemFileError(f"cannot read: {error}", file=str(shown)) from None
    if tree.docinfo.doctype:
        raise SystemFileError("a DOCTYPE (DTD, entity declarations) is not allowed in an SSP "
                              "file; refused", file=str(shown))
    root = tree.getroot()
    try:
        validate_tree(root, schema)
    except Exception as error:  # fmpy raises a bare Exception listing the schema errors
        raise SystemFileError(_schema_summary(str(error)), file=str(shown)) from None
    return root


def _schema_summary(text: str) -> str:
    """fmpy's schema report (a title line, then one line per error) as one line:
    the first error and how many more."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    errors = lines[1:] if len(lines) > 1 else lines
    extra = len(errors) - 1
    more = f" (and {extra} more schema error{'s' if extra > 1 else ''})" if extra else ""
    return f"not valid SSP 1.0: {errors[0] if errors else 'schema validation failed'}{more}"


def confined_source(source: str | None, base_dir: Path, *, file: str,
                    component: str) -> Path:
    """Resolve a component's ``source`` inside ``base_dir`` or refuse it.

    Nothing is opened: the path is checked as text first (``..``, absolute
    paths, URI schemes), then resolved (symbolic links are read, not
    followed into files) and checked again.

    Parameters
    ----------
    source : str
        The ``source`` attribute: a relative URI reference or a ``file:`` URI.
    base_dir : Path
        The extracted archive, or the folder of the SSD file.
    file, component : str
        For the message.

    Returns
    -------
    Path
        The resolved absolute path, inside ``base_dir``.

    Raises
    ------
    SystemFileError
        Naming the component and the source.
    """
    def refuse(why: str) -> SystemFileError:
        return SystemFileError(f"source '{source}' {why}; only files inside the "
                               f"{'archive' if _is_workdir(base_dir) else 'system folder'} are "
                               "loaded (refused before opening anything)", file=file,
                               component=component)

    if not source:
        raise SystemFileError("component has no source", file=file, component=component)
    parts = urlsplit(source)
    if len(parts.scheme) > 1:  # one letter is a drive, not a scheme
        if parts.scheme.lower() != "file":
            raise refuse(f"uses the URI scheme '{parts.scheme}'")
        if parts.netloc not in ("", "localhost"):
            raise refuse(f"names the host '{parts.netloc}'")
    if parts.query or parts.fragment:
        raise refuse("has a query or fragment")
    relative = Path(unquote(parts.path))
    roots = {Path(os.path.abspath(base_dir)), Path(base_dir).resolve()}
    target = relative if relative.is_absolute() else Path(base_dir).resolve() / relative
    lexical = Path(os.path.normpath(target))
    if not any(root in lexical.parents for root in roots):
        raise refuse("is outside" if relative.is_absolute() else "leads outside with '..'")
    real = lexical.resolve()
    if Path(base_dir).resolve() not in real.parents:
        raise refuse("leads outside through a symbolic link")
    return real


def _is_workdir(base_dir: Path) -> bool:
    from .archive import TEMP_PREFIX

    return Path(base_dir).name.startswith(f"{TEMP_PREFIX}ssp_")


def _read_ssd(ssd_path: Path, shown: Path, base_dir: Path) -> System:
    file = str(shown)
    root = _parse(ssd_path, shown, "SystemStructureDescription.xsd")
    units = _units(root.find("ssd:Units", NS), file)
    reader = _BindingReader(file, base_dir, units)
    xsystem = root.find("ssd:System", NS)
    components, connections, dangling = flatten(xsystem, file=file, units=units,
                                                read_bindings=reader)
    components = [dataclasses.replace(c, source=confined_source(c.source, base_dir, file=file,
                                                                component=c.name))
                  for c in components]
    system = System(name=xsystem.get("name") or root.get("name") or shown.stem,
                    components=components, connections=connections, base_dir=base_dir,
                    source_file=shown, units=units)
    system.start_time, system.stop_time, system.step_size = _read_experiment(root, file)
    system.inputs_without_source = dangling
    return system


def _units(element, file: str, known: dict | None = None) -> dict[str, Unit]:
    units = dict(known or {})
    if element is None:
        return units
    for xunit in element.iterfind("ssc:Unit", NS):
        name = xunit.get("name")
        base = xunit.find("ssc:BaseUnit", NS)
        try:
            unit = unit_from_attributes(name, None if base is None else base.attrib)
        except ValueError as error:
            raise SystemFileError(f"bad unit definition: {error}", file=file) from None
        if name in units and units[name] != unit:
            raise SystemFileError(f"unit '{name}' is defined twice, differently", file=file)
        units[name] = unit
    return units


class _BindingReader:
    """Start values (and their units) of an element's ``ssd:ParameterBindings``."""

    def __init__(self, file: str, base_dir: Path, units: dict):
        self.file = file
        self.base_dir = base_dir
        self.units = units

    def __call__(self, element, component: str | None):
        values: dict[str, StartValue] = {}
        value_units: dict[str, str] = {}
        for binding in element.iterfind("ssd:ParameterBindings/ssd:ParameterBinding", NS):
            if binding.get("type", PARAMETER_SET_MIME) != PARAMETER_SET_MIME:
                raise SystemFileError(f"parameter binding type '{binding.get('type')}' is "
                                      "not supported", file=self.file, component=component)
            if binding.find("ssd:ParameterMapping", NS) is not None:
                raise SystemFileError("parameter mappings are not supported", file=self.file,
                                      component=component)
            prefix = binding.get("prefix") or ""
            sets = list(binding.iterfind("ssd:ParameterValues/ssv:ParameterSet", NS))
            if binding.get("source"):
                sets.append(self._external(binding.get("source"), component))
            for parameter_set in sets:
                for name, value, unit in self._parameters(parameter_set, component, prefix):
                    values[name] = value
                    if unit is None:
                        value_units.pop(name, None)
                    else:
                        value_units[name] = unit
        return values, value_units

    def _external(self, source: str, component: str | None):
        if ":" in source or source.startswith("/"):
            raise SystemFileError(f"parameter binding source '{source}' is not a relative "
                                  "file reference; only files inside the system's folder "
                                  "are supported", file=self.file, component=component)
        base = self.base_dir.resolve()
        target = (base / source).resolve()
        if base not in target.parents:
            raise SystemFileError(f"parameter binding source '{source}' is outside the "
                                  "system's folder; refused", file=self.file,
                                  component=component)
        if not target.is_file():
            raise SystemFileError(f"referenced file '{source}' not found", file=self.file,
                                  component=component)
        return _parse(target, target, "SystemStructureParameterValues.xsd")

    def _parameters(self, parameter_set, component: str | None, prefix: str):
        file = self.file
        local_units = _units(parameter_set.find("ssv:Units", NS), file, self.units)
        for key, unit in local_units.items():
            self.units.setdefault(key, unit)
        for parameter in parameter_set.iterfind("ssv:Parameters/ssv:Parameter", NS):
            name = prefix + parameter.get("name")
            typed = next((c for c in parameter if isinstance(c.tag, str)), None)
            kind = etree.QName(typed).localname if typed is not None else None
            if kind not in ("Real", "Integer", "Boolean", "String"):
                raise SystemFileError(f"parameter values of type {kind} are not supported",
                                      file=file, component=component, variable=name)
            unit = typed.get("unit") if kind == "Real" else None
            if unit is not None and unit not in self.units:
                raise SystemFileError(f"parameter unit '{unit}' is not defined in the Units "
                                      "of the SSD or the parameter set", file=file,
                                      component=component, variable=name)
            yield name, parse_literal(kind, typed.get("value"), file=file,
                                      component=component, variable=name), unit


def _read_experiment(root, file: str) -> tuple[float | None, ...]:
    experiment = root.find("ssd:DefaultExperiment", NS)
    start = stop = step = None
    if experiment is not None:
        start = _float_or_none(experiment.get("startTime"), file, "startTime")
        stop = _float_or_none(experiment.get("stopTime"), file, "stopTime")
        for annotation in experiment.iterfind("ssd:Annotations/ssc:Annotation", NS):
            if annotation.get("type") == ANNOTATION_TYPE:
                for child in annotation:
                    if isinstance(child.tag, str):
                        step = _float_or_none(child.get("stepSize"), file, "stepSize") or step
    return start, stop, step


def _float_or_none(text: str | None, file: str, what: str) -> float | None:
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        raise SystemFileError(f"DefaultExperiment {what} '{text}' is not a number",
                              file=file) from None
