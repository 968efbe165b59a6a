"""The C core's IMU and thermal functions through their binding (sarins_fmu.core.imu / .thermal):
closed forms, thread-count independence, refused arrays, and a sanitizer build (slow)."""

import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu import imu as imu_mod, imu_step, turntable
from sarins_fmu.core import _lib, imu as core_imu, thermal as core_thermal
from sarins_fmu.imu import IMU, StaticBase
from sarins_fmu.rotations import mat_to_rotvec, rotvec_to_mat as _rotvec_to_mat
from sarins_fmu.thermal import Ambient

ROOT = Path(__file__).resolve().parent.parent
H, N_SUB = 1.0, 200


def _errors(k, rng=None, scale=0.0):
    """Sensor-error arguments of core_imu.increments for K intervals: zero, or random of size ``scale``."""
    rng = rng or np.random.default_rng(0)

    def r(*shape):
        return rng.standard_normal(shape) * scale

    mis = r(3, 3) * (1 - np.eye(3))
    return dict(g_sf=r(k, 3), g_mis=mis, g_bias=r(k, 3), g_quad=r(3), g_lowrate=r(3),
                g_lowrate_width=np.full(3, 0.05), g_sens=r(3, 3), a_sf=r(k, 3), a_mis=mis.T.copy(),
                a_bias=r(k, 3), a_quad=r(3))


def _increments(axes, angle0, rate0, accel, w_t, f_t, h=H, n_sub=N_SUB, threads=None, lanes=True, **errors):
    k = np.shape(angle0)[0]
    args = {**_errors(k), **errors}
    return core_imu.increments(axes, angle0, rate0, accel, w_t, f_t, h, n_sub, args["g_sf"], args["g_mis"],
                               args["g_bias"], args["g_quad"], args["g_lowrate"], args["g_lowrate_width"],
                               args["g_sens"], args["a_sf"], args["a_mis"], args["a_bias"], args["a_quad"],
                               threads=threads, lanes=lanes)


def rotvec_to_mat(v):
    return _rotvec_to_mat(np.asarray(v, dtype=float))


def _cross(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def test_static_base_gives_earth_rate_and_the_rotated_specific_force():
    """No gimbal motion, no errors: dtheta = w_t h; dv = int_0^h exp(s [w x]) ds f_t (Rodrigues), to the
    velocity algorithm's second-order residual ~ (|w| h)^2 |f| / 30 (2e-11 m/s here)."""
    w = np.array([1.1e-5, 6.2e-5, 3.9e-5])  # rad/s, an Earth rate resolved in a yawed base
    f = np.array([0.03, -0.02, 9.79])  # m/s^2
    zeros = np.zeros((4, 1))
    dtheta, dv = _increments([[0.0, 0.0, 1.0]], zeros, zeros, zeros, np.tile(w, (4, 1)), np.tile(f, (4, 1)))
    assert_allclose(dtheta, np.tile(w * H, (4, 1)), rtol=1e-14, atol=1e-20)
    wn = np.linalg.norm(w)
    k = _cross(w / wn)
    integral = H * np.eye(3) + (1 - math.cos(wn * H)) / wn * k + (H - math.sin(wn * H) / wn) * (k @ k)
    assert_allclose(dv, np.tile(integral @ f, (4, 1)), rtol=0, atol=(wn * H) ** 2 * np.linalg.norm(f) / 10)


def test_constant_rate_table_turns_the_body_and_holds_the_force_in_the_start_frame():
    """Table at 6 deg/s about z from angle a0, no base rotation: dtheta = (0, 0, rate h) and
    dv = Rz(a0)^T f_t h (the force is constant in t, and b(k-1) is fixed in t), to the trapezoid's
    (rate dt)^2 / 12 of the force across the axis."""
    rate, a0 = math.radians(6.0), np.array([[0.3], [2.0], [-1.0]])
    f = np.array([0.4, -0.3, 9.8])
    dtheta, dv = _increments([[0.0, 0.0, 1.0]], a0, np.full((3, 1), rate), np.zeros((3, 1)), np.zeros((3, 3)),
                             np.tile(f, (3, 1)))
    assert_allclose(dtheta, np.tile([0.0, 0.0, rate * H], (3, 1)), rtol=1e-14, atol=1e-18)
    for k in range(3):
        tol = math.hypot(f[0], f[1]) * H * (rate * H / N_SUB) ** 2 / 12 * 1.5
        assert_allclose(dv[k], rotvec_to_mat(np.array([0.0, 0.0, a0[k, 0]])).T @ f * H, rtol=0, atol=tol)


def test_coning_motion_matches_the_exact_rotation_of_the_cone():
    """Classical coning C(t) = Rz(W t) Rx(beta) Rz(-W t) built from three gimbals: the interval's rotation
    vector is that of C(t0)^T C(t1), to the residual of the trapezoid minor increments (measured 0.16
    (W dt)^2 of the coning drift W beta^2 / 2 h).  Summing the rates would be off by the whole drift
    (1e-3 rad); composing the minor rotations without the two-sample correction by 0.32 (W dt)^2 of it,
    beyond the tolerance of 0.2 (W dt)^2."""
    big_w, beta = 2 * math.pi, math.radians(1.0)
    axes = [[0, 0, 1], [1, 0, 0], [0, 0, 1]]
    t0 = np.array([0.0, 0.37, 5.1])
    angle0 = np.column_stack([big_w * t0, np.full(3, beta), -big_w * t0])
    rate0 = np.tile([big_w, 0.0, -big_w], (3, 1))
    dtheta, _ = _increments(axes, angle0, rate0, np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)))

    def attitude(t):
        return rotvec_to_mat([0, 0, big_w * t]) @ rotvec_to_mat([beta, 0, 0]) @ rotvec_to_mat([0, 0, -big_w * t])

    drift = big_w * beta ** 2 / 2 * H  # what a missing coning correction would leave, rad
    tol = drift * (big_w * H / N_SUB) ** 2 / 5
    for k, t in enumerate(t0):
        exact = mat_to_rotvec(attitude(t).T @ attitude(t + H))
        assert_allclose(dtheta[k], exact, rtol=0, atol=tol)
    assert tol < drift / 1000


def test_truth_is_the_gimbal_chain_rate():
    """sarins_imu_truth: omega_ib_b = mat_bt w_t + omega_tb_b for one gimbal about z."""
    th, rate, acc, tau = 0.4, 0.1, 0.02, 0.3
    w_t, f_t = np.array([[1e-5, 2e-5, 3e-5]]), np.array([[0.1, 0.2, 9.8]])
    out = core_imu.truth([[0, 0, 1.0]], [[th]], [[rate]], [[acc]], 0, tau, w_t, f_t)
    angle = th + (rate + 0.5 * acc * tau) * tau
    mat_bt = rotvec_to_mat([0, 0, angle]).T
    assert_allclose(out[:3], mat_bt @ w_t[0] + [0, 0, rate + acc * tau], rtol=1e-14)
    assert_allclose(out[3:], mat_bt @ f_t[0], rtol=1e-14)


def test_thermal_exact_steps_follow_the_exponential_solution():
    """dT/dt = (A0 + s t + dT - T)/tau: T(t) = A0 + s t + dT - s tau + (T0 - A0 - dT + s tau) exp(-t/tau),
    whatever the steps."""
    a0, slope, heat, tau, temp0 = 20.0, 1e-3, 6.0, 600.0, 15.0
    h = np.random.default_rng(2).uniform(0.0, 120.0, 50)
    t = np.cumsum(h)
    amb = a0 + slope * np.concatenate([[0.0], t])
    out = core_thermal.exact_steps(h, amb, [heat], [tau], [temp0])[:, 0]
    exact = a0 + slope * t + heat - slope * tau + (temp0 - a0 - heat + slope * tau) * np.exp(-t / tau)
    assert_allclose(out, exact, rtol=1e-13)
    assert core_thermal.exact_step(temp0, a0, a0, 0.0, heat, tau) == temp0  # a zero step changes nothing


def test_die_temperature_follows_the_first_order_lag_of_a_ramp():
    """Reported T = T0 + r t, die starting at T0: T_die = T0 + r (t - tau (1 - exp(-t/tau))); tau = 0 passes
    the reported temperature through."""
    r, tau, h = 0.01, 150.0, 2.0
    t = h * np.arange(1, 301)
    reported = np.column_stack([20.0 + r * t, 20.0 + r * t])
    die = np.array([20.0, 20.0])
    out = core_thermal.die_temperatures([20.0, 20.0], reported, h, [tau, 0.0], die)
    assert_allclose(out[:, 0], 20.0 + r * (t - tau * (1 - np.exp(-t / tau))), rtol=1e-13)
    assert np.array_equal(out[:, 1], reported[:, 1])
    assert np.array_equal(die, out[-1])


@pytest.mark.parametrize("threads", [1, 2, 3, 8])
def test_batch_results_do_not_depend_on_the_thread_count(threads):
    rng = np.random.default_rng(5)
    k, axes = 301, [[0, 0, 1], [1, 0, 0]]
    gimbal = [rng.uniform(-1, 1, (k, 2)) for _ in range(3)]
    base = [np.tile([1e-5, 6e-5, 4e-5], (k, 1)), np.tile([0.0, 0.0, 9.8], (k, 1))]
    errors = _errors(k, rng, scale=1e-3)
    reference = _increments(axes, *gimbal, *base, n_sub=20, threads=1, **errors)
    assert all(np.isfinite(x).all() for x in reference)
    out = _increments(axes, *gimbal, *base, n_sub=20, threads=threads, **errors)
    assert np.array_equal(out[0], reference[0]) and np.array_equal(out[1], reference[1])


@pytest.mark.parametrize("n_axes", [1, 2, 3, 6, 9])
@pytest.mark.parametrize("lowrate", [False, True])
def test_simd_lanes_give_the_scalar_loops_bits(n_axes, lowrate):
    """The minor loop evaluated SARINS_IMU_LANES intervals side by side equals, bit for bit (signed zeros
    too), the one-interval-at-a-time loop (its minor steps' independent terms side by side in lanes, in
    blocks of 64 steps), on random inputs: any operation reordered in a lane would show here.  K = 23 leaves
    a remainder; 9 gimbals exceed the lanes' limit (all one at a time); n_sub = 1, 3, 7, 257 leave a part of
    a lane group (257: after four whole blocks), 200 is the FMU's."""
    rng = np.random.default_rng(100 + n_axes + 10 * lowrate)
    k = 23
    axes = rng.standard_normal((n_axes, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    gimbal = [rng.uniform(-4, 4, (k, n_axes)), rng.uniform(-3, 3, (k, n_axes)), rng.uniform(-0.5, 0.5, (k, n_axes))]
    gimbal[1][:4] = 0.0  # a block of still gimbals (exact zeros along the loop)
    gimbal[2][:6] = 0.0
    base = [rng.standard_normal((k, 3)) * 1e-4, rng.standard_normal((k, 3)) * 5.0]
    base[0][:2] = 0.0
    # error terms as large as the increments, so that a rounding changed in any one of them reaches the output
    errors = _errors(k, rng, scale=0.3)
    errors["g_lowrate"] = np.array([0.7, -0.5, 0.9]) if lowrate else np.zeros(3)
    errors["g_lowrate_width"] = np.array([1e-4, 1.5, 3.0])  # rad/s: exp from 0 (underflow) to ~1
    for n_sub, h in ((200, 1.0), (7, 0.3), (257, 0.9), (3, 0.2), (1, 0.5), (2, 1.5)):  # the last: rad-sized steps
        scalar = _increments(axes, *gimbal, *base, h=h, n_sub=n_sub, threads=1, lanes=False, **errors)
        lanes = _increments(axes, *gimbal, *base, h=h, n_sub=n_sub, threads=1, **errors)
        assert all(np.isfinite(x).all() for x in scalar)
        for got, want in zip(lanes, scalar):
            assert np.array_equal(got.view(np.uint64), want.view(np.uint64))


@pytest.mark.parametrize("n_axes", [1, 2, 3])
@pytest.mark.parametrize("quad", [False, True])
def test_one_interval_loop_shortcuts_keep_the_lanes_bits(n_axes, quad):
    """The one-interval loop (the FMU's step) takes a still gimbal's cos and sin once per interval, the parts
    of gimbal 0's rotation that do not depend on its angle once, and leaves out the quadratic terms' division
    by dt when their coefficients are zero; the interval lanes (the in-process run) do none of that.  Bit for
    bit the same, signed zeros too: still gimbals at multiples of pi/2 (the exact reduction of sin and cos)
    and at +-0 with +-0 rates and accelerations, Earth rate and gravity with exact zero components, error
    terms all +-0 (an ideal sensor: zero sums) or random."""
    rng = np.random.default_rng(40 + n_axes + 10 * quad)
    k = 16
    axes = rng.standard_normal((n_axes, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    axes[0] = [0.0, 0.0, 1.0]
    choose = rng.choice
    gimbal = [choose([0.0, -0.0, math.pi / 2, math.pi, -math.pi, 1.5 * math.pi, 1e-30, 0.3], (k, n_axes)),
              choose([0.0, -0.0, 0.1], (k, n_axes)), choose([0.0, -0.0, 0.05], (k, n_axes))]
    gimbal[1][:4] = gimbal[2][:4] = 0.0  # all gimbals still
    gimbal[1][4:6] = gimbal[2][4:6] = -0.0
    w_t = np.tile([0.0, 5.5e-5, 4.2e-5], (k, 1))
    w_t[::3] = -0.0
    f_t = np.tile([-0.0, 0.0, 9.79], (k, 1))
    for scale in (0.0, 0.3):  # standard normals times 0.0: zeros of both signs
        errors = _errors(k, rng, scale=scale)
        errors["g_lowrate"] = np.zeros(3)
        if not quad:
            errors["g_quad"] = np.zeros(3) * -1.0
            errors["a_quad"] = np.zeros(3)
        for n_sub, h in ((200, 1.0), (7, 0.3)):
            scalar = _increments(axes, *gimbal, w_t, f_t, h=h, n_sub=n_sub, threads=1, lanes=False, **errors)
            lanes = _increments(axes, *gimbal, w_t, f_t, h=h, n_sub=n_sub, threads=1, **errors)
            assert all(np.isfinite(x).all() for x in scalar)
            for got, want in zip(lanes, scalar):
                assert np.array_equal(got.view(np.uint64), want.view(np.uint64))


def test_imu_runs_are_the_same_whatever_sarins_threads(monkeypatch):
    sched = turntable.single_axis("forward-reverse", 400.0, grid=1.0, align_time=0.0)
    runs = []
    for threads in ("1", "2", "5"):
        monkeypatch.setenv("SARINS_THREADS", threads)
        sensor = IMU(imu_mod.preset("mems"), StaticBase(0.6), sched.axes, seed=3, ambient=Ambient(amplitude=2.0))
        runs.append(np.hstack(sensor.step(*sched.state(np.arange(300) * 1.0))))
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])
    monkeypatch.setenv("SARINS_THREADS", "zero")
    with pytest.raises(ValueError, match="SARINS_THREADS must be a positive integer"):
        core_imu.thread_count()


def test_bad_arrays_are_refused_with_a_clear_error():
    zeros = np.zeros((2, 1))
    with pytest.raises(ValueError, match=r"angle0 must have shape \(3, 1\)"):
        _increments([[0, 0, 1.0]], np.zeros((3, 2)), np.zeros((3, 1)), np.zeros((3, 1)), np.zeros((3, 3)),
                    np.zeros((3, 3)))
    with pytest.raises(ValueError, match="w_t must have shape"):
        _increments([[0, 0, 1.0]], zeros, zeros, zeros, np.zeros((3, 3)), np.zeros((2, 3)))
    die = np.zeros(6, dtype=np.float32)
    with pytest.raises(ValueError, match="die is written in place"):
        core_thermal.die_temperatures(np.zeros(6), np.zeros((2, 6)), 1.0, np.zeros(6), die)
    strided = np.zeros(12)[::2]
    with pytest.raises(ValueError, match="not C-contiguous"):
        core_thermal.die_temperatures(np.zeros(6), np.zeros((2, 6)), 1.0, np.zeros(6), strided)
    sensor = IMU(imu_mod.preset("nav-rlg"), StaticBase(0.6))
    temps, out3 = np.empty((1, 6)), [np.empty((1, 3)) for _ in range(4)]
    with pytest.raises(ValueError, match="state table must be"):
        core_imu.advance(sensor._table.astype(np.int32), [20.0], temps, *out3)
    with pytest.raises(ValueError, match="does not fit the layout"):
        core_imu.advance(sensor._table[:5], [20.0], temps, *out3)
    consts = sensor.state_arrays()[imu_step.CONSTS]
    consts[11] = 0.0  # the azimuth gyro's hysteresis width: it divides
    with pytest.raises(ValueError, match="does not fit the layout"):
        core_imu.advance(sensor._table, [20.0], temps, *out3)
    consts[11] = imu_mod.preset("nav-rlg").axial_hysteresis_width
    streams = sensor.state_arrays()[imu_step.RNG]
    streams[1, 3] += 1.0  # the GM stream's (row 1) increment, low half: made even, not a stream state
    before = [a.copy() for a in sensor.state_arrays()]
    with pytest.raises(ValueError, match="random stream state in it is not one"):
        core_imu.advance(sensor._table, [20.0], temps, *out3)
    assert all(np.array_equal(a, b) for a, b in zip(before, sensor.state_arrays()))  # nothing changed
    streams[1, 3] -= 1.0
    core_imu.advance(sensor._table, [20.0], temps, *out3)
    streams[0, 6] = 0.5  # the white-noise stream's (drawn last, after the thermal advance) spare flag
    before = [a.copy() for a in sensor.state_arrays()]
    with pytest.raises(ValueError, match="random stream state in it is not one"):
        core_imu.steps(sensor._table, [[0.0]], [[0.0]], [[0.0]], np.zeros((1, 3)), np.zeros((1, 3)), [20.0])
    assert all(np.array_equal(a, b) for a, b in zip(before, sensor.state_arrays()))  # nothing changed


def test_one_call_one_interval_and_the_threaded_path_agree(monkeypatch):
    """sarins_imu_one_interval (the FMU's step) == sarins_imu_steps (IMU.step below PARALLEL_MIN intervals)
    == advance + threaded minor loop + white noise (IMU.step from PARALLEL_MIN on), on the same state."""
    runs = []
    for way in ("steps", "threaded", "one_interval"):
        monkeypatch.setattr(core_imu, "PARALLEL_MIN", 0 if way == "threaded" else 64)
        sensor = IMU(imu_mod.preset("mems"), StaticBase(0.6), [[0, 0, 1.0]], seed=4)
        sensor.step([[0.1]], [[0.2]], [[0.0]])  # the streams move on
        if way == "one_interval":
            out = core_imu.one_interval(sensor._table, [0.3], [0.2], [0.01], 20.0)
        else:
            out = [x[0] for x in sensor.step([[0.3]], [[0.2]], [[0.01]], ambient=[20.0])]
        runs.append(np.concatenate(out))
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])


SANITIZED_RUN = textwrap.dedent("""
    import numpy as np
    from sarins_fmu import imu, turntable
    from sarins_fmu.core import _lib, imu as core_imu
    from sarins_fmu.imu import IMU, StaticBase, HeldBase, VEHICLE_ATTITUDE_AXES
    assert str(_lib.library_path()) == {lib!r}, _lib.library_path()
    sched = turntable.single_axis("forward-reverse", 300.0, grid=1.0, align_time=0.0)
    for preset in ("ideal", "nav-rlg", "mems"):
        s = IMU(imu.preset(preset), StaticBase(0.6), sched.axes, seed=1)
        for k0, k1 in ((0, 150), (150, 151), (151, 250)):
            out = s.step(*sched.state(np.arange(k0, k1) * 1.0))
            assert all(np.isfinite(x).all() for x in out)
        core_imu.one_interval(s._table, [0.1], [0.2], [0.0], 21.0)
    moving = IMU(imu.preset("mems"), HeldBase(), [*VEHICLE_ATTITUDE_AXES, (0, 0, 1)], seed=2)
    moving.base.hold([0, 7e-5, 4e-5], [0, 0, 9.8])
    moving.step(np.zeros((1, 4)), np.full((1, 4), 0.01), np.zeros((1, 4)))
    print("sanitized run ok")
""")


@pytest.mark.slow
def test_core_under_address_and_undefined_behaviour_sanitizers(tmp_path):
    """Rebuild the core with ASan + UBSan and run IMU batches and the one-interval step through the binding."""
    core = ROOT / "sarins_fmu" / "core"
    lib = tmp_path / "_sarins_core_asan.so"
    flags = ["-std=c11", "-O1", "-g", "-fPIC", "-shared", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-ffp-contract=off",
             "-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]
    subprocess.run(["gcc", *flags, "-I", str(core), *sorted(map(str, core.glob("*.c"))), "-o", str(lib), "-lm"],
                   check=True, capture_output=True, text=True)
    libasan = subprocess.run(["gcc", "-print-file-name=libasan.so"], check=True, capture_output=True,
                             text=True).stdout.strip()
    assert os.path.isabs(libasan), f"gcc does not know libasan.so: {libasan}"
    env = {**os.environ, "SARINS_CORE_LIB": str(lib), "LD_PRELOAD": libasan, "PYTHONPATH": str(ROOT),
           "ASAN_OPTIONS": "detect_leaks=0:abort_on_error=1", "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1",
           "SARINS_THREADS": "2"}
    run = subprocess.run([sys.executable, "-c", SANITIZED_RUN.format(lib=str(lib))], env=env, capture_output=True,
                         text=True, timeout=900)
    report = run.stderr[-4000:]
    assert run.returncode == 0 and "sanitized run ok" in run.stdout, report
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr, report


def test_library_override_names_a_missing_file(monkeypatch):
    monkeypatch.setenv("SARINS_CORE_LIB", "/nonexistent/_sarins_core.so")
    with pytest.raises(_lib.CoreNotBuilt, match="SARINS_CORE_LIB names /nonexistent"):
        _lib.library_path()


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_a_forked_child_runs_threaded_batches():
    """A campaign worker forked after the parent used the thread pool still runs (and matches) a batch."""
    import multiprocessing

    rng = np.random.default_rng(1)
    gimbal = [rng.uniform(-1, 1, (200, 1)) for _ in range(3)]
    base = [np.zeros((200, 3)), np.tile([0.0, 0.0, 9.8], (200, 1))]
    parent = _increments([[0, 0, 1.0]], *gimbal, *base, n_sub=10, threads=2)
    with multiprocessing.get_context("fork").Pool(1) as pool:
        child = pool.apply_async(_increments, ([[0, 0, 1.0]], *gimbal, *base), dict(n_sub=10, threads=2)).get(60)
    assert np.array_equal(parent[0], child[0]) and np.array_equal(parent[1], child[1])
