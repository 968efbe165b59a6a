"""Multi-gimbal turntable profiles: dual-axis RINS (seed 002), seed 003's
three-axis rate table, chamber profile, 24-position tumble and rate test.

The kinematics is checked independently of the package: mat_tb(t) is built
here from the schedule's angles with a plain Rodrigues formula, the body rate
omega_tb^b is obtained by finite-differencing it, and both are compared with
the chain-rate formula and with the IMU kernel's truth."""

import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from sarins_fmu.core import imu as core_imu
from sarins_fmu import turntable as tt

E = np.eye(3)
AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


# ---------------------------------------------------------------- helpers

def rot(axis, angle):
    """Rodrigues: exp(angle [axis x])."""
    a = np.asarray(axis, float)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return E + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def mat_tb(sched, t):
    angles, _, _ = sched.state(t)
    m = E.copy()
    for a, th in zip(sched.axes, angles[0]):
        m = m @ rot(a, th)
    return m


def log_so3(m):
    """Rotation vector of a rotation matrix (angle < pi)."""
    c = np.clip((np.trace(m) - 1) / 2, -1, 1)
    angle = math.acos(c)
    v = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]]) / 2
    return v if angle < 1e-12 else v * angle / math.sin(angle)


def rate_fd(sched, t, h=1e-4):
    """omega_tb^b by central differences: mat_tb(t-h)^T mat_tb(t+h) = exp(2h [w x])."""
    return log_so3(mat_tb(sched, t - h).T @ mat_tb(sched, t + h)) / (2 * h)


def rate_chain(sched, t):
    """omega_tb^b = sum_j (R_{j+1} ... R_{A-1})^T thetadot_j a_j, accumulated outside in."""
    angles, rates, _ = sched.state(t)
    w = np.zeros(3)
    for a, th, thd in zip(sched.axes, angles[0], rates[0]):
        w = rot(a, th).T @ w + thd * a
    return w


def check_kinematics(sched, times):
    """Finite-difference body rate == chain formula == IMU kernel truth; f_b = mat_bt f_t."""
    f_t = np.array([0.0, 0.0, 9.8])
    for t in times:
        w_chain = rate_chain(sched, t)
        assert_allclose(rate_fd(sched, t), w_chain, atol=1e-7, err_msg=f"t={t}")
        angle, rate, acc = sched.state(t)
        truth = core_imu.truth(sched.axes, angle, rate, acc, 0, 0.0, np.zeros((1, 3)), f_t[None, :])
        assert_allclose(truth[:3], w_chain, atol=1e-13)
        assert_allclose(truth[3:], mat_tb(sched, t).T @ f_t, atol=1e-12)


def sample_times(sched, n, seed=0):
    """Random times inside the schedule, off the grid."""
    rng = np.random.default_rng(seed)
    return np.sort(rng.uniform(sched.times[0] + 0.5, sched.end_time - 0.5, n)) + 0.123


def test_imports_from_this_worktree():
    root = Path(__file__).resolve().parents[1]
    assert Path(tt.__file__).resolve().is_relative_to(root), tt.__file__


def test_chain_matrix_matches_the_yaw_pitch_roll_order():
    from sarins_fmu.rotations import euler_to_mat
    angles = [0.3, -0.7, 1.1]
    assert_allclose(tt.chain_matrix(tt.RATE_TABLE_AXES, angles), euler_to_mat(*angles), atol=1e-14)
    assert_allclose(tt.chain_matrix(tt.DUAL_AXIS_AXES, [0.4, 0.9]), rot([0, 1, 0], 0.4) @ rot([0, 0, 1], 0.9),
                    atol=1e-15)


# ---------------------------------------------------------------- dual axis

def test_dual_axis_sequence_and_modulation():
    sched = tt.dual_axis(600.0, dwell=10.0)
    assert_allclose(sched.axes, [[0, 1, 0], [0, 0, 1]])
    sched.check_grid(1.0)
    t = np.arange(0.0, sched.end_time + 1.0, 1.0)
    angle, rate, _ = sched.state(t)
    # the two gimbals never move together; every move is rest to rest
    assert not np.any((rate[:, 0] != 0) & (rate[:, 1] != 0))
    assert np.max(np.abs(rate[:, 1])) == pytest.approx(math.radians(6), rel=1e-12)
    # positions at rest, in order: (outer, inner) deg
    still = np.all(rate == 0, axis=1)
    pos = np.round(np.degrees(angle[still]), 9)
    pos = pos[np.r_[True, np.any(np.diff(pos, axis=0) != 0, axis=1)]]
    expected = [(0, 0), (0, 360), (0, 0), (180, 0), (180, 360), (180, 0), (0, 0)]
    assert len(pos) >= len(expected)
    assert_allclose(pos[:len(expected)], expected, atol=1e-9)
    assert sched.end_time >= 600.0
    assert_allclose(sched.state(sched.end_time)[0], 0.0, atol=1e-12)
    # modulation: over whole periods the azimuth gyro axis spends as long up
    # as down (mean vertical component 0) and the horizontal axes average out
    tf = np.arange(0.0, sched.end_time, 0.05) + 0.025
    ang = sched.state(tf)[0]
    z_up = np.cos(ang[:, 0])  # (mat_tb e_z) . e_z = cos(eta_out)
    assert abs(z_up.mean()) < 1e-6
    x_b = np.stack([np.cos(ang[:, 0]) * np.cos(ang[:, 1]), np.sin(ang[:, 1]),
                    -np.sin(ang[:, 0]) * np.cos(ang[:, 1])], axis=1)  # mat_tb e_x
    assert_allclose(x_b.mean(axis=0)[:2], 0.0, atol=1e-6)


def test_dual_axis_kinematics_during_simultaneous_rotation_parts():
    sched = tt.dual_axis(400.0, inner_rate_dps=20, inner_accel_dps2=4, outer_rate_dps=15, outer_accel_dps2=3)
    check_kinematics(sched, sample_times(sched, 40))


def test_dual_axis_alignment_matches_single_axis_indexing():
    dual = tt.dual_axis(7200.0, align_time=3600.0, align_dwell=300.0)
    single = tt.single_axis("forward-reverse", 7200.0, align_time=3600.0, align_dwell=300.0)
    t = np.arange(0.0, 3600.0, 0.5)
    a_d, r_d, _ = dual.state(t)
    a_s, r_s, _ = single.state(t)
    assert np.all(a_d[:, 0] == 0) and np.all(r_d[:, 0] == 0)
    assert_allclose(a_d[:, 1], a_s[:, 0], atol=1e-12)
    assert_allclose(r_d[:, 1], r_s[:, 0], atol=1e-15)
    _, r, _ = dual.state([3599.0, 3600.0, 3600.5])
    assert np.all(r[:2] == 0) and r[2, 1] > 0


@pytest.mark.parametrize("kwargs", [
    dict(duration=float("nan")), dict(duration=-1.0), dict(duration=0.0), dict(grid=0.0),
    dict(inner_rate_dps=-6), dict(outer_rate_dps=0), dict(inner_accel_dps2=float("nan")),
    dict(dwell=-1.0), dict(align_time=float("inf")), dict(align_dwell=-5),
])
def test_dual_axis_rejects_bad_input(kwargs):
    args = dict(duration=600.0) | kwargs
    with pytest.raises(ValueError, match="must be"):
        tt.dual_axis(args.pop("duration"), **args)


# ---------------------------------------------------------------- seed 003 rate table

def test_rate_table_triangle_waves_at_the_papers_values():
    sched = tt.rate_table_3axis(2000.0)
    assert_allclose(sched.axes, [[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    sched.check_grid(1.0)
    assert sched.end_time == 600.0 + 4 * 400.0  # whole 400 s periods after 10 min warm-up
    t = np.arange(0.0, sched.end_time + 50, 0.5)
    angle, rate, acc = sched.state(t)
    warm = t < 600
    assert np.all(angle[warm] == 0) and np.all(rate[warm] == 0)
    max_dps = np.array([100.0, 10.0, 1.0])  # outer, middle, inner
    assert_allclose(np.degrees(np.abs(rate).max(axis=0)), max_dps, rtol=1e-12)
    assert_allclose(np.degrees(np.abs(acc[~warm & (t < sched.end_time)]).max(axis=0)), max_dps / 100, rtol=1e-12)
    assert_allclose(np.degrees(np.abs(acc[~warm & (t < sched.end_time)]).min(axis=0)), max_dps / 100, rtol=1e-12)
    # the triangle: rate(600 + tau) = max * tri(tau / 400 s), angle back to 0 each period
    tau = (t[~warm] - 600.0) % 400.0
    tri = np.where(tau < 100, tau / 100, np.where(tau < 300, 2 - tau / 100, tau / 100 - 4))
    inside = t[~warm] < sched.end_time
    assert_allclose(np.degrees(rate[~warm][inside]), tri[inside, None] * max_dps, atol=1e-10)
    k = np.searchsorted(t, 600.0 + 400.0 * np.arange(5))
    assert_allclose(angle[k], 0.0, atol=1e-9)
    assert np.all(rate[t >= sched.end_time] == 0)


def test_rate_table_kinematics_and_grid():
    sched = tt.rate_table_3axis(1500.0, warmup=100.0, inner_rate_dps=30, inner_accel_dps2=3,
                                middle_rate_dps=45, middle_accel_dps2=2)
    check_kinematics(sched, sample_times(sched, 60, seed=1))
    fine = tt.rate_table_3axis(900.0, warmup=7.0, grid=0.3, outer_accel_dps2=0.7)
    fine.check_grid(0.3)
    # the quarter period 100/0.7 s is rounded up to the grid: rate kept, acceleration lowered
    rate, acc = fine.state(np.arange(0, fine.end_time, 0.3))[1:]
    assert np.degrees(np.abs(rate[:, 0]).max()) == pytest.approx(100.0, rel=1e-9)
    assert np.degrees(np.abs(acc[:, 0]).max()) <= 0.7


@pytest.mark.parametrize("kwargs", [
    dict(duration=float("nan")), dict(duration=0.0), dict(grid=0.0), dict(grid=-1.0),
    dict(outer_rate_dps=-100), dict(middle_accel_dps2=0.0), dict(inner_rate_dps=float("nan")), dict(warmup=-1),
])
def test_rate_table_rejects_bad_input(kwargs):
    args = dict(duration=3600.0) | kwargs
    with pytest.raises(ValueError, match="must be"):
        tt.rate_table_3axis(args.pop("duration"), **args)


# ---------------------------------------------------------------- 24-position tumble

@pytest.mark.parametrize("grid", [1.0, 0.01])
def test_tumble_24_positions_are_static_and_level(grid):
    sched, pos = tt.tumble_24(grid=grid)
    sched.check_grid(grid)
    assert len(pos) == 24 and pos.dtype == tt.TUMBLE_DTYPE
    assert_allclose(pos["end"] - pos["start"], 180.0)
    assert np.all(pos["start"][1:] > pos["end"][:-1])  # a move between consecutive positions
    # each body axis up and down, at each of the 4 headings
    combos = {(str(u), round(math.degrees(h)) % 360) for u, h in zip(pos["up"], pos["heading"])}
    assert combos == {(s + a, h) for s in "+-" for a in "xyz" for h in (0, 90, 180, 270)}
    z = E[2]
    for row in pos:
        t = np.linspace(row["start"], row["end"], 7)
        angle, rate, acc = sched.state(t)
        assert np.all(np.abs(rate) < 1e-15) and np.all(acc[:-1] == 0)  # acc at `end` is the next move's
        assert_allclose(angle, np.broadcast_to(row["angles"], angle.shape), atol=1e-12)
        for tk in t:
            m = mat_tb(sched, tk)
            e_up = E[AXIS_INDEX[row["up"][1]]]
            assert_allclose(m @ e_up, z if row["up"][0] == "+" else -z, atol=1e-12)
            assert_allclose(m.T @ z, row["up_b"], atol=1e-12)
    # the 4 positions of an orientation differ only by the heading, a turn about the vertical
    for up in np.unique(pos["up"]):
        rows = pos[pos["up"] == up]
        levelled = [rot(z, -r["heading"]) @ mat_tb(sched, r["start"]) for r in rows]
        assert_allclose(levelled, np.broadcast_to(levelled[0], (4, 3, 3)), atol=1e-12)


def test_tumble_moves_only_the_gimbals_that_must_change():
    sched, pos = tt.tumble_24(dwell=30.0, rate_dps=20.0, accel_dps2=5.0)
    for a, b in zip(pos[:-1], pos[1:]):
        t = np.arange(a["end"], b["start"], 0.25)
        rate = sched.state(t)[1]
        moving = np.any(np.abs(rate) > 0, axis=0)
        changed = np.abs(b["angles"] - a["angles"]) > 1e-12
        assert_array_equal(moving, changed)
        assert changed.sum() == 1
        assert np.abs(rate).max() <= math.radians(20.0) * (1 + 1e-12)
    check_kinematics(sched, sample_times(sched, 40, seed=2))


@pytest.mark.parametrize("kwargs", [dict(dwell=0.0), dict(dwell=float("nan")), dict(rate_dps=-10),
                                    dict(accel_dps2=0), dict(grid=0.0)])
def test_tumble_rejects_bad_input(kwargs):
    with pytest.raises(ValueError, match="must be"):
        tt.tumble_24(**kwargs)


# ---------------------------------------------------------------- rate test

def test_rate_test_windows_are_whole_revolutions_at_constant_rate():
    sched, win = tt.rate_test()
    sched.check_grid(1.0)
    assert len(win) == 66 and win.dtype == tt.RATE_WINDOW_DTYPE
    nominal = np.degrees(win["rate_nominal"][:22])
    assert_allclose(sorted(nominal), sorted(np.r_[tt.RATE_TEST_MAGNITUDES_DPS, -np.array(tt.RATE_TEST_MAGNITUDES_DPS)]))
    assert np.abs(nominal).max() == 200.0 and len(set(nominal)) == 22
    assert_allclose(win["rate"], win["rate_nominal"], rtol=1e-12)  # exact on a 1 s grid
    assert list(dict.fromkeys(win["axis"])) == ["+x", "+y", "+z"]
    z = E[2]
    for w in win:
        a0, r0, _ = sched.state(w["start"])
        a1, r1, _ = sched.state(w["end"])
        # whole revolutions of the outer gimbal, middle and inner still
        assert_allclose(a1[0, 0] - a0[0, 0], 2 * math.pi * w["revolutions"] * np.sign(w["rate"]), atol=1e-9)
        assert_allclose(a1[0, 1:], a0[0, 1:], atol=0)
        t = np.linspace(w["start"], w["end"], 9)
        _, rate, acc = sched.state(t[:-1])
        assert np.all(acc == 0)
        assert_allclose(rate[:, 0], w["rate"], rtol=1e-12)
        assert np.all(rate[:, 1:] == 0)
        # the named body axis is vertical, and the body rate is rate * up_b
        m = mat_tb(sched, 0.5 * (w["start"] + w["end"]))
        assert_allclose(m @ E[AXIS_INDEX[w["axis"][1]]], z, atol=1e-12)
        assert_allclose(rate_chain(sched, w["start"] + 0.3), w["rate_b"], atol=1e-13)
        # acceleration and deceleration lie outside the window
        assert sched.state(w["start"] - 0.5)[2][0, 0] != 0 and sched.state(w["end"])[2][0, 0] != 0


def test_rate_test_options_and_kinematics():
    sched, win = tt.rate_test(rates_dps=[7.3, -250.0, 0.7], axis_up=["-y", "X", "-z"], min_duration=60.0,
                              accel_dps2=25.0, grid=0.01, settle=2.0, rate_tol=1e-4)
    sched.check_grid(0.01)
    assert list(win["axis"]) == ["-y"] * 3 + ["+x"] * 3 + ["-z"] * 3
    assert np.all(win["end"] - win["start"] >= 60.0 - 1e-9)
    assert_allclose(win["rate"], win["rate_nominal"], rtol=1e-4)
    assert_allclose(np.abs(win["rate"]) * (win["end"] - win["start"]), 2 * math.pi * win["revolutions"], rtol=1e-12)
    for w in win:
        a0, a1 = sched.state(w["start"])[0][0, 0], sched.state(w["end"])[0][0, 0]
        assert abs(abs(a1 - a0) - 2 * math.pi * w["revolutions"]) < 1e-9
        assert sched.state(w["start"] - 1.0)[2][0, 0] == 0  # settling at constant rate
        assert_allclose(mat_tb(sched, w["start"]).T @ E[2], w["up_b"], atol=1e-12)
    assert_allclose(win["up_b"][win["axis"] == "-y"], [[0, -1, 0]] * 3)
    check_kinematics(sched, sample_times(sched, 40, seed=3))


@pytest.mark.parametrize("kwargs, match", [
    (dict(rates_dps=[10.0, 0.0]), "non-zero"), (dict(rates_dps=[float("nan")]), "non-zero"),
    (dict(rates_dps=[]), "empty"), (dict(axis_up=("w",)), "unknown body axis"), (dict(axis_up=()), "at least one"),
    (dict(min_duration=-1.0), "must be"), (dict(accel_dps2=-1.0), "must be"), (dict(grid=0.0), "must be"),
    (dict(settle=float("nan")), "must be"), (dict(rate_tol=0.5), "at most"),
    (dict(rates_dps=[100 * math.sqrt(2)], grid=0.7, rate_tol=1e-15), "whole revolutions"),
])
def test_rate_test_rejects_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        tt.rate_test(**kwargs)


# ---------------------------------------------------------------- through the IMU

def test_ideal_imu_on_the_rate_test_and_tumble_sees_rate_and_gravity_on_the_named_axis(lat):
    from sarins_fmu.earth import RATE as EARTH_RATE
    from sarins_fmu.imu import IMU, ImuModel, StaticBase
    base = StaticBase(lat)
    f_t, w_t = base.specific_force_t(), base.inertial_rate_t()
    sched, win = tt.rate_test(rates_dps=[50.0, -20.0], axis_up=["-x", "y"], accel_dps2=20.0)
    imu = IMU(ImuModel(), base, sched.axes, output_interval=1.0, internal_rate=50.0)
    t = np.arange(0.0, sched.end_time)
    dtheta, dv, _ = imu.step(*sched.state(t))
    for w in win:
        k = slice(int(w["start"]), int(w["end"]))
        T = w["end"] - w["start"]
        # whole revolutions about the vertical: the horizontal Earth rate and
        # the horizontal components average out; the up axis sees rate + Earth's vertical rate
        assert_allclose(dtheta[k].sum(axis=0), (w["rate"] + EARTH_RATE * math.sin(lat)) * T * w["up_b"], atol=1e-8)
        assert_allclose(dv[k].sum(axis=0), f_t[2] * T * w["up_b"], atol=1e-8)
    sched, pos = tt.tumble_24(dwell=20.0, rate_dps=30.0, accel_dps2=30.0)
    imu = IMU(ImuModel(), base, sched.axes, output_interval=1.0, internal_rate=50.0)
    t = np.arange(0.0, sched.end_time)
    dtheta, dv, _ = imu.step(*sched.state(t))
    for p in pos:
        k = slice(int(p["start"]), int(p["end"]))
        mat_bt = tt.chain_matrix(sched.axes, p["angles"]).T
        w_b, f_b = mat_bt @ w_t, mat_bt @ f_t
        # dv in b at the interval start: f T + (w x f) T^2 / 2 (rotation compensation, T = 1 s)
        assert_allclose(dv[k], np.broadcast_to(f_b + 0.5 * np.cross(w_b, f_b), dv[k].shape), atol=1e-8)
        assert_allclose(dv[k] @ p["up_b"], f_t[2], rtol=1e-8)  # gravity on the named axis
        assert_allclose(dtheta[k], np.broadcast_to(w_b, dtheta[k].shape), atol=1e-16)
