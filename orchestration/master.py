"""Fixed-step co-simulation master for FMI 2.0 and FMI 3.0 co-simulation FMUs.

FMI 3.0 FMUs run beside FMI 2.0 ones in the same system: scalars of every
numeric type, Boolean and String, and arrays (``<Dimension>``, fixed or
set by a structural parameter) moved by one ``fmi3Get*``/``fmi3Set*`` call
per link; structural parameters given start values are set in Configuration
Mode.  No event mode, clocks or intermediate update (see
:func:`orchestration.fmu.read_description`); an FMU that sets
``terminateSimulation`` in ``fmi3DoStep`` ends the run after that step
(``result.meta['terminated_by']``).

Algorithm (per communication step ``[t, t + h]``, ``t = t0 + n h``):

- **Gauss-Seidel** (default): components are stepped in the order of the
  connection graph (:func:`~orchestration.coupling.gauss_seidel_order`);
  before stepping one, its inputs are set from the current outputs of its
  sources, which were already stepped to ``t + h`` (except over edges broken
  to cut a cycle, which carry the values at ``t``).
- **Jacobi** (strict): every connected output is read (values at ``t``)
  before any input is set, then every component is stepped: a one-step delay
  per connection, also through FMUs with direct feedthrough (a chain of two
  links lags two steps).

Values cross a connection through its unit conversion and linear
transformation (:mod:`orchestration.unit_links`), if it has one.

Initialisation: ``fmi2Instantiate``, ``fmi2SetupExperiment`` (start time, no
stop time: some FMUs, OpenModelica's among them, refuse a step that passes a
defined stop time by a rounding error), start values,
``fmi2EnterInitializationMode`` for every component (FMI 3.0:
``fmi3InstantiateCoSimulation``, structural parameters in Configuration Mode,
the other start values, ``fmi3EnterInitializationMode`` with the start time); then, in stepping order,
each component's inputs are set from its sources' outputs and it calls
``fmi2ExitInitializationMode`` (so an FMU initialises from the values its
sources start with, e.g. an IMU from the chamber's start temperature; sources
over broken cycle edges give their start values); outputs are copied to
inputs once more, and the first row is recorded at ``t0``.  Rows after that are recorded after
``fmi2DoStep(t, h)`` with time ``t + h``.

The communication step is, in this order: the ``step_size`` argument, the
system file's step annotation, the FMUs' ``DefaultExperiment`` stepSize
(their common value, else the smallest; a :class:`DefaultStepWarning` says
which).  Real-time pacing starts after initialisation and the run's worst
lag is reported in ``result.meta['realtime']``.
"""
from __future__ import annotations

import math
import signal
import time
from collections.abc import Callable, Sequence
from ctypes import c_double
from pathlib import Path

import warnings

import numpy as np

from . import interrupt
from .coupling import (algebraic_loops, check_connections, check_connector_types, find_variable,
                       gauss_seidel_order,
                       group_links, output_dependencies, warn_unconnected)
from .errors import (DefaultStepWarning, OrchestrationError, ScheduleError, StartValueError,
                     UnknownComponentError)
from .fmitypes import NUMPY_TYPES, c_type, family, size_of, value_type, variable_shape
from .fmu import FMUInstance, UnpackedFMU
from .pacing import Progress, RealTimePacer
from .rawcalls import (FMI_WARNING, DoStep3Flags, do_step, getter, handle, setter, step_args,
                       value_args, value_buffer, vr_array)
from .recorder import Recorder, ResultArray, select_variables
from .schedule import StepSpec, make_schedule
from . import steploop
from .steploop import OpSpec
from .ssp_reader import ANNOTATION_TYPE, read_system
from .system import StartValue, System
from .unit_links import connection_maps, start_in_variable_unit

__all__ = ["Master", "simulate_system", "SCHEMES", "StepCallback"]

SCHEMES = ("gauss-seidel", "jacobi")
StepCallback = Callable[[float, "Master"], bool | None]
_SETTABLE_CAUSALITIES = ("parameter", "structuralParameter", "input")
MAX_RECORD_BYTES = 2**31  # recorder storage preallocated for one run (rows x values x 8 bytes)
C_BLOCK_STEPS = 512  # steps per call into the compiled loop (a signal is acted on between calls)
LOOPS = ("auto", "c", "python")
def _check_scheme(scheme: str) -> str:
    normalized = scheme.lower().replace("_", "-")
    if normalized not in SCHEMES:
        raise ValueError(f"unknown coupling scheme '{scheme}'; use one of {SCHEMES}")
    return normalized


def coerce_value(variable, value, *, component: str, file: str | None,
                 shape: tuple[int, ...] = ()) -> StartValue | list:
    """Convert ``value`` to the python type matching the FMI type of ``variable``.

    For an FMI 3.0 array of ``shape`` (not ``()``), ``value`` is a sequence or
    array of that shape (or flat, with as many elements) and a flat list of
    converted elements (row-major) is returned.  Integers must fit the
    variable's type (``UInt64`` takes no negative value).
    """
    if shape:
        elements = np.asarray(value, dtype=object)
        if elements.shape not in (shape, (size_of(shape),)):
            raise StartValueError(f"an array of shape {list(shape)} needs {size_of(shape)} values, "
                                  f"got {value!r}", file=file, component=component,
                                  variable=variable.name)
        return [coerce_value(variable, v, component=component, file=file)
                for v in elements.ravel().tolist()]
    kind = value_type(variable)
    kind_family = family(kind)

    def fail() -> None:
        raise StartValueError(f"{value!r} is not a valid {variable.type} value",
                              file=file, component=component, variable=variable.name)

    if kind_family == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            fail()
        return float(value)
    if kind_family == "integer":
        if isinstance(value, bool) or not (isinstance(value, int) or
                                           (isinstance(value, float) and value.is_integer())):
            fail()
        limits = np.iinfo(NUMPY_TYPES[kind])
        if not limits.min <= int(value) <= limits.max:
            fail()
        return int(value)
    if kind_family == "boolean":
        if not isinstance(value, (bool, int)) or value not in (0, 1):
            fail()
        return bool(value)
    if kind_family != "string" or not isinstance(value, str):
        fail()
    return value


class Master:
    """Run a system of FMI 2.0 and FMI 3.0 co-simulation FMUs.

    Parameters
    ----------
    system : System, str or Path
        A :class:`~orchestration.system.System` or an SSP/SSD file to read.
    scheme : {'gauss-seidel', 'jacobi'}
        Coupling scheme.
    record : sequence of str, optional
        ``component.variable`` names or shell patterns to record; default:
        every output of every component.
    logging_on : bool
        ``loggingOn`` passed to the FMUs, so that their error messages reach
        the :class:`~orchestration.errors.FMUCallError` raised on failures.
    loop : {'auto', 'c', 'python'}
        The inner loop: ``'c'`` runs the steps through the compiled loop
        (:mod:`orchestration.steploop`; the same calls, the same numbers, without
        the per-call cost of Python), ``'python'`` in Python, ``'auto'`` in C
        when it is built and the run has no real-time pacing and no callback.

    Raises
    ------
    SystemDescriptionError
        (and subclasses) for unknown files, components or variables,
        incompatible connections and invalid start values.

    Notes
    -----
    FMUs are extracted once, when the master is created; every
    :meth:`simulate` instantiates, runs, terminates and frees them, so a
    master can run many experiments.  Call :meth:`close` (or use ``with``)
    to delete the extracted files.
    """

    def __init__(self, system: System | str | Path, *, scheme: str = "gauss-seidel",
                 record: Sequence[str] | None = None, logging_on: bool = True, loop: str = "auto"):
        if loop not in LOOPS:
            raise ValueError(f"unknown loop {loop!r}; use one of {LOOPS}")
        self.loop = loop
        self._owns_system = not isinstance(system, System)
        self.system = system if isinstance(system, System) else read_system(system)
        self.scheme = _check_scheme(scheme)
        self.logging_on = logging_on
        self.instances: list[FMUInstance] = []
        self.time: float | None = None
        self.terminated_by: str | None = None
        self._unpacked: dict[Path, UnpackedFMU] = {}
        try:
            self._prepare(record)
        except BaseException:
            self.close()
            raise

    # preparation ------------------------------------------------------------
    def _prepare(self, record: Sequence[str] | None) -> None:
        system = self.system
        file = None if system.source_file is None else str(system.source_file)
        self.names = [c.name for c in system.components]
        self.units = []
        for component in system.components:
            interrupt.check()
            path = system.fmu_path(component)
            if path not in self._unpacked:
                self._unpacked[path] = UnpackedFMU(path, component.name)
            self.units.append(self._unpacked[path])
        self.files = [str(u.path) for u in self.units]
        self.variables = [u.variables for u in self.units]
        check_connector_types(system.components, self.variables, self.files, file)
        self.shapes: list[dict[str, tuple[int, ...]]] = []
        self.start_values = [self._check_start_values(i) for i in range(len(self.names))]
        checked = check_connections(system.connections, self.names, self.variables,
                                    self.files, file, self.shapes)
        descriptions = [u.description for u in self.units]
        maps = connection_maps(checked, descriptions, self.files, system.units, file)
        self.links = group_links(checked, maps, self.shapes)
        self.dependencies = [output_dependencies(d) for d in descriptions]
        if self.scheme == "gauss-seidel":
            self.order, self.broken = gauss_seidel_order(self.names, self.links,
                                                         self.dependencies)
        else:
            self.order, self.broken = list(range(len(self.names))), []
        self.loops = [str(c) for c in algebraic_loops(self.links, self.dependencies)]
        self.unconnected = warn_unconnected(self.names, self.variables, checked,
                                            [dict(s) for s in self.start_values])
        self.selection = select_variables(self.names, self.variables, record, self.files)

    def _check_start_values(self, i: int) -> dict[str, tuple[object, StartValue]]:
        """Checked start values of component ``i``; appends its array shapes to ``self.shapes``.

        Structural parameters are converted first: their values set the
        shapes of the arrays whose start values follow.
        """
        component = self.system.components[i]
        variables = self.variables[i]
        structural = {name: value for name, value in component.parameters.items()
                      if name in variables and variables[name].causality == "structuralParameter"}
        starts = self._checked_starts(i, structural, {})
        shapes = {}
        for var in variables.values():
            if getattr(var, "dimensions", None):
                try:
                    shapes[var.name] = variable_shape(var, {n: v for n, (_, v) in starts.items()})
                except ValueError as error:
                    raise StartValueError(str(error), file=self.files[i], component=component.name,
                                          variable=var.name) from None
        self.shapes.append(shapes)
        others = {name: value for name, value in component.parameters.items()
                  if name not in structural}
        return {**starts, **self._checked_starts(i, others, shapes)}

    def _checked_starts(self, i: int, values: dict, shapes: dict) -> dict:
        component = self.system.components[i]
        checked = {}
        for name, value in values.items():
            var = find_variable(self.variables[i], name, component=component.name,
                                file=self.files[i], role="variable (start value)")
            settable = (var.causality in _SETTABLE_CAUSALITIES
                        or var.initial in ("exact", "approx"))
            if var.variability == "constant" or var.causality == "independent" \
                    or not settable:
                raise StartValueError(
                    f"cannot set a start value on a variable with causality "
                    f"'{var.causality}' and variability '{var.variability}'",
                    file=self.files[i], component=component.name, variable=name)
            value = coerce_value(var, value, component=component.name, file=self.files[i],
                                 shape=shapes.get(name, ()))
            if name in component.parameter_units:
                value = self._convert_start(i, var, value, component.parameter_units[name])
            checked[name] = (var, value)
        return checked

    def _convert_start(self, i: int, var, value: float, unit_name: str) -> float:
        """Convert a start value given in ``unit_name`` to the variable's unit."""
        return start_in_variable_unit(value, unit_name, var, self.units[i].description, self.system.units,
                                      file=self.system._file, component=self.names[i])

    # public helpers -----------------------------------------------------------
    def _resolve(self, qualified: str):
        component, variable = self.system.split(qualified)
        if component not in self.names:
            raise UnknownComponentError("unknown component", component=component)
        i = self.names.index(component)
        var = find_variable(self.variables[i], variable, component=component,
                            file=self.files[i])
        if not self.instances:
            raise OrchestrationError(f"'{qualified}': values can only be read or set during "
                                     "a run (from a step callback)")
        return self.instances[i], var

    def get(self, qualified: str) -> StartValue | np.ndarray:
        """Current value of ``component.variable`` (during a run, e.g. in a callback).

        An FMI 3.0 array comes as a numpy array of its shape.
        """
        instance, var = self._resolve(qualified)
        kind = value_type(var)
        shape = self.shapes[self.instances.index(instance)].get(var.name, ())
        if instance.fmi3:
            values = instance.call(f"get{kind}", [var.valueReference], size_of(shape))
        else:
            values = instance.call(f"get{kind}", [var.valueReference])
        if shape:
            return np.array(values, dtype=NUMPY_TYPES[kind]).reshape(shape)
        value = values[0]
        if kind == "String":
            return value.decode("utf-8") if isinstance(value, bytes) else value
        return bool(value) if kind == "Boolean" else value

    def set(self, qualified: str, value: StartValue) -> None:
        """Set an input or tunable parameter ``component.variable`` during a run."""
        instance, var = self._resolve(qualified)
        if not (var.causality == "input" or (var.causality == "parameter"
                                             and var.variability == "tunable")):
            raise StartValueError("only inputs and tunable parameters can be set during a "
                                  "run", file=str(instance.unpacked.path),
                                  component=instance.name, variable=var.name)
        shape = self.shapes[self.instances.index(instance)].get(var.name, ())
        value = coerce_value(var, value, component=instance.name,
                             file=str(instance.unpacked.path), shape=shape)
        instance.call(f"set{value_type(var)}", [var.valueReference],
                      value if shape else [value])

    # run ----------------------------------------------------------------------
    def simulate(self, stop_time: float | None = None, step_size: StepSpec | None = None, *,
                 start_time: float | None = None, output_every: int = 1,
                 progress: bool | None = None, realtime: float | None = None,
                 callback: StepCallback | None = None, profile: bool = False) -> ResultArray:
        """Run the system and return the recorded results.

        Parameters
        ----------
        stop_time : float, optional
            Stop time, s (default: the system file's).
        step_size : float, list of (until_time, step) or 1-D array, optional
            Communication step (s), a step schedule, or the communication
            points (default: the system file's step).
        start_time : float, optional
            Start time, s (default: the system file's, else 0).
        output_every : int
            Record every Nth communication step (the first and last rows are
            always recorded).
        progress : bool or None
            Show a tqdm bar; ``None`` shows it for long runs only.
        realtime : float, optional
            Real-time pacing factor: wall-clock seconds per simulated second.
        callback : callable, optional
            ``callback(time, master)`` after every step; it may read and set
            values with :meth:`get` / :meth:`set` and stop the run by
            returning ``False``.
        profile : bool
            Measure where the loop's time goes (compiled loop only, no pacing,
            no callback): ``result.meta['profile']`` gives the wall seconds of
            each component's doStep, gets and sets, of the conversions, of
            recording and of the master's own work (the rest).

        Returns
        -------
        ResultArray
            Structured array, ``time`` first, then ``component.variable``
            fields; ``result.meta`` states the scheme, stepping order, broken
            loop edges, algebraic loops, converted connections, step and its
            source, whether the run was stopped early and, with
            ``realtime``, the pacing report (worst lag, late steps).

        Raises
        ------
        ScheduleError
            For invalid times or steps.
        FMUCallError
            When an FMU returns discard, error or fatal; all instances are
            released before it propagates.
        orchestration.interrupt.Interrupted
            Inside :func:`orchestration.interrupt.handle_signals`, on SIGINT
            or SIGTERM (all instances released first).  Its ``partial``
            attribute holds the rows recorded so far (a ResultArray whose
            ``meta['interrupted_at']`` is the time the last completed step
            reached), or ``None`` if the loop had not started.
        """
        start = self.system.start_time if start_time is None else start_time
        start = 0.0 if start is None else float(start)
        stop = self.system.stop_time if stop_time is None else stop_time
        step, step_source = self._step(step_size)
        segments = make_schedule(start, stop, step)
        if not (isinstance(output_every, int) and output_every >= 1):
            raise ScheduleError(f"output_every must be a positive integer, got {output_every!r}",
                                names=("output_every",))
        self._check_variable_steps(segments)
        total = sum(s.count for s in segments)
        columns = 1 + sum(size_of(self.shapes[i].get(var.name, ())) for i, var in self.selection)
        record_bytes = (total // output_every + 3) * columns * 8
        if record_bytes > MAX_RECORD_BYTES:
            raise ScheduleError(f"recording {total // output_every + 1} rows of "
                                f"{columns} values needs {record_bytes:.3g} bytes, "
                                f"more than the limit of {MAX_RECORD_BYTES} bytes (MAX_RECORD_BYTES); "
                                "record fewer rows or variables",
                                names=("stop_time", "step_size", "output_every"))
        meta = self._meta(start, segments, total, output_every, realtime)
        meta["step_source"] = step_source
        pacer = None if realtime is None else RealTimePacer(realtime, start, capacity=total)
        bar = Progress(total, progress, description=self.system.name)
        recorder = None
        try:
            self._initialize(start)
            recorder = Recorder([inst.slave for inst in self.instances], self.names,
                                self.selection, total // output_every + 3, self.shapes)
            self._sample(recorder, start)
            if pacer is not None:
                pacer.start()  # the clock starts once every FMU is loaded and initialised
            if profile and (pacer is not None or callback is not None or self.loop == "python"):
                raise OrchestrationError("profile=True needs the compiled loop: no real-time pacing, no "
                                         "callback, loop 'auto' or 'c'")
            compiled = self._compiled(recorder, profile) if pacer is None and callback is None else None
            if profile and compiled is None:
                raise OrchestrationError("profile=True needs the compiled loop (orchestration/_steploop), "
                                         "which is not built: reinstall the package with 'pip install -e .'")
            meta["loop"] = "c" if compiled is not None else "python"
            if compiled is not None:
                began = time.perf_counter()
                steps = self._c_loop(compiled, segments, total, recorder, output_every, bar)
                if profile:
                    meta["profile"] = self._profile(compiled, steps, time.perf_counter() - began)
            else:
                steps = self._loop(segments, total, recorder, output_every, bar, pacer, callback)
        except interrupt.Interrupted as stop:
            stop.partial = None
            if recorder is not None and recorder.count:
                stop.partial = recorder.result({**meta, "interrupted_at": self.time,
                                                "signal": signal.Signals(stop.signum).name})
            raise
        finally:
            bar.close()
            self._release()
        meta["steps"] = steps
        meta["stopped_early"] = steps < total
        if self.terminated_by is not None:
            meta["terminated_by"] = self.terminated_by
        meta["end_time"] = float(recorder.time[recorder.count - 1])
        if pacer is not None:
            meta["realtime"] = pacer.report()
            meta["max_realtime_lag"] = pacer.max_lag
        return recorder.result(meta)

    def _step(self, step_size: StepSpec | None) -> tuple[StepSpec, str]:
        """The communication step and where it comes from (argument, system file, FMUs)."""
        if step_size is not None:
            return step_size, "argument"
        if self.system.step_size is not None:
            return self.system.step_size, "system file"
        declared = []
        for name, unit in zip(self.names, self.units):
            experiment = unit.description.defaultExperiment
            if experiment is not None and experiment.stepSize is not None:
                try:
                    declared.append((float(experiment.stepSize), name))
                except ValueError:
                    continue
        declared = [(h, name) for h, name in declared if math.isfinite(h) and h > 0.0]
        if not declared:
            raise ScheduleError("no communication step: none given, none in the system file "
                                f"(it has no '{ANNOTATION_TYPE}' step annotation) and no FMU "
                                "declares a DefaultExperiment stepSize; give one (--step)")
        smallest = min(h for h, _ in declared)
        listing = ", ".join(f"{name} {h:g} s" for h, name in declared)
        if all(h == smallest for h, _ in declared):
            source = (f"the FMUs' common DefaultExperiment stepSize ({listing})"
                      if len(declared) > 1 else f"the DefaultExperiment stepSize of {listing}")
        else:
            source = f"the smallest DefaultExperiment stepSize of the FMUs ({listing})"
        warnings.warn(f"no communication step given and none in the system file: using "
                      f"{smallest:g} s, {source}", DefaultStepWarning, stacklevel=4)
        return smallest, source

    def _check_variable_steps(self, segments) -> None:
        """Refuse a varying step for FMUs that declare they cannot handle one."""
        steps = [s.step for s in segments]
        if all(math.isclose(h, steps[0], rel_tol=1e-9) for h in steps):
            return
        for name, unit in zip(self.names, self.units):
            if not unit.description.coSimulation.canHandleVariableCommunicationStepSize:
                raise ScheduleError(f"component '{name}' (FMU '{unit.path}') cannot handle a "
                                    "variable communication step; use a fixed step")

    def _meta(self, start: float, segments, total: int, every: int,
              realtime: float | None) -> dict:
        single = len({s.step for s in segments}) == 1
        return {"tool": "orchestration", "system": self.system.name, "scheme": self.scheme,
                "order": [self.names[i] for i in self.order],
                "broken_connections": [str(c) for link in self.links
                                       if (link.source, link.target) in self.broken
                                       for c in link.connections],
                "algebraic_loop": list(self.loops),
                "converted_connections": {str(c): list(m) for link in self.links
                                          if link.maps is not None
                                          for c, m in zip(link.connections, link.maps)
                                          if m != (1.0, 0.0)},
                "start_time": start, "stop_time": segments[-1].end,
                "step": segments[0].step if single else "schedule",
                "planned_steps": total, "output_every": every, "realtime_factor": realtime,
                "unconnected_inputs": list(self.unconnected),
                "inputs_without_source": list(self.system.inputs_without_source)}

    def _initialize(self, start: float) -> None:
        self.time = None
        self.terminated_by = None
        for name, unit in zip(self.names, self.units):
            interrupt.check()
            instance = FMUInstance(name, unit, logging_on=self.logging_on)
            self.instances.append(instance)
            instance.instantiate()
        for instance, values in zip(self.instances, self.start_values):
            settings = [(var.causality == "structuralParameter",
                         (value_type(var), var.valueReference,
                          value if isinstance(value, list) else [value]))
                        for var, value in values.values()]
            instance.setup(start, [s for structural, s in settings if structural],
                           [s for structural, s in settings if not structural])
        self._build_plan()
        # inputs get their sources' initial outputs while still in Initialization Mode (FMI 2.0
        # allows setting inputs there), each component leaving it after its sources did
        for index in self.order:
            interrupt.check()
            self._transfer(self._incoming[index], start)
            self.instances[index].call("exitInitializationMode")
            self.instances[index].mark_initialized()
        for gets, sets, _ in self._plan:
            self._transfer((gets, sets), start)
        self.time = start

    def _build_plan(self) -> None:
        """Prepare function pointers, buffers and conversions for the inner loop.

        ``self._plan`` is a list of stages ``(gets, sets, steps)``: every get
        of a stage is made (``fmi2Get*``/``fmi3Get*``, then converted, then
        cast where the two ends' C types differ) before any set
        (``fmi2Set*``/``fmi3Set*``), then the stage's components are stepped.
        Gauss-Seidel has one stage per component in stepping order; Jacobi one
        stage with every transfer and every component.  The calls' arguments
        are ctypes objects made here (:mod:`orchestration.rawcalls`).
        """
        slaves = [inst.slave for inst in self.instances]
        handles = [handle(s) for s in slaves]
        fmi3 = [inst.fmi3 for inst in self.instances]
        self._incoming = {i: ([], []) for i in range(len(slaves))}
        for link in self.links:
            n = link.values
            source, target = link.source, link.target
            target_kind = link.target_kind or link.kind
            buffer = value_buffer(link.kind, n, fmi3[source])
            convert = None
            if link.maps is not None:
                view = np.ctypeslib.as_array(buffer)
                sizes = link.sizes or [1] * len(link.maps)
                factors = np.repeat([m[0] for m in link.maps], sizes)
                offsets = np.repeat([m[1] for m in link.maps], sizes)
                convert = (view, factors, offsets)
            gets, sets = self._incoming[target]
            gets.append((getter(slaves[source], link.kind),
                         value_args(slaves[source], handles[source], vr_array(link.source_vrs),
                                    buffer, n),
                         convert, source, f"{_api(fmi3[source])}Get{link.kind}"))
            into = buffer
            if c_type(target_kind, fmi3[target]) != c_type(link.kind, fmi3[source]):
                into = value_buffer(target_kind, n, fmi3[target])
                gets.append((_caster(np.ctypeslib.as_array(buffer), np.ctypeslib.as_array(into)),
                             (), None, target, f"cast {link.kind} to {target_kind}"))
            sets.append((setter(slaves[target], target_kind),
                         value_args(slaves[target], handles[target], vr_array(link.target_vrs),
                                    into, n),
                         target, f"{_api(fmi3[target])}Set{target_kind}"))
        self._c_t, self._c_h = c_double(), c_double()
        flags = [DoStep3Flags() if f else None for f in fmi3]
        self._terminate_flags = [(f.terminate, i) for i, f in enumerate(flags) if f is not None]
        steps = [(do_step(s), step_args(s, handles[i], self._c_t, self._c_h, flags[i]), i,
                  f"{_api(fmi3[i])}DoStep") for i, s in enumerate(slaves)]
        if self.scheme == "gauss-seidel":
            self._plan = [(*self._incoming[i], [steps[i]]) for i in self.order]
        else:
            gets = [g for i in self.order for g in self._incoming[i][0]]
            sets = [s for i in self.order for s in self._incoming[i][1]]
            self._plan = [(gets, sets, [steps[i] for i in self.order])]
        # the inner loop's calls in order, each (function, arguments, component, call name, conversion);
        # doStep's time and step are the c_doubles self._c_t and self._c_h, updated by the loop
        self._ops = []
        for gets, sets, stage_steps in self._plan:
            self._ops += [(get, args, index, call, convert) for get, args, convert, index, call in gets]
            self._ops += [(set_, args, index, call, None) for set_, args, index, call in sets]
            self._ops += [(step, args, index, call, None) for step, args, index, call in stage_steps]
        self._specs = self._op_specs(flags)

    def _op_specs(self, flags) -> list[OpSpec]:
        """The inner loop's operations in C terms (:mod:`orchestration.steploop`), in the order of
        ``self._ops``; each names the operation it belongs to."""
        specs = []
        for owner, (function, args, index, call, convert) in enumerate(self._ops):
            fmi3 = self.instances[index].fmi3
            if call.startswith("cast"):
                source, target = function.arrays
                specs.append(OpSpec("cast", owner, source=source, target=target))
            elif call.endswith("DoStep"):
                specs.append(OpSpec("step", owner, function=function, instance=args[0], fmi3=fmi3,
                                    flags=flags[index]))
            else:
                n_values = args[4].value if fmi3 else len(args[1])
                specs.append(OpSpec("values", owner, function=function, instance=args[0], vrs=args[1],
                                    values=args[3], n_values=n_values, fmi3=fmi3))
            if convert is not None:
                view, factors, offsets = convert
                specs.append(OpSpec("map", owner, values=view, factors=factors, offsets=offsets))
        return specs

    def _transfer(self, transfers, time: float) -> None:
        """Make every get of ``transfers = (gets, sets)`` (and convert, cast), then every set."""
        gets, sets = transfers[0], transfers[1]
        for get, args, convert, index, call in gets:
            if (status := get(*args)) > FMI_WARNING:
                self._fail(index, call, status, time)
            if convert is not None:
                view, factors, offsets = convert
                np.multiply(view, factors, out=view)
                np.add(view, offsets, out=view)
        for set_, args, index, call in sets:
            if (status := set_(*args)) > FMI_WARNING:
                self._fail(index, call, status, time)

    def _fail(self, index: int, call: str, status: int, time: float) -> None:
        instance = self.instances[index]
        instance.time = time
        instance.fail(call, status)

    def _sample(self, recorder: Recorder, time: float) -> None:
        block = recorder.sample(time)
        if block >= 0:
            index, kind = recorder.block_owner(block)
            self._fail(index, f"{_api(self.instances[index].fmi3)}Get{kind}", 3, time)

    def _loop(self, segments, total: int, recorder: Recorder, every: int, bar: Progress,
              pacer: RealTimePacer | None, callback: StepCallback | None) -> int:
        ops, fail, sample = self._ops, self._fail, recorder.sample
        c_t, c_h = self._c_t, self._c_h
        multiply, add = np.multiply, np.add
        pending = interrupt.PENDING
        done = 0
        next_record = min(every, total)
        next_tick = bar.next_tick
        terminate = self._terminate_flags
        for segment in segments:
            begin, h, count_ = segment.begin, segment.step, segment.count
            c_h.value = h
            for j in range(count_):
                t = begin + j * h
                c_t.value = t
                # the plan's calls in order: in each stage every get (and conversion) before any set
                for function, args, index, call, convert in ops:
                    if (status := function(*args)) > FMI_WARNING:
                        fail(index, call, status, t)
                    if convert is not None:
                        multiply(convert[0], convert[1], out=convert[0])
                        add(convert[0], convert[2], out=convert[0])
                done += 1
                t_end = segment.end if j == count_ - 1 else begin + (j + 1) * h
                self.time = t_end
                if terminate and self._terminated(terminate):
                    if recorder.time[recorder.count - 1] != t_end:
                        self._sample(recorder, t_end)
                    return done
                if done == next_record:
                    if sample(t_end) >= 0:
                        self._sample(recorder, t_end)
                    next_record = min(next_record + every, total)
                if pending[0]:
                    interrupt.check()
                if pacer is not None:
                    pacer.wait(t_end, h)
                if done == next_tick:
                    bar.tick(done)
                    next_tick = bar.next_tick
                if callback is not None and callback(t_end, self) is False:
                    if recorder.time[recorder.count - 1] != t_end:
                        self._sample(recorder, t_end)
                    return done
        return done

    def _profile(self, compiled, steps: int, wall: float) -> dict:
        """Where the compiled loop's ``wall`` seconds went (see :meth:`simulate`, ``profile``)."""
        components = {name: {"doStep": 0.0, "get": 0.0, "set": 0.0} for name in self.names}
        conversions = 0.0
        for spec, seconds in zip(compiled.specs, compiled.seconds):
            _, _, index, call, _ = self._ops[spec.owner]
            if spec.kind in ("map", "cast"):
                conversions += float(seconds)
            else:
                part = "doStep" if call.endswith("DoStep") else "get" if "Get" in call else "set"
                components[self.names[index]][part] += float(seconds)
        record = float(compiled.seconds[-1])
        spent = sum(sum(parts.values()) for parts in components.values()) + conversions + record
        return {"steps": steps, "wall_s": wall, "components": components, "conversions_s": conversions,
                "record_s": record, "master_s": wall - spent}

    def _compiled(self, recorder: Recorder, profile: bool = False):
        """The plan as a :class:`~orchestration.steploop.CompiledLoop`, or None (no library, a plan it
        cannot run, or ``loop='python'``)."""
        lib = steploop.load() if self.loop != "python" else None
        if lib is None:
            if self.loop == "c":
                raise OrchestrationError("loop='c': the compiled loop (orchestration/_steploop) is not built; "
                                         "reinstall the package with 'pip install -e .'")
            return None
        try:
            return steploop.CompiledLoop(lib, self._specs, recorder, profile)
        except ValueError:
            if self.loop == "c":
                raise
            return None

    def _c_loop(self, compiled, segments, total: int, recorder: Recorder, every: int, bar: Progress) -> int:
        """:meth:`_loop` without pacing or callback, a block of steps per call into C."""
        pending = interrupt.PENDING
        done, next_record = 0, min(every, total)
        for segment in segments:
            j = 0
            while j < segment.count:
                block = min(C_BLOCK_STEPS, segment.count - j)
                if bar.next_tick > done:
                    block = min(block, bar.next_tick - done)
                s = compiled.run(segment.begin, segment.step, segment.end, j, block, segment.count, done, total,
                                 every, next_record)
                j += s.done - done
                done, next_record = s.done, s.next_record
                if s.done > 0:
                    self.time = s.t_end
                if s.outcome == steploop.CALL_FAILED:
                    _, _, index, call, _ = self._ops[compiled.owners[s.where]]
                    self._fail(index, call, s.status, s.t_fail)
                elif s.outcome == steploop.BAD_OP:
                    raise OrchestrationError(f"the compiled loop refused operation {s.where} of its plan")
                elif s.outcome == steploop.RECORD_FAILED:
                    index, kind = recorder.block_owner(s.where)
                    self._fail(index, f"{_api(self.instances[index].fmi3)}Get{kind}", s.status, s.t_fail)
                elif s.outcome == steploop.FULL:
                    raise OrchestrationError("the recorder's storage is full (a bug: rows were planned)")
                elif s.outcome == steploop.TERMINATED:
                    self._terminated(self._terminate_flags)
                    if recorder.time[recorder.count - 1] != s.t_end:
                        self._sample(recorder, s.t_end)
                    return done
                if pending[0]:
                    interrupt.check()
                if done == bar.next_tick:
                    bar.tick(done)
        return done

    def _terminated(self, flags) -> bool:
        """True (and ``self.terminated_by`` set) if an FMI 3.0 FMU's last fmi3DoStep asked to end."""
        for flag, index in flags:
            if flag.value:
                self.terminated_by = self.names[index]
                return True
        return False

    def _release(self) -> None:
        """Terminate and free every instance as the FMI state machine allows."""
        fatal = {inst.unpacked.path for inst in self.instances if inst._state == "fatal"}
        for instance in reversed(self.instances):
            if instance.unpacked.path in fatal:
                instance._state = "fatal"  # FMI 2.0: no call to any instance of that FMU
            instance.release()
        self.instances = []
        self._plan = []
        self._ops = []

    def close(self) -> None:
        """Release instances and delete the extracted FMUs (idempotent)."""
        self._release()
        for unit in self._unpacked.values():
            unit.remove()
        self._unpacked.clear()
        workdir = getattr(self.system, "_workdir", None) if hasattr(self, "system") else None
        if getattr(self, "_owns_system", False) and workdir is not None:
            workdir.cleanup()  # the .ssp this master extracted

    def __enter__(self) -> Master:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _api(fmi3: bool) -> str:
    """The C function prefix, for call names in messages."""
    return "fmi3" if fmi3 else "fmi2"


def _caster(source: np.ndarray, target: np.ndarray):
    """A call for the plan copying ``source`` into ``target`` with a C cast; returns status 0.
    Its ``arrays`` are the two buffers (for the compiled loop)."""

    def cast() -> int:
        np.copyto(target, source, casting="unsafe")
        return 0

    cast.arrays = (source, target)
    return cast


def simulate_system(system: System | str | Path, stop_time: float | None = None,
                    step_size: StepSpec | None = None, *, scheme: str = "gauss-seidel",
                    record: Sequence[str] | None = None, **options) -> ResultArray:
    """Read (if needed), run and clean up a system in one call.

    Parameters
    ----------
    system : System, str or Path
        System or SSP/SSD file.
    stop_time : float, optional
        Stop time, s.
    step_size : float, schedule or array, optional
        See :meth:`Master.simulate`.
    scheme : {'gauss-seidel', 'jacobi'}
        Coupling scheme.
    record : sequence of str, optional
        Variables to record (default: all outputs).
    **options
        Other keyword arguments of :meth:`Master.simulate`.

    Returns
    -------
    ResultArray
    """
    with Master(system, scheme=scheme, record=record) as master:
        return master.simulate(stop_time, step_size, **options)
