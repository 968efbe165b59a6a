"""Fault list for one FMU, driven through FMPy (issue 14, grown for issue 21).

Run as ``python fmu_faults.py FMU_PATH`` in a fresh process (a crash or a
hang then costs that process, not the test run); it prints one JSON line per
case, ``{"category", "case", "outcome", "detail"}``, as soon as the case is
done, then ``DONE``.  The outcomes:

* ``clean``: refused where the contract says, with fmi2Error and a logged
  reason (a bad parameter: at fmi2ExitInitializationMode, the message naming
  the parameter); or, for the few cases the FMU may run, run to the end with
  finite outputs;
* ``wrong status``: refused, but late (a bad parameter accepted at
  initialisation and refused at the first step), with another status, or
  with no logged reason;
* ``silently accepted``: run as if nothing were wrong.

``hang`` and ``crash`` are what the caller sees of the process (timeout,
non-zero exit): the last case printed names where it happened.

The categories: bad parameter values (every parameter: NaN and infinities
for Reals, the int32 extremes for Integers, a word no parameter takes for
Strings, plus a range table below), first step not at the start time, NaN
inputs, bad value references and types, calls in the wrong order.
"""

from __future__ import annotations

import json
import math
import sys

INT_MIN, INT_MAX = -2**31, 2**31 - 1

# Values outside each parameter's range (beyond NaN / infinities / int32 extremes), by FMU.
RANGES = {
    "Turntable": {
        "rate": [0.0, -1.0], "accel": [0.0, -1.0], "dwell": [-1.0], "align_time": [-1.0], "align_dwell": [-1.0],
        "grid": [0.0, -1.0], "duration": [0.0, -1.0], "ambient_period": [0.0], "revolutions": [0, -1],
        "warmup": [-1.0], "chamber_ramp": [0.0, -1.0], "chamber_hold": [-1.0], "chamber_step": [-1.0],
        "chamber_step_hold": [-1.0], "outer_rate": [-1.0], "outer_accel": [-1.0], "ambient_amplitude": [-1.0],
    },
    "IMUThermal": {
        "lat": [2.0], "internal_rate": [0.0, -1.0], "aging_days": [-1.0], "seed": [-1],
        "gimbals": ["", "w", "x,y,z,x"],
        **{f"gyro_random_walk_{a}": [-1.0] for a in "xyz"},
        **{f"gyro_bias_corr_time_{a}": [0.0] for a in "xyz"},
        **{f"accel_hysteresis_width_{a}": [0.0] for a in "xyz"},
        **{f"lowrate_width_{a}": [0.0] for a in "xyz"},
        "flicker_tau_min": [0.0], "aging_corr_time": [0.0], "time_constant_gyro_z": [0.0, -1.0],
        "self_heating_gyro_z": [1e300],
    },
    "StrapdownINS": {
        "lat0": [2.0], "align_time": [-1.0], "coarse_time": [-1.0], "kf_arw": [-1.0],
        "kf_velocity_meas_std": [0.0], "kf_tilt0_std": [-1.0], "pitch0": [2.0],
    },
    "GNSSReceiver": {
        "rate_hz": [0.5, 25.0], "seed": [-1], "pos_gm_tau": [0.0], "vel_white_e": [-1.0], "lever_x": [1e400],
        "outages": ["5:3", "a:b", "1:2;"*17],
    },
    "AidedINS": {
        "step": [0.0, -1.0], "arw": [-1.0], "cov_every": [0.0, 2.5], "zupt_std": [0.0], "lat0": [2.0],
        "gnss_pos_std_e": [0.0], "gnss_vel_std_u": [-1.0], "use_velocity": [2, -1], "latency": [-1.0],
        "zaru_std": [0.0, -1.0], "nhc_std": [0.0], "odo_std": [0.0],
        "state_scale_factors": [2, -1], "state_lever_arm": [2], "state_gnss_pos_gm": [-1], "state_gnss_vel_gm": [3],
        "gyro_sf0_std": [0.0], "accel_sf0_std": [-1.0], "sf_tau": [-1.0], "lever0_std": [0.0],
        "gnss_pos_gm_std_e": [-1.0], "gnss_pos_gm_tau": [0.0], "gnss_vel_gm_std_n": [-1.0], "gnss_vel_gm_tau": [-1.0],
        "zupt_source": [2, -1], "zvd_window": [1, 4097], "zvd_gamma": [0.0], "zvd_vrw": [0.0, -1.0], "zvd_arw": [0.0],
    },
    "VehicleMotion": {
        "legs": ["", "fly 3", "drive -5 10"], "lat0": [2.0], "lead_time": [-1.0], "grid": [0.0],
        "sway_period": [0.0], "reference_speed": [0.0], "body_seed": [-1],
    },
    "DriftModelUpdater": {
        "prior_points": [0.0, -1.0], "prior_t_max": [-10.0], "latency": [-1.0], "forgetting_factor": [0.0, 1.5],
        "forgetting_time_scale": [0.0], "time_threshold": [-1.0], "speed_threshold": [-1.0], "kf_arw": [-1.0],
        "model_file": ["/nonexistent/model.json"],
    },
    "RBFIdentifier": {
        "trigger_time": [-1.0], "latency": [-1.0], "model_file": ["/nonexistent/model.json"],
    },
    "IMULog": {"log_file": ["", "/nonexistent/log.csv"]},
    "TrajectoryIMU": {
        "segments": ["", "1 0 0", "1.5 0 0 0", "1 0 0 0 0", "0 0 0 0"], "step": [0.0, -1.0, 2.0],
        "substeps": [0, 1001], "lat0": [1.6], "pitch0": [1.56], "speed0": [-1.0], "arw": [-1.0], "gyro_rw": [-1.0],
        "seed": [-1], "odo_rate_hz": [-1.0, 30.0], "odo_scale_factor": [0.5], "odo_noise_std": [-1.0],
        "odo_resolution": [-1.0], "odo_seed": [-1], "zupt_enable": [3, -1], "nhc_enable": [2, -1],
        "zupt_std": [-1.0], "nhc_std": [-1.0], "jitter_seed": [-1], "vib_accel_rms": [-1.0], "vib_rate_rms": [float("nan")],
    },
}

# parameters that need another one set to matter (a value is refused only with these set too)
CONTEXT = {
    ("Turntable", "chamber_ramp"): {"ambient_mode": "chamber"},
    ("Turntable", "chamber_hold"): {"ambient_mode": "chamber"},
    ("Turntable", "chamber_step"): {"ambient_mode": "chamber"},
    ("Turntable", "chamber_step_hold"): {"ambient_mode": "chamber"},
    ("Turntable", "chamber_first"): {"ambient_mode": "chamber"},
    **{("AidedINS", name): {"zupt_source": 1, "zvd_vrw": 1e-3, "zvd_arw": 1e-4}  # the detector's, read when it runs
       for name in ("zvd_window", "zvd_gamma", "zvd_vrw", "zvd_arw")},
}

# FMUs that need a parameter to run at all (a fixture file), given by the caller as NAME=VALUE arguments
STEPS = 3


def bad_values(model: str, var) -> list:
    """Every bad value tried for one parameter."""
    if var.type == "Real":
        values = [math.nan, math.inf, -math.inf]
    elif var.type == "Integer":
        values = [INT_MIN]
    elif var.type == "String":
        values = ["no-such-value"] if var.name not in ("legs",) else []
    else:
        values = []
    return values + [v for v in RANGES.get(model, {}).get(var.name, []) if v not in values]


class Host:
    """One FMU through FMPy's low-level API, with its log."""

    def __init__(self, path: str, base: dict):
        from fmpy import extract, read_model_description

        self.md = read_model_description(path)
        self.dir = extract(path)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.base = base
        self.log: list[tuple[int, str]] = []
        self.step = self.md.defaultExperiment.stepSize if self.md.defaultExperiment else 1.0
        self.step = float(self.step or 1.0)
        self.name = None

    def new(self, guid=None):
        from fmpy.fmi2 import FMU2Slave
        from orchestration import fmilog

        self.log = []
        if self.name is None:
            self.name = fmilog.register("fault", lambda status, category, text: self.log.append((status, text)))
        f = FMU2Slave(guid=guid or self.md.guid, unzipDirectory=self.dir,
                      modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=self.name)
        f.instantiate(loggingOn=False, callbacks=fmilog.callbacks())
        self.set(f, self.base)
        return f

    def set(self, f, values: dict):
        for name, value in values.items():
            vr = [self.vars[name].valueReference]
            kind = self.vars[name].type
            if kind == "String":
                f.setString(vr, [value])
            elif kind == "Integer":
                f.setInteger(vr, [int(value)])
            else:
                f.setReal(vr, [float(value)])

    def init(self, f, start=0.0):
        f.setupExperiment(startTime=start)
        f.enterInitializationMode()
        f.exitInitializationMode()
        return f

    def errors(self):
        return [m for status, m in self.log if status >= 3]


def _refused(call):
    """(refused with an error status?, status text) of one call."""
    from fmpy.fmi1 import FMICallException

    try:
        call()
    except FMICallException as exc:
        return True, str(exc)
    except Exception as exc:  # noqa: BLE001 - FMPy raises a bare Exception for a NULL instance
        return True, str(exc)
    return False, "ok"


def _free(f):
    try:
        f.freeInstance()
    except Exception:  # noqa: BLE001
        pass


def parameter_case(host: Host, model: str, var, value):
    """A bad parameter value: fmi2Error at fmi2ExitInitializationMode with a reason naming it."""
    f = host.new()
    try:
        context = CONTEXT.get((model, var.name), {})
        host.set(f, context)
        refused, _ = _refused(lambda: host.set(f, {var.name: value}))
        if refused:  # refused when set: fine as long as it says why
            return ("clean" if host.errors() else "wrong status"), "refused at set"
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        refused, status = _refused(f.exitInitializationMode)
        if refused:
            named = any(var.name in m for m in host.errors())
            ok = "status 3" in status and named
            return ("clean" if ok else "wrong status"), f"{status}; {host.errors()[-1:]}"
        for k in range(STEPS):
            refused, status = _refused(lambda k=k: f.doStep(k * host.step, host.step))
            if refused:
                return "wrong status", f"accepted at initialisation, refused at step {k}: {host.errors()[-1:]}"
        return "silently accepted", "initialised and stepped"
    finally:
        _free(f)


def first_step_cases(host: Host):
    """A first fmi2DoStep that does not start at the start time."""
    for start, t in ((0.0, 5.0 * host.step), (0.0, -host.step), (100.0 * host.step, 0.0)):
        f = host.new()
        try:
            refused, status = _refused(lambda f=f, start=start: host.init(f, start))
            if refused:
                yield f"start {start}: initialisation", "wrong status", status
                continue
            refused, status = _refused(lambda f=f, t=t: f.doStep(t, host.step))
            ok = refused and "status 3" in status and any("start time" in m for m in host.errors())
            yield (f"start {start:g} s, first step at {t:g} s",
                   "clean" if ok else ("wrong status" if refused else "silently accepted"), status)
        finally:
            _free(f)


def nan_input_cases(host: Host):
    """A NaN input: refused with a reason, or (an input the configuration does not use) finite outputs."""
    for v in host.md.modelVariables:
        if v.causality != "input" or v.type != "Real":
            continue
        f = host.new()
        try:
            host.init(f)
            refused, status = _refused(lambda f=f, v=v: (f.setReal([v.valueReference], [math.nan]),
                                                         f.doStep(0.0, host.step)))
            if refused:
                yield f"NaN {v.name}", ("clean" if host.errors() else "wrong status"), status
                continue
            outs = [o.valueReference for o in host.md.modelVariables if o.causality == "output" and o.type == "Real"]
            finite = all(math.isfinite(x) for x in f.getReal(outs)) if outs else True
            yield f"NaN {v.name}", "clean" if finite else "silently accepted", "ran, outputs finite: unused input"
        finally:
            _free(f)


def reference_cases(host: Host):
    """Unknown value references and wrong types: fmi2Error with a reason, the instance still usable."""
    real = next(v for v in host.md.modelVariables if v.type == "Real").valueReference
    output = next((v for v in host.md.modelVariables if v.causality == "output" and v.type == "Real"), None)
    fixed = next((v for v in host.md.modelVariables if v.causality == "parameter" and v.variability == "fixed"),
                 None)
    cases = {
        "getReal unknown": lambda f: host.init(f).getReal([987654]),
        "setReal unknown": lambda f: f.setReal([987654], [1.0]),
        "getInteger unknown": lambda f: host.init(f).getInteger([987655]),
        "getString unknown": lambda f: host.init(f).getString([987656]),
        "getInteger of a Real": lambda f: host.init(f).getInteger([real]),
        "setString of a Real": lambda f: f.setString([real], ["x"]),
        "setBoolean of a Real": lambda f: f.setBoolean([real], [True]),
    }
    if output is not None:
        cases["set an output"] = lambda f: f.setReal([output.valueReference], [1.0])
    if fixed is not None:
        cases["set a fixed parameter after init"] = lambda f: host.set(host.init(f), {fixed.name: fixed.start})
    yield from _each_refused(host, cases)


def _each_refused(host: Host, cases: dict):
    """(case, verdict, status) of each call on a fresh instance: clean when refused with fmi2Error and a
    logged reason."""
    for name, call in cases.items():
        f = host.new()
        try:
            refused, status = _refused(lambda f=f, call=call: call(f))
            ok = refused and "status 3" in status and host.errors()
            yield name, "clean" if ok else ("wrong status" if refused else "silently accepted"), status
        finally:
            _free(f)


def order_cases(host: Host):
    """Calls in the wrong order (FMI 2.0 section 4.2.4): fmi2Error with a reason."""
    def after_terminate(f):
        host.init(f)
        f.doStep(0.0, host.step)
        f.terminate()
        f.doStep(host.step, host.step)

    def non_contiguous(f):
        host.init(f)
        f.doStep(0.0, host.step)
        f.doStep(7.0 * host.step, host.step)

    cases = {
        "exitInitializationMode before enter": lambda f: f.exitInitializationMode(),
        "doStep before initialisation": lambda f: f.doStep(0.0, host.step),
        "terminate before initialisation": lambda f: f.terminate(),
        "enterInitializationMode twice": lambda f: (f.setupExperiment(startTime=0.0), f.enterInitializationMode(),
                                                   f.enterInitializationMode()),
        "doStep after terminate": after_terminate,
        "doStep not continuing the previous one": non_contiguous,
        "negative step": lambda f: host.init(f).doStep(0.0, -host.step),
        "NaN step": lambda f: host.init(f).doStep(0.0, math.nan),
    }
    if host.md.coSimulation.canGetAndSetFMUstate:  # a native FMU: a state blob that is not one is refused
        cases["deSerializeFMUstate of garbage"] = lambda f: host.init(f).deSerializeFMUstate(b"not a state" * 20)
    else:
        cases["getFMUstate"] = lambda f: host.init(f).getFMUState()
    yield from _each_refused(host, cases)
    refused, status = _refused(lambda: host.new(guid="{00000000-0000-0000-0000-000000000000}"))
    yield "wrong GUID", "clean" if refused else "silently accepted", status


def run(path: str, base: dict, out=sys.stdout, skip=()) -> None:
    """Every case on the FMU at ``path`` (``base``: parameters set in every instance; ``skip``: parameter
    cases, e.g. "revolutions = 0", reported as ``hang`` without running them: one found hanging before)."""
    host = Host(path, base)
    model = host.md.modelName

    def emit(category, case, outcome, detail):
        out.write(json.dumps({"category": category, "case": case, "outcome": outcome, "detail": str(detail)[:300]})
                  + "\n")
        out.flush()

    for var in host.md.modelVariables:
        if var.causality != "parameter":
            continue
        for value in bad_values(model, var):
            case = f"{var.name} = {value!r}"
            if case in skip:
                emit("bad parameter", case, "hang", "skipped: hung in an earlier run")
                continue
            outcome, detail = parameter_case(host, model, var, value)
            emit("bad parameter", case, outcome, detail)
    for case, outcome, detail in first_step_cases(host):
        emit("first step not at the start time", case, outcome, detail)
    for case, outcome, detail in nan_input_cases(host):
        emit("NaN input", case, outcome, detail)
    for case, outcome, detail in reference_cases(host):
        emit("bad value reference", case, outcome, detail)
    for case, outcome, detail in order_cases(host):
        emit("wrong call order", case, outcome, detail)
    f = host.init(host.new())  # after all of it, a fresh instance still runs
    for k in range(STEPS):
        f.doStep(k * host.step, host.step)
    f.freeInstance()
    out.write("DONE\n")


if __name__ == "__main__":  # python fmu_faults.py FMU [NAME=VALUE ...] [--skip "CASE" ...]
    fmu, *rest = sys.argv[1:]
    skips = [rest[i + 1] for i, a in enumerate(rest) if a == "--skip"]
    settings = [a for i, a in enumerate(rest) if a != "--skip" and (i == 0 or rest[i - 1] != "--skip")]
    run(fmu, dict(s.split("=", 1) for s in settings), skip=skips)
