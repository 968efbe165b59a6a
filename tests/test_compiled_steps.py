"""The physics FMUs' steps (native C FMUs: fmus/c): the chain's outputs the same as the
in-process library bit for bit, the same under both master schemes, and every error
reported at the call that caused it."""


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
    """Every Real output of an FMU (the INS's INS_FIRST first)."""
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


def _run(fmu_dir, n, ins_params=None, ins_inputs=constant_correction):
    chain = Chain(fmu_dir, ins_params)
    try:
        return chain.step(n, ins_inputs)
    finally:
        chain.free()


def test_fmu_chain_equals_the_in_process_run_bit_for_bit(fmu_dir):
    """5400 steps: alignment, navigation and a compensation change; the INS outputs at every navigation
    step are those of the in-process run."""
    n = 5400
    rows = _run(fmu_dir, n)
    ref = run_static(align_hours=ALIGN / 3600, nav_hours=(n - ALIGN) / 3600, seed=0,
                     correction_dph=0.01, correction_from_hours=CORRECTION_FROM / 3600)
    nav = int(ALIGN)
    assert np.array_equal(rows[nav:, 0], ref.lat_error)
    assert np.array_equal(rows[nav:, 1], ref.position_error)
    assert np.array_equal(rows[nav:, 2], ref.attitude[:, 0])


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


def test_temperature_model_correction_equals_the_library(fmu_dir):
    """The correction c + (a T + b) T in the native INS step: the navigation rows those of the library's
    INS with the model evaluated at each interval's temperature, solution_time = t + h."""
    n = 4300
    rows = _run(fmu_dir, n, ins_inputs=model_correction)
    chain = Chain(fmu_dir)
    chain.free()
    nav = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
    expected = _in_process_ins(chain, rows, fmu_dir)  # one batch: its alignment rows hold the batch's end
    got = np.column_stack([chain.column(rows, f"ins.{v}") for v in nav])
    assert np.array_equal(got[int(ALIGN):], expected[int(ALIGN):])
    assert np.array_equal(chain.column(rows, "ins.solution_time"), np.arange(1.0, n + 1.0))
    # the model (and its change) turned the heading: the same run without any correction differs
    assert not np.array_equal(chain.column(rows, "ins.yaw")[-100:],
                              chain.column(_run(fmu_dir, n, ins_inputs=None), "ins.yaw")[-100:])


def test_immediate_navigation_navigates_from_the_first_step(fmu_dir):
    """align_time = 0: navigation from yaw0, pitch0, roll0 at once, every output finite."""
    start = dict(align_time=0.0, yaw0=0.2, pitch0=0.001, roll0=-0.002)
    rows = _run(fmu_dir, 1500, ins_params=start)
    assert np.isfinite(rows).all()
    assert (rows[:, -1] == 2).all()  # navigating from the first step


@pytest.mark.parametrize("fault, slave, message", [
    (dict(increment_end_time=10.0), "ins", "would skip an interval"),
    (dict(temp_gyro_z=float("nan")), "ins", "temp_gyro_z"),
    (dict(axial_drift_correction_a=float("inf")), "ins", "not finite"),
    (dict(motion_time=-5.0), "imu", "no turntable motion"),
    (dict(angle_1=float("nan")), "imu", "NaN"),
])
def test_errors_are_reported_at_the_call_that_caused_them(fmu_dir, fault, slave, message):
    chain = Chain(fmu_dir)
    try:
        chain.step(1300, None)  # navigating
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


def _system_runs(system, record, schemes=("gauss-seidel", "jacobi")):
    """{scheme: result} of the master's runs of ``system``."""
    import warnings

    from orchestration import simulate_system

    runs = {}
    for scheme in schemes:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            runs[scheme] = simulate_system(system, system.stop_time, 1.0, scheme=scheme, record=record,
                                           progress=False)
    return runs


TAGS = {"ins": "ins.solution_time", "imu": "imu.increment_end_time"}


def _assert_same_runs(runs):
    """The two schemes' records agree bit for bit row by row once each FMU's rows are matched by its
    time tag (Jacobi records the same solutions a step later)."""
    first, other = runs.values()
    assert first.dtype.names == other.dtype.names
    for fmu, tag in TAGS.items():
        names = [n for n in first.dtype.names if n.startswith(fmu + ".")]
        if not names:
            continue
        ta, tb = first[tag], other[tag]
        common, ia, ib = np.intersect1d(ta[ta > 0], tb[tb > 0], return_indices=True)
        assert len(common) > 0.9 * len(ta), (fmu, len(common), len(ta))
        ia, ib = np.flatnonzero(ta > 0)[ia], np.flatnonzero(tb > 0)[ib]
        for name in names:
            assert np.array_equal(first[name][ia], other[name][ib]), name


def _recorded_outputs(fmu_dir, label, fmu):
    """The record names of every Real output of ``fmu`` (its inputs lag a step under Jacobi)."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu_dir / fmu))
    return [f"{label}.{v.name}" for v in md.modelVariables if v.causality == "output" and v.type == "Real"]


def test_vehicle_system_is_the_same_under_both_schemes(fmu_dir):
    """IMUThermal on a moving base (base = input) and StrapdownINS: every output of both bit for bit the
    same under Gauss-Seidel and Jacobi, matched by their time tags."""
    from sarins.systems import vehicle_rins

    legs = "drive 60 10; turn 90; drive 60 12; stop 30"
    system = vehicle_rins(fmu_dir, hours=0.25, vehicle=dict(legs=legs, lead_time=300.0),
                          ins=dict(coarse_time=120.0), imu=dict(seed=3))
    record = _recorded_outputs(fmu_dir, "ins", "StrapdownINS.fmu") + _recorded_outputs(fmu_dir, "imu",
                                                                                        "IMUThermal.fmu")
    _assert_same_runs(_system_runs(system, record))


@pytest.mark.slow
def test_online_vehicle_system_is_the_same_under_both_schemes(fmu_dir):
    """vehicle_rins_online (the updater sends its model a, b, c every step, tagged one step ahead, and
    updates it once): every INS output the same under both schemes, matched by solution_time; one
    update."""
    from sarins.systems import vehicle_rins_online

    record = _recorded_outputs(fmu_dir, "ins", "StrapdownINS.fmu") + ["updater.n_updates"]
    runs = _system_runs(vehicle_rins_online(fmu_dir), record)
    _assert_same_runs(runs)
    for scheme, run in runs.items():
        assert run["updater.n_updates"][-1] == 1, scheme


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
