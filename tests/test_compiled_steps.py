"""The slaves' compiled steps (fmus.compiled_steps): the same outputs as the Python
do_step bit for bit, called from C (no Python) or through do_step, the same as the
in-process library, and every error still reported by the Python do_step at the call
that caused it."""

import sys

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_driver import IMU_TO_INS, TT_TO_IMU, Slave
from sarins_fmu import imu, turntable
from sarins_fmu._jit import HAVE_NUMBA
from sarins_fmu.experiments import run_static
from sarins_fmu.imu import IMU, StaticBase
from sarins_fmu.thermal import Ambient
from sarins_fmu.units import DPH_TO_RPS

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="the compiled steps need numba")

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


class Chain:
    """Turntable -> IMUThermal -> StrapdownINS through FMPy, Gauss-Seidel, 1 s steps."""

    def __init__(self, fmu_dir):
        self.tt = Slave(fmu_dir / "Turntable.fmu", "turntable")
        self.imu = Slave(fmu_dir / "IMUThermal.fmu", "imu")
        self.ins = Slave(fmu_dir / "StrapdownINS.fmu", "ins")
        self.tt.set(align_time=ALIGN)
        self.ins.set(align_time=ALIGN)
        for s in (self.tt, self.imu, self.ins):
            s.fmu.enterInitializationMode()
        self.link()
        for s in (self.tt, self.imu, self.ins):
            s.fmu.exitInitializationMode()
        self.k = 0

    def link(self):
        self.imu.fmu.setReal([self.imu.vr[n] for n in TT_TO_IMU], self.tt.get(*TT_TO_IMU))
        self.ins.fmu.setReal([self.ins.vr[n] for n in IMU_TO_INS], self.imu.get(*IMU_TO_INS))

    def step(self, n, correction=True):
        rows = []
        for _ in range(n):
            t = float(self.k)
            self.tt.fmu.doStep(t, 1.0)
            self.imu.fmu.setReal([self.imu.vr[n] for n in TT_TO_IMU], self.tt.get(*TT_TO_IMU))
            self.imu.fmu.doStep(t, 1.0)
            self.ins.fmu.setReal([self.ins.vr[n] for n in IMU_TO_INS], self.imu.get(*IMU_TO_INS))
            if correction and t == ALIGN + 600.0:  # a new compensation, well before its apply_from
                self.ins.set(axial_drift_correction=CORRECTION, axial_drift_apply_from=CORRECTION_FROM)
            self.ins.fmu.doStep(t, 1.0)
            rows.append([x for s in (self.ins, self.imu, self.tt) for x in s.get(*_outputs(s))]
                        + [self.ins.fmu.getInteger([self.ins.vr["phase"]])[0]])
            self.k += 1
        return np.array(rows)

    def free(self):
        for s in (self.ins, self.imu, self.tt):
            s.free()


def _count_python_steps(monkeypatch):
    """Count calls of the shipped slaves' Python do_step (by class name)."""
    counts = {}
    for name, module in list(sys.modules.items()):
        if not name.endswith(("_imu_thermal_slave", "_strapdown_ins_slave", "_turntable_slave")):
            continue
        for cls_name in ("IMUThermal", "StrapdownINS", "Turntable"):
            cls = getattr(module, cls_name, None)
            if cls is None:
                continue
            original = cls.do_step

            def counted(self, t, h, original=original, cls_name=cls_name):
                counts[cls_name] = counts.get(cls_name, 0) + 1
                return original(self, t, h)

            monkeypatch.setattr(cls, "do_step", counted)
    return counts


def _run(fmu_dir, n):
    chain = Chain(fmu_dir)
    try:
        return chain.step(n)
    finally:
        chain.free()


def test_fmu_chain_compiled_equals_python_and_in_process_bit_for_bit(fmu_dir, monkeypatch):
    """5400 steps: alignment, navigation past a random-number block (4096 intervals)
    and a compensation change; every output of the three FMUs at every step, with the
    compiled steps called from C, through do_step, and without them; and the
    in-process run."""
    n = 5400
    _run(fmu_dir, 2)  # loads the shipped slave modules
    counts = _count_python_steps(monkeypatch)
    fast = _run(fmu_dir, n)
    python_steps = dict(counts)
    monkeypatch.setenv("SARINS_FMU_NO_FAST_STEP", "1")
    counts.clear()
    via_do_step = _run(fmu_dir, n)
    do_step_calls = dict(counts)
    monkeypatch.setenv("SARINS_FMU_NO_COMPILED_STEP", "1")
    python = _run(fmu_dir, n)
    ref = run_static(align_hours=ALIGN / 3600, nav_hours=(n - ALIGN) / 3600, seed=0,
                     correction_dph=0.01, correction_from_hours=CORRECTION_FROM / 3600)
    nav = int(ALIGN)
    assert np.array_equal(fast, python)
    assert np.array_equal(via_do_step, python)
    assert np.array_equal(fast[nav:, 0], ref.lat_error)
    assert np.array_equal(fast[nav:, 1], ref.position_error)
    assert np.array_equal(fast[nav:, 2], ref.attitude[:, 0])
    # from C, do_step ran only where the compiled step declines: the first steps, the coarse
    # alignment and its end, a new random block, the compensation change
    assert python_steps["Turntable"] <= 2 and python_steps["IMUThermal"] <= 3, python_steps
    assert python_steps["StrapdownINS"] <= 300 + 4, python_steps
    assert do_step_calls["IMUThermal"] == n  # with SARINS_FMU_NO_FAST_STEP every step enters Python


@pytest.mark.parametrize("fault, slave, message", [
    (dict(increment_end_time=10.0), "ins", "would skip an interval"),
    (dict(motion_time=-5.0), "imu", "no turntable motion"),
    (dict(angle_1=float("nan")), "imu", "NaN"),
])
def test_errors_are_reported_at_the_call_while_steps_run_compiled(fmu_dir, fault, slave, message):
    chain = Chain(fmu_dir)
    try:
        chain.step(1300, correction=False)  # navigating: every step compiled
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
        target.set(**fault)
        if slave == "ins":
            chain.imu.fmu.doStep(t, 1.0)
        with pytest.raises(FMICallException, match="status 3"):
            target.fmu.doStep(t, 1.0)
        errors = [text for status, _, text in target.log if status == 3]
        assert any(message in text for text in errors), target.log[-5:]
    finally:
        chain.free()


def test_random_blocks_do_not_change_the_streams():
    """Any block size and any chunking give the same increments (mems: every random term)."""
    sched = turntable.single_axis("forward-reverse", 700.0, grid=1.0, align_time=0.0)
    runs = []
    for rows, chunk in ((4096, 600), (1, 1), (7, 13), (50, 600)):
        s = IMU(imu.preset("mems"), StaticBase(0.6), sched.axes, seed=9, block_rows=rows,
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


def test_vehicle_system_compiled_equals_python_bit_for_bit(fmu_dir, monkeypatch):
    """IMUThermal on a moving base (base = input) and StrapdownINS, every output, both schemes."""
    import warnings

    from orchestration import simulate_system
    from sarins.systems import vehicle_rins

    legs = "drive 60 10; turn 90; drive 60 12; stop 30"
    system = vehicle_rins(fmu_dir, hours=0.3, vehicle=dict(legs=legs, lead_time=300.0),
                          ins=dict(coarse_time=120.0), imu=dict(seed=3))
    record = ["ins.*", "imu.*"]
    runs = {}
    for compiled in (True, False):
        if not compiled:
            monkeypatch.setenv("SARINS_FMU_NO_COMPILED_STEP", "1")
        for scheme in ("gauss-seidel", "jacobi"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                runs[compiled, scheme] = simulate_system(system, 900.0, 1.0, scheme=scheme, record=record,
                                                         progress=False)
    for scheme in ("gauss-seidel", "jacobi"):
        fast, python = runs[True, scheme], runs[False, scheme]
        assert fast.dtype.names == python.dtype.names
        for name in fast.dtype.names:
            assert np.array_equal(fast[name], python[name]), (scheme, name)
