"""The physics FMUs' steps (native now: fmus/c): the same outputs as the Python
do_step bit for bit, called from C (no Python) or through do_step, the same as the
in-process library, and every error still reported by the Python do_step at the call
that caused it."""

import sys

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_driver import IMU_TO_INS, TT_TO_IMU, Slave
from sarins_fmu import imu, turntable
from sarins_fmu.experiments import run_static
from sarins_fmu.imu import IMU, StaticBase
from sarins_fmu.thermal import Ambient
from sarins_fmu.units import DPH_TO_RPS

ALIGN = 1200.0  # s (coarse alignment: the default 300 s)
CORRECTION = 0.01 * DPH_TO_RPS  # rad/s, from nav time CORRECTION_FROM on
CORRECTION_FROM = 1800.0
INS_FIRST = ["lat_error", "position_error", "yaw"]  # the INS's outputs compared with the in-process run


def _outputs(slave):
    """Every Real output of an FMU (the INS's INS_FIRST first): a new output that a compiled step
    forgot to write shows up as a difference."""
    names = [v.name for v in slave.md.modelVariables if v.causality == "output" and v.type == "Real"]
    if "lat_error" in names:
        names = INS_FIRST + [n for n in names if n not in INS_FIRST]
    return names


def constant_correction(k):
    """INS inputs before step k: a new constant compensation well before its apply_from."""
    if k == ALIGN + 600:
        return dict(axial_drift_correction=CORRECTION, axial_drift_apply_from=CORRECTION_FROM)
    return None


class Chain:
    """Turntable -> IMUThermal -> StrapdownINS through FMPy, Gauss-Seidel, 1 s steps."""

    def __init__(self, fmu_dir, ins_params=None):
        self.tt = Slave(fmu_dir / "Turntable.fmu", "turntable")
        self.imu = Slave(fmu_dir / "IMUThermal.fmu", "imu")
        self.ins = Slave(fmu_dir / "StrapdownINS.fmu", "ins")
        self.tt.set(align_time=ALIGN)
        self.ins.set(**{"align_time": ALIGN, **dict(ins_params or {})})
        for s in (self.tt, self.imu, self.ins):
            s.fmu.enterInitializationMode()
        self.link()
        for s in (self.tt, self.imu, self.ins):
            s.fmu.exitInitializationMode()
        self.k = 0
        self.names = [f"{label}.{n}" for label, s in (("ins", self.ins), ("imu", self.imu), ("tt", self.tt))
                      for n in _outputs(s)] + ["ins.phase"]

    def link(self):
        self.imu.fmu.setReal([self.imu.vr[n] for n in TT_TO_IMU], self.tt.get(*TT_TO_IMU))
        self.ins.fmu.setReal([self.ins.vr[n] for n in IMU_TO_INS], self.imu.get(*IMU_TO_INS))

    def step(self, n, ins_inputs=constant_correction):
        """n steps; ``ins_inputs(k)``: INS inputs to set before step k (a dict or None)."""
        rows = []
        for _ in range(n):
            t = float(self.k)
            self.tt.fmu.doStep(t, 1.0)
            self.imu.fmu.setReal([self.imu.vr[n] for n in TT_TO_IMU], self.tt.get(*TT_TO_IMU))
            self.imu.fmu.doStep(t, 1.0)
            self.ins.fmu.setReal([self.ins.vr[n] for n in IMU_TO_INS], self.imu.get(*IMU_TO_INS))
            inputs = ins_inputs(self.k) if ins_inputs is not None else None
            if inputs:
                self.ins.set(**inputs)
            self.ins.fmu.doStep(t, 1.0)
            rows.append([x for s in (self.ins, self.imu, self.tt) for x in s.get(*_outputs(s))]
                        + [self.ins.fmu.getInteger([self.ins.vr["phase"]])[0]])
            self.k += 1
        return np.array(rows)

    def column(self, rows, name):
        return rows[:, self.names.index(name)]

    def free(self):
        for s in (self.ins, self.imu, self.tt):
            s.free()


def _count_python_steps(monkeypatch):
    """Count calls of the shipped slaves' Python do_step (by class name)."""
    counts = {}
    for name, module in list(sys.modules.items()):
        if not name.endswith(("_imu_thermal_slave", "_strapdown_ins_slave")):
            continue
        for cls_name in ("IMUThermal", "StrapdownINS"):
            cls = getattr(module, cls_name, None)
            if cls is None:
                continue
            original = cls.do_step

            def counted(self, t, h, original=original, cls_name=cls_name):
                counts[cls_name] = counts.get(cls_name, 0) + 1
                return original(self, t, h)

            monkeypatch.setattr(cls, "do_step", counted)
    return counts


def _run(fmu_dir, n, ins_params=None, ins_inputs=constant_correction):
    chain = Chain(fmu_dir, ins_params)
    try:
        return chain.step(n, ins_inputs)
    finally:
        chain.free()


def _three_ways(fmu_dir, monkeypatch, n, **run):
    """The runs with the compiled steps from C, through do_step and without them, and the
    Python do_step calls of the first two (by class)."""
    _run(fmu_dir, 2)  # loads the shipped slave modules
    counts = _count_python_steps(monkeypatch)
    fast = _run(fmu_dir, n, **run)
    python_steps = dict(counts)
    monkeypatch.setenv("SARINS_FMU_NO_FAST_STEP", "1")
    counts.clear()
    via_do_step = _run(fmu_dir, n, **run)
    do_step_calls = dict(counts)
    monkeypatch.setenv("SARINS_FMU_NO_COMPILED_STEP", "1")
    python = _run(fmu_dir, n, **run)
    monkeypatch.delenv("SARINS_FMU_NO_FAST_STEP")
    monkeypatch.delenv("SARINS_FMU_NO_COMPILED_STEP")
    return fast, via_do_step, python, python_steps, do_step_calls


def test_fmu_chain_compiled_equals_python_and_in_process_bit_for_bit(fmu_dir, monkeypatch):
    """5400 steps: alignment, navigation past a random-number block (4096 intervals)
    and a compensation change; every output of the three FMUs at every step, with the
    compiled steps called from C, through do_step, and without them; and the
    in-process run."""
    n = 5400
    fast, via_do_step, python, python_steps, do_step_calls = _three_ways(fmu_dir, monkeypatch, n)
    ref = run_static(align_hours=ALIGN / 3600, nav_hours=(n - ALIGN) / 3600, seed=0,
                     correction_dph=0.01, correction_from_hours=CORRECTION_FROM / 3600)
    nav = int(ALIGN)
    assert np.array_equal(fast, python)
    assert np.array_equal(via_do_step, python)
    assert np.array_equal(fast[nav:, 0], ref.lat_error)
    assert np.array_equal(fast[nav:, 1], ref.position_error)
    assert np.array_equal(fast[nav:, 2], ref.attitude[:, 0])
    # the three FMUs of the chain are native: no Python step at all, with or without the switches
    assert not python_steps and not do_step_calls, (python_steps, do_step_calls)


MODEL = (2e-5 * DPH_TO_RPS, -4e-4 * DPH_TO_RPS, 0.01 * DPH_TO_RPS)  # a, b, c of c + (a T + b) T, rad/s/degC^n
MODEL_2 = (-1e-5 * DPH_TO_RPS, 3e-4 * DPH_TO_RPS, 0.004 * DPH_TO_RPS)
SENDER_FROM, SENDER_CHANGE = 3600, 4000  # steps: a sender tags its set apply_from = nav start + 1 s from here


def model_correction(k):
    """INS inputs before step k: a temperature model from nav time CORRECTION_FROM on, then a sender
    (like the DriftModelUpdater) that repeats its set with apply_from one step ahead, every step, and
    changes it once."""
    a, b, c = MODEL if k < SENDER_CHANGE else MODEL_2
    model = dict(axial_drift_correction=c, axial_drift_correction_b=b, axial_drift_correction_a=a)
    if k == ALIGN + 600:
        return dict(model, axial_drift_apply_from=CORRECTION_FROM)
    if k >= SENDER_FROM:
        return dict(model, axial_drift_apply_from=k - ALIGN + 1.0)
    return None


def _in_process_ins(chain, rows, fmu_dir):
    """The library's INS (sarins_fmu.ins) on the chain's increments in one batch, with the model in force
    of each interval (model_correction's rules) evaluated at its temp_gyro_z: the expected navigation
    rows."""
    from dataclasses import fields

    from sarins_fmu import ins
    from sarins_fmu.drift_model import drift_model_value
    from sarins_fmu.ins import InsConfig, StrapdownINS

    k = np.arange(rows.shape[0])
    temp = chain.column(rows, "imu.temp_gyro_z")
    coef = np.where(((k - ALIGN >= CORRECTION_FROM) & (k < SENDER_CHANGE + 1))[:, None], MODEL, 0.0)
    coef[k >= SENDER_CHANGE + 1] = MODEL_2
    correction = drift_model_value(coef.T, temp)
    dtheta, dv = (np.column_stack([chain.column(rows, f"imu.{q}_{a}") for a in "xyz"]) for q in ("dtheta", "dv"))
    slave = Slave(fmu_dir / "StrapdownINS.fmu", "start values")  # the FMU's parameter defaults
    try:
        names = ["lat0", "lon0", "height0", "coarse_time"] + [f"kf_{f.name}" for f in fields(ins.AlignmentFilter)]
        values = dict(zip(names, slave.get(*names)))
    finally:
        slave.free()
    filt = ins.AlignmentFilter(**{n[3:]: v for n, v in values.items() if n.startswith("kf_")})
    config = InsConfig(lat=values["lat0"], lon=values["lon0"], height=values["height0"], align_time=ALIGN,
                       coarse_time=values["coarse_time"], step=1.0, filter=filt)
    return StrapdownINS(config).step(dtheta, dv, correction)


def test_temperature_model_correction_compiled_equals_python_and_the_library(fmu_dir, monkeypatch):
    """The correction c + (a T + b) T through the compiled INS step: every output bit for bit as the
    Python do_step, the navigation rows those of the library's INS with the model evaluated at each
    interval's temperature, solution_time = t + h."""
    n = 4300
    fast, via_do_step, python, python_steps, _ = _three_ways(fmu_dir, monkeypatch, n,
                                                            ins_inputs=model_correction)
    assert np.array_equal(fast, python)
    assert np.array_equal(via_do_step, python)
    chain = Chain(fmu_dir)
    chain.free()
    nav = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
    expected = _in_process_ins(chain, fast, fmu_dir)  # one batch: its alignment rows hold the batch's end
    got = np.column_stack([chain.column(fast, f"ins.{v}") for v in nav])
    assert np.array_equal(got[int(ALIGN):], expected[int(ALIGN):])
    assert np.array_equal(chain.column(fast, "ins.solution_time"), np.arange(1.0, n + 1.0))
    # the model (and its change) turned the heading: the same run without any correction differs
    assert not np.array_equal(chain.column(fast, "ins.yaw")[-100:],
                              chain.column(_run(fmu_dir, n, ins_inputs=None), "ins.yaw")[-100:])
    assert "StrapdownINS" not in python_steps, python_steps  # a native FMU: no Python step at all


def test_immediate_navigation_compiled_equals_python(fmu_dir, monkeypatch):
    """align_time = 0 (navigation from yaw0, pitch0, roll0 at once): every output the same whatever the
    other FMUs' compiled steps do."""
    start = dict(align_time=0.0, yaw0=0.2, pitch0=0.001, roll0=-0.002)
    fast, via_do_step, python, python_steps, _ = _three_ways(fmu_dir, monkeypatch, 1500, ins_params=start)
    assert np.array_equal(fast, python)
    assert np.array_equal(via_do_step, python)
    assert "StrapdownINS" not in python_steps, python_steps  # a native FMU
    assert (fast[:, -1] == 2).all()  # navigating from the first step


@pytest.mark.parametrize("fault, slave, message", [
    (dict(increment_end_time=10.0), "ins", "would skip an interval"),
    (dict(temp_gyro_z=float("nan")), "ins", "temp_gyro_z"),
    (dict(axial_drift_correction_a=float("inf")), "ins", "not finite"),
    (dict(motion_time=-5.0), "imu", "no turntable motion"),
    (dict(angle_1=float("nan")), "imu", "NaN"),
])
def test_errors_are_reported_at_the_call_while_steps_run_compiled(fmu_dir, fault, slave, message):
    chain = Chain(fmu_dir)
    try:
        chain.step(1300, None)  # navigating: every step compiled
        if "motion_time" in fault:  # a wrong tag passes once (the set kept from the last step is tagged t)
            t = float(chain.k)
            chain.tt.fmu.doStep(t, 1.0)
            chain.link()
            chain.imu.set(**fault)
            chain.imu.fmu.doStep(t, 1.0)
            chain.k += 1
            fault = {}
        t = float(chain.k)
        chain.tt.fmu.doStep(t, 1.0)
        chain.link()
        target = getattr(chain, slave)
        if slave == "ins":  # the INS gets the increments of this step, then the fault
            chain.imu.fmu.doStep(t, 1.0)
            chain.link()
        target.set(**fault)
        with pytest.raises(FMICallException, match="status 3"):
            target.fmu.doStep(t, 1.0)
        errors = [text for status, _, text in target.log if status == 3]
        assert any(message in text for text in errors), target.log[-5:]
    finally:
        chain.free()


def test_chunking_does_not_change_the_streams():
    """Any chunking of a run gives the same increments (mems: every random term; the C core's streams
    continue where the last step left them, one interval or 600 per call)."""
    sched = turntable.single_axis("forward-reverse", 700.0, grid=1.0, align_time=0.0)
    runs = []
    for chunk in (600, 1, 13, 7, 250):
        s = IMU(imu.preset("mems"), StaticBase(0.6), sched.axes, seed=9,
                ambient=Ambient(mean=20, amplitude=3, period=500))
        out = []
        for k0 in range(0, 600, chunk):
            a, r, c = sched.state(np.arange(k0, min(600, k0 + chunk)) * 1.0)
            out.append(np.hstack(s.step(a, r, c)))
        runs.append(np.vstack(out))
    for other in runs[1:]:
        assert np.array_equal(runs[0], other)


def test_ins_filter_history_is_the_same_stepped_one_by_one_or_in_one_batch():
    """StrapdownINS.p_history (preallocated, one row per fine-alignment step) whatever the batching."""
    from sarins_fmu.ins import InsConfig, StrapdownINS

    sched = turntable.single_axis("forward-reverse", 1000.0, grid=1.0, align_time=900.0, align_dwell=300.0)
    sensor = IMU(imu.preset("nav-rlg"), StaticBase(0.6), sched.axes, seed=1)
    dtheta, dv, _ = sensor.step(*sched.state(np.arange(900) * 1.0))
    config = InsConfig(lat=0.6, align_time=900.0, coarse_time=300.0)
    batch, single = StrapdownINS(config), StrapdownINS(config)
    batch.step(dtheta, dv)
    for k in range(900):
        single.step(dtheta[k], dv[k])
    assert batch.p_history.shape == (600, 9) and np.isfinite(batch.p_history).all()
    assert np.array_equal(batch.p_history, single.p_history)
    assert np.array_equal(batch.q, single.q) and batch.steps == single.steps == 900


def _system_runs(system, record, monkeypatch, schemes=("gauss-seidel", "jacobi")):
    """{(compiled, scheme): result} of the master's runs with and without the compiled steps, and the
    Python do_step calls of the compiled runs {scheme: {class: calls}}."""
    import warnings

    from orchestration import simulate_system

    runs, calls = {}, {}
    for compiled in (True, False):
        if not compiled:
            monkeypatch.setenv("SARINS_FMU_NO_COMPILED_STEP", "1")
        for scheme in schemes:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                if compiled:  # loads the shipped slave modules, then counts their Python steps
                    simulate_system(system, 2.0, 1.0, scheme=scheme, record=record[:1], progress=False)
                    counts = _count_python_steps(monkeypatch)
                runs[compiled, scheme] = simulate_system(system, system.stop_time, 1.0, scheme=scheme,
                                                         record=record, progress=False)
                if compiled:
                    calls[scheme] = dict(counts)
                    monkeypatch.undo()
    return runs, calls


def _assert_same_runs(runs):
    for (compiled, scheme), fast in runs.items():
        if compiled:
            python = runs[False, scheme]
            assert fast.dtype.names == python.dtype.names
            for name in fast.dtype.names:
                assert np.array_equal(fast[name], python[name]), (scheme, name)


def test_vehicle_system_compiled_equals_python_bit_for_bit(fmu_dir, monkeypatch):
    """IMUThermal on a moving base (base = input) and StrapdownINS, every output, both schemes."""
    from sarins.systems import vehicle_rins

    legs = "drive 60 10; turn 90; drive 60 12; stop 30"
    system = vehicle_rins(fmu_dir, hours=0.25, vehicle=dict(legs=legs, lead_time=300.0),
                          ins=dict(coarse_time=120.0), imu=dict(seed=3))
    runs, _ = _system_runs(system, ["ins.*", "imu.*"], monkeypatch)
    _assert_same_runs(runs)


@pytest.mark.slow
def test_online_vehicle_system_compiled_equals_python_and_stays_compiled(fmu_dir, monkeypatch):
    """vehicle_rins_online (the updater sends its model a, b, c every step, tagged one step ahead, and
    updates it once): every INS and updater output as without the compiled steps, both schemes; the
    INS (native) runs no Python step."""
    from sarins.systems import vehicle_rins_online

    system = vehicle_rins_online(fmu_dir)
    runs, calls = _system_runs(system, ["ins.*", "updater.*"], monkeypatch)
    _assert_same_runs(runs)
    for scheme, counts in calls.items():
        assert runs[True, scheme]["updater.n_updates"][-1] == 1
        assert "StrapdownINS" not in counts, (scheme, counts)  # a native FMU: no Python step at all


def _queue_every_pair(inputs, step):
    """The compensation in force per interval when every new input pair is queued (the rule without
    dropping repeated values), written out as the reference."""
    import collections

    current, pending, seen, out = (0.0,) * len(inputs[0][0]), collections.deque([inputs[0]]), inputs[0], []
    for k, (value, apply_from) in enumerate(inputs):
        if (value, apply_from) != seen:
            while pending and pending[-1][1] >= apply_from - 1e-6 * step:
                pending.pop()
            seen = (value, apply_from)
            pending.append(seen)
        while pending and k * step >= pending[0][1] - 1e-6 * step:
            current = pending.popleft()[0]
        out.append(current)
    return out


def test_compensation_drops_repeated_values_without_changing_what_is_in_force():
    """The FMU's compensation queue (the C core's) does not queue a pair whose value equals the one it
    would follow; the value in force at every interval is that of queueing every pair (random senders:
    repeated values, apply_from moving on, back, or staying)."""
    from sarins_fmu.core.ins import CompensationQueue

    rng = np.random.default_rng(5)
    for _ in range(200):
        n, values = 60, [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.5, 0.0)]
        inputs, apply_from = [], 0.0
        for k in range(n):
            apply_from = max(k + 0.0, apply_from + float(rng.choice([-3.0, 0.0, 1.0, 1.0, 4.0])))
            inputs.append((values[int(rng.integers(3))] if rng.random() < 0.3 or not inputs else inputs[-1][0],
                           apply_from))
        comp = CompensationQueue(*inputs[0])
        got = [comp.value_at(float(k), value, a, 1.0) for k, (value, a) in enumerate(inputs)]
        assert got == _queue_every_pair(inputs, 1.0)
    one = (1.0, 0.0, 0.0)
    comp = CompensationQueue(one, 1.0)  # a sender repeating its value one step ahead: nothing more queued
    for k in range(20):
        assert comp.value_at(float(k), one, k + 1.0, 1.0) == ((0.0, 0.0, 0.0) if k < 1 else one)
        assert comp.queued == (1 if k < 1 else 0)


def test_compensation_queue_refuses_late_pairs_and_overflow_without_changing():
    """A pair whose apply_from lies before the interval about to be integrated, a non-finite pair, and
    more pairs waiting than the queue holds are refused with a reason; the queue is left as it was."""
    from sarins_fmu.core.ins import CompensationQueue

    comp = CompensationQueue((0.0, 0.0, 0.0), 0.0)
    assert comp.value_at(0.0, (1.0, 0.0, 0.0), 5.0, 1.0) == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="arrived when the INS integrates the interval starting at 2 s"):
        comp.value_at(2.0, (2.0, 0.0, 0.0), 1.0, 1.0)
    with pytest.raises(ValueError, match="not finite"):
        comp.value_at(2.0, (2.0, float("nan"), 0.0), 9.0, 1.0)
    assert comp.queued == 1 and comp.value_at(5.0, (1.0, 0.0, 0.0), 5.0, 1.0) == (1.0, 0.0, 0.0)
    k = 6
    while True:  # a sender changing its value every step, 10^4 steps ahead
        try:
            comp.value_at(float(k), (float(k), 0.0, 0.0), k + 1e4, 1.0)
        except ValueError as exc:
            assert "wait to apply" in str(exc)
            break
        k += 1
    assert comp.queued == k - 6 == 256
