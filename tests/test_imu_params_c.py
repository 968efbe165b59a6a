"""The IMU's flat parameters and presets as data in the C core (sarins_fmu/core/imu_params.c, generated
from sarins_fmu/imu_params.py and the presets of sarins_fmu/imu.py) and the IMU built from them in C
(sarins_fmu/core/imu_build.c)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu import imu, imu_dynamics, imu_params, imu_step
from sarins_fmu.core import imu as core_imu
from sarins_fmu.imu import IMU, StaticBase
from sarins_fmu.imu_correlated import flicker_term_std
from sarins_fmu.thermal import Ambient

ROOT = Path(__file__).resolve().parents[1]
NAMES = [name for name, _, _ in imu_params.PARAMETERS]


def test_the_generated_c_sources_are_current():
    header, source = imu_params.c_sources()
    for path, text in ((imu_params.C_HEADER, header), (imu_params.C_SOURCE, source)):
        assert (ROOT / path).read_text() == text, f"{path} is stale: run python -m sarins_fmu.imu_params"


def test_the_c_presets_are_the_python_presets_bit_for_bit():
    assert core_imu.param_names() == tuple(NAMES)
    assert core_imu.preset_names() == tuple(imu.PRESETS)
    for name, model in imu.PRESETS.items():
        flat = imu_params.flatten(model)
        assert np.array_equal(core_imu.preset_params(name), [flat[n] for n in NAMES]), name
    with pytest.raises(ValueError, match="no IMU preset 'tactical'"):
        core_imu.preset_params("tactical")


BAD = [("gyro_random_walk_y", -1e-6, "must be non-negative"), ("accel_bias_instability_z", -1.0, "non-negative"),
       ("gyro_bias_corr_time_x", 0.0, "must be positive"), ("accel_hysteresis_width_y", -2.0, "positive"),
       ("gyro_flicker_z", -1e-7, "non-negative"), ("accel_rate_random_walk_x", -1.0, "non-negative"),
       ("gyro_turn_on_bias_x", -1.0, "non-negative"), ("lowrate_width_z", 0.0, "positive"),
       ("aging_corr_time", -5.0, "positive"), ("flicker_tau_min", 0.0, "positive"),
       ("flicker_tau_max", 0.5, "must exceed flicker_tau_min"), ("time_constant_accel_z", 0.0, "positive"),
       ("die_time_constant_gyro_y", -1.0, "non-negative"), ("g_sensitivity_zx", math.inf, "must be finite"),
       ("gyro_bias_x", math.nan, "must be finite"), ("axial_block_time_constant", -1.0, "non-negative"),
       ("axial_hysteresis_width", 0.0, "must be positive"), ("axial_hysteresis_relax_time", -3.0, "non-negative"),
       ("axial_drift_grad", math.inf, "must be finite"),
       ("gyro_filter_time_constant_y", -1e-3, "non-negative"), ("accel_rate_hysteresis_width_x", 0.0, "positive"),
       ("gyro_rate_hysteresis_time_z", -1.0, "non-negative"), ("accel_lever_arm_zy", math.nan, "must be finite")]


@pytest.mark.parametrize("name, value, rule", BAD)
def test_c_checks_refuse_what_the_python_model_refuses(name, value, rule):
    par = core_imu.preset_params("mems")
    par[NAMES.index(name)] = value
    problem = core_imu.check_params(par)
    assert problem.startswith(name + " ") and rule in problem, problem
    with pytest.raises(ValueError):
        imu_params.apply_overrides(imu.preset("mems"), {name: value})


def test_c_checks_accept_every_preset_and_random_valid_overrides():
    rng = np.random.default_rng(3)
    for name in imu.PRESETS:
        assert core_imu.check_params(core_imu.preset_params(name)) is None
    for _ in range(50):
        par = core_imu.preset_params("mems")
        picks = rng.choice(len(NAMES), 10, replace=False)
        par[picks] *= rng.uniform(0.5, 2.0, 10)  # positive factors keep signs, keep tau_min < tau_max mostly
        model_ok = True
        try:
            imu_params.apply_overrides(imu.preset("mems"), {NAMES[i]: par[i] for i in picks})
        except ValueError:
            model_ok = False
        assert (core_imu.check_params(par) is None) == model_ok


@pytest.mark.parametrize("preset", ["ideal", "nav-rlg", "mems"])
def test_the_c_built_table_holds_the_model(preset):
    """Each constant array against the model's fields (imu_step's layout)."""
    m = imu.preset(preset)
    h = 0.5
    s = IMU(m, StaticBase(0.6), output_interval=h, internal_rate=200.0, seed=2).state_arrays()
    cat = np.concatenate
    assert np.array_equal(s[imu_step.CONSTS], [0.0, h, m.axial_drift_dtdt, float(m.thermal.has_die_lag),
                                               float(preset == "mems"), 100.0, 0.0, 0.0, *m.axial_thermal_par])
    tau_gm = cat([m.gyro.bias_corr_time, m.accel.bias_corr_time])
    assert np.array_equal(s[imu_step.SENSOR_PAR][:2], [m.thermal.self_heating, m.thermal.time_constant])
    np.testing.assert_allclose(s[imu_step.SENSOR_PAR][2], np.exp(-h / tau_gm), rtol=2e-16, atol=0)
    assert np.array_equal(s[imu_step.SENSOR_PAR][3], cat([m.gyro.bias_instability, m.accel.bias_instability]))
    assert np.array_equal(s[imu_step.COEF], [getattr(t, f) for t in (m.gyro, m.accel)
                                             for f in ("bias", "bias_tc1", "bias_tc2", "scale_factor", "scale_factor_tc")])
    assert np.array_equal(s[imu_step.TRIAD], [m.axial_drift_poly, m.gyro.quadratic, m.lowrate_gain, m.lowrate_width,
                                              m.accel.quadratic, m.gyro.random_walk, m.accel.random_walk])
    assert np.array_equal(s[imu_step.MATS], cat([m.gyro.misalignment, m.g_sensitivity, m.accel.misalignment]))
    corr = s[imu_step.CORR_PAR]
    stack = lambda f: cat([getattr(m.gyro, f), getattr(m.accel, f)])  # noqa: E731
    assert np.array_equal(corr[[0, 1, 2, 3, 4, 5, 7]], [m.thermal.die_time_constant, stack("bias_dtdt"),
                                                         stack("scale_factor_dtdt"), stack("hysteresis"),
                                                         stack("hysteresis_width"), stack("rate_random_walk"),
                                                         stack("turn_on_bias")])
    taus = np.geomspace(m.flicker_tau_min, m.flicker_tau_max, s[imu_step.PHI].shape[0])
    assert taus.shape[0] == max(2, math.ceil(3 * math.log10(m.flicker_tau_max / m.flicker_tau_min)) + 1)
    np.testing.assert_allclose(s[imu_step.PHI], np.exp(-h / taus), rtol=2e-16, atol=0)
    assert np.array_equal(s[imu_step.Q], np.outer(np.full(taus.shape[0], flicker_term_std(1.0, taus)),
                                                   stack("flicker")))
    assert np.array_equal(s[imu_step.DYN_PAR], imu_dynamics.parameters(m))  # the output dynamics' rows
    assert np.array_equal(s[imu_step.DYN_STATE], np.zeros((imu_dynamics.STATE_ROWS, 6)))


def test_a_restart_puts_the_output_dynamics_back_at_rest():
    """reset() after a run: the same outputs as a fresh IMU (the dynamics' filter, play and started rows too)."""
    m = imu.preset("mems")
    a = IMU(m, StaticBase(0.6), output_interval=0.005, seed=4)
    rate = np.full((30, 1), 0.3)
    first = a.step(np.cumsum(rate, axis=0) * 0.005, rate, np.zeros((30, 1)))
    assert np.any(a.state_arrays()[imu_step.DYN_STATE] != 0.0)
    a.reset()
    assert np.array_equal(a.state_arrays()[imu_step.DYN_STATE], np.zeros((imu_dynamics.STATE_ROWS, 6)))
    again = a.step(np.cumsum(rate, axis=0) * 0.005, rate, np.zeros((30, 1)))
    for x, y in zip(first, again):
        assert np.array_equal(x, y)


@pytest.mark.parametrize("start", ["hot", "cold"])
def test_a_run_starts_at_the_ambient_plus_the_self_heating_when_hot(start):
    m = imu.preset("mems")
    s = IMU(m, StaticBase(0.6), seed=1, thermal_start=start, ambient=Ambient(mean=17.25)).state_arrays()
    expected = 17.25 + (np.asarray(m.thermal.self_heating) if start == "hot" else np.zeros(6))
    assert np.array_equal(s[imu_step.CLOCK], [0.0, 17.25])
    assert np.array_equal(s[imu_step.STATE][0], expected)
    assert np.array_equal(s[imu_step.STATE][2], [expected[2], expected[2], 0, 0, 0, 0])  # z block node, play
    assert np.array_equal(s[imu_step.CORR_STATE], [expected, expected, np.zeros(6)])
    assert not np.any(s[imu_step.X_FLICKER] == 0.0)  # the flicker terms' stationary start is drawn


def test_build_refuses_a_bad_vector_and_start_a_bad_ambient():
    sensor = IMU(imu.preset("nav-rlg"), StaticBase(0.6))
    par = core_imu.preset_params("nav-rlg")
    par[NAMES.index("gyro_bias_corr_time_x")] = -1.0
    with pytest.raises(ValueError, match="IMU parameter gyro_bias_corr_time_x must be positive"):
        core_imu.build(sensor._table, par, 0.0, 1.0, 200, 0.0, 0)
    with pytest.raises(ValueError, match="does not fit the layout"):
        core_imu.start(sensor._table, -300.0, True, 0)
    wrong = core_imu.preset_params("mems")  # more flicker terms than the table's rows
    wrong[NAMES.index("flicker_tau_max")] = 1e9
    with pytest.raises(ValueError, match="does not fit the layout"):
        core_imu.build(sensor._table, wrong, 0.0, 1.0, 200, 0.0, 0)
