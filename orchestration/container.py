"""Package a whole system as one FMU with FMPy's container FMU.

:func:`build_container_fmu` writes an **FMI 2.0** co-simulation FMU (FMPy's
``fmpy.container_fmu`` writes FMI 2.0 or 3.0 depending on the model
description it is given; we give it 2.0) whose prebuilt ``container_fmu``
binary loads the nested FMUs from ``resources/`` and couples them by the
system's connections.  Its variables are ``time`` (independent, value
reference 0, which the container binary expects) and, named
``component.variable``: every
output of every component, every start value of the system (as a parameter
whose start the container applies when it is instantiated, String values
included: the binary sets them with ``fmi2SetString``), and every
unconnected input.

Coupling (FMPy's container binary): at ``fmi2ExitInitializationMode`` it
copies every connection while all components are still in Initialization
Mode, then lets them exit; each ``doStep`` steps all components and then
copies every connection.  That is a **Jacobi** scheme (compare with
``Master(..., scheme='jacobi')``) whose first step uses the outputs the
components had in Initialization Mode: a component whose outputs feed
another must compute them there (in ``fmi2EnterInitializationMode``), not
only when it leaves it.

Start values given in another unit (SSP ``ssv:Real unit``) are converted
to the variable's unit here, like the master does.  Refused (with the
connection named): connections that need a unit conversion or a linear
transformation (the binary copies values as they are).  Refused (with the
component named): FMI 3.0 components, which an FMI 2.0 container cannot host
(run such systems with the master).
"""
from __future__ import annotations

import shutil
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .coupling import check_connections, value_type
from .errors import ImporterUnavailableError, SystemDescriptionError
from .master import coerce_value
from .ssp_reader import parse_literal, read_system
from .system import System
from .unit_links import refuse_conversions, start_in_variable_unit

__all__ = ["build_container_fmu", "CONTAINER_FMI_VERSION"]

CONTAINER_FMI_VERSION = "2.0"


@dataclass(frozen=True)
class Part:
    """One component of a container built by a writer (``engine`` a callable): its name in the system, its
    FMU file and its (FMPy) model description."""

    name: str
    fmu: Path
    description: object


@dataclass(frozen=True)
class Exposed:
    """One container variable: ``name`` (``component.variable``), FMI 2.0 type, causality, variability, start
    (Python value or None) and the component variable it maps to (part index, value reference)."""

    name: str
    type: str
    causality: str
    variability: str
    start: object
    part: int
    vr: int
    description: str = ""


@dataclass(frozen=True)
class Link:
    """A connection: type and (part index, value reference) at both ends."""

    type: str
    src: int
    src_vr: int
    dst: int
    dst_vr: int




def build_container_fmu(system: System | str | Path, out_path: str | Path, *,
                        step_size: float | None = None, parallel: bool = False,
                        engine: str | Callable = "fmpy") -> Path:
    """Write ``system`` as one FMI 2.0 co-simulation container FMU.

    Parameters
    ----------
    system : System, str or Path
        System or SSP/SSD file.
    out_path : str or Path
        FMU file to write.
    step_size : float, optional
        Fixed step written as the default experiment's step (default: the
        system's).
    parallel : bool
        Let the container step the components in parallel threads (``engine="fmpy"`` only).
    engine : str or callable
        ``"fmpy"``: FMPy's container binary (linux64, win64, darwin64).  A callable: a container
        writer of your own, called as ``engine(out_path, name=, parts=, exposed=, links=, step=,
        start_time=, stop_time=)`` with the checked :class:`Part`, :class:`Exposed` and
        :class:`Link` lists (same variables as FMPy's, value references 0, 1, ...), returning the
        written FMU; its ``ValueError`` becomes a SystemDescriptionError.  (The project's own:
        ``fmus.system_container.write_container_fmu``.)

    Returns
    -------
    Path
        The written FMU.

    Raises
    ------
    SystemDescriptionError
        For the same description errors the master reports.
    ImporterUnavailableError
        If the installed fmpy has no (JSON-configured) ``container_fmu``.
    """
    if callable(engine):
        if parallel:
            raise ValueError("parallel: only FMPy's container steps components in threads")
        return _build_with_writer(system, out_path, step_size, engine)
    if engine != "fmpy":
        raise ValueError(f"engine {engine!r}: 'fmpy' or a container writer (a callable)")
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, Unknown

    try:
        from fmpy.container_fmu import Configuration
        from fmpy.container_fmu import config as cfg
        from fmpy.container_fmu.cli import create_container_fmu
    except ImportError as error:
        raise ImporterUnavailableError(f"this fmpy has no JSON container_fmu ({error}); "
                                       "fmpy 0.3.32 is known to work") from None

    system = system if isinstance(system, System) else read_system(system)
    out_path = Path(out_path).resolve()
    step = system.step_size if step_size is None else step_size
    with tempfile.TemporaryDirectory(prefix="orchestration_container_") as scratch:
        components, variables, files = [], [], []
        for component in system.components:
            path = _unique_copy(system.fmu_path(component), Path(scratch) / "fmus")
            description = _hosted_description(path, system.fmu_path(component), component.name)
            components.append(cfg.Component(name=component.name, filename=path,
                                            modelDescription=description))
            variables.append({v.name: v for v in description.modelVariables})
            files.append(str(path))
        names = [c.name for c in system.components]
        checked = check_connections(system.connections, names, variables, files)
        refuse_conversions(system, checked, [c.modelDescription for c in components], files,
                           "the container FMU")
        connections = [cfg.Connection(startElement=components[i],
                                      startConnectors=[_json_typed(start)],
                                      endElement=components[j], endConnectors=[end])
                       for i, start, j, end, _ in checked]
        mappings = {mapped: [(components[i], var)]
                    for mapped, i, var in _exposed_variables(system, components, variables, checked)}
        description = ModelDescription(
            fmiVersion=CONTAINER_FMI_VERSION, modelName=system.name,
            instantiationToken="{" + str(uuid.uuid4()) + "}",
            generationTool="orchestration (fmpy.container_fmu)",
            coSimulation=CoSimulation(modelIdentifier="container_fmu",
                                      fixedInternalStepSize=step,
                                      canHandleVariableCommunicationStepSize=True),
            defaultExperiment=DefaultExperiment(startTime=system.start_time,
                                                stopTime=system.stop_time, stepSize=step),
            modelVariables=[_time_variable()] + list(mappings))
        # FMI 2.0 (2.2.8): ModelStructure lists every output, and (initial = calculated) every output
        # among the initial unknowns; importers such as fmusim refuse a description without them
        outputs = [v for v in description.modelVariables if v.causality == "output"]
        description.outputs = [Unknown(variable=v) for v in outputs]
        description.initialUnknowns = [Unknown(variable=v) for v in outputs]
        configuration = Configuration(parallelDoStep=parallel, modelDescription=description,
                                      components=components, connections=connections,
                                      variableMappings=mappings)
        unzipdir = Path(scratch) / "container"
        unzipdir.mkdir()
        out_path.parent.mkdir(parents=True, exist_ok=True)
        if out_path.exists():
            out_path.unlink()
        create_container_fmu(configuration, unzipdir, out_path)
    return out_path


def _time_variable():
    """The independent variable ``time``; the container binary reserves value reference 0
    for it (its variable ``k`` in container.json has value reference ``k + 1``)."""
    from fmpy.model_description import ModelVariable

    return ModelVariable(name="time", type="Real", causality="independent",
                         variability="continuous")


def _json_typed(variable):
    """Copy of a variable whose type uses the container's JSON names (Float64, Int32).

    fmpy 0.3.32 converts these names for mapped variables but not for
    connections, whose type it writes verbatim.
    """
    import attrs

    names = {"Real": "Float64", "Integer": "Int32", "Enumeration": "Int32"}
    return attrs.evolve(variable, type=names.get(variable.type, variable.type))


def _unique_copy(fmu: Path, folder: Path) -> Path:
    """Copy an FMU so that different FMUs get different file stems (nested folder names)."""
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / fmu.name
    if target.exists():
        if target.read_bytes() == fmu.read_bytes():
            return target
        target = folder / f"{fmu.stem}_{len(list(folder.iterdir()))}{fmu.suffix}"
    if not fmu.is_file():
        raise SystemDescriptionError("FMU file not found", file=str(fmu))
    shutil.copyfile(fmu, target)
    return target


def _exposed_variables(system: System, components, variables, checked) -> list:
    """Container variables: [(variable, component index, component variable)]."""
    from fmpy.model_description import ModelVariable

    fed = {(j, end.name) for _, _, j, end, _ in checked}
    mappings = []
    for i, component in enumerate(system.components):
        for var in variables[i].values():
            exposed = var.causality == "output" or var.name in component.parameters or \
                (var.causality == "input" and (i, var.name) not in fed)
            if not exposed:
                continue
            start = None
            if var.name in component.parameters:
                start = coerce_value(var, component.parameters[var.name],
                                     component=component.name, file=None)
                if var.name in component.parameter_units:  # the container applies starts as they are
                    start = start_in_variable_unit(start, component.parameter_units[var.name], var,
                                                   components[i].modelDescription, system.units,
                                                   file=None, component=component.name)
            elif var.causality == "input" and var.start is not None:
                start = parse_literal(value_type(var), var.start, component=component.name,
                                      variable=var.name)
            causality = "output" if var.causality == "output" else \
                "parameter" if var.causality == "parameter" else "input"
            variability = var.variability if causality != "input" else "continuous"
            if var.type != "Real" and variability == "continuous":
                variability = "discrete"
            mapped = ModelVariable(name=f"{component.name}.{var.name}", type=var.type,
                                   causality=causality, variability=variability,
                                   start=None if start is None else _literal(start),
                                   initial="exact" if causality == "parameter" else None)
            mappings.append((mapped, i, var))
    return mappings


def _literal(value) -> str:
    """XML/JSON literal of a start value (the container reads starts as strings)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)


def _hosted_description(path, file, component: str):
    """The model description of the FMU at ``path`` (``file``: the name errors give), which must be
    FMI 2.0 like the container."""
    from fmpy import read_model_description

    description = read_model_description(str(path), validate=False)
    if description.fmiVersion != CONTAINER_FMI_VERSION:
        raise SystemDescriptionError(
            f"the container FMU is FMI {CONTAINER_FMI_VERSION} and hosts FMI "
            f"{CONTAINER_FMI_VERSION} components only; this one is FMI "
            f"{description.fmiVersion} (run the system with the master instead)",
            file=str(file), component=component)
    return description


class _Described:
    """A component as _exposed_variables sees it (its model description)."""

    def __init__(self, description):
        self.modelDescription = description


def _build_with_writer(system, out_path, step_size, write_container_fmu: Callable) -> Path:
    """``engine`` a writer: the same checks and variables as FMPy's container, written by the writer."""

    system = system if isinstance(system, System) else read_system(system)
    step = system.step_size if step_size is None else step_size
    parts, variables, files = [], [], []
    for component in system.components:
        path = system.fmu_path(component)
        if not Path(path).is_file():
            raise SystemDescriptionError("FMU file not found", file=str(path))
        description = _hosted_description(path, path, component.name)
        if description.coSimulation is None:
            raise SystemDescriptionError("the container hosts co-simulation FMUs only", file=str(path),
                                         component=component.name)
        parts.append(Part(component.name, Path(path), description))
        variables.append({v.name: v for v in description.modelVariables})
        files.append(str(path))
    names = [c.name for c in system.components]
    checked = check_connections(system.connections, names, variables, files)
    refuse_conversions(system, checked, [p.description for p in parts], files, "the container FMU")
    links = [Link(value_type(start), i, start.valueReference, j, end.valueReference)
             for i, start, j, end, _ in checked]
    exposed = [Exposed(m.name, m.type, m.causality, m.variability,
                       None if m.start is None else parse_literal(value_type(var), m.start,
                                                                   component=parts[i].name,
                                                                   variable=var.name),
                       i, var.valueReference)
               for m, i, var in _exposed_variables(system, [_Described(p.description) for p in parts],
                                                   variables, checked)]
    out_path = Path(out_path).resolve()
    try:
        return write_container_fmu(out_path, name=system.name, parts=parts, exposed=exposed, links=links,
                                   step=step, start_time=system.start_time, stop_time=system.stop_time)
    except ValueError as error:
        raise SystemDescriptionError(str(error)) from None
