"""Seed 003's three-axis rate table: the dynamic sweep, the 24-position tumble and the rate test."""

from __future__ import annotations

import numpy as np

from ..checks import number
from ..core.schedule import UP_NAMES, rate_test_magnitudes_dps
from ..units import DEG_TO_RAD
from .schedule import AXIS_X, AXIS_Y, AXIS_Z, GimbalSchedule, chain_matrix
from .segments import built

# three-axis rate table (seed 003, TBL-3302-CT): outer about the base vertical
# z, middle about the outer frame's x, inner about the middle frame's y:
# mat_tb = Rz(theta_outer) Rx(theta_middle) Ry(theta_inner), i.e. the
# yaw-pitch-roll order of :func:`sarins_fmu.rotations.euler_to_mat`
RATE_TABLE_AXES = (AXIS_Z, AXIS_X, AXIS_Y)

# seed 003's rate test: 22 rates within +-200 deg/s; the paper does not list
# them.  Our choice (the C core's default, sarins_rate_test_magnitudes_dps):
# 11 magnitudes on a 1-2-3-5 pattern (roughly log-spaced, 1 and 2 deg/s in
# the low-rate region of the MEMS preset (nonlinearity width 2 deg/s), the
# range end 200), each with both signs.
RATE_TEST_MAGNITUDES_DPS = rate_test_magnitudes_dps()

TUMBLE_DTYPE = np.dtype([("start", float), ("end", float), ("up", "U2"), ("heading", float),
                         ("angles", float, (3,)), ("up_b", float, (3,))])
RATE_WINDOW_DTYPE = np.dtype([("start", float), ("end", float), ("axis", "U2"), ("rate", float),
                              ("rate_nominal", float), ("revolutions", int), ("up_b", float, (3,)),
                              ("rate_b", float, (3,))])


def rate_table_3axis(duration: float, *, inner_rate_dps: float = 1.0, inner_accel_dps2: float = 0.01,
                     middle_rate_dps: float = 10.0, middle_accel_dps2: float = 0.1,
                     outer_rate_dps: float = 100.0, outer_accel_dps2: float = 1.0, grid: float = 1.0,
                     warmup: float = 600.0) -> GimbalSchedule:
    """Seed 003's dynamic-calibration profile on a three-axis rate table.

    Gimbal 0 (outer) turns about the base vertical z, gimbal 1 (middle) about
    the outer frame's x, gimbal 2 (inner) about the middle frame's y, and the
    inner frame carries the IMU::

        mat_tb = Rz(theta_outer) Rx(theta_middle) Ry(theta_inner)   (axes :data:`RATE_TABLE_AXES`)

    After a static warm-up (seed 003: the MIMU is powered and warmed up for
    10 min), all three gimbals move at once, each sweeping its rate as a
    triangle wave between -max and +max at constant |acceleration| (seed 003:
    inner 0.01 deg/s^2 between +-1 deg/s, middle 0.1 deg/s^2 between +-10
    deg/s, outer 1 deg/s^2 between +-100 deg/s, repeated).  One period of
    gimbal j, with T_q = max_j / accel_j rounded up to ``grid``::

        accel +max/T_q for T_q, -max/T_q for 2 T_q, +max/T_q for T_q

    so the rate goes 0 -> +max -> -max -> 0 and the angle returns to its
    start (excursion max * T_q, i.e. 100 deg inner, 1000 deg middle, 10000 deg
    outer with the paper's values).  The peak rates are kept exactly; the
    acceleration is lowered (never raised) when max/accel is not a whole
    number of grid steps.  Each gimbal repeats whole periods until the end of
    the schedule covers ``duration``, then rests.  With the paper's values all
    three periods are 400 s, so the gimbals stay in phase.  The chamber
    temperature runs at the same time: see :func:`sarins_fmu.thermal.chamber_profile`.

    Parameters
    ----------
    duration : float
        Length the schedule must cover, warm-up included, s.
    inner_rate_dps, middle_rate_dps, outer_rate_dps : float
        Rate amplitude of each gimbal, deg/s, >= 0 (0 keeps that gimbal still).
    inner_accel_dps2, middle_accel_dps2, outer_accel_dps2 : float
        Magnitude of each gimbal's angular acceleration, deg/s^2, > 0.
    grid : float
        Time grid on which the acceleration may change, s, > 0.
    warmup : float
        Static warm-up at the start, s (rounded up to ``grid``), >= 0.

    Returns
    -------
    GimbalSchedule
        Three gimbals (outer, middle, inner), at rest at angle 0 at t = 0.

    Raises
    ------
    ValueError
        On NaN or infinite input, negative rates or warm-up, or a
        non-positive duration, acceleration or grid.
    """
    gimbals = {f"table_{name}_{q}": number(f"{name}_{q}_{unit}", value) * DEG_TO_RAD
               for name, q, unit, value in (
                   ("outer", "rate", "dps", outer_rate_dps), ("outer", "accel", "dps2", outer_accel_dps2),
                   ("middle", "rate", "dps", middle_rate_dps), ("middle", "accel", "dps2", middle_accel_dps2),
                   ("inner", "rate", "dps", inner_rate_dps), ("inner", "accel", "dps2", inner_accel_dps2))}
    rename = {f"table_{name}_{q}": f"{name}_{q}" for name in ("inner", "middle", "outer") for q in ("rate", "accel")}
    return built("rate-table-3axis", rename, duration=number("duration", duration), grid=number("grid", grid),
                 warmup=number("warmup", warmup), **gimbals)[0]


def _up_vector_b(angles) -> np.ndarray:
    """Base up (t-frame z) resolved in b on the three-axis chain, rounded to the exact +-1/0 it nominally is."""
    return np.round(chain_matrix(RATE_TABLE_AXES, angles).T @ np.array(AXIS_Z)) + 0.0


def tumble_24(*, dwell: float = 180.0, rate_dps: float = 10.0, accel_dps2: float = 10.0,
              grid: float = 1.0) -> tuple[GimbalSchedule, np.ndarray]:
    """Seed 003's 24-position static tumble on the three-axis rate table.

    The chain is that of :func:`rate_table_3axis` (outer about base z, middle
    about outer x, inner about middle y).  Each body axis is pointed up and
    down (6 orientations) at 4 headings (outer angle 0, 90, 180, 270 deg),
    with a ``dwell`` s static stop at each position (seed 003: 3 min of data
    per position).  The orientations are set with one gimbal each, as
    (middle, inner) angles in deg::

        +z (0, 0), +x (0, -90), -z (0, -180), -x (0, -270), +y (90, -270), -y (-90, -270)

    visited in this order, so every change of orientation is a single
    rest-to-rest move of the middle or the inner gimbal (-90, -90, -90, +90,
    -180 deg).  The headings are visited 0, 90, 180, 270 for the 1st, 3rd and
    5th orientation and 270, 180, 90, 0 for the others, so the outer gimbal
    only moves by 90 deg within an orientation and stays put when the
    orientation changes.  The schedule starts at rest at angle 0 (+z up,
    heading 0) with the first dwell at t = 0; only the gimbals that must
    change move.

    Parameters
    ----------
    dwell : float
        Static time at each position, s (rounded up to ``grid``), > 0.
    rate_dps, accel_dps2 : float
        Peak rate (deg/s) and acceleration (deg/s^2) of the moves, > 0.
    grid : float
        Time grid on which the acceleration may change, s, > 0.

    Returns
    -------
    schedule : GimbalSchedule
        Three gimbals (outer, middle, inner).
    positions : ndarray (24,) of :data:`TUMBLE_DTYPE`
        One row per dwell window: ``start``, ``end`` (s, on the grid; the
        table is at rest on [start, end]), ``up`` (the body axis pointing up,
        '+x' ... '-z'), ``heading`` (outer angle mod 2 pi, rad, positive
        counter-clockwise seen from above), ``angles`` (nominal gimbal angles,
        rad, as the schedule holds them), ``up_b`` (base up resolved in the
        body frame: a static accelerometer triad reads g * up_b).

    Raises
    ------
    ValueError
        On NaN or infinite input, or a non-positive dwell, rate, acceleration
        or grid.
    """
    sched, w = built("tumble-24", dwell=number("dwell", dwell), rate=number("rate_dps", rate_dps) * DEG_TO_RAD,
                     accel=number("accel_dps2", accel_dps2) * DEG_TO_RAD, grid=number("grid", grid))
    rows = [(r["start"], r["end"], UP_NAMES[r["up"]], r["heading"], r["angles"], _up_vector_b(r["angles"]))
            for r in w]
    return sched, np.array(rows, dtype=TUMBLE_DTYPE)


def rate_test(*, rates_dps=None, axis_up=("x", "y", "z"), min_duration: float | None = None,
              accel_dps2: float = 10.0, grid: float = 1.0, position_rate_dps: float = 10.0,
              settle: float = 0.0, rate_tol: float = 1e-3) -> tuple[GimbalSchedule, np.ndarray]:
    """Seed 003's rate test on the three-axis rate table.

    The chain is that of :func:`rate_table_3axis`.  For each entry of
    ``axis_up`` in turn, the middle and inner gimbals point that body axis up
    (moving together, rest to rest, at ``position_rate_dps``), as (middle,
    inner) angles in deg::

        +z (0, 0), -z (0, 180), +x (0, -90), -x (0, 90), +y (90, 0), -y (-90, 0)

    then the outer (vertical) gimbal turns at each rate of ``rates_dps``:
    from rest it accelerates to the rate, holds it for ``settle`` s and then
    for the measurement window of k whole revolutions, and decelerates to
    rest; the acceleration and deceleration lie outside the window.  Seed
    003 takes "whole-revolution data at 22 rate points within +-200 deg/s"
    per axis but does not list them; the default here is our choice,
    +-:data:`RATE_TEST_MAGNITUDES_DPS` (1, 2, 3, 5, 10, 20, 30, 50, 100, 150,
    200 deg/s, each positive then negative, ascending magnitude).

    So that each window starts and ends on the grid (the IMU's output
    instants) and spans whole revolutions exactly, the table rate is set to
    2 pi k / (n grid) with the smallest k (revolutions) and an integer n
    (grid steps) within ``rate_tol`` of the nominal rate; on a 1 s grid every
    default rate is met exactly (k <= 5).  The window reports the rate
    actually used.

    Parameters
    ----------
    rates_dps : sequence of float, optional
        Nominal table rates, deg/s, non-zero; the sign is the sense about the
        base up axis (counter-clockwise seen from above positive).
    axis_up : sequence of {'x', 'y', 'z', '+x', ..., '-z'}
        Body axes pointed up in turn ('x' means '+x').
    min_duration : float, optional
        Shortest window, s; by default one revolution.
    accel_dps2 : float
        Angular acceleration of the outer gimbal's spin-up and spin-down and
        of the positioning moves, deg/s^2, > 0 (our choice: seed 003 does not
        give one).
    grid : float
        Time grid on which the acceleration may change, s, > 0.
    position_rate_dps : float
        Peak rate of the positioning moves, deg/s, > 0.
    settle : float
        Constant-rate time before each window, s (rounded up to ``grid``).
    rate_tol : float
        Largest relative change of a rate allowed to fit whole revolutions
        on the grid, in (0, 0.1].

    Returns
    -------
    schedule : GimbalSchedule
        Three gimbals (outer, middle, inner), at rest at angle 0 at t = 0.
    windows : ndarray (len(axis_up) * len(rates_dps),) of :data:`RATE_WINDOW_DTYPE`
        ``start``, ``end`` (s, on the grid), ``axis`` (the body axis up,
        '+x' ...), ``rate`` (outer gimbal rate inside the window, rad/s:
        the rate about the named body axis, relative to the base),
        ``rate_nominal`` (rad/s), ``revolutions`` (k), ``up_b`` (base up in
        b), ``rate_b`` (omega_tb^b = rate * up_b, rad/s; add the Earth rate
        resolved in b for what a gyro triad senses).

    Raises
    ------
    ValueError
        On NaN or infinite input, a zero rate, an unknown axis name, a
        non-positive acceleration, grid or positioning rate, negative
        durations, or rates that do not fit whole revolutions on the grid.
    """
    if rates_dps is None:
        rates = None
    else:
        rates = []
        for r in np.atleast_1d(np.asarray(rates_dps, dtype=object)).tolist():
            try:
                rates.append(float(r) * DEG_TO_RAD)
            except (TypeError, ValueError):
                raise ValueError(f"rates_dps must be numbers, got {r!r}") from None
    if isinstance(axis_up, str):
        axis_up = (axis_up,)
    rename = {"rate": "position_rate", "dwell": "settle", "test_rates": "rates", "test_axes": "axis_up",
              "test_min_duration": "min_duration", "test_rate_tol": "rate_tol"}
    sched, w = built("rate-test", rename, test_rates=rates, test_axes=",".join(str(a) for a in axis_up),
                     test_min_duration=0.0 if min_duration is None else number("min_duration", min_duration),
                     accel=number("accel_dps2", accel_dps2) * DEG_TO_RAD, grid=number("grid", grid),
                     rate=number("position_rate_dps", position_rate_dps) * DEG_TO_RAD,
                     dwell=number("settle", settle), test_rate_tol=number("rate_tol", rate_tol))
    rows = []
    for r in w:
        up_b = _up_vector_b(r["angles"])
        rows.append((r["start"], r["end"], UP_NAMES[r["up"]], r["rate"], r["rate_nominal"], r["revolutions"], up_b,
                     r["rate"] * up_b + 0.0))
    return sched, np.array(rows, dtype=RATE_WINDOW_DTYPE)
