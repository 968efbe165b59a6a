"""Run a system under Ecos (``pip install ecospy``; Linux needs Debian ``libtbb12``).

Ecos's ``fixed_step_algorithm`` is a **Jacobi** scheme: every model is
stepped (in parallel by default) on the inputs set before the step, then
outputs are passed on.  Compare it with ``Master(..., scheme='jacobi')``.

Two ways in:

- ``via='ssp'``: ``EcosSimulation(ssp_path=...)``.  Ecos groups SSP
  parameter values by ``ParameterSet`` *name* and applies one named set at
  ``init``; this works when all sets share one name, as the SSPs written by
  :mod:`orchestration.ssp_writer` do.  Ecos fails on SSPs with system-level
  connectors (which the master refuses as well).
- ``via='structure'``: the same system rebuilt through
  ``EcosSimulationStructure`` (models, typed connections, one parameter set).

``via='auto'`` uses the SSP when the system was given as an SSP/SSD file with
a single parameter-set name, else the structure API.
"""
from __future__ import annotations

import tempfile
from collections.abc import Sequence
from pathlib import Path

from lxml import etree

from ..coupling import value_type
from ..errors import ImporterUnavailableError
from ..master import coerce_value
from ..recorder import ResultArray
from ..ssp_reader import SSD_NAME
from ..ssp_writer import START_VALUES_SET, write_ssp
from ..system import System
from .common import Selection, build_result, fixed_step, resolve

__all__ = ["simulate_with_ecos", "load_ecospy"]

_SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"


def load_ecospy():
    """Import ecospy or raise ImporterUnavailableError saying what is missing."""
    try:
        import ecospy
    except ImportError as error:
        raise ImporterUnavailableError(f"ecospy is not installed ({error}); "
                                       "pip install ecospy") from None
    except OSError as error:  # libecosc.so failed to load (e.g. libtbb.so.12 missing)
        raise ImporterUnavailableError(f"ecospy's native library does not load ({error}); "
                                       "on Debian/Ubuntu: apt-get install libtbb12") from None
    return ecospy


def _parameter_set_names(path: Path) -> set[str]:
    import zipfile

    if path.is_dir():
        path = path / SSD_NAME
    if zipfile.is_zipfile(path):
        with zipfile.ZipFile(path) as archive:
            root = etree.fromstring(archive.read(SSD_NAME))
    else:
        root = etree.parse(str(path)).getroot()
    return {s.get("name") for s in root.iter(f"{{{_SSV}}}ParameterSet")}


def simulate_with_ecos(system: System | str | Path, stop_time: float | None = None,
                       step_size: float | None = None, *, start_time: float | None = None,
                       record: Sequence[str] | None = None, via: str = "auto") -> ResultArray:
    """Run ``system`` with Ecos and record like the master does.

    Parameters
    ----------
    system : System, str or Path
        System or SSP/SSD file.
    stop_time, step_size, start_time : float, optional
        As for :meth:`orchestration.Master.simulate` (fixed step only).
    record : sequence of str, optional
        Variables or patterns to record (default: all outputs).
    via : {'auto', 'ssp', 'structure'}
        How the system is handed to Ecos (see module notes).

    Returns
    -------
    ResultArray
        ``time`` from ``t0 + n h`` (Ecos accumulates its clock by addition),
        then the recorded fields; ``meta['scheme'] == 'jacobi'``.

    Raises
    ------
    ImporterUnavailableError
        If ecospy or its native library is missing.
    """
    ecospy = load_ecospy()
    described = resolve(system)
    start, h, count = fixed_step(described, start_time, stop_time, step_size)
    selection = Selection(described, record)
    is_file = not isinstance(system, System)
    names = _parameter_set_names(Path(system)) if is_file else set()
    if via == "auto":
        via = "ssp" if is_file and len(names) <= 1 else "structure"
    structure = None
    with tempfile.TemporaryDirectory(prefix="orchestration_ecos_") as scratch:
        if via == "ssp":
            path = str(system) if is_file else str(write_ssp(described, Path(scratch) / "s.ssp"))
            if not is_file:
                names = {START_VALUES_SET}
            simulation = ecospy.EcosSimulation(step_size=h, ssp_path=path)
            parameter_set = next(iter(names)) if names else None
        elif via == "structure":
            structure = _structure(ecospy, described, selection)
            simulation = ecospy.EcosSimulation(step_size=h, structure=structure)
            parameter_set = START_VALUES_SET
        else:
            raise ValueError(f"via must be 'auto', 'ssp' or 'structure', not {via!r}")
        try:
            times, rows = _run(simulation, selection, start, h, count, parameter_set)
        finally:
            simulation.free()
            if structure is not None:
                structure.free()
    meta = {"tool": "ecos", "tool_version": repr(ecospy.EcosLib.version()), "via": via,
            "scheme": "jacobi", "system": described.name, "start_time": start, "step": h,
            "steps": count}
    return build_result(selection, times, rows, meta)


def _structure(ecospy, system: System, selection: Selection):
    """Build an EcosSimulationStructure equal to ``system`` (caller frees it)."""
    structure = ecospy.EcosSimulationStructure()
    for component in system.components:
        structure.add_model(component.name, str(system.fmu_path(component)))
    index = {name: i for i, name in enumerate(selection.names)}
    connect = {"Real": structure.make_real_connection,
               "Integer": structure.make_int_connection,
               "Boolean": structure.make_bool_connection,
               "String": structure.make_string_connection}
    for c in system.connections:
        var = selection.variables[index[c.start_component]][c.start_variable]
        connect[value_type(var)](f"{c.start_component}::{c.start_variable}",
                                 f"{c.end_component}::{c.end_variable}")
    values = {}
    for i, component in enumerate(system.components):
        for name, value in component.parameters.items():
            var = selection.variables[i][name]
            values[f"{component.name}::{name}"] = coerce_value(var, value,
                                                               component=component.name,
                                                               file=None)
    structure.add_parameter_set(START_VALUES_SET, values)
    return structure


def _run(simulation, selection: Selection, start: float, h: float, count: int,
         parameter_set: str | None):
    getters = {"Real": simulation.get_real, "Integer": simulation.get_integer,
               "Boolean": simulation.get_bool}
    readers = [(getters[kind], f"{selection.names[i]}::{var.name}")
               for (i, var), kind in zip(selection.chosen, selection.kinds)]
    simulation.init(start, parameter_set)
    rows = [[get(name) for get, name in readers]]
    for _ in range(count):
        simulation.step()
        rows.append([get(name) for get, name in readers])
    simulation.terminate()
    return [start + n * h for n in range(count + 1)], rows
