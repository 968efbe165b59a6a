"""IMU parameters at the extremes of a double: the core's parameter checks (sarins_imu_check_params and
the bounds of sarins_imu_param_bound, the ones the IMUThermal FMU and the library both run) either refuse
a value, naming the parameter, or the IMU built from it gives finite increments and temperatures for its
first steps.  Every flat parameter of two presets (tests/imu_bound_cases.py: NaN, +-inf, +-1e300, the
largest magnitude its derived bound accepts and the next double above it), in process and through the
native IMUThermal FMU."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import imu_bound_cases as cases
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
    assert "gyro_bias_y = " in core_imu.check_rate_params(par, 200.0)
    assert "must be at most pi/2 rad" in core_imu.check_rate_params(par, 200.0)
    par[NAMES.index("gyro_bias_y")] = -limit
    assert core_imu.check_rate_params(par, 100.0).startswith("gyro_bias_y ")
    with pytest.raises(ValueError, match="IMU parameter gyro_bias_z = 1000.0 is outside"):
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


# ----------------------------------------------------------------- every parameter, every extreme (issue 31)


@pytest.mark.parametrize("preset", ["mems", "nav-rlg"])
def test_every_parameter_at_every_extreme_is_refused_by_name_or_steps_finite(preset):
    """Before the derived bounds, 645 of the 2944 cases of this sweep failed (199 non-finite steps, 150
    refusals that did not name the flat parameter, 296 values just above their bound accepted); now none."""
    rows = cases.sweep((preset,))
    assert len(rows) > 5 * len(NAMES)
    assert cases.failing(rows) == []


def test_each_bound_is_accepted_and_the_next_double_refused_by_name():
    par = core_imu.preset_params("mems")
    bounded = 0
    for i, name in enumerate(NAMES):
        bound = core_imu.param_bound(par, 200.0, i)
        if bound is None:
            continue
        bounded += 1
        for sign in (1.0, -1.0):
            trial = par.copy()
            trial[i] = sign * bound
            if core_imu.check_params(trial) is not None:  # a negative time constant: refused by its sign
                continue
            assert core_imu.check_rate_params(trial, 200.0) is None, name
            trial[i] = sign * np.nextafter(bound, np.inf)
            problem = core_imu.check_rate_params(trial, 200.0)
            assert problem is not None and problem.startswith(f"{name} = "), (name, problem)
            assert f"is outside [{-bound!r}, {bound!r}]" in problem, problem
    assert bounded > 150


def test_the_scale_factor_bound_keeps_the_sensed_rate_sign():
    """|sf| + |sf_tc| 975 + |sf_dtdt| R + |misalignment row| + |lowrate_gain| + |q| full scale <= 1, so that
    1 + those never goes negative: with the ideal preset every other term is zero, so the scale factor's bound
    is exactly 1, and the misalignment's alone 1 too; nav-rlg's misalignment row leaves 1 - 2 x 1 arcsec."""
    ideal = core_imu.preset_params("ideal")
    assert core_imu.param_bound(ideal, 200.0, NAMES.index("gyro_scale_factor_y")) == 1.0
    assert core_imu.param_bound(ideal, 200.0, NAMES.index("accel_misalignment_zx")) == 1.0
    nav = core_imu.preset_params("nav-rlg")
    expected = 1.0 - 2 * 4.84813681109536e-06
    assert core_imu.param_bound(nav, 200.0, NAMES.index("gyro_scale_factor_x")) == pytest.approx(expected, rel=1e-15)
    with pytest.raises(ValueError, match=r"gyro_scale_factor_x = 1.5 is outside \[-0.9999"):
        imu.IMU(imu_params.apply_overrides(imu.preset("nav-rlg"), {"gyro_scale_factor_x": 1.5}),
                imu.StaticBase(SITE_LAT))


def test_the_axial_drift_bound_is_the_gyro_budget_at_1000_degc():
    """a T^2 at |T| = 1000 degC within the z gyro's budget, 3 pi/4 rad per minor step less its other
    terms: with the ideal preset, a <= 3 pi/4 x 200 / 1000^2."""
    ideal = core_imu.preset_params("ideal")
    bound = core_imu.param_bound(ideal, 200.0, NAMES.index("axial_drift_a"))
    assert bound == pytest.approx(0.75 * np.pi * 200.0 / 1000.0**2, rel=1e-15)


@pytest.mark.parametrize("rate", [1.0, 10.0, 50.0, 100.0, 200.0, 1000.0, 10000.0])
def test_every_shipped_preset_builds_at_internal_rates_in_use(rate):
    for name in imu.PRESETS:
        assert core_imu.check_rate_params(core_imu.preset_params(name), rate) is None, (name, rate)
        imu.IMU(imu.preset(name), imu.StaticBase(SITE_LAT), output_interval=1.0, internal_rate=rate)


def test_the_lowrate_width_is_bounded_below_by_a_normal_minor_step_product():
    """dt w >= DBL_MIN: e / (dt w) is never 0/0 (5e-324 rad/s at 200 Hz turned the first step NaN)."""
    par = core_imu.preset_params("mems")
    i = NAMES.index("lowrate_width_y")
    par[i] = 2.0**-1022 * 200.0
    assert core_imu.check_rate_params(par, 200.0) is None
    assert cases.outcome("mems", "lowrate_width_y", par[i]) == "finite"
    par[i] = np.nextafter(par[i], 0.0)
    assert core_imu.check_rate_params(par, 200.0).startswith(f"lowrate_width_y = {float(par[i])!r} is below ")


def test_the_ambient_is_bounded_by_the_core_header():
    header = (Path(core_imu.__file__).parent / "imu_build.h").read_text()
    assert f"#define SARINS_IMU_AMBIENT_MAX {core_imu.AMBIENT_MAX!r} " in header
    sensor = imu.IMU(imu.preset("nav-rlg"), imu.StaticBase(SITE_LAT))
    zero = np.zeros((1, 1))
    sensor.step(zero, zero, zero, ambient=[core_imu.AMBIENT_MAX])
    with pytest.raises(ValueError, match="at most 500 degC"):
        sensor.step(zero, zero, zero, ambient=[np.nextafter(core_imu.AMBIENT_MAX, np.inf)])


# ----------------------------------------------------------------- the native FMU: the same refusals


FMU_VALUES = (1e300, -1e300, 5e-324)


def test_the_fmu_refuses_every_extreme_by_its_variable_name_or_steps_finite(fmu_dir):
    """Every flat parameter (an FMI variable of the same name) at +-1e300 and 5e-324 over the mems preset: fmi2Error
    at fmi2ExitInitializationMode with the variable named, or three finite steps on a turning table."""
    from fmpy.fmi1 import FMICallException

    from fmu_driver import Slave, unpack

    outputs = [f"dtheta_{a}" for a in "xyz"] + [f"dv_{a}" for a in "xyz"]
    rate = cases.max_rate() / np.sqrt(2.0)
    bad = []
    unpacked = unpack(fmu_dir / "IMUThermal.fmu")  # one extraction for the 621 instances
    for name in NAMES:
        for value in FMU_VALUES:
            slave = Slave(fmu_dir / "IMUThermal.fmu", "bounds", unpacked=unpacked)
            try:
                slave.set(preset="mems", gimbals="z,x", **{name: value})
                slave.fmu.enterInitializationMode()
                slave.set(angle_1=0.0, angle_2=0.0, rate_1=rate, rate_2=rate, ambient_temp=20.0, motion_time=0.0)
                try:
                    slave.fmu.exitInitializationMode()
                except FMICallException:
                    errors = [m for status, _, m in slave.log if status == 3]
                    if not any(cases.names_it(name, m) for m in errors):  # (a pair rule names both: flicker_tau_*)
                        bad.append((name, value, errors))
                    continue
                for k in range(3):
                    slave.set(angle_1=rate * k, angle_2=rate * k, motion_time=float(k))
                    slave.fmu.doStep(float(k), 1.0)
                    if not np.all(np.isfinite(slave.get(*outputs))):
                        bad.append((name, value, "non-finite"))
                        break
            finally:
                slave.free()
    assert bad == []


@pytest.mark.parametrize("preset", ["mems", "nav-rlg"])
@pytest.mark.parametrize("size", [2, 6, 20])
def test_random_combinations_are_refused_by_name_or_step_finite(preset, size):
    """300 random combinations of `size` bounded parameters, each between 1e-3 and 2 x its own bound
    (tests/imu_bound_cases.py combinations): each is refused naming one of them or steps finite.  Before the
    thermal step's series branch, 9 of 3,000 were not finite (a dT/dt coefficient with a time constant above
    ~1e300 s: the lag's step rounded to a 480 degC jump)."""
    rows = cases.combinations(preset, 300, seed=size, size=size)
    assert [r for r in rows if r[1] not in cases.CLEAN] == []
    assert {r[1] for r in rows} == cases.CLEAN  # both outcomes occur: the sweep reaches the bounds
