"""Seed 002 experiments: S metric, 300-day model update, campaign quick profile."""

import json
import math

import numpy as np
import pytest

from sarins_fmu.experiments import online_rls
from sarins_fmu.experiments.online_rls import aged_coefficients, model_update_run, s_metric
from sarins_fmu.imu import preset


def test_s_metric_closed_forms():
    # constant offset c: S = 50 |c|
    assert s_metric([1e-6, 2e-4, 0.003], [1e-6, 2e-4, 0.001]) == pytest.approx(50 * 0.002, rel=1e-12)
    # linear difference crossing zero at 25 degC: two triangles of 25 x 25k / 2
    k = 1e-4
    assert s_metric([0.0, k, -25 * k], [0.0, 0.0, 0.0]) == pytest.approx(2 * 0.5 * 25 * 25 * k, rel=1e-12)
    # quadratic T^2 - 50 T + 400 (roots 10, 40) against a numerical integral
    t = np.linspace(0, 50, 200001)
    d = np.abs(t**2 - 50 * t + 400)
    assert s_metric([1.0, -50.0, 400.0], [0.0, 0.0, 0.0]) == pytest.approx(np.trapezoid(d, t), rel=1e-8)
    with pytest.raises(ValueError):
        s_metric([0, 0, 1], [0, 0, 0], (10.0, 0.0))


def test_ageing_readings_have_the_same_300_day_spread():
    model = preset("nav-rlg")
    days = np.arange(0.0, 301.0)
    end = {kind: np.array([aged_coefficients(model, days, s, kind)[-1] for s in range(300)]) - model.axial_drift_poly
           for kind in ("markov", "integrated")}
    expected = model.aging_sigma * math.sqrt(1 - math.exp(-2 * 300 / 360))
    for kind, change in end.items():
        np.testing.assert_allclose(change.std(axis=0), expected, rtol=0.15, err_msg=kind)
    with pytest.raises(ValueError):
        aged_coefficients(model, days, 0, "linear")


def test_exact_estimates_ff_rls_tracks_the_ageing_best():
    """With error-free stop estimates, FF-RLS beats plain RLS, which beats no update."""
    s = np.array([[r["s_none"], r["s_rls"], r["s_ff"]]
                  for r in (model_update_run(seed=k, estimate="truth") for k in range(30))])
    mean = s.mean(axis=0)
    assert mean[2] < mean[1] < mean[0]
    r = model_update_run(seed=0, estimate="truth")
    assert r["calibration_rms_dph"] < 1e-12 and np.all(np.abs(r["stop_error_dph"]) < 1e-12)
    assert r["truth_dph"].shape == (301, 3) and r["ff_history_dph"].shape == (20, 3)


@pytest.mark.slow
def test_quick_campaign_writes_a_report_and_ff_rls_beats_no_update(tmp_path):
    from sarins.cli import main

    out = tmp_path / "online-rls"
    assert main(["campaign", "online-rls", "--profile", "quick", "--workers", "1", "--out", str(out), "--no-progress"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["monte_carlo"]["markov-nav-rlg-filter"]["runs"] == 8  # the headline: the preset
    # FF-RLS beats no update where the stop estimates are good (the premise unit, a sensitivity row); on
    # nav-rlg the stops' 0.01 deg/h noise decides (the report states it)
    mc = summary["monte_carlo"]["markov-premise-filter"]
    assert mc["runs"] == 8 and mc["mean_s_ff"] < mc["mean_s_none"]
    assert summary["stop_filter"]["nav-rlg"]["runs"] == 4 and summary["stop_filter"]["premise"]["runs"] == 1
    assert summary["stop_filter"]["indexed-nav-rlg"]["runs"] == 4  # the same stops, the RINS indexed
    assert summary["stop_filter"]["zupt-nav-rlg"]["runs"] == 4  # the same stops through the aided filter's ZUPT
    veh = summary["vehicle"]["markov-nav-rlg"]
    assert veh["runs"] == 1 and veh["mean_cep_initial"] > 0
    report = (out / "report.md").read_text()
    assert "Table 2" in report and "fig5_curves.png" in report
    assert "## The stop through the aided filter's zero-velocity updates (nav-rlg)" in report
    # the comparison table (sarins.comparison), with what the quick profile is too small to test
    assert "| claim | paper value | ours (median) | ours 5-95 % | paper's percentile in ours |" in report
    assert "| mean S after FF-RLS (°/h·°C), Table 2 | 0.066 |" in report
    assert "**The quick profile is too small to test:** 30-min stop" in report and "Table 5" in report
    assert "## What limits the 30-minute stop" in report
    assert "## Indexing the dual-axis RINS during the stop (nav-rlg)" in report and "| with indexing | 4 |" in report
    for name in ("stop_convergence.png", "fig4_parameters.png", "fig6_s_values.png", "fig8_position_errors.png"):
        assert (out / name).stat().st_size > 1000
    # resumable: a second call finds every run stored
    assert main(["campaign", "online-rls", "--profile", "quick", "--workers", "1", "--out", str(out), "--no-progress"]) == 0


def test_bad_arguments():
    with pytest.raises(ValueError):
        online_rls.simulate_stop(duration=0.5)
    with pytest.raises(ValueError):
        model_update_run(estimate="guess")
    with pytest.raises(ValueError):
        online_rls.imu_unit("fog")
