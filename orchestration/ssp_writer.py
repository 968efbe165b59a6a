"""Write a :class:`~orchestration.system.System` as SSP 1.0.

:func:`write_ssd` writes ``SystemStructure.ssd`` with component sources
relative to the SSD's folder; :func:`write_ssp` writes an ``.ssp`` archive
with the FMUs under ``resources/``.  Start values go inline, as
``ParameterBindings/ParameterBinding/ParameterValues/ssv:ParameterSet`` of
each component, all named ``start_values`` (Ecos applies parameter sets by
name, so one common name lets it apply them all), which fmpy, Ecos and other
SSP tools read.  Each component
declares connectors for its inputs, outputs and the parameters it sets, with
their types read from the FMU.  The step size, which SSP 1.0 has no element
for, is kept in a ``DefaultExperiment`` annotation of type
``org.sarins-fmu.master``.
"""
from __future__ import annotations

import os
import zipfile
from pathlib import Path

from lxml import etree

from .errors import SystemFileError
from .fmu import read_description
from .ssp_reader import ANNOTATION_TYPE, SSD_NAME
from .system import System
from .units import EXPONENTS

__all__ = ["write_ssd", "write_ssp", "ssd_bytes", "START_VALUES_SET"]

START_VALUES_SET = "start_values"  # one ParameterSet name for all components (Ecos applies sets by name)

_SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
_SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
_SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
_NSMAP = {"ssc": _SSC, "ssd": _SSD, "ssv": _SSV}
_SSP_TYPES = {"Real": "Real", "Integer": "Integer", "Enumeration": "Integer",
              "Boolean": "Boolean", "String": "String",
              # FMI 3.0 types as the SSP 1.0 type of their family
              "Float32": "Real", "Float64": "Real", **{t: "Integer" for t in (
                  "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")}}


def _tag(namespace: str, name: str) -> str:
    return f"{{{namespace}}}{name}"


def _literal(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def ssd_bytes(system: System, sources: dict[str, str]) -> bytes:
    """Return the XML of ``SystemStructure.ssd`` for ``system``.

    Parameters
    ----------
    system : System
        The system to describe.
    sources : dict
        ``{component name: source URI written in the SSD}``.
    """
    root = etree.Element(_tag(_SSD, "SystemStructureDescription"), nsmap=_NSMAP,
                         version="1.0", name=system.name)
    xsystem = etree.SubElement(root, _tag(_SSD, "System"), name=system.name)
    elements = etree.SubElement(xsystem, _tag(_SSD, "Elements"))
    connector_units = _connector_units(system)
    for component in system.components:
        _component_element(elements, system, component, sources[component.name],
                           connector_units)
    if system.connections:
        connections = etree.SubElement(xsystem, _tag(_SSD, "Connections"))
        for c in system.connections:
            xconnection = etree.SubElement(
                connections, _tag(_SSD, "Connection"), startElement=c.start_component,
                startConnector=c.start_variable, endElement=c.end_component,
                endConnector=c.end_variable)
            hop = c.hops[0] if c.hops else None
            if hop is not None and hop.suppress_unit_conversion:
                xconnection.set("suppressUnitConversion", "true")
            if hop is not None and (hop.factor, hop.offset) != (1.0, 0.0):
                etree.SubElement(xconnection, _tag(_SSC, "LinearTransformation"),
                                 factor=_literal(float(hop.factor)),
                                 offset=_literal(float(hop.offset)))
    if system.units:
        xunits = etree.SubElement(root, _tag(_SSD, "Units"))
        for unit in system.units.values():
            xunit = etree.SubElement(xunits, _tag(_SSC, "Unit"), name=unit.name)
            base = etree.SubElement(xunit, _tag(_SSC, "BaseUnit"))
            for key, exponent in zip(EXPONENTS, unit.exponents or ()):
                if exponent:
                    base.set(key, str(exponent))
            if unit.factor != 1.0:
                base.set("factor", _literal(float(unit.factor)))
            if unit.offset != 0.0:
                base.set("offset", _literal(float(unit.offset)))
    _experiment_element(root, system)
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


def _connector_units(system: System) -> dict[tuple[str, str], str]:
    """Declared connector units of the connections; refuse what SSD cannot hold flat."""
    units: dict[tuple[str, str], str] = {}
    for c in system.connections:
        if len(c.hops) > 1 and any(h.start_unit or h.end_unit or h.suppress_unit_conversion
                                   or (h.factor, h.offset) != (1.0, 0.0) for h in c.hops):
            raise SystemFileError(f"connection {c} runs through system connectors with units "
                                  "or transformations, which a flat SSD cannot hold",
                                  file=None if system.source_file is None
                                  else str(system.source_file))
        if not c.hops:
            continue
        for key, unit in (((c.start_component, c.start_variable), c.hops[0].start_unit),
                          ((c.end_component, c.end_variable), c.hops[-1].end_unit)):
            if unit is None:
                continue
            if units.setdefault(key, unit) != unit:
                raise SystemFileError(f"connector {'.'.join(key)} is given two units "
                                      f"('{units[key]}' and '{unit}')")
    return units


def _component_element(parent, system: System, component, source: str,
                       connector_units: dict) -> None:
    description = read_description(system.fmu_path(component), component.name, fmi3=True)
    variables = {v.name: v for v in description.modelVariables}
    xcomponent = etree.SubElement(parent, _tag(_SSD, "Component"), name=component.name,
                                  type="application/x-fmu-sharedlibrary", source=source)
    connectors = etree.SubElement(xcomponent, _tag(_SSD, "Connectors"))
    for variable in description.modelVariables:
        kind = variable.causality
        if kind in ("input", "output") or (kind == "parameter" and
                                          variable.name in component.parameters):
            connector = etree.SubElement(connectors, _tag(_SSD, "Connector"),
                                         name=variable.name, kind=kind)
            typed = etree.SubElement(connector,
                                     _tag(_SSC, _SSP_TYPES.get(variable.type, "Real")))
            unit = connector_units.get((component.name, variable.name))
            if unit is not None:
                typed.set("unit", unit)
    if len(connectors) == 0:
        xcomponent.remove(connectors)
    if not component.parameters:
        return
    bindings = etree.SubElement(xcomponent, _tag(_SSD, "ParameterBindings"))
    binding = etree.SubElement(bindings, _tag(_SSD, "ParameterBinding"))
    values = etree.SubElement(binding, _tag(_SSD, "ParameterValues"))
    pset = etree.SubElement(values, _tag(_SSV, "ParameterSet"), version="1.0",
                            name=START_VALUES_SET)
    parameters = etree.SubElement(pset, _tag(_SSV, "Parameters"))
    for name, value in component.parameters.items():
        if isinstance(value, (list, tuple)) or getattr(value, "ndim", 0) > 0:
            raise SystemFileError(f"start value {value!r} cannot be written to SSP 1.0 (scalars "
                                  "only; an FMI 3.0 array takes its start values in python)",
                                  component=component.name, variable=name)
        variable = variables.get(name)
        type_name = _SSP_TYPES.get(variable.type, "Real") if variable is not None else \
            _python_type(value)
        xparameter = etree.SubElement(parameters, _tag(_SSV, "Parameter"), name=name)
        etree.SubElement(xparameter, _tag(_SSV, type_name), value=_literal(value))


def _python_type(value) -> str:
    if isinstance(value, bool):
        return "Boolean"
    if isinstance(value, int):
        return "Integer"
    if isinstance(value, str):
        return "String"
    return "Real"


def _experiment_element(root, system: System) -> None:
    if system.start_time is None and system.stop_time is None and system.step_size is None:
        return
    attributes = {}
    if system.start_time is not None:
        attributes["startTime"] = _literal(float(system.start_time))
    if system.stop_time is not None:
        attributes["stopTime"] = _literal(float(system.stop_time))
    experiment = etree.SubElement(root, _tag(_SSD, "DefaultExperiment"), **attributes)
    if system.step_size is not None:
        annotations = etree.SubElement(experiment, _tag(_SSD, "Annotations"))
        annotation = etree.SubElement(annotations, _tag(_SSC, "Annotation"),
                                      type=ANNOTATION_TYPE)
        etree.SubElement(annotation, "master", stepSize=_literal(float(system.step_size)))


def write_ssd(system: System, path: str | Path) -> Path:
    """Write ``system`` as an SSD file whose FMUs stay where they are.

    Parameters
    ----------
    system : System
        System to write.
    path : str or Path
        SSD file to write (conventionally ``SystemStructure.ssd``); component
        sources are written relative to its folder.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    SystemFileError
        If an FMU is not inside the SSD's folder (the reader loads FMUs
        from there only; write an ``.ssp`` to pack FMUs from elsewhere).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    sources = {}
    folder = path.parent.resolve()
    for component in system.components:
        fmu = system.fmu_path(component)
        _check_fmu(fmu, component.name)
        if folder not in fmu.parents:
            raise SystemFileError(f"the FMU is not inside the SSD's folder {folder}; the reader "
                                  "loads FMUs from there only (copy it there, or write an .ssp)",
                                  file=str(fmu), component=component.name)
        sources[component.name] = Path(os.path.relpath(fmu, folder)).as_posix()
    path.write_bytes(ssd_bytes(system, sources))
    return path


def write_ssp(system: System, path: str | Path) -> Path:
    """Write ``system`` as an ``.ssp`` archive with its FMUs in ``resources/``.

    Parameters
    ----------
    system : System
        System to write.
    path : str or Path
        Archive to write.

    Returns
    -------
    Path
        The written archive.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    sources: dict[str, str] = {}
    packed: dict[Path, str] = {}
    for component in system.components:
        fmu = system.fmu_path(component)
        _check_fmu(fmu, component.name)
        if fmu not in packed:
            name = f"resources/{fmu.name}"
            if name in packed.values():
                name = f"resources/{component.name}_{fmu.name}"
            packed[fmu] = name
        sources[component.name] = packed[fmu]
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr(SSD_NAME, ssd_bytes(system, sources))
        for fmu, name in packed.items():
            archive.write(fmu, name)
    return path


def _check_fmu(fmu: Path, component: str) -> None:
    if not fmu.is_file():
        raise SystemFileError("FMU file not found", file=str(fmu), component=component)
