"""Run a system under libcosim (``pip install libcosimpy``, Open Simulation Platform).

libcosim's fixed-step algorithm is **Jacobi**: all slaves are stepped (in
parallel) on inputs set before the step, then variables are transferred.
Its clock is an integer number of nanoseconds, so steps must be whole
nanoseconds.  The system is rebuilt through the execution API (local slaves,
initial values, typed connections) and read back with a last-value observer
after every step.  libcosimpy 0.0.6 cannot connect Integer variables (its
``connect_integer_variables`` is broken): such systems raise
:class:`~orchestration.errors.ImporterUnavailableError`.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ..coupling import value_type
from ..errors import FMUCallError, ImporterUnavailableError, ScheduleError
from ..master import coerce_value
from ..recorder import ResultArray
from ..system import System
from .common import Selection, build_result, fixed_step, resolve

__all__ = ["simulate_with_libcosim", "load_libcosimpy"]

NANOSECONDS = 1_000_000_000  # libcosim time unit per second


def load_libcosimpy():
    """Import libcosimpy's execution module or raise ImporterUnavailableError."""
    try:
        from libcosimpy import CosimExecution, CosimObserver, CosimSlave
        from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    except ImportError as error:
        raise ImporterUnavailableError(f"libcosimpy is not installed ({error}); "
                                       "pip install libcosimpy") from None
    except OSError as error:
        raise ImporterUnavailableError(f"libcosimpy's native library does not load "
                                       f"({error})") from None
    log_output_level(CosimLogLevel.WARNING)
    return CosimExecution, CosimObserver, CosimSlave


def simulate_with_libcosim(system: System | str | Path, stop_time: float | None = None,
                           step_size: float | None = None, *,
                           record: Sequence[str] | None = None) -> ResultArray:
    """Run ``system`` with libcosim and record like the master does.

    Parameters
    ----------
    system : System, str or Path
        System or SSP/SSD file.
    stop_time, step_size : float, optional
        As for :meth:`orchestration.Master.simulate`; the start time is 0
        (libcosim's execution starts there) and the step must be a whole
        number of nanoseconds.
    record : sequence of str, optional
        Variables or patterns to record (default: all outputs).

    Returns
    -------
    ResultArray
        Rows at ``t0 + h, ..., stop`` (libcosim initialises its slaves in
        its first step, so there is no observable row at ``t0``);
        ``meta['scheme'] == 'jacobi'``.
    """
    execution_module, observer_module, slave_module = load_libcosimpy()
    described = resolve(system)
    start, h, count = fixed_step(described, 0.0, stop_time, step_size)
    step_ns = round(h * NANOSECONDS)
    if abs(step_ns - h * NANOSECONDS) > 1e-6 * NANOSECONDS * h:
        raise ScheduleError(f"libcosim needs a step of whole nanoseconds, got {h!r} s")
    selection = Selection(described, record)
    execution = execution_module.CosimExecution.from_step_size(step_ns)
    slaves = [execution.add_local_slave(slave_module.CosimLocalSlave(
        str(described.fmu_path(c)), c.name)) for c in described.components]
    _apply_start_values(execution, described, selection, slaves)
    _connect(execution, described, selection, slaves)
    observer = observer_module.CosimObserver.create_last_value()
    execution.add_observer(observer)
    rows = []
    for n in range(count):
        if not execution.step():
            raise FMUCallError(described.name, "cosim_execution_step", 3, start + n * h)
        rows.append(_read(observer, selection, slaves))
    meta = {"tool": "libcosim", "scheme": "jacobi", "system": described.name,
            "start_time": start, "step": h, "steps": count}
    return build_result(selection, [start + n * h for n in range(1, count + 1)], rows, meta)


def _apply_start_values(execution, system: System, selection: Selection, slaves) -> None:
    setters = {"Real": execution.real_initial_value, "Integer": execution.integer_initial_value,
               "Boolean": execution.boolean_initial_value,
               "String": execution.string_initial_value}
    for i, component in enumerate(system.components):
        for name, value in component.parameters.items():
            var = selection.variables[i][name]
            setters[value_type(var)](slaves[i], var.valueReference,
                                     coerce_value(var, value, component=component.name,
                                                  file=None))


def _connect(execution, system: System, selection: Selection, slaves) -> None:
    connect = {"Real": execution.connect_real_variables,
               "Integer": execution.connect_integer_variables,
               "Boolean": execution.connect_boolean_variables,
               "String": execution.connect_string_variables}
    index = {name: i for i, name in enumerate(selection.names)}
    for c in system.connections:
        i, j = index[c.start_component], index[c.end_component]
        start = selection.variables[i][c.start_variable]
        end = selection.variables[j][c.end_variable]
        try:
            connect[value_type(start)](slaves[i], start.valueReference, slaves[j],
                                       end.valueReference)
        except AttributeError as error:  # libcosimpy 0.0.6: Integer connections are broken
            raise ImporterUnavailableError(f"libcosimpy cannot make the {start.type} "
                                           f"connection {c} ({error})") from None


def _read(observer, selection: Selection, slaves) -> list:
    readers = {"Real": observer.last_real_values, "Integer": observer.last_integer_values,
               "Boolean": observer.last_boolean_values}
    return [readers[kind](slaves[i], [var.valueReference])[0]
            for (i, var), kind in zip(selection.chosen, selection.kinds)]
