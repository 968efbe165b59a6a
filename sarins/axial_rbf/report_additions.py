"""Report sections for seed 000's missing steps: the multi-temperature
compensation before the hot network (and its sensitivity to the drift terms
beyond temperature), the cold network on the paper's 6 rows, the Fig. 1
longitude-sign question, and the noise x latitude sweep.

Every number printed here comes from the campaign summary
(:func:`sarins.axial_rbf.campaign.execute`); each function returns Markdown
lines (and writes its figure, if any, into the report folder).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sarins_fmu import imu as imu_mod
from sarins_fmu.experiments import axial_rbf as s0
from sarins_fmu.units import DPH_TO_RPS

from .fig1 import ratio_lon_to_lat, sign_analysis
from .runs import calibration_error_rms_dph
from .sweep import CLAIM_DPH


def _md(headers, rows) -> str:
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def _rms(entries) -> float:
    return float(np.sqrt(np.mean([e["error_dph"] ** 2 for e in entries])))


def _stats(entries) -> tuple:
    err = np.array([e["error_dph"] for e in entries])
    nm = np.array([e["max_nmi"] for e in entries])
    return (f"{np.sqrt(np.mean(err ** 2)):.5f}", f"{np.max(np.abs(err)):.5f}", f"{np.mean(nm):.2f}",
            f"{np.max(nm):.2f}")


# ---------------------------------------------------------------- multi-temperature compensation
MT_METHODS = [("rbf_hot_model", "hot network, no compensation (Table 4's setting without [15])"),
              ("mt_hot", "compensation + hot network trained on raw hot runs"),
              ("mt_hot_mt", "compensation + hot network trained on compensated hot runs (the paper's step)"),
              ("rbf", "cold network (24 rows), no compensation"),
              ("mt_cold_mt", "compensation + cold network trained on compensated cold runs")]


def multitemp_section(summary: dict) -> list[str]:
    """Calibration table and the cold held-out runs with and without the compensation."""
    mt = summary["multitemp"]
    cold = summary["comparison"].get("cold", {})
    set_ = mt["settings"]
    lines = ["## Multi-temperature compensation before the hot network (cold start)", "",
             "Seed 000 sec. 2.3: \"轴向陀螺漂移经过多温度点补偿后[15]，利用热态 RBF 神经网络进行辨识\" -- the axial "
             "drift is first compensated at multiple temperature points (its ref. [15]) and then identified with "
             "the hot network. Implemented in `sarins_fmu/identify/multitemp.py`: a simulated chamber calibration "
             f"of the unit (still, z up, one session, turn-on constant 0, seed {summary['seed']}) holds each "
             f"point {set_['settle_hours']:g} h to settle and averages the z-gyro rate minus W sin L over the next "
             f"{set_['average_hours']:g} h; the table (linear between points, held outside) is subtracted from the z "
             "gyro in real time from switch-on. The calibration costs "
             f"{mt['wall_seconds']:.0f} s of simulation.", "",
             _md(["point", "z-gyro temp. (degC)", "measured drift (deg/h)", "unit's steady law (deg/h)",
                  "calibration error (deg/h)"],
                 [(i + 1, f"{t:.2f}", f"{d:+.5f}", f"{w:+.5f}", f"{d - w:+.5f}")
                  for i, (t, d, w) in enumerate(zip(mt["temp_c"], mt["drift_dph"], mt["law_dph"]))]), ""]
    lines += [f"Calibration error RMS {calibration_error_rms_dph(mt):.5f} deg/h (white noise and bias instability "
              "over the averaging window, plus the z gyro's misalignment to the horizontal Earth rate, a constant "
              "the identification absorbs).", ""]
    present = [(k, label) for k, label in MT_METHODS if k in cold]
    if not present:
        return lines
    tests = summary["test"]["cold"]
    rows = []
    for i, t in enumerate(tests):
        row = [i + 1, f"{t['drift_dph']:+.5f}"]
        row += [f"{cold[k][i]['error_dph']:+.5f} / {cold[k][i]['max_nmi']:.2f}" for k, _ in present]
        rows.append(row)
    lines += ["Same held-out cold starts, identification error (deg/h) / 72 h position error (nmi), with and "
              "without the compensation. With the compensation the drift removed over the 72 h is the table's "
              "mean along the run's temperature plus the identified residual.", "",
              _md(["#", "true drift (deg/h)"] + [k for k, _ in present], rows), "",
              _md(["method", "what", "RMS error (deg/h)", "max error (deg/h)", "mean nmi/72h", "max nmi/72h"],
                  [(k, label, *_stats(cold[k])) for k, label in present]), ""]
    lines.append(_multitemp_verdict(cold, present))
    return lines + [""]


def _multitemp_verdict(cold: dict, present) -> str:
    rms = {k: _rms(cold[k]) for k, _ in present}
    text = "RMS identification error: " + ", ".join(f"{k} {rms[k]:.5f}" for k, _ in present) + " deg/h."
    if "mt_hot_mt" in rms and "rbf_hot_model" in rms:
        text += (f" The compensation before the hot network takes its RMS error from {rms['rbf_hot_model']:.5f} to "
                 f"{rms['mt_hot_mt']:.5f} deg/h (x{rms['mt_hot_mt'] / rms['rbf_hot_model']:.2f}).")
        if "rbf" in rms:
            side = "below" if rms["mt_hot_mt"] < rms["rbf"] else "above"
            text += (f" Compensation + hot network ends {side} the uncompensated cold network "
                     f"({rms['mt_hot_mt']:.5f} vs {rms['rbf']:.5f} deg/h).")
        text += " The paper found 0.0005-0.0015 deg/h after compensation + hot network."
        if rms["mt_hot_mt"] < 0.0005:
            text += (" Here it is lower: a table measured at steady points removes the static part of this "
                     "unit's drift, and what is left (the temperature-rate and block-gradient terms of the warm-up, "
                     "the hysteresis loop's branch, the calibration's error, the turn-on constant) is mostly "
                     "constant over the run. The gradient and hysteresis coefficients are sized from sources and "
                     "stated premises (docs/imu-presets.md), not to meet the paper's band; the paper's unit, whose "
                     "cold-start drift it found \"hard to remove by temperature compensation\", evidently changes "
                     "more over a run than they make this one.")
    return text


# ---------------------------------------------------------------- sensitivity to the terms beyond temperature
def sensitivity_section(summary: dict, band: tuple) -> list[str]:
    """The labelled sensitivity study (not a claim): compensation + hot network on units whose
    block-gradient, temperature-rate and hysteresis terms are k times the campaign's;
    ``band``: the paper's (low, high) drift error, deg/h."""
    from sarins.comparison import MIN_RUNS, Claim

    sens = summary.get("sensitivity")
    if not sens:
        return []
    lo, hi = band
    base = imu_mod.preset("nav-rlg")
    grad, hyst = base.axial_drift_grad / DPH_TO_RPS, base.axial_hysteresis / DPH_TO_RPS
    body, holds = [], []
    for k in sens["scales"]:
        entries = sens["rows"][k]
        err = np.abs([e["error_dph"] for e in entries])
        cells = Claim("x", band, err, digits=4).cells()
        inside = int(np.sum((err >= lo) & (err <= hi)))
        if lo <= float(np.median(err)) <= hi:
            holds.append(k)
        body.append((f"{k:g}" + (" (the campaign)" if k == 1.0 else ""), f"{k * grad:.2g}",
                     f"{k * s0.DTDT_DPH_PER_CPH:.2g}", f"{k * hyst:.2g}",
                     f"{sens['calibration_rms_dph'][k]:.5f}", cells[2], cells[3], f"{inside} of {len(err)}", cells[4],
                     f"{min(e['max_nmi'] for e in entries):.2f} .. {max(e['max_nmi'] for e in entries):.2f}"))
    n = len(sens["rows"][sens["scales"][0]])
    lines = ["## Sensitivity (not a claim): the drift terms beyond temperature x k", "",
             "The paper's 0.0005-0.0015 deg/h after compensation + hot network depends on how much of the unit's "
             "drift a steady-point table cannot see. This unit's three terms beyond temperature -- block-gradient "
             "coefficient, temperature-rate coefficient, heating/cooling hysteresis half-height -- have no public "
             "source (docs/imu-presets.md). Here all three are scaled together by k (block time constant "
             f"{base.axial_block_time_constant:g} s and loop width {base.axial_hysteresis_width:g} degC unchanged), "
             "and for each k the whole chain is redone on the scaled unit, in process: its own multi-temperature "
             "calibration, its compensated hot training runs, its hot_mt network, and the same held-out cold "
             "starts (same drifts, temperatures and noise seeds) compensated with its own table and identified "
             "with its own network. k = 1 is the campaign (its row equals the comparison table's). The other "
             "rows are what-ifs: no k other than 1 has a source, and none is a result about the paper's unit. "
             "*table - steady law*: the calibration table against the drift law at steady temperature; it holds "
             "the calibration's noise and, growing with k, the hysteresis branch the table takes in (the points "
             "are approached from below).",
             "", _md(["k", "gradient (deg/h/degC)", "rate (deg/h per degC/h)", "hysteresis (deg/h)",
                      "table - steady law, RMS (deg/h)", "abs. drift error, median (deg/h)", "5-95 %",
                      f"in {lo:g}-{hi:g}", "paper's band percentile in ours",
                      "max error over 72 h, lowest .. highest run (nmi)"], body), ""]
    ran = ", ".join(f"{k:g}" for k in sens["scales"])
    if n < MIN_RUNS:
        text = (f"**The {summary['profile']} profile is too small to test:** {n} held-out cold starts per k "
                f"(fewer than {MIN_RUNS}).")
    elif holds:
        first = sens["scales"].index(min(holds))
        gap = f"; k between {sens['scales'][first - 1]:g} and {min(holds):g} not run" if first else ""
        text = (f"The smallest k run at which the paper's band holds the median drift error is k = {min(holds):g} "
                f"(k run: {ran}{gap}). That factor has no source: it is what this unit's terms beyond temperature would "
                "have to be, against the sizes the campaign uses, for its compensated cold starts to reach the "
                "paper's band -- a published RLG coefficient of that size would be needed to call it the paper's.")
    else:
        text = f"The paper's band holds the median drift error at none of the k run ({ran}); no k has a source."
    text += f" The study added {sens['wall_seconds']:.0f} s to this invocation (reused runs are not rerun)."
    return lines + [text, ""]


# ---------------------------------------------------------------- the unit calibrated to seed 000, Table 4
def calibrated_section(summary: dict, sourced_claims: list, calibrated_claims: list, fitted: int) -> list[str]:
    """The unit calibrated to seed 000, Table 4 (``--calibrate``), beside the sourced unit: the fitted sizes
    and the figure fitted to, the search's trials, and every claim of the comparison table on both units.

    ``sourced_claims``, ``calibrated_claims``: the comparison table's claims
    (:func:`sarins.axial_rbf.report.comparison_claims`) of the sourced and the calibrated unit, in the
    same order; ``fitted``: the index of the claim the calibration fitted (not a test)."""
    from sarins.comparison import CALIBRATED_HEADER, MIN_RUNS, calibrated_rows

    cal = summary.get("calibrated")
    if not cal:
        return []
    fit, sub = cal["fit"], cal["summary"]
    k, target = fit["k"], fit["target_dph"]
    base = imu_mod.preset("nav-rlg")
    grad, hyst = base.axial_drift_grad / DPH_TO_RPS, base.axial_hysteresis / DPH_TO_RPS
    sourced_median = float(np.median(np.abs([e["error_dph"] for e in summary["comparison"]["cold"]["mt_hot_mt"]])))
    sizes = [("factor k on the three sizes", "1", f"{k:g}"),
             ("block-gradient coefficient k_g (deg/h/degC)", f"{grad:.3g}", f"{fit['gradient_dph_per_c']:.4g}"),
             ("temperature-rate coefficient d (deg/h per degC/h)", f"{s0.DTDT_DPH_PER_CPH:.3g}",
              f"{fit['rate_dph_per_cph']:.4g}"),
             ("hysteresis half-height H (deg/h)", f"{hyst:.3g}", f"{fit['hysteresis_dph']:.4g}"),
             ("median abs. drift error, compensation + hot network, cold starts (deg/h)",
              f"{sourced_median:.4g}", f"{fit['median_dph']:.4g} (target {target:.4g})")]
    lines = ["## Calibrated unit (calibrated to seed 000, Table 4)", "",
             "Everything above is the sourced unit, whose block-gradient coefficient, temperature-rate coefficient "
             "and hysteresis half-height are stated premises (docs/imu-presets.md). Here those three sizes are "
             "scaled together by one factor k (block time constant and loop width unchanged) and k is fitted by "
             "code (`sarins/axial_rbf/calibrate.py`) to one figure: the median, over the "
             f"{fit['n_runs']} held-out cold starts, of abs(table mean + identified residual - true drift) over the evaluation window "
             "equals the centre of seed 000's Table 4 band 0.0005-0.0015 deg/h, taken as its geometric centre "
             f"sqrt(0.0005 x 0.0015) = {target:.6f} deg/h (the band spans a factor 3; the search works on ln k "
             "and ln of the median). Each trial k redoes the sensitivity study's chain for that k: the scaled "
             "unit's own multi-temperature calibration, compensated hot training runs, hot_mt network and "
             "compensated held-out cold starts (in process; k = 1 is the sourced unit's comparison-table value). "
             "Search: from k = 1 by factors of 3 until the target is bracketed, then regula falsi (Illinois) on "
             f"ln k, trial k rounded to 4 digits, tolerance {100 * fit['rtol']:g} % on the median, at most 12 "
             "trials; deterministic (seeded experiments and noise).", "",
             _md(["size", "sourced unit (premise)", "calibrated to seed 000, Table 4"], sizes), "",
             "Trials (k: median deg/h): " + ", ".join(f"{tk:g}: {tv:.4g}" for tk, tv in fit["trials"])
             + f". {'Converged' if fit['converged'] else '**Not converged**'}: median/target - 1 = "
               f"{100 * (fit['median_dph'] / target - 1):+.2f} % after {len(fit['trials'])} trials "
               f"({fit['wall_seconds']:.0f} s, reused runs not rerun).", ""]
    body = calibrated_rows(sourced_claims, calibrated_claims, fitted)
    lines += ["The calibrated unit's campaign: the sourced campaign's experiments, drifts, temperatures and noise "
              "seeds on the calibrated unit, with its own multi-temperature calibration, training runs, networks "
              "and held-out runs (in process, no live runs). The fitted row is the calibration's own figure; "
              "every other row is validation of the calibrated unit against the rest of the paper (paper's "
              f"percentile as in the comparison table above; fewer than {MIN_RUNS} runs: not tested).", "",
              _md(CALIBRATED_HEADER, body), ""]
    hot, cold = sub["test"]["hot"], sub["test"]["cold"]
    if hot:
        herr = np.array([t["ident_dph"] - t["drift_dph"] for t in hot])
        text = (f"Calibrated unit, hot start: identification error RMS {np.sqrt(np.mean(herr ** 2)):.5f} deg/h, max "
                f"{np.max(np.abs(herr)):.5f} deg/h over {len(hot)} held-out experiments")
        if cold:
            wins = sum(t["max_cold_nmi"] < t["max_hot_nmi"] for t in cold)
            text += f"; cold start: the cold model beats the hot model on {wins} of {len(cold)}"
        lines += [text + ".", ""]
    lines += ["The sourced unit stays the campaign's unit and its comparison table the report's headline: k has no "
              "source beyond this one figure of the paper, so the calibrated sizes say what the paper's unit would "
              "have to do for Table 4, not what a published RLG does.", ""]
    return lines


# ---------------------------------------------------------------- 6 rows vs 24 rows
def cold6_section(summary: dict) -> list[str]:
    """The cold network trained on the paper's 6 rows beside the 24-row one."""
    cold = summary["comparison"].get("cold", {})
    six = summary.get("six", {})
    if not six or "rbf" not in cold:
        return []
    nets = summary["nets"]
    body = [("rbf (all rows)", nets["cold"].metadata.get("n_samples"), f"{nets['cold'].settings.spread:g}",
             nets["cold"].n_neurons, *_stats(cold["rbf"]))]
    for name, net in six.items():
        first = (int(name.rsplit("_", 1)[1]) - 1) * 6
        body.append((f"{name} (rows {first + 1}-{first + 6})", net.metadata.get("n_samples"),
                     f"{net.settings.spread:g}", net.n_neurons, *_stats(cold[name])))
    rms6 = [_rms(cold[name]) for name in six]
    tests = summary["test"]["cold"]
    per = [(i + 1, f"{t['drift_dph']:+.5f}", f"{cold['rbf'][i]['error_dph']:+.5f}",
            *(f"{cold[name][i]['error_dph']:+.5f}" for name in six)) for i, t in enumerate(tests)]
    return ["## Cold network: the paper's 6 rows beside all training rows", "",
            "The paper trained its cold network on the 6 rows of its Table 4. Here the cold network is also "
            "trained on each disjoint 6-row block of the training rows (generation order; block 1 is the "
            "paper-sized model), same inputs, goal and SPREAD selection (leave-one-out), evaluated on the same "
            "held-out cold starts (nmi/72h from the affine error map).", "",
            _md(["model", "rows", "SPREAD", "neurons", "RMS error (deg/h)", "max error (deg/h)", "mean nmi/72h",
                 "max nmi/72h"], body), "",
            _md(["#", "true drift (deg/h)", "all rows error (deg/h)"] + [f"{n} error (deg/h)" for n in six], per),
            "",
            f"RMS error with all {nets['cold'].metadata.get('n_samples')} rows {_rms(cold['rbf']):.5f} deg/h; with "
            f"6 rows {min(rms6):.5f} .. {max(rms6):.5f} deg/h over the {len(six)} blocks (mean "
            f"{np.mean(rms6):.5f}).", ""]


# ---------------------------------------------------------------- Fig. 1 longitude sign
def fig1_section(summary: dict) -> list[str]:
    """The closed-form check and the sign statistics of the simulated runs."""
    fig = summary["fig1"]
    c = fig["check"]
    rows = [(f"{d:+.4f}", f"{h:+.0f}", f"{sl:+.6f}", f"{cl:+.6f}", f"{so:+.6f}", f"{co:+.6f}")
            for d, h, sl, cl, so, co in zip(c["drift_dph"], c["heading_arcsec"], c["sim_lat_deg"], c["cf_lat_deg"],
                                            c["sim_lon_deg"], c["cf_lon_deg"])]
    ratio = ratio_lon_to_lat(s0.SITE_LAT_DEG)
    lines = ["## Fig. 1: the sign of the longitude error", "",
             "The paper (sec. 2.1): at 12 h, \"纬度误差输出为正时，经度误差时正时负\" -- with a positive latitude "
             "error the longitude error is sometimes positive, sometimes negative -- so it uses the latitude "
             "error only. Closed form on a static base (Titterton & Weston sec. 12.3, Savage ch. 12; "
             "`sarins_fmu/static_errors.py`): a constant azimuth drift e gives dL = (cos L/W)(1 - cos Wt) e and "
             "dlon = sin L (t - sin Wt / W) e, the same sign at every t > 0 (at 12 h dlon/dL = tan L (Wt - sin Wt)/"
             f"(1 - cos Wt) = {ratio:.3f} at 28.222 deg); an initial heading error phi_U gives dL = -cos L sin(Wt) "
             "phi_U, which vanishes at 12 h (the paper's reason for 12 h), and dlon = -sin L (1 - cos Wt) phi_U, "
             "largest at 12 h (-2 sin L phi_U).", "",
             "Ideal IMU started on the true attitude (with the heading error given), 12 h at 28.222 deg, "
             "simulation against the closed form (deg):", "",
             _md(["drift (deg/h)", "heading error (arcsec)", "sim. dL", "closed form dL", "sim. dlon",
                  "closed form dlon"], rows), ""]
    lines += _sign_lines("Campaign runs (nav-rlg unit, 4 h alignment, hot and cold, training and held-out)",
                         fig["signs"])
    sweep = summary.get("sweep")
    if sweep:
        lines += _sweep_sign_lines(sweep)
    lines.append(_fig1_verdict(fig["signs"], ratio))
    return lines + [""]


def _sign_lines(what: str, s: dict) -> list[str]:
    lines = [f"{what}: {s['n']} runs; {s['lat_pos']} with a positive 12 h latitude error, "
             f"{s['lat_pos_lon_neg']} of them with a negative longitude error; signs differ on {s['differ']} of "
             f"{s['n']}."]
    if "n_decomposed" in s:
        lines[-1] += (f" On the {s['n_decomposed']} in-process runs (alignment heading error known, RMS "
                      f"{s['heading_rms_arcsec']:.1f} arcsec): RMS longitude error {s['rms_lon_deg']:.5f} deg; "
                      f"after subtracting the closed form of the run's own deterministic drift "
                      f"{s['rms_minus_drift_deg']:.5f} deg; after subtracting the heading-error term too "
                      f"{s['rms_minus_both_deg']:.5f} deg. The drift alone predicts differing signs on "
                      f"{s['drift_only_differ']} runs; of the {s['differ_decomposed']} runs with differing signs, "
                      f"drift + heading closed form predicts {s['differ_predicted']}.")
    return lines + [""]


def _sweep_sign_lines(sweep: dict) -> list[str]:
    body = []
    scales = sorted({p["noise_scale"] for p in sweep["points"]})
    scale = min(scales, key=lambda v: abs(v - s0.GYRO_NOISE_SCALE))
    for lat in sorted({p["lat_deg"] for p in sweep["points"]}):
        rows = [r for r in sweep["rows"] if r["lat_deg"] == lat and r["noise_scale"] == scale]
        s = sign_analysis(rows)
        body.append((f"{lat:g}", s["n"], s["lat_pos"], s["lat_pos_lon_neg"], s["differ"],
                     f"{s['heading_rms_arcsec']:.1f}", f"{s['rms_minus_drift_deg']:.5f}",
                     f"{s['rms_minus_both_deg']:.5f}", f"{s['differ_predicted']} / {s['differ_decomposed']}"))
    return [f"Sweep runs (hot starts, noise scale {scale:g}) by latitude (at the equator sin L = 0 takes both the "
            "drift and the heading term out of the longitude error, so its sign is anyone's):", "",
            _md(["latitude (deg)", "runs", "dL > 0", "of which dlon < 0", "signs differ", "heading error RMS (arcsec)",
                 "dlon - drift term RMS (deg)", "dlon - drift - heading RMS (deg)", "differing signs predicted"],
                body), ""]


def _fig1_verdict(s: dict, ratio: float) -> str:
    text = (f"**Finding.** In the campaign's runs the paper's observation is rare: {s['lat_pos_lon_neg']} of "
            f"{s['lat_pos']} runs with a positive latitude error have a negative longitude error (all signs: "
            f"{s['differ']} of {s['n']} differ). The azimuth drift alone "
            f"gives the longitude error the sign of the latitude error ({ratio:.2f} of it at 12 h)")
    if "n_decomposed" in s:
        text += (f" (the drift closed form predicts differing signs on {s['drift_only_differ']} of the "
                 f"{s['n_decomposed']} decomposed runs). The heading error the alignment leaves "
                 f"({s['heading_rms_arcsec']:.1f} arcsec RMS) reaches the longitude error at 12 h with its largest "
                 "weight, -2 sin L phi_U, while it cancels from the latitude error: adding it to the closed form "
                 f"takes the longitude residual from {s['rms_minus_drift_deg']:.5f} to {s['rms_minus_both_deg']:.5f} "
                 f"deg and predicts {s['differ_predicted']} of the {s['differ_decomposed']} differing signs. A "
                 "sign flip needs |drift| (t - sin Wt/W) < (1 - cos Wt) |phi_U|, i.e. below "
                 f"{s['flip_threshold_dph']:.5f} deg/h for the RMS heading error; {s['below_threshold']} of the "
                 f"{s['n_decomposed']} decomposed runs have a drift that small, and it flips only where the heading "
                 f"error has the opposite sign (the drifts are uniform in +-{s0.DRIFT_RANGE_DPH} deg/h). The paper's "
                 "mixed signs thus point to drifts below such a threshold, larger heading errors than here, or "
                 "longitude-error sources this unit does not have")
    return text + (". The longitude error at 12 h thus mixes the drift with the heading error and cannot give the "
                   "drift alone (the paper's \"singular solution\"); the latitude error holds the drift and almost "
                   "none of the heading error.")


# ---------------------------------------------------------------- sweep
def sweep_section(sweep: dict, folder: Path) -> tuple[list[str], list[str]]:
    """Table and figure of the noise x latitude sweep; returns (lines, figure names)."""
    pts = sweep["points"]
    scales = sorted({p["noise_scale"] for p in pts})
    lats = sorted({p["lat_deg"] for p in pts})
    at = {(p["noise_scale"], p["lat_deg"]): p for p in pts}

    def cell(p):
        mark = "**yes**" if p["holds"] else "no"
        return f"{p['rbf_rms_dph']:.5f} / {p['rbf_max_dph']:.5f} / {p['floor_dph']:.5f} {mark}"

    body = [(f"{s:g}", *(cell(at[(s, lat)]) for lat in lats)) for s in scales]
    n = pts[0]
    cf = [(f"{s:g}", *(f"{at[(s, lat)]['closed_rms_dph']:.5f} ({at[(s, lat)]['closed_within'] * 100:.0f} %)"
                       for lat in lats)) for s in scales]
    held = [p for p in pts if p["holds"]]
    lines = ["## Identification error over gyro noise and latitude (sweep)", "",
             f"Grid **{sweep['grid']}**, seed {sweep['seed']}: hot starts, {n['n_train']} training and "
             f"{n['n_test']} held-out experiments per point, the same experiments (drifts, temperatures, noise "
             "seeds) at every point; only the gyro white noise and bias instability (scale s times the nav-rlg "
             "preset's; a sensitivity study: the campaign's unit is s = "
             f"{s0.GYRO_NOISE_SCALE:g}, the preset's own noise) and the site latitude change. Each point trains its own hot "
             "network (SPREAD by leave-one-out). Cells: RBF RMS / max error on the held-out rows / analytic 1-sigma "
             "floor sqrt(3/2 (N^2 + 2 sigma_b^2 tau) t) / (cos L (1 - cos Wt)/W) (`sarins_fmu/static_errors.py`), "
             f"deg/h; **yes** where every held-out error is below the paper's {CLAIM_DPH} deg/h.", "",
             _md(["noise scale \\ latitude (deg)"] + [f"{lat:g}" for lat in lats], body), "",
             "Closed-form inversion of Table 1 on all rows of each point (no training): RMS error, deg/h (share of "
             f"rows within {CLAIM_DPH} deg/h):", "",
             _md(["noise scale \\ latitude (deg)"] + [f"{lat:g}" for lat in lats], cf), "",
             _sweep_verdict(pts, held), ""]
    return lines, [_sweep_figure(pts, scales, lats, folder)]


def _sweep_verdict(pts, held) -> str:
    ratio = np.array([p["closed_rms_dph"] / p["floor_dph"] for p in pts if p["floor_dph"] > 0])
    floor_ok = [p for p in pts if p["floor_holds"]]
    text = (f"**Where 0.0003 deg/h holds.** Every held-out error of the point's RBF network was below it at "
            f"{len(held)} of {len(pts)} points ({_where(held)}). The analytic floor puts 2 sigma (95 % of "
            f"identifications) below it at {len(floor_ok)} points ({_where(floor_ok)}). The closed-form RMS over "
            f"all rows is {ratio.min():.2f} .. {ratio.max():.2f} times the analytic floor (median "
            f"{np.median(ratio):.2f}): the error is the gyro noise in the 12 h latitude error, growing with the "
            "noise scale and as 1/cos L with latitude (the latitude error's sensitivity to the drift is "
            "cos L (1 - cos Wt)/W while its noise does not depend on latitude).")
    gap = max(p["truth_gap_rms_dph"] for p in pts)
    low = min(pts, key=lambda p: p["noise_scale"])["noise_scale"]
    low_cf = [p["closed_rms_dph"] for p in pts if p["noise_scale"] == low]
    text += (f" Below the noise sits a deterministic part: the 12 h latitude error weighs the drift's history over "
             "the first 12 h, the truth is its 72 h mean, and on these hot starts (daily ambient swing up to 1 degC, "
             f"drift slope {s0.K1_DPH_PER_C:g} deg/h per degC) the two differ by up to {gap:.5f} deg/h RMS (mean "
             f"{np.mean([p['truth_gap_mean_dph'] for p in pts]):+.5f}): the closed form levels off there at "
             f"s = {low:g} ({min(low_cf):.5f} .. {max(low_cf):.5f} deg/h), while a trained network can absorb the "
             "mean offset.")
    here = min(pts, key=lambda p: abs(p["noise_scale"] - s0.GYRO_NOISE_SCALE) + abs(p["lat_deg"] - s0.SITE_LAT_DEG))
    text += (f" The held-out rows are the same experiments at every point, and their noise happens to be "
             f"{'smaller' if here['closed_test_rms_dph'] < here['closed_train_rms_dph'] else 'larger'} than the "
             f"training rows' (closed form at s = {here['noise_scale']:g}, {here['lat_deg']:g} deg: RMS "
             f"{here['closed_test_rms_dph']:.5f} on them against {here['closed_train_rms_dph']:.5f} deg/h on the "
             "training rows), so the per-point RBF figures share that draw; the floor is the sample-free "
             "statement.")
    odd = [p for p in pts if p["spread"] != 8.0]
    if odd:
        text += (" Leave-one-out chose a SPREAD other than 8 at " + ", ".join(
            f"s = {p['noise_scale']:g}, {p['lat_deg']:g} deg (SPREAD {p['spread']:g}, max error "
            f"{p['rbf_max_dph']:.4f} deg/h)" for p in odd)
                 + ": narrow Gaussians fitted to noisy rows do not extrapolate to held-out inputs outside the "
                   "training ones, where the closed form (no training) stays at the floor.")
    return text


def _where(points) -> str:
    by_lat = {}
    for p in points:
        by_lat.setdefault(p["lat_deg"], []).append(p["noise_scale"])
    return "; ".join(f"{lat:g} deg: s = {', '.join(f'{v:g}' for v in sorted(vals))}"
                     for lat, vals in sorted(by_lat.items())) or "nowhere"


def _sweep_figure(pts, scales, lats, folder: Path) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, lat in enumerate(lats):
        row = [next(p for p in pts if p["noise_scale"] == s and p["lat_deg"] == lat) for s in scales]
        color = f"C{i}"
        ax.loglog(scales, [p["closed_rms_dph"] for p in row], "o-", color=color, label=f"{lat:g} deg")
        ax.loglog(scales, [p["rbf_rms_dph"] for p in row], "x", color=color, ms=7)
        ax.loglog(scales, [p["floor_dph"] for p in row], "--", color=color, lw=1)
    ax.axhline(CLAIM_DPH, color="k", ls=":", label="0.0003 deg/h (paper)")
    ax.set_xlabel("gyro noise scale (x nav-rlg ARW and bias instability)")
    ax.set_ylabel("identification error RMS (deg/h)")
    ax.set_title("Hot start: closed form, all rows (o-); RBF, held-out (x); analytic floor (--)", fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    name = "fig5_sweep.png"
    fig.savefig(Path(folder) / name, dpi=90)
    plt.close(fig)
    return name
