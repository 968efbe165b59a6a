"""The C schedule and ambient builders (core/schedule.h, core/ambient.h) through their binding, against
closed forms, and their refusals."""

import ctypes
import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu.core import schedule as cs
from sarins_fmu.turntable import GimbalSchedule

DEG = math.pi / 180.0
CORE = Path(cs.__file__).resolve().parent

# the Turntable FMU's parameters (SI) with odd grids, dwells and revolutions
CASES = [
    ("none", dict(duration=1000.0, grid=0.3)),
    ("continuous", dict(duration=700.0, rate=7.3 * DEG, accel=0.9 * DEG, grid=0.3, align_time=0.0)),
    ("forward-reverse", dict(duration=3000.0, rate=6 * DEG, accel=6 * DEG, dwell=7.7, revolutions=3, grid=0.3,
                             align_time=0.0)),
    ("forward-reverse", dict(duration=5000.0, rate=10 * DEG, accel=2.5 * DEG, dwell=0.0, revolutions=2, grid=0.01,
                             align_time=1999.5, align_dwell=17.3)),
    ("four-position", dict(duration=4000.0, rate=10 * DEG, accel=5 * DEG, dwell=60.4, grid=2.5, align_time=0.0)),
    ("dual-axis", dict(duration=4000.0, rate=6 * DEG, accel=6 * DEG, outer_rate=3.3 * DEG, outer_accel=0.7 * DEG,
                       dwell=0.4, grid=0.3, align_time=1000.0, align_dwell=30.0)),
    ("rate-table-3axis", dict(duration=3000.0, grid=0.3, warmup=7.0, table_inner_rate=30 * DEG,
                              table_inner_accel=3 * DEG, table_middle_accel=0.33 * DEG, table_outer_accel=0.7 * DEG)),
    ("tumble-24", dict(dwell=7.7, rate=20 * DEG, accel=5 * DEG, grid=0.3)),
    ("rate-test", dict(rate=10 * DEG, accel=25 * DEG, dwell=2.0, grid=0.01, test_rates=[7.3 * DEG, -250 * DEG],
                       test_axes="-y, X", test_min_duration=60.0, test_rate_tol=1e-4)),
]


def peak_rates(scheme, p):
    """Largest |rate| each gimbal may reach, rad/s."""
    if scheme == "dual-axis":
        return [p["outer_rate"], p["rate"]]
    if scheme == "rate-table-3axis":
        d = dict(table_inner_rate=1 * DEG, table_middle_rate=10 * DEG, table_outer_rate=100 * DEG) | p
        return [d["table_outer_rate"], d["table_middle_rate"], d["table_inner_rate"]]
    if scheme == "rate-test":
        return [max(abs(r) for r in p["test_rates"]) * (1 + p["test_rate_tol"]), p["rate"], p["rate"]]
    return [p.get("rate", 6 * DEG)] * (3 if scheme == "tumble-24" else 1)


@pytest.mark.parametrize("scheme, p", CASES, ids=[f"{s}-{i}" for i, (s, _) in enumerate(CASES)])
def test_schedule_is_exact_on_the_grid_and_within_the_peaks(scheme, p):
    b = cs.build_schedule(scheme, **p)
    grid = p["grid"]
    steps = b.times / grid
    # accelerations change only on the grid, starting at rest at 0 at t = 0
    assert_allclose(steps, np.round(steps), atol=1e-9 * steps.max())
    assert b.times[0] == 0.0 and np.all(np.diff(b.times) > 0)
    assert np.all(b.angle0 == 0) and np.all(b.rate0 == 0)
    angle_bp, rate_bp = cs.integrate(b.times, b.accel, b.angle0, b.rate0)
    assert np.all(np.abs(rate_bp) <= np.array(peak_rates(scheme, p)) * (1 + 1e-12))
    # the integration is the closed form: rate and angle continuous, quadratic in between
    dt = np.diff(b.times)[:, None]
    assert_allclose(rate_bp[1:], rate_bp[:-1] + b.accel * dt, atol=1e-12)
    assert_allclose(angle_bp[1:], angle_bp[:-1] + rate_bp[:-1] * dt + 0.5 * b.accel * dt**2, atol=1e-9)
    assert b.gimbal_axes == cs.gimbal_axes(scheme) and b.axes.shape == (len(b.gimbal_axes.split(",")), 3)
    GimbalSchedule(b.axes, b.times, b.accel, b.angle0, b.rate0).check_grid(grid)
    if scheme not in ("continuous", "rate-test"):
        assert b.times[-1] >= p.get("duration", 0.0) - 1e-9


@pytest.mark.parametrize("scheme, p, turn", [
    ("forward-reverse", CASES[2][1], 3 * 2 * math.pi), ("forward-reverse", CASES[3][1], 2 * 2 * math.pi),
    ("four-position", CASES[4][1], 0.5 * math.pi)])
def test_every_move_ends_at_rest_on_the_commanded_angle(scheme, p, turn):
    b = cs.build_schedule(scheme, **p)
    angle_bp, rate_bp = cs.integrate(b.times, b.accel, b.angle0, b.rate0)
    # at rest to rounding (single-axis schedules add the segments' durations in s, 0.3 s is no binary fraction)
    at_rest = np.abs(rate_bp[:, 0]) < 1e-12
    assert at_rest.sum() > 10 and at_rest[-1]
    aligning = b.times < p["align_time"]
    # the alignment indexes by quarter turns; then every move is one turn of the scheme (or a quarter turn)
    k = angle_bp[at_rest & aligning, 0] / (0.5 * math.pi)
    assert_allclose(k, np.round(k), atol=1e-11)
    moves = np.diff(angle_bp[at_rest & ~aligning, 0]) / turn
    assert set(np.round(moves, 11)) <= ({-1.0, 0.0, 1.0} if scheme == "forward-reverse" else {-3.0, -1.0, 0.0, 2.0})
    assert len(set(np.round(moves, 11)) - {0.0}) >= 2


def test_dual_axis_flips_the_outer_gimbal_by_half_turns():
    b = cs.build_schedule("dual-axis", **CASES[5][1])
    angle_bp, rate_bp = cs.integrate(b.times, b.accel, b.angle0, b.rate0)
    still = np.all(np.abs(rate_bp) < 1e-15, axis=1)
    k = angle_bp[still, 0] / math.pi  # outer at 0 or +180 deg
    assert_allclose(k, np.round(k), atol=1e-12)
    assert set(np.round(k)) == {0.0, 1.0}
    assert np.all(rate_bp[:, 0][b.times <= 1000.0] == 0)  # the alignment moves the inner gimbal only


def test_rate_table_rates_are_triangle_waves_of_the_given_amplitudes():
    p = dict(duration=2000.0, grid=1.0, warmup=600.0)
    b = cs.build_schedule("rate-table-3axis", **p)
    _, rate_bp = cs.integrate(b.times, b.accel, b.angle0, b.rate0)
    assert_allclose(np.abs(rate_bp).max(axis=0), np.array([100.0, 10.0, 1.0]) * DEG, rtol=1e-12)
    assert b.times[1] == 600.0 and np.all(b.accel[0] == 0)  # warm-up at rest
    # acceleration +a, -a, +a with |a| = amplitude / quarter period (100 s here)
    moving = b.accel[1:]
    assert_allclose(np.unique(np.round(np.abs(moving) / DEG, 12), axis=0), [[1.0, 0.1, 0.01]])


def test_tumble_and_rate_test_windows():
    b = cs.build_schedule("tumble-24", dwell=10.0, rate=10 * DEG, accel=10 * DEG, grid=1.0)
    sched = GimbalSchedule(b.axes, b.times, b.accel, b.angle0, b.rate0)
    assert len(b.windows) == 24 and set(b.windows["up"]) == set(range(6))
    for w in b.windows:
        angle, rate, acc = sched.state(np.linspace(w["start"], w["end"], 5))
        assert np.all(rate == 0) and np.all(acc[:-1] == 0)
        assert_allclose(angle, np.broadcast_to(w["angles"], angle.shape), atol=1e-12)
        assert w["end"] - w["start"] == 10.0
    r = cs.build_schedule("rate-test", **CASES[8][1])
    sched = GimbalSchedule(r.axes, r.times, r.accel, r.angle0, r.rate0)
    assert [cs.UP_NAMES[u] for u in r.windows["up"]] == ["-y", "-y", "+x", "+x"]
    for w in r.windows:
        a0, a1 = sched.state([w["start"], w["end"]])[0][:, 0]
        assert_allclose(a1 - a0, math.copysign(2 * math.pi * w["revolutions"], w["rate"]), atol=1e-9)
        assert w["end"] - w["start"] >= 60.0 - 1e-9
        assert abs(w["rate"] / w["rate_nominal"] - 1) <= 1e-4


def test_default_rate_test_uses_the_default_magnitudes_on_x_y_z():
    b = cs.build_schedule("rate-test")
    mags = np.array(cs.rate_test_magnitudes_dps())
    assert len(b.windows) == 3 * 2 * len(mags)
    assert_allclose(b.windows["rate_nominal"][:22] / DEG, np.ravel(np.c_[mags, -mags]), rtol=1e-15)
    assert [cs.UP_NAMES[u] for u in b.windows["up"][::22]] == ["+x", "+y", "+z"]


def test_move_segments_cover_the_angle_at_the_peak_or_below():
    for angle in (math.pi, -0.5 * math.pi, 7.3, 1e-3):
        segs = cs.move_segments(angle, 6 * DEG, 2 * DEG, 0.3)
        dur = np.array([d for d, _ in segs])
        acc = np.array([a for _, a in segs])
        rate = np.concatenate([[0.0], np.cumsum(acc * dur)])
        area = np.sum(rate[:-1] * dur + 0.5 * acc * dur**2)
        assert_allclose(area, angle, rtol=1e-12)
        assert abs(rate[-1]) < 1e-15 and np.max(np.abs(rate)) <= 6 * DEG * (1 + 1e-12)
        assert_allclose(dur / 0.3, np.round(dur / 0.3), atol=1e-9)
    assert cs.move_segments(0.0, 1.0, 1.0, 1.0) == []


# ---------------------------------------------------------------- chamber and ambient

def test_chamber_profile_reaches_the_set_points_and_holds():
    ramp, hold = 0.75 / 60, 1200.0
    times, temps = cs.chamber_profile(40000.0, -15.0, 35.0, ramp, hold, 20.0, 300.0, "high", 12.5, 600.0)
    assert times[0] == 0.0 and times[-1] == 40000.0 and np.all(np.diff(times) > 0)
    assert temps[1] == 20.0 and times[1] == 300.0  # the delay at the start temperature
    assert times[2] == 300.0 + 15.0 / ramp and temps[2] == 35.0  # first ramp to the hot end, no stops
    slope = np.diff(temps) / np.diff(times)
    assert_allclose(np.abs(slope[2:-1])[slope[2:-1] != 0], ramp, rtol=1e-12)
    held = np.diff(times)[2:-1][slope[2:-1] == 0]
    set_points = temps[:-1][2:-1][slope[2:-1] == 0]
    assert_allclose(held[np.isin(set_points, [-15.0, 35.0])], hold)
    assert_allclose(held[~np.isin(set_points, [-15.0, 35.0])], 600.0)
    assert set(set_points) == {35.0, 22.5, 10.0, -2.5, -15.0}
    cycle = cs.chamber_cycle_time(-15.0, 35.0, ramp, hold, 12.5, 600.0)
    assert cycle == pytest.approx(2 * (50.0 / ramp + hold + 3 * 600.0), rel=1e-15)


def test_chamber_cut_is_interpolated_on_the_ramp():
    times, temps = cs.chamber_profile(2700.0 + 900.0 + 1800.0 + 600.0, -25.0, 40.0, 1 / 60, 1800.0, 20.0, 0.0, "low",
                                      0.0, 0.0)
    assert_allclose(times, [0.0, 2700.0, 4500.0, 6000.0])
    assert temps[-1] == pytest.approx(-25.0 + 1500.0 / 60)  # 25 min into the ramp up from -25 at 1 degC/min


def test_ambient_values_and_segment_are_the_closed_forms():
    t = np.linspace(-50.0, 2e5, 1001)
    value = cs.ambient_values(t, 21.0, 3.0, 86400.0, 0.3, 1e-5, None)
    assert_allclose(value, 21.0 + 3.0 * np.sin(2 * np.pi * t / 86400.0 + 0.3) + 1e-5 * t, rtol=1e-14)
    assert cs.ambient_values(123.0, 21.0, 0.0, 86400.0, 0.0, 0.0, None) == 21.0
    profile = ([0.0, 100.0, 300.0], [10.0, 20.0, 20.0])
    assert_allclose(cs.ambient_values([-5.0, 0.0, 50.0, 100.0, 200.0, 400.0], 0, 0, 1, 0, 0, profile),
                    [10.0, 10.0, 15.0, 20.0, 20.0, 20.0])
    a0, slope = cs.ambient_segment(40.0, 20.0, 0, 0, 1, 0, 0, profile)
    assert (a0, slope) == (14.0, 0.1)  # on the ramp: the ramp's slope
    a0, slope = cs.ambient_segment(90.0, 20.0, 0, 0, 1, 0, 0, profile)
    assert a0 == 19.0 and slope == pytest.approx(1.0 / 20.0)  # half the step on the ramp, half held


# ---------------------------------------------------------------- refusals

@pytest.mark.parametrize("scheme, p, message", [
    ("sideways", {}, "unknown scheme 'sideways'; choose one of none, continuous, forward-reverse"),
    ("forward-reverse", dict(grid=float("nan")), "grid must be finite, got nan s"),
    ("forward-reverse", dict(grid=-1e-5), "grid must be positive, got -1e-05 s"),
    ("none", dict(duration=float("inf")), "duration must be finite, got inf s"),
    ("four-position", dict(dwell=-1.0), "dwell must be non-negative, got -1.0 s"),
    ("continuous", dict(rate=-DEG), "rate must be non-negative, got -0.017453292519943295 rad/s (-1.0 deg/s)"),
    ("continuous", dict(rate=0.0, align_time=0.0), "rate and accel must be positive for a rotating scheme"),
    ("forward-reverse", dict(revolutions=1.5), "revolutions must be a positive whole number, got 1.5"),
    ("forward-reverse", dict(revolutions=0), "revolutions must be a positive whole number, got 0.0"),
    ("dual-axis", dict(outer_accel=0.0), "outer_accel must be positive, got 0.0 rad/s^2 (0.0 deg/s^2)"),
    ("rate-table-3axis", dict(table_middle_rate=-1.0), "table_middle_rate must be non-negative"),
    ("tumble-24", dict(dwell=0.0), "dwell must be positive, got 0.0 s"),
    ("rate-test", dict(test_rates=[]), "test_rates must not be empty"),
    ("rate-test", dict(test_rates=[0.1, 0.0]), "test_rates must be finite and non-zero, got 0.0 rad/s"),
    ("rate-test", dict(test_axes="x,w"), "unknown body axis 'w' in axis_up"),
    ("rate-test", dict(test_axes=" "), "unknown body axis '' in axis_up"),
    ("rate-test", dict(test_axes=""), "test_axes must name at least one body axis"),
    ("rate-test", dict(test_rate_tol=0.5), "test_rate_tol must be at most 0.1, got 0.5"),
    # the grid does not divide a whole number of revolutions within the tolerance
    ("rate-test", dict(test_rates=[100 * math.sqrt(2) * DEG], grid=0.7, test_rate_tol=1e-15),
     "cannot fit whole revolutions at 141.421356 deg/s on a 0.7 s grid within a relative rate change of 1e-15"),
    ("none", dict(duration=1e12, grid=1e-6), "more than 2^53 steps of the 1e-06 s grid"),
    ("forward-reverse", dict(duration=1e7, grid=1e-3, rate=1000 * DEG, accel=1e5 * DEG, align_time=0.0),
     "the schedule needs more than 8388608 breakpoints"),
])
def test_bad_parameters_are_refused_with_a_reason(scheme, p, message):
    with pytest.raises(ValueError) as info:
        cs.build_schedule(scheme, **p)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("kwargs, message", [
    (dict(duration=0.0), "duration must be positive, got 0.0 s"),
    (dict(ramp=float("nan")), "ramp must be finite, got nan degC/s"),
    (dict(hold=-1.0), "hold must be non-negative, got -1.0 s"),
    (dict(low=50.0), "low must be below high, got 50.0 and 40.0 degC"),
    (dict(low=-300.0), "low must be above absolute zero, got -300.0 degC"),
    (dict(first="middle"), "first must be 'low' or 'high', got 'middle'"),
    (dict(step=-1.0), "step must be non-negative, got -1.0 degC"),
    (dict(duration=2e20, delay=1e20, hold=0.0), "does not advance at t = 1e\\+20 s"),
])
def test_bad_chamber_parameters_are_refused_with_a_reason(kwargs, message):
    p = dict(duration=3600.0, low=-25.0, high=40.0, ramp=1 / 60, hold=1800.0, start=20.0, delay=0.0, first="low",
             step=0.0, step_hold=0.0) | kwargs
    with pytest.raises(ValueError, match=message):
        cs.chamber_profile(**p)
    with pytest.raises(ValueError, match="span must be positive and finite, got 0.0"):
        cs.ambient_segment(0.0, 0.0, 20.0, 0.0, 1.0, 0.0, 0.0, None)


def test_builder_refuses_arrays_smaller_than_its_size_query():
    p = cs.Params()
    cs._defaults(ctypes.byref(p))
    p.scheme = b"four-position"
    n_times, n_axes, n_windows = ctypes.c_int64(), ctypes.c_int64(), ctypes.c_int64()
    msg = ctypes.create_string_buffer(200)
    assert cs._size(ctypes.byref(p), ctypes.byref(n_times), ctypes.byref(n_axes), ctypes.byref(n_windows), msg,
                    200) == 0
    m = n_times.value - 1  # one breakpoint short
    times, angle_bp, rate_bp, accel = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    s = cs.Schedule(capacity=m, times=times.ctypes.data, angle_bp=angle_bp.ctypes.data,
                    rate_bp=rate_bp.ctypes.data, accel=accel.ctypes.data)
    assert cs._build(ctypes.byref(p), ctypes.byref(s), msg, 200) == cs.CAPACITY
    assert msg.value.startswith(b"the schedule has more than the")
    s.capacity = m + 1
    big = [np.empty(m + 1) for _ in range(4)]
    s.times, s.angle_bp, s.rate_bp, s.accel = (a.ctypes.data for a in big)
    assert cs._build(ctypes.byref(p), ctypes.byref(s), msg, 200) == 0 and msg.value == b""
    assert s.n_times == m + 1 and s.gimbal_axes == b"z"


def test_builders_allocate_nothing():
    """The builders write only into the caller's arrays (no heap: the FMU calls them after allocating once)."""
    for name in ("schedule.c", "ambient.c", "report.c"):
        text = (CORE / name).read_text()
        assert not any(f in text for f in ("malloc(", "calloc(", "realloc(", "free(")), name
