"""Helpers shared by the third-party importers."""
from __future__ import annotations

import numpy as np

from ..coupling import VALUE_TYPES, check_connections
from ..errors import ScheduleError
from ..fmu import read_description
from ..recorder import NUMPY_TYPES, ResultArray, select_variables
from ..schedule import make_schedule
from ..ssp_reader import read_system
from ..system import System
from ..unit_links import refuse_conversions

__all__ = ["resolve", "fixed_step", "Selection", "build_result"]


def resolve(system: System | str) -> System:
    """Return a System, reading it if a path was given."""
    return system if isinstance(system, System) else read_system(system)


def fixed_step(system: System, start_time, stop_time, step_size) -> tuple[float, float, int]:
    """Start, step and number of steps of a fixed-step run (engines take no schedule)."""
    start = system.start_time if start_time is None else start_time
    start = 0.0 if start is None else float(start)
    stop = system.stop_time if stop_time is None else stop_time
    step = system.step_size if step_size is None else step_size
    if step is None or np.ndim(step) != 0:
        raise ScheduleError("third-party importers need one fixed communication step")
    segment = make_schedule(start, stop, float(step))[0]
    return start, segment.step, segment.count


class Selection:
    """What to record, resolved from the FMUs' model descriptions.

    Attributes
    ----------
    names : list of str
        Component names.
    variables : list of dict
        ``{name: ModelVariable}`` per component.
    chosen : list of (int, ModelVariable)
        Recorded variables in master order.
    """

    def __init__(self, system: System, record):
        self.names = [c.name for c in system.components]
        files, self.variables, descriptions = [], [], []
        for component in system.components:
            path = system.fmu_path(component)
            files.append(str(path))
            descriptions.append(read_description(path, component.name))
            self.variables.append({v.name: v for v in descriptions[-1].modelVariables})
        self.chosen = select_variables(self.names, self.variables, record, files)
        checked = check_connections(system.connections, self.names, self.variables, files)
        refuse_conversions(system, checked, descriptions, files, "this third-party importer")
        self.fields = [f"{self.names[i]}.{v.name}" for i, v in self.chosen]
        self.kinds = [VALUE_TYPES[v.type] for _, v in self.chosen]


def build_result(selection: Selection, times, rows, meta: dict) -> ResultArray:
    """Assemble rows (one sequence of values per row) into a ResultArray."""
    dtype = [("time", np.float64)] + [(f, NUMPY_TYPES[k]) for f, k in
                                      zip(selection.fields, selection.kinds)]
    out = np.empty(len(rows), dtype=dtype)
    out["time"] = times
    for k, field in enumerate(selection.fields):
        out[field] = [row[k] for row in rows]
    return ResultArray(out, meta)
