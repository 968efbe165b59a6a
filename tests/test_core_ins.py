"""The C core's INS family and turntable through the Python binding: closed forms, bad arrays, FMU steps.

The physics is ``sarins_fmu/core/{earth,rotations,filter,ins,turntable}.c``; the system-level
tests (tests/test_ins.py, test_kalman.py, test_turntable*.py) run it inside the library.
"""

import math

import numpy as np
import pytest

from sarins_fmu import earth, ins_kernel
from sarins_fmu import rotations as rot
from sarins_fmu.core import ins as core_ins
from sarins_fmu.kalman import N_STATES, StopFilterSettings, stop_filter_steps
from sarins_fmu.turntable.schedule import GimbalSchedule, state_into
from sarins_fmu.units import DPH_TO_RPS

LAT = math.radians(32.0)
DAY = 86400


def test_earth_constants_are_the_wgs84_defining_values():
    assert (earth.A, earth.F, earth.RATE, earth.GM) == (6378137.0, 1.0 / 298.257223563, 7.2921151467e-5, 3.986004418e14)
    assert earth.E2 == earth.F * (2.0 - earth.F) and earth.B == earth.A * (1.0 - earth.F)
    assert (earth.GAMMA_E, earth.GAMMA_P) == (9.7803253359, 9.8321849378)


def test_gravity_at_equator_and_pole_is_somiglianas_and_falls_with_height():
    assert earth.gravity(0.0, 0.0) == earth.GAMMA_E
    assert earth.gravity(math.pi / 2, 0.0) == pytest.approx(earth.GAMMA_P, rel=1e-14)
    assert earth.gravity(-math.pi / 2, 0.0) == pytest.approx(earth.GAMMA_P, rel=1e-14)
    # free-air gradient at the equator: -2 g / a (1 + f + m), about -3.086e-6 s^-2
    gradient = (earth.gravity(0.0, 1.0) - earth.gravity(0.0, -1.0)) / 2.0
    assert gradient == pytest.approx(-2 * earth.GAMMA_E / earth.A * (1 + earth.F + earth._M), rel=1e-6)
    lat = np.linspace(-1.5, 1.5, 7)
    assert np.array_equal(earth.gravity(lat, 100.0), [earth.gravity(x, 100.0) for x in lat])


def test_radii_closed_forms_and_vectorised():
    assert earth.radii(0.0) == (earth.A * (1.0 - earth.E2), earth.A)
    r_m, r_n = earth.radii(math.pi / 2)
    assert r_m == pytest.approx(r_n, rel=1e-15) and r_n == pytest.approx(earth.A / math.sqrt(1 - earth.E2), rel=1e-15)
    lat = np.linspace(-1.5, 1.5, 12).reshape(3, 4)
    r_m, r_n = earth.radii(lat)
    assert r_m.shape == (3, 4)
    assert np.array_equal(np.stack([r_m, r_n]).reshape(2, -1).T, [earth.radii(x) for x in lat.ravel()])


def test_rotation_bindings_are_vectorised_and_consistent():
    rng = np.random.default_rng(0)
    phi = rng.standard_normal((5, 3))
    mats = rot.rotvec_to_mat(phi)
    assert mats.shape == (5, 3, 3)
    assert np.allclose(mats, rot.quat_to_mat(rot.rotvec_to_quat(phi)), atol=1e-15)
    for k in range(5):
        assert np.array_equal(mats[k], rot.rotvec_to_mat(phi[k]))
    ypr = rng.standard_normal((4, 3))
    assert np.array_equal(rot.euler_to_mat(ypr[:, 0], ypr[:, 1], ypr[:, 2])[2], rot.euler_to_mat(*ypr[2]))


def _static_increments(k, lat, h, eps_z=0.0):
    """Increments of a level, north-pointing (mat_nb = I) IMU at rest: dtheta = w_ie^n h (+ eps_z h about up),
    dv = f h + (dtheta x f h) / 2 with f = (0, 0, g) (the velocity increment in the body axes of the step's start)."""
    w = np.array([0.0, earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)])
    f = np.array([0.0, 0.0, earth.gravity(lat, 0.0)])
    dv = f * h + 0.5 * np.cross(w * h, f * h)
    dtheta = w * h + np.array([0.0, 0.0, eps_z * h])
    return np.tile(dtheta, (k, 1)), np.tile(dv, (k, 1))


def _navigate(k, h, eps_z=0.0, q0=(1.0, 0.0, 0.0, 0.0)):
    q, v, pos = np.array(q0, float), np.zeros(3), np.array([LAT, 0.0, 0.0])
    dtheta, dv = _static_increments(k, LAT, h, eps_z)
    return ins_kernel.nav_steps(q, v, pos, dtheta, dv, h, np.zeros(3), np.zeros(3), np.zeros(k))


def test_static_ins_stays_at_rest_with_exact_increments():
    out = _navigate(DAY, 1.0)
    assert np.max(np.abs(out[:, 0] - LAT)) * earth.A < 0.02  # m in 24 h (second-order terms of the 1 s step)
    assert np.max(np.abs(out[:, 3:5])) < 1e-5  # m/s


@pytest.mark.parametrize("drift_dph", [0.003, -0.001])
def test_azimuth_drift_gives_the_latitude_error_closed_form(drift_dph):
    """dL(t) = cos L / w_ie (1 - cos w_ie t) eps over 24 h (seed 000 Table 1, our sign)."""
    eps = drift_dph * DPH_TO_RPS
    out = _navigate(DAY, 1.0, eps_z=eps)
    t = np.arange(1, DAY + 1, dtype=float)
    expected = math.cos(LAT) / earth.RATE * (1 - np.cos(earth.RATE * t)) * eps
    peak = 2 * math.cos(LAT) * eps / earth.RATE
    assert np.max(np.abs(out[:, 0] - LAT - expected)) < 0.01 * abs(peak)


def test_tilt_error_oscillates_with_the_schuler_period():
    """An initial east tilt of 10 arcsec: v_N swings with period 2 pi sqrt(R / g) (84.4 min)."""
    tilt = 10.0 / 3600 * math.pi / 180
    out = _navigate(5 * 3600, 1.0, q0=rot.rotvec_to_quat([tilt, 0.0, 0.0]))
    v_n = out[:, 4]
    t = np.arange(1, len(v_n) + 1, dtype=float)
    idx = np.nonzero((v_n[:-1] > 0) & (v_n[1:] <= 0))[0]
    crossings = t[idx] + v_n[idx] / (v_n[idx] - v_n[idx + 1])
    assert len(crossings) >= 3
    assert np.mean(np.diff(crossings)) == pytest.approx(earth.schuler_period(LAT), rel=0.005)
    assert np.max(np.abs(v_n)) == pytest.approx(tilt * math.sqrt(earth.gravity(LAT, 0.0) * earth.A), rel=0.05)


def test_nav_steps_in_one_batch_equal_one_by_one():
    h, k = 1.0, 50
    rng = np.random.default_rng(1)
    dtheta, dv = _static_increments(k, LAT, h)
    dtheta = dtheta + 1e-6 * rng.standard_normal((k, 3))
    states = [(np.array([1.0, 0, 0, 0]), np.zeros(3), np.array([LAT, 0.1, 5.0])) for _ in range(2)]
    batch = ins_kernel.nav_steps(*states[0], dtheta, dv, h, np.zeros(3), np.zeros(3), np.zeros(k))
    rows = [ins_kernel.nav_steps(*states[1], dtheta[i:i + 1], dv[i:i + 1], h, np.zeros(3), np.zeros(3), np.zeros(1))
            for i in range(k)]
    assert np.array_equal(batch, np.concatenate(rows))
    assert all(np.array_equal(a, b) for a, b in zip(*states))


def _static_body_increments(k, lat, mat_nb, h=1.0, gyro_bias=(0.0, 0.0, 0.0), accel_bias=(0.0, 0.0, 0.0)):
    """Increments of an IMU at rest with attitude mat_nb (and constant body-frame sensor biases, rad/s and
    m/s^2): dtheta = w_b h, dv = f_b h + (w_b h x f_b h) / 2 with w_b, f_b the Earth rate and specific force
    resolved in the body."""
    w = mat_nb.T @ np.array([0.0, earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)])
    f = mat_nb.T @ np.array([0.0, 0.0, earth.gravity(lat, 0.0)])
    dtheta = (w + np.asarray(gyro_bias)) * h
    dv = (f + np.asarray(accel_bias)) * h + 0.5 * np.cross(w * h, f * h)
    return np.tile(dtheta, (k, 1)), np.tile(dv, (k, 1))


def _coarse_attitude(lat, mat_nb, **biases):
    """(yaw, pitch, roll) right after a 300 s coarse alignment of the core's INS on these increments."""
    from sarins_fmu.ins import InsConfig, StrapdownINS

    ins = StrapdownINS(InsConfig(lat=lat, align_time=600.0, coarse_time=300.0))
    dtheta, dv = _static_body_increments(300, lat, mat_nb, **biases)
    out = ins.step(dtheta, dv)
    assert ins.phase == "fine" and np.array_equal(out[-1, 6:9], ins.attitude_euler())
    return np.array(ins.attitude_euler())


@pytest.mark.parametrize("lat, yaw, pitch, roll", [(LAT, 0.7, 0.01, -0.02), (-0.9, -2.5, -0.03, 0.002),
                                                   (0.1, 3.0, 0.0, 0.05)])
def test_coarse_alignment_finds_the_attitude_of_an_ideal_static_imu(lat, yaw, pitch, roll):
    """Levelling and gyrocompassing in the inertial frame: an error-free static IMU gives its attitude back."""
    got = _coarse_attitude(lat, rot.euler_to_mat(yaw, pitch, roll))
    err = (got - [yaw, pitch, roll] + math.pi) % (2 * math.pi) - math.pi
    assert np.max(np.abs(err[1:])) < 1e-9  # rad, levelling
    assert abs(err[0]) < 1e-7  # rad, gyrocompassing (Earth rate 7.3e-5 rad/s)


def test_coarse_alignment_errors_follow_the_static_closed_forms():
    """Level, north-pointing IMU: an x (east) accelerometer bias tilts the found vertical by nabla / g
    (roll error -nabla / g), and an x gyro drift eps turns the found north by eps / (W cos L) (yaw error
    +eps / (W cos L)), Titterton & Weston sec. 10.3."""
    lat = LAT
    g = earth.gravity(lat, 0.0)
    nabla, eps = 1e-4 * g, 0.01 * DPH_TO_RPS
    roll = _coarse_attitude(lat, np.eye(3), accel_bias=(nabla, 0.0, 0.0))[2]
    assert roll == pytest.approx(-nabla / g, rel=1e-3)
    yaw = _coarse_attitude(lat, np.eye(3), gyro_bias=(eps, 0.0, 0.0))[0]
    assert yaw == pytest.approx(eps / (earth.RATE * math.cos(lat)), rel=0.02)


def test_fmu_state_struct_copy_restores_the_run_bit_for_bit():
    """The StrapdownINS FMU's state is its struct: a copy of its bytes taken in the fine alignment,
    restored after 400 more steps (the end of the alignment, a queued temperature-model correction),
    gives the same outputs again, bit for bit."""
    rng = np.random.default_rng(2)
    mat = rot.euler_to_mat(0.4, 0.001, -0.002)
    dtheta, dv = _static_body_increments(1000, LAT, mat)
    dtheta = dtheta + 1e-7 * rng.standard_normal(dtheta.shape)
    from sarins_fmu.ins import InsConfig

    config = core_ins.config_array(InsConfig(lat=LAT, align_time=600.0, coarse_time=120.0))
    f = core_ins.FmuState()
    f.setup(config, [0.0, 0.0, 0.0], 0.0)
    inputs = np.zeros(len(core_ins.FMU_INPUTS))
    inputs[7] = 20.0
    f.start(inputs)

    def run(k0, k1):
        rows = []
        for k in range(k0, k1):
            inputs[:3], inputs[3:6], inputs[6], inputs[7] = dtheta[k], dv[k], k + 1.0, 20.0 + 1e-3 * k
            if k == 650:  # a temperature model, queued to apply from nav time 100 s
                inputs[8:12] = 1e-8, 2e-10, 3e-12, 100.0
            f.do_step(inputs, float(k), 1.0)
            rows.append(np.append(f.out, f.phase))
        return np.array(rows)

    run(0, 500)
    saved, saved_inputs = f.buffer.copy(), inputs.copy()
    first = run(500, 900)
    assert first[-1, -1] == 2 and first[0, -1] == 1
    f.buffer[:] = saved
    inputs[:] = saved_inputs
    assert np.array_equal(run(500, 900), first)


@pytest.mark.parametrize("fault", ["step", "changed_step", "tag", "nan", "late", "overflow", "config"])
def test_fmu_step_refusals_give_a_reason_and_change_nothing(fault):
    from sarins_fmu.ins import InsConfig

    config = core_ins.config_array(InsConfig(lat=LAT, align_time=0.0, coarse_time=0.0))
    f = core_ins.FmuState()
    f.setup(config, [0.1, 0.0, 0.0], 0.0)
    inputs = np.zeros(len(core_ins.FMU_INPUTS))
    f.start(inputs)
    dtheta, dv = _static_body_increments(3, LAT, rot.euler_to_mat(0.1, 0.0, 0.0))
    for k in range(3):
        inputs[:3], inputs[3:6], inputs[6] = dtheta[k], dv[k], k + 1.0
        f.do_step(inputs, float(k), 1.0)
    inputs[:3], inputs[3:6], inputs[6] = dtheta[0], dv[0], 4.0
    t, h, reason = 3.0, 1.0, ""
    if fault == "step":
        h, reason = -1.0, "must be positive and finite"
    elif fault == "changed_step":
        h, reason = 2.0, "this FMU needs a fixed step"
    elif fault == "tag":
        inputs[6], reason = 3.0, "were already integrated"
    elif fault == "nan":
        inputs[1], reason = np.nan, "NaN or infinity"
    elif fault == "late":
        inputs[8], inputs[11], reason = 1e-7, 1.0, "arrived when the INS integrates the interval starting at 3 s"
    elif fault == "overflow":
        inputs[8], inputs[10], inputs[11], inputs[7] = 1e-7, 1e300, 3.0, 1e10
        reason = "axial correction contains NaN or infinity"
    else:
        bad = config.copy()
        bad[3], bad[4] = 60.0, 1e-3  # align_time, coarse_time (s)
        f = core_ins.FmuState()
        f.setup(bad, [0.0, 0.0, 0.0], 0.0)
        reason = "coarse_time must span at least two steps"
        with pytest.raises(ValueError, match=reason):
            f.start(inputs)
        return
    before = f.buffer.copy()
    with pytest.raises(ValueError, match=reason):
        f.do_step(inputs, t, h)
    assert np.array_equal(f.buffer, before)


def test_turntable_constant_acceleration_segment():
    a, w0, th0 = 0.3, -0.2, 0.5
    s = GimbalSchedule(axes=[(0, 0, 1.0)], times=[0.0, 10.0, 20.0], accel=[[a], [0.0]], angle0=[th0], rate0=[w0])
    tau = np.linspace(0.0, 9.99, 37)
    angle, rate, acc = s.state(tau)
    assert np.allclose(angle[:, 0], th0 + w0 * tau + 0.5 * a * tau**2, rtol=1e-15, atol=1e-15)
    assert np.array_equal(rate[:, 0], w0 + a * tau)
    assert np.all(acc[:, 0] == a)
    # after the last breakpoint the rate holds; before the first, the initial rate
    angle, rate, acc = s.state([25.0, -2.0])
    assert rate[0, 0] == w0 + a * 10.0 and acc[0, 0] == 0.0
    assert angle[0, 0] == pytest.approx(th0 + w0 * 10 + 0.5 * a * 100 + (w0 + a * 10) * 15, rel=1e-14)
    assert angle[1, 0] == th0 + w0 * -2.0 and rate[1, 0] == w0


def test_stop_filter_rejects_arrays_it_cannot_update_in_place():
    s = StopFilterSettings()
    p = s.initial_covariance()
    vel, att = np.zeros((3, 2)), np.zeros((3, 3))
    with pytest.raises(ValueError, match="written in place"):
        stop_filter_steps(np.zeros(N_STATES, dtype=np.float32), p, vel, att, LAT, 1.0, s.process_noise(), 1e-6)
    with pytest.raises(ValueError, match="written in place"):
        stop_filter_steps(np.zeros(N_STATES), np.asfortranarray(p + np.tri(N_STATES) * 1e-30), vel, att, LAT, 1.0,
                          s.process_noise(), 1e-6)
    with pytest.raises(ValueError, match="must have shape"):
        stop_filter_steps(np.zeros(N_STATES), p, vel, att[:2], LAT, 1.0, s.process_noise(), 1e-6)
    x = np.zeros(N_STATES)
    out = stop_filter_steps(x, p, vel.tolist(), att, LAT, 1.0, s.process_noise(), 1e-6)  # inputs may be lists
    assert out.shape == (3, 2) and np.isfinite(out).all()


def test_ins_and_turntable_bindings_reject_bad_in_place_arrays():
    dtheta, dv = _static_increments(2, LAT, 1.0)
    args = (dtheta, dv, 1.0, np.zeros(3), np.zeros(3), np.zeros(2))
    with pytest.raises(ValueError, match="q is written in place"):
        ins_kernel.nav_steps([1.0, 0, 0, 0], np.zeros(3), np.zeros(3), *args)
    with pytest.raises(ValueError, match="pos is written in place"):
        ins_kernel.nav_steps(np.array([1.0, 0, 0, 0]), np.zeros(3), np.zeros(6)[::2], *args)
    with pytest.raises(ValueError, match="v must have shape"):
        ins_kernel.nav_steps(np.array([1.0, 0, 0, 0]), np.zeros(4), np.zeros(3), *args)
    with pytest.raises(ValueError, match="dv must have shape"):
        ins_kernel.nav_steps(np.array([1.0, 0, 0, 0]), np.zeros(3), np.zeros(3), dtheta, dv[:1], *args[2:])
    with pytest.raises(ValueError, match="p is written in place"):
        ins_kernel.align_steps(np.array([1.0, 0, 0, 0]), np.zeros(3), np.zeros(3), dtheta, dv, 1.0, np.zeros(3),
                               np.zeros(3), np.zeros(9), np.eye(9).astype(int), np.ones(9), 1e-6)
    s = GimbalSchedule(axes=[(0, 0, 1.0)], times=[0.0, 10.0], accel=[[0.1]], angle0=[0.0], rate0=[0.0])
    t = np.array([1.0, 2.0])
    with pytest.raises(ValueError, match="angle is written in place"):
        state_into(t, *s.tables(), np.zeros((2, 1), dtype=np.float32), np.zeros((2, 1)), np.zeros((2, 1)))


# ------------------------------------------------------------------ sanitizers

SANITIZED_RUN = """
import math
import numpy as np
from fmus.strapdown_ins_slave import StrapdownINS
from sarins_fmu import earth, ins_kernel, rotations as rot
from sarins_fmu.core import _lib
from sarins_fmu.kalman import StopKalmanFilter
from sarins_fmu.turntable import single_axis

print("core", _lib.library_path())
lat = 0.55
rng = np.random.default_rng(0)
earth.radii(np.linspace(-1.5, 1.5, 101)); earth.gravity(np.linspace(-1.5, 1.5, 101), 10.0)
phi = rng.standard_normal((20, 3)); rot.rotvec_to_mat(phi); rot.rotvec_to_quat(phi * 1e-10)
rot.quat_to_mat(rot.quat_mult(rng.standard_normal((20, 4)), rng.standard_normal((20, 4)))); rot.euler_to_mat(*phi.T)
w = np.array([0.0, earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)])
f = np.array([0.0, 0.0, earth.gravity(lat, 0.0)])
k = 400
dth = np.tile(w, (k, 1)) + 1e-7 * rng.standard_normal((k, 3))
dv = np.tile(f + 0.5 * np.cross(w, f), (k, 1)) + 1e-5 * rng.standard_normal((k, 3))
q, v, pos = np.array([1.0, 0, 0, 0]), np.zeros(3), np.array([lat, 0.0, 0.0])
ins_kernel.coarse_steps(q.copy(), np.zeros(3), dth, dv)
x, p = np.zeros(9), np.eye(9) * 1e-4
ins_kernel.align_steps(q, v, pos, dth, dv, 1.0, np.zeros(3), np.zeros(3), x, p, np.full(9, 1e-12), 1e-6)
ins_kernel.nav_steps(q, v, pos, dth, dv, 1.0, np.zeros(3), np.zeros(3), np.zeros(k))
ins_kernel.held_row(q, pos)
stop = StopKalmanFilter(lat)
stop.step(1e-3 * rng.standard_normal((k, 2)), 1e-4 * rng.standard_normal((k, 3)))
sched = single_axis("forward-reverse", 3600.0)
sched.state(np.linspace(-10.0, 4000.0, 3001))

# the INS FMU's step, through the slave run in process (the core's whole FMU step)
ins = StrapdownINS(instance_name="ins", resources="/tmp")
ins.align_time, ins.coarse_time = 300.0, 60.0
ins.enter_initialization_mode(); ins.exit_initialization_mode()
for n in range(400):
    for i, a in enumerate("xyz"):
        setattr(ins, f"dtheta_{a}", float(dth[n, i])); setattr(ins, f"dv_{a}", float(dv[n, i]))
    ins.increment_end_time = n + 1.0
    ins.temp_gyro_z = 25.0
    assert ins.do_step(float(n), 1.0)
assert ins.solution_time == 400.0 and ins.phase == 2, ins.phase
# refused steps (a skipped interval, another step size): refused, nothing touched
ins.increment_end_time = 402.0
before = ins._fmi_buffer.copy(), ins._core.buffer.copy()
assert not ins.do_step(400.0, 1.0) and not ins.do_step(400.0, 2.0)
assert np.array_equal(ins._fmi_buffer, before[0]) and np.array_equal(ins._core.buffer, before[1])
# the library's INS across its three phases (coarse alignment's end included)
from sarins_fmu.ins import InsConfig, StrapdownINS as LibraryINS
lib_ins = LibraryINS(InsConfig(lat=lat, align_time=300.0, coarse_time=60.0))
assert np.isfinite(lib_ins.step(dth, dv)).all() and lib_ins.phase == "navigate"
print("sanitized run ok")
"""


def _build_sanitized_core(out_dir):
    """The core's sources built with AddressSanitizer and UndefinedBehaviorSanitizer (every report fatal)."""
    import subprocess
    from pathlib import Path

    from sarins_fmu.core import _lib

    lib = Path(out_dir) / "libsarins_core_asan.so"
    sources = sorted(str(p) for p in _lib.HERE.glob("*.c"))
    subprocess.run(["gcc", "-std=c11", "-O1", "-g", "-fPIC", "-shared", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-ffp-contract=off",
                    "-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer",
                    f"-I{_lib.HERE}", *sources, "-o", str(lib), "-lm"], check=True, capture_output=True, text=True)
    return lib


@pytest.mark.slow
def test_ins_filter_and_turntable_under_address_and_undefined_behaviour_sanitizers(tmp_path):
    """The INS, filter and turntable functions and the INS FMU step (valid and refused steps) run on a core
    built with -fsanitize=address,undefined, loaded through SARINS_CORE_LIB in a fresh interpreter with
    libasan preloaded; any sanitizer report fails the run."""
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    if shutil.which("gcc") is None:
        pytest.skip("needs gcc")
    libasan = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True, text=True).stdout.strip()
    if not Path(libasan).is_file():
        pytest.skip("gcc has no libasan")
    lib = _build_sanitized_core(tmp_path)
    script = tmp_path / "run.py"
    script.write_text(SANITIZED_RUN)
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, SARINS_CORE_LIB=str(lib), LD_PRELOAD=libasan, ASAN_OPTIONS="detect_leaks=0",
               UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1", PYTHONPATH=str(root))
    run = subprocess.run([sys.executable, str(script)], cwd=root, env=env, capture_output=True, text=True, timeout=1200)
    report = run.stdout + run.stderr
    assert run.returncode == 0, report[-4000:]
    assert f"core {lib}" in run.stdout  # the sanitized build, not the regular one
    assert "sanitized run ok" in run.stdout
    for marker in ("ERROR: AddressSanitizer", "runtime error:", "UndefinedBehaviorSanitizer"):
        assert marker not in report, report[-4000:]
