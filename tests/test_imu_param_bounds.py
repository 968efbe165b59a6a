"""IMU parameters at the extremes of a double: the core's parameter check (sarins_imu_check_params, the
one the IMUThermal FMU and the library both run) either refuses a value, naming the parameter, or the
IMU built from it gives finite increments and temperatures for its first steps.  Swept over the
parameters whose bounds the core derives (the flicker band, the self-heating rise, the gyro biases)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu import imu, imu_params
from sarins_fmu.core import imu as core_imu
from sarins_fmu.site import SITE_LAT

EXTREMES = (1e308, -1e308, 5e-324, -5e-324, 1e300)
NAMES = [name for name, _, _ in imu_params.PARAMETERS]
BOUNDED = ([f"gyro_bias_{a}" for a in "xyz"] + ["flicker_tau_min", "flicker_tau_max"]
           + [f"self_heating_{s}_{a}" for s in ("gyro", "accel") for a in "xyz"])


def _first_steps_finite(name: str, value: float, steps: int = 3) -> bool:
    model = imu_params.apply_overrides(imu.preset("nav-rlg"), {name: value})
    sensor = imu.IMU(model, imu.StaticBase(SITE_LAT, 0.0, 0.0, 0.0), np.array([[0.0, 0.0, 1.0]]),
                     output_interval=1.0, internal_rate=200.0, seed=0)
    sensor.reset(ambient0=20.0)
    zero = np.zeros((1, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(steps):
            out = sensor.step(zero, zero, zero, ambient=[20.0])
            if not all(np.all(np.isfinite(x)) for x in out):
                return False
    return True


@pytest.mark.parametrize("name", BOUNDED)
def test_an_extreme_value_is_refused_by_name_or_steps_finite(name):
    for value in EXTREMES:
        par = core_imu.preset_params("nav-rlg")
        par[NAMES.index(name)] = value
        problem = core_imu.check_params(par) or core_imu.check_rate_params(par, 200.0)
        if problem is not None:
            assert name in problem, (value, problem)
        else:
            assert _first_steps_finite(name, value), (name, value)


def test_the_flicker_band_is_bounded_by_double_precision():
    """tau_max / tau_min <= 2^52: the band's term count stays <= 49; one ulp wider is refused by name."""
    par = core_imu.preset_params("nav-rlg")
    tau_max = par[NAMES.index("flicker_tau_max")]
    par[NAMES.index("flicker_tau_min")] = tau_max / 2.0**52
    assert core_imu.check_params(par) is None
    assert core_imu.flicker_count(tau_max / 2.0**52, tau_max) <= 49
    par[NAMES.index("flicker_tau_min")] = np.nextafter(tau_max / 2.0**52, 0.0)
    assert core_imu.check_params(par).startswith("flicker_tau_min must be at least")
    par[NAMES.index("flicker_tau_min")] = 5e-324
    assert core_imu.check_params(par).startswith("flicker_tau_min ")


def test_a_gyro_bias_is_bounded_by_a_quarter_turn_per_minor_step():
    """|gyro_bias| <= (pi/2) x internal_rate: at 200 Hz, 314.159 rad/s is built and steps finite, the next
    double up is refused by name, as is the same bias at 100 Hz."""
    limit = 0.5 * np.pi * 200.0
    par = core_imu.preset_params("nav-rlg")
    par[NAMES.index("gyro_bias_y")] = -limit
    assert core_imu.check_params(par) is None and core_imu.check_rate_params(par, 200.0) is None
    assert _first_steps_finite("gyro_bias_y", -limit, steps=5)
    par[NAMES.index("gyro_bias_y")] = np.nextafter(-limit, -np.inf)
    assert core_imu.check_rate_params(par, 200.0).startswith("gyro_bias_y must be at most pi/2 rad")
    par[NAMES.index("gyro_bias_y")] = -limit
    assert core_imu.check_rate_params(par, 100.0).startswith("gyro_bias_y ")
    with pytest.raises(ValueError, match="IMU parameter gyro_bias_z must be at most"):
        _first_steps_finite("gyro_bias_z", 1e3)


def test_minor_steps_per_interval_are_bounded_in_python_and_in_the_core_header():
    """2^30 minor steps per output interval at most (a state with more, or a fraction, is not a table)."""
    header = (Path(core_imu.__file__).parent / "imu.h").read_text()
    assert f"#define SARINS_IMU_MAX_SUB {core_imu.MAX_SUB} " in header
    base = imu.StaticBase(SITE_LAT, 0.0, 0.0, 0.0)
    model = imu.preset("nav-rlg")
    with pytest.raises(ValueError, match="at most 1073741824"):
        imu.IMU(model, base, output_interval=2.0**30 + 1, internal_rate=1.0)
    imu.IMU(model, base, output_interval=2.0**30, internal_rate=1.0)
