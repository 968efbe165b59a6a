"""Seed 002's stop through the aided filter's zero-velocity updates, against the stop filter (eqs 4-6)."""

import numpy as np
import pytest

from sarins_fmu.experiments.online_rls import simulate_stop, stop_data
from sarins_fmu.experiments.online_rls_zupt import simulate_zupt_stop, stop_truth
from sarins_fmu.rotations import euler_to_mat

SHORT = dict(duration=600.0, temperature=20.0)


def test_stop_truth_is_the_turning_imu_at_rest():
    d = stop_data(seed=1, **SHORT)
    truth = stop_truth(d)
    n = d.dtheta.shape[0]
    assert truth.n_steps == n and truth.time[-1] == pytest.approx(600.0)
    assert truth.stationary().all()  # every step a true zero-velocity step
    for k in (0, 7, 123, n):  # the attitude rows give back the turntable's matrix
        assert np.allclose(euler_to_mat(*truth.attitude[k]), d.attitude(k), atol=1e-12)
    # the increments' azimuth rotation is the table's turn (the Earth rate adds < 1e-4 rad over a step)
    yaw = np.unwrap(truth.attitude[:, 0])
    assert np.allclose(d.dtheta[:, 2], np.diff(yaw), atol=2e-4)


def test_zupt_filter_matches_the_stop_filter_on_the_same_stops():
    """Both filters are given the same record, densities and priors: the same 1-sigma (to 2 %) and the
    same estimate to a fraction of it; each error inside 3 sigma (nav-rlg, full 30-min stops)."""
    for seed in (0, 2):
        kwargs = dict(seed=seed, temperature=5.0 + 40.0 * ((seed * 0.618) % 1.0))
        a, b = simulate_stop(**kwargs), simulate_zupt_stop(**kwargs)
        assert b["truth_dph"] == pytest.approx(a["truth_dph"], rel=1e-12)
        assert b["mean_temperature"] == pytest.approx(a["mean_temperature"], rel=1e-12)
        assert b["std_dph"] == pytest.approx(a["std_dph"], rel=0.02)
        assert abs(b["estimate_dph"] - a["estimate_dph"]) < 0.25 * a["std_dph"]
        assert abs(b["error_dph"]) < 3 * b["std_dph"]
        assert abs(b["heading_error_arcsec"]) < 3 * b["heading_std_arcsec"]
        assert b["time"].shape == b["estimate_curve_dph"].shape == a["time"].shape
        assert b["std_curve_dph"][0] > b["std_curve_dph"][-1]  # the drift's sigma falls through the stop


def test_zupt_filter_subtracts_the_compensation_as_the_ins_does():
    """A compensation c0 (rad/s) on the azimuth gyro is a unit whose drift is c0 smaller: the same residual
    estimate, the estimate c0 larger."""
    from sarins_fmu.experiments.online_rls import imu_unit
    from sarins_fmu.units import RPS_TO_DPH

    c0 = 1e-7  # rad/s, 0.02 deg/h
    poly = np.asarray(imu_unit("nav-rlg").axial_drift_poly, float)
    a = simulate_zupt_stop(seed=3, coefficients=poly, compensation=[0.0, 0.0, c0], **SHORT)
    b = simulate_zupt_stop(seed=3, coefficients=poly - [0.0, 0.0, c0], **SHORT)
    assert a["estimate_dph"] - c0 * RPS_TO_DPH == pytest.approx(b["estimate_dph"], abs=1e-7)
    assert a["error_dph"] == pytest.approx(b["error_dph"], abs=1e-7)
    assert a["std_dph"] == pytest.approx(b["std_dph"], rel=1e-9)


def test_navigate_starts_from_the_given_row_and_refuses_a_bad_one():
    from sarins_fmu.aided import ImuNoise, navigate

    d = stop_data(seed=4, duration=20.0)
    truth = stop_truth(d)
    zeros = np.zeros_like(d.dtheta)
    start = truth.nav_rows([0])[0]
    start[3] = 0.5  # m/s east
    imu = (d.dtheta, d.dv, zeros, zeros)
    res = navigate(truth, noise=ImuNoise(arw=1e-6, vrw=1e-5), aiding=(), imu=imu, initial=start)
    assert res.error[0, 3] == pytest.approx(0.5, abs=0.01)  # no aiding: the start's velocity error stays
    with pytest.raises(ValueError, match="initial must be 9 finite"):
        navigate(truth, aiding=(), imu=imu, initial=start[:8])
    bad = start.copy()
    bad[6] = np.nan
    with pytest.raises(ValueError, match="initial must be 9 finite"):
        navigate(truth, aiding=(), imu=imu, initial=bad)


def test_campaign_zupt_stops_pair_with_the_plain_ones_and_match_their_schema():
    from sarins.online_rls.campaign import build_tasks

    for profile, least in (("quick", 1), ("paper", 20)):
        tasks = {t.id: t for t in build_tasks(profile, seed=7)}
        zupt = sorted(k for k in tasks if k.startswith("stop-zupt-nav-rlg-"))
        assert len(zupt) >= least
        for k in zupt:  # the same seed and temperature as the stop filter's stop
            plain = tasks["stop-nav-rlg-" + k.rsplit("-", 1)[1]]
            assert tasks[k].kwargs == plain.kwargs and tasks[k].fn is simulate_zupt_stop
            assert set(tasks[k].schema) == set(plain.schema) | {"heading_error_arcsec", "heading_std_arcsec"}


def test_report_pairs_the_two_filters_by_stop():
    from sarins.online_rls.report import stop_summary, zupt_stop_lines

    def stop(est, err, std, **extra):
        return {"estimate_dph": est, "error_dph": err, "std_dph": std, **extra}

    results = {}
    for k, (e_stop, e_zupt) in enumerate(((0.010, 0.011), (-0.020, -0.018), (0.001, 0.0005), (0.004, 0.003))):
        results[f"stop-nav-rlg-{k:03d}"] = stop(e_stop, e_stop, 0.016)
        results[f"stop-zupt-nav-rlg-{k:03d}"] = stop(e_zupt, e_zupt, 0.016, heading_error_arcsec=10.0 * (-1) ** k,
                                                     heading_std_arcsec=19.0)
    text = "\n".join(zupt_stop_lines(results))
    assert "| stop filter (eqs 4-6) | 4 | 0.0070 | -0.0169 .. 0.0091 | 0.0114 | 1/4 | 0.0160 |" in text
    assert "| aided filter, ZUPT | 4 | 0.0070 | -0.0152 .. 0.0098 | 0.0107 | 1/4 | 0.0160 |" in text
    # paired differences 0.001, 0.002, -0.0005, -0.001: rms 0.00132
    assert "differ by 0.0013 °/h rms" in text and "10.0\" rms (its own 1σ 19.0\")" in text
    assert stop_summary(results)["zupt-nav-rlg"]["runs"] == 4
    assert zupt_stop_lines({k: v for k, v in results.items() if "zupt" not in k}) == []
