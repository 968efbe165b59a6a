"""One entry point for tools that name a scheme (FMU parameters, CLI)."""

from __future__ import annotations

from ..core.schedule import gimbal_axes
from .rate_table import rate_table_3axis, rate_test, tumble_24
from .rins import ROTATION_SCHEMES, dual_axis, single_axis
from .schedule import GimbalSchedule

SCHEMES = ROTATION_SCHEMES + ("dual-axis", "rate-table-3axis", "tumble-24", "rate-test")


def gimbal_axes_of(scheme: str) -> str:
    """Gimbal chain of a scheme as axis letters, outer first (e.g. 'y,z'; the core's
    ``sarins_scheme_gimbal_axes``)."""
    axes = gimbal_axes(scheme) if isinstance(scheme, str) else None
    if axes is None:
        raise ValueError(f"unknown scheme {scheme!r}; known: {', '.join(SCHEMES)}")
    return axes


def schedule_for(scheme: str, duration: float, *, rate_dps: float = 6.0, accel_dps2: float = 6.0,
                 dwell: float = 0.0, revolutions: int = 1, align_time: float = 0.0, align_dwell: float = 300.0,
                 grid: float = 1.0, outer_rate_dps: float = 6.0, outer_accel_dps2: float = 6.0,
                 table_rates_dps=(1.0, 10.0, 100.0), table_accels_dps2=(0.01, 0.1, 1.0),
                 warmup: float = 600.0) -> GimbalSchedule:
    """Schedule of any named scheme (:data:`SCHEMES`).

    Single-axis schemes and 'dual-axis' use ``rate_dps``/``accel_dps2`` for
    the (inner) azimuth gimbal; 'dual-axis' flips the outer gimbal at
    ``outer_rate_dps``/``outer_accel_dps2``; 'rate-table-3axis' sweeps the
    inner, middle and outer gimbals with ``table_rates_dps`` /
    ``table_accels_dps2`` (inner first, seed 003) after ``warmup`` s;
    'tumble-24' (:func:`tumble_24`) stops ``dwell`` s at each position and
    moves at ``rate_dps``/``accel_dps2``; 'rate-test' (:func:`rate_test`,
    default rates, axes x, y, z) spins up at ``accel_dps2``, settles
    ``dwell`` s and positions at ``rate_dps``.
    """
    if scheme not in SCHEMES:
        raise ValueError(f"unknown scheme {scheme!r}; choose one of {', '.join(SCHEMES)}")
    if scheme in ROTATION_SCHEMES:
        return single_axis(scheme, duration, rate_dps=rate_dps, accel_dps2=accel_dps2, dwell=dwell, grid=grid,
                           revolutions=revolutions, align_time=align_time, align_dwell=align_dwell)
    if scheme == "dual-axis":
        return dual_axis(duration, inner_rate_dps=rate_dps, inner_accel_dps2=accel_dps2,
                         outer_rate_dps=outer_rate_dps, outer_accel_dps2=outer_accel_dps2, dwell=dwell,
                         grid=grid, align_time=align_time, align_dwell=align_dwell)
    if scheme == "tumble-24":
        return tumble_24(dwell=dwell, rate_dps=rate_dps, accel_dps2=accel_dps2, grid=grid)[0]
    if scheme == "rate-test":
        return rate_test(accel_dps2=accel_dps2, grid=grid, position_rate_dps=rate_dps, settle=dwell)[0]
    (ri, rm, ro), (ai, am, ao) = table_rates_dps, table_accels_dps2
    return rate_table_3axis(duration, inner_rate_dps=ri, inner_accel_dps2=ai, middle_rate_dps=rm,
                            middle_accel_dps2=am, outer_rate_dps=ro, outer_accel_dps2=ao, grid=grid,
                            warmup=warmup)
