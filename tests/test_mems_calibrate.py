"""Seed 003's calibrated unit: the scaled sizes, the fit of the traditional model's std reduction (a fake
f(k) in the default run, a small real calibration in the slow one), the recordings' keys and the report
section."""

import math
import re
from pathlib import Path

import pytest

from sarins.calibration_fit import ScaleFit, fit_scale
from sarins.mems_calibration import analysis
from sarins.mems_calibration import calibrate as cal
from sarins.mems_calibration import report as rep
from sarins_fmu import imu, imu_params
from sarins_fmu.experiments import mems_calibration as mc

ROOT = Path(__file__).resolve().parents[1]


def test_fit_scale_is_shared_with_seed_000():
    from sarins.axial_rbf import calibrate as axial

    assert axial.fit_scale is fit_scale and axial.ScaleFit is ScaleFit


def test_calibrated_terms_are_the_presets_unsourced_time_correlated_sizes():
    flat = imu_params.flatten(imu.preset("mems"))
    assert len(mc.CALIBRATED_TERMS) == 21 and set(mc.CALIBRATED_TERMS) <= set(flat)
    assert all(flat[name] != 0.0 for name in mc.CALIBRATED_TERMS)
    assert "gyro_bias_dtdt_x" not in mc.CALIBRATED_TERMS  # sourced ([STIM300]): not scaled
    rows = {m.group(1): m.group(2) for m in re.finditer(r"^\| `(\w+)_\[xyz\]` \|[^|]*\|[^|]*\| (\w+)",
                                                          _mems_table(), re.M)}
    for family in {name.rsplit("_", 1)[0] for name in mc.CALIBRATED_TERMS}:
        assert rows[family] == "unsourced", family
    assert mc.scaled_overrides(1.0) == {}
    doubled = mc.scaled_overrides(2.0)
    assert doubled == {name: 2.0 * flat[name] for name in mc.CALIBRATED_TERMS}
    for bad in (0.0, -1.0, math.nan, math.inf, mc.MAX_SCALE * 1.01):
        with pytest.raises(ValueError, match="scale"):
            mc.scaled_overrides(bad)


def _mems_table() -> str:
    text = (ROOT / "docs" / "imu-presets.md").read_text(encoding="utf-8")
    return text.split("## Preset `mems`")[1].split("\n## ")[0]


def test_max_scale_is_inside_the_cores_bounds_and_just_below_them():
    base = imu.StaticBase(0.5)
    imu.IMU(mc.recording_model("heldout", 3, scale=mc.MAX_SCALE), base, internal_rate=200.0)
    with pytest.raises(ValueError, match="gyro_scale_factor_dtdt"):
        over = imu_params.apply_overrides(imu.preset("mems"), {
            name: v * 25.0 / mc.MAX_SCALE for name, v in mc.scaled_overrides(mc.MAX_SCALE).items()})
        imu.IMU(over, base, internal_rate=200.0)


def test_scale_reaches_the_recording_and_an_ablation_still_wins():
    flat = imu_params.flatten(mc.recording_model("dynamic", 3, scale=3.0))
    preset = imu_params.flatten(imu.preset("mems"))
    assert flat["gyro_hysteresis_x"] == 3.0 * preset["gyro_hysteresis_x"]
    assert flat["gyro_bias_dtdt_x"] == preset["gyro_bias_dtdt_x"]
    off = mc.recording_overrides("heldout", 3, "hysteresis", scale=3.0)
    assert off["gyro_hysteresis_x"] == 0.0 and off["accel_rate_hysteresis_x"] == 3.0 * preset["accel_rate_hysteresis_x"]
    assert mc.recording_overrides("heldout", 3) == {}  # the sourced unit: the keys of earlier campaigns


def _fake_reductions(calls):
    def fake(k, *, profile_name, seed, prof):  # falls smoothly with k, as measured (15.4 % at k = 1)
        calls.append(k)
        return {"std": 15.4 / (1.0 + 0.14 * (k - 1.0)), "mean": 3.6 - 0.8 * (k - 1.0), "mae": 1.0, "sys": 1.0,
                "n_test": 1000}
    return fake


def test_calibration_fits_the_std_reduction_and_reports_the_mean(monkeypatch):
    calls = []
    monkeypatch.setattr(cal, "traditional_reductions", _fake_reductions(calls))
    fit = cal.calibrate_traditional()
    assert fit.converged and abs(fit.std_reduction / 4.7 - 1.0) <= fit.rtol
    assert calls[0] == 1.0 and [t[0] for t in fit.trials] == calls and len(calls) <= 12
    assert max(calls) <= mc.MAX_SCALE  # the search stays inside the core's bounds
    assert fit.mean_reduction == 3.6 - 0.8 * (fit.k - 1.0) and fit.paper_mean == 9.2
    preset = imu_params.flatten(imu.preset("mems"))
    assert fit.sizes == {name: preset[name] * fit.k for name in mc.CALIBRATED_TERMS}
    assert (fit.figure, fit.profile, fit.seed, fit.n_test) == ("seed 003, Table 3", "quick", 3, 1000)
    calls.clear()
    assert cal.calibrate_traditional().trials == fit.trials  # deterministic


def test_calibration_refuses_bad_targets_and_a_vanishing_reduction(monkeypatch):
    for bad in (0.0, 100.0, -4.7):
        with pytest.raises(ValueError, match="target"):
            cal.calibrate_traditional(target_std=bad)
    monkeypatch.setattr(cal, "traditional_reductions", lambda k, **_: {"std": 10.0 - k, "mean": 0.0, "n_test": 1})
    with pytest.raises(ValueError, match="std reduction is"):
        cal.calibrate_traditional(target_std=0.5)  # the bracket reaches k = 24, where 10 - k < 0


def _summary(profile="quick"):
    red = {name: {"mean": 10.0 + i, "std": 5.0 + i, "mae": 6.0 + i, "sys": 7.0 + i}
           for i, name in enumerate(("traditional", "rbf", "grnn", "lstm"))}
    fit = {"k": 16.97, "sizes": {"gyro_hysteresis_x": 1.0, "accel_bias_dtdt_x": 2.0}, "std_reduction": 4.71,
           "mean_reduction": -9.7, "target_std": 4.7, "paper_mean": 9.2, "figure": "seed 003, Table 3",
           "trials": [[1.0, 15.4, 3.6], [16.97, 4.71, -9.7]], "converged": True, "rtol": 0.02, "profile": "quick",
           "seed": 3, "n_test": 1000, "wall_seconds": 50.0}
    sub = {"profile": "quick", "n_test": 1000, "reductions": red, "order": analysis.ordering(red)}
    return {"reductions": {n: dict(r, std=r["std"] + 1) for n, r in red.items()}, "profile": profile,
            "calibrated": {"fit": fit, "summary": sub}}


def test_report_section_marks_the_fitted_row_and_keeps_the_sourced_unit():
    lines = rep.calibrated_section(_summary())
    text = "\n".join(lines)
    assert lines[0] == "## Calibrated unit (calibrated to seed 003, Table 3 traditional)"
    assert "k = **16.97**" in text and "`gyro_hysteresis_[xyz]`" in text and "`accel_bias_dtdt_[xyz]`" in text
    trad = next(line for line in lines if line.startswith("| traditional"))
    assert "| 10.0 / 6.0 | 10.0 / 5.0 (std: fitted to this: not a test) |" in trad
    assert sum("fitted to this" in line for line in lines) == 1
    assert "-9.7 % at the fitted k against the paper's 9.2 %" in text
    assert "the tables above stay the sourced unit's" in text
    assert "Recurrent > shallow > traditional holds on: |mean|, std, mean |r|, systematic" in text
    assert "profile's, the calibrated" not in text
    assert "The sourced unit's column is the paper profile's" in "\n".join(rep.calibrated_section(_summary("paper")))
    assert rep.calibrated_section({"reductions": {}}) == []
    assert rep._scale_text({"scale": 1.0}) == "" and "x 16.97" in rep._scale_text({"scale": 16.97})


def test_calibrated_campaign_keeps_its_own_recordings(monkeypatch, tmp_path):
    from sarins.mems_calibration import campaign

    runs = []
    monkeypatch.setattr("sarins.campaign.run_campaign", lambda tasks, folder, **_: runs.append(tasks) or {})
    monkeypatch.setattr("sarins.mems_calibration.storage.StoredRecordings", lambda result: result)
    campaign.record_all("quick", tmp_path, engine="inprocess", progress=False)
    campaign.record_all("quick", tmp_path / "c", engine="inprocess", scale=16.97, progress=False)
    plain, scaled = runs
    assert [t.id for t in plain] == [t.id for t in scaled] == list(mc.KINDS)
    assert all("scale" not in t.kwargs for t in plain)  # the sourced unit's records keep their keys
    assert all(t.kwargs["scale"] == 16.97 for t in scaled)
    with pytest.raises(ValueError, match="scale"):
        campaign.record_all("quick", tmp_path / "d", engine="inprocess", scale=30.0, progress=False)
    assert campaign.calibrated_folder(tmp_path, 16.97) == tmp_path / "calibrated-k16.97"


def test_cli_has_the_calibrate_flag():
    import argparse

    from sarins.mems_calibration import campaign

    parser = argparse.ArgumentParser()
    campaign.add_arguments(parser)
    assert parser.parse_args(["--calibrate"]).calibrate and not parser.parse_args([]).calibrate


@pytest.mark.slow  # about 20 s: a real calibration on a small profile (20 Hz records, short held-out run)
def test_small_calibration_converges_on_real_recordings():
    small = mc.with_profile(mc.profile("quick"), step=0.05, cal_step=0.25, warmup=60.0,
                            test={"step_c": 0.0, "hold_min": 2.0})
    at = {k: cal.traditional_reductions(k, prof=small) for k in (1.0, 6.0)}
    assert at[6.0]["std"] < at[1.0]["std"]  # the unseen terms grow: the traditional model removes less
    target = at[6.0]["std"]  # reached at k = 6 by construction
    fit = cal.calibrate_traditional(target_std=target, prof=small, profile_name="small")
    assert fit.converged and abs(fit.std_reduction / target - 1.0) <= fit.rtol
    assert fit.trials[0] == (1.0, at[1.0]["std"], at[1.0]["mean"])  # k = 1 is the sourced unit, bit for bit
    assert abs(math.log(fit.k / 6.0)) < 0.2 and len(fit.trials) <= 12
    assert fit.profile == "small" and fit.n_test == at[1.0]["n_test"]
