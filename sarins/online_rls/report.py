"""Tables, figures (PNG) and the Markdown report of ``sarins campaign online-rls``.

Takes the campaign's ``{task id: result dict}`` (see :mod:`sarins.online_rls.campaign`) and
writes ``report.md``, ``summary.json`` and the figures into the output
directory.  Units of the papers: °/h, °/h·°C (S), m, °C.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np


HEAD_VEHICLE = "veh-markov-nav-rlg"  # configuration shown in Figs 7-8 and Table 4
HEAD_MC = "mc-markov-nav-rlg-filter"  # configuration shown in Figs 4-6 and Table 1
HEAD_STOP = "stop-nav-rlg"  # the stop filter's headline unit
HEAD_STOP_INDEXED = "stop-indexed-nav-rlg"  # the same stops with the RINS indexed (issue 20)
# seed 002's headline numbers: sec. 2 (stop filter), Table 2 (mean S), Table 5 (vehicle)
PAPER_STOP_DPH = 0.002
PAPER_S_FF = 0.066
PAPER_FF_OVER_NONE = 0.5
PAPER_CEP_CHANGE_PCT = -47.0
PAPER_MAX_RADIAL_CHANGE_PCT = -78.0


def _group(results: dict, prefix: str) -> list:
    return [results[k] for k in sorted(results) if k.startswith(prefix)]


def _configs(results: dict, kind: str) -> list:
    """Distinct '<kind>-<...>' configuration prefixes (without the seed)."""
    return sorted({k.rsplit("-", 1)[0] for k in results if k.startswith(kind + "-")})


def stop_summary(results: dict) -> dict:
    """Stop-filter statistics per unit ('indexed-<unit>': the indexed stops): runs, rms / max error,
    mean 1σ, within 0.002 °/h, median abs error and the 5 and 95 % points of the error."""
    out = {}
    for cfg in _configs(results, "stop"):
        runs = _group(results, cfg + "-")
        err = np.array([r["error_dph"] for r in runs])
        out[cfg.split("-", 1)[1]] = {
            "runs": len(runs), "rms_error_dph": float(np.sqrt(np.mean(err**2))),
            "mean_error_dph": float(np.mean(err)), "max_abs_error_dph": float(np.max(np.abs(err))),
            "mean_std_dph": float(np.mean([r["std_dph"] for r in runs])),
            "within_0.002": int(np.sum(np.abs(err) < 0.002)),
            "median_abs_error_dph": float(np.median(np.abs(err))),
            "p5_error_dph": float(np.percentile(err, 5.0)), "p95_error_dph": float(np.percentile(err, 95.0)),
        }
    return out


def mc_summary(results: dict) -> dict:
    """Mean S (°/h·°C) per configuration for no update / RLS / FF-RLS and the λ sweep."""
    out = {}
    for cfg in _configs(results, "mc"):
        runs = _group(results, cfg + "-")
        s = np.array([[r["s_none"], r["s_rls"], r["s_ff"]] for r in runs])
        lam = np.array([r["s_lambda"] for r in runs])
        out[cfg[3:]] = {
            "runs": len(runs), "mean_s_none": float(s[:, 0].mean()), "mean_s_rls": float(s[:, 1].mean()),
            "mean_s_ff": float(s[:, 2].mean()), "ff_over_none": float(s[:, 2].mean() / s[:, 0].mean()),
            "ff_better_runs": int(np.sum(s[:, 2] < s[:, 0])),
            "lambdas": np.asarray(runs[0]["sensitivity_lambdas"]).tolist(),
            "mean_s_lambda": lam.mean(axis=0).tolist(),
            "calibration_rms_dph": float(np.mean([r["calibration_rms_dph"] for r in runs])),
            "stop_rms_error_dph": float(np.sqrt(np.mean(np.concatenate([r["stop_error_dph"] for r in runs]) ** 2))),
        }
    return out


def vehicle_summary(results: dict) -> dict:
    """CEP / max radial error (m) initial vs updated model per configuration."""
    out = {}
    for cfg in _configs(results, "veh"):
        runs = _group(results, cfg + "-")
        get = lambda key, runs=runs: np.array([r[key] for r in runs], float)  # noqa: E731
        out[cfg[4:]] = {
            "runs": len(runs), "mean_updates": float(get("n_updates").mean()),
            "mean_cep_initial": float(get("cep_initial").mean()), "mean_cep_updated": float(get("cep_updated").mean()),
            "mean_max_initial": float(get("max_radial_initial").mean()),
            "mean_max_updated": float(get("max_radial_updated").mean()),
            "median_cep_initial": float(np.median(get("cep_initial"))),
            "median_cep_updated": float(np.median(get("cep_updated"))),
            "runs_improved_cep": int(np.sum(get("cep_updated") < get("cep_initial"))),
            "mean_s_initial": float(get("s_initial").mean()), "mean_s_updated": float(get("s_updated").mean()),
        }
    return out


BOUND_LAT_DEG = 40.0  # latitude of the campaign's stops (online_rls.simulate_stop), deg
BOUND_STOP_S = 1800.0  # the paper's 30-minute stop, s


def stop_bound(unit: str, lat_deg: float = BOUND_LAT_DEG, duration: float = BOUND_STOP_S) -> dict:
    """Filter-independent 1-sigma azimuth-drift accuracy of a stop (deg/h), :mod:`sarins_fmu.stop_accuracy`.

    ``full``: the unit's gyro ARW on all axes and its VRW; ``horizontal``: only the
    horizontal gyros' ARW; ``azimuth``: the azimuth gyro's ARW and the VRW;
    ``heading_walk``: N/sqrt(T); ``with_prior``: ``full`` combined with the stop
    filter's prior on the drift (``StopFilterSettings.azimuth_drift0_std``)."""
    import math

    from sarins_fmu.experiments.online_rls import imu_unit
    from sarins_fmu.kalman import StopFilterSettings
    from sarins_fmu.stop_accuracy import stop_drift_accuracy
    from sarins_fmu.units import DEG_TO_RAD, RPS_TO_DPH

    model = imu_unit(unit)
    arw_h, arw_u = float(model.gyro.random_walk[0]), float(model.gyro.random_walk[2])
    vrw = float(model.accel.random_walk[0])
    lat = lat_deg * DEG_TO_RAD
    acc = lambda **kw: stop_drift_accuracy(lat=lat, duration=duration, **kw)  # noqa: E731
    full = acc(arw_horizontal=arw_h, arw_azimuth=arw_u, vrw=vrw)
    prior = StopFilterSettings.for_model(model).azimuth_drift0_std
    return {"unit": unit, "arw_dpsh": arw_h * 60.0 / DEG_TO_RAD, "vrw_ug": vrw / 9.80665e-6,
            "full": full.final_std * RPS_TO_DPH,
            "horizontal": acc(arw_horizontal=arw_h, arw_azimuth=0.0, vrw=0.0).final_std * RPS_TO_DPH,
            "azimuth": acc(arw_horizontal=0.0, arw_azimuth=arw_u, vrw=vrw).final_std * RPS_TO_DPH,
            "heading_walk": full.heading_walk_std * RPS_TO_DPH, "prior": prior * RPS_TO_DPH,
            "with_prior": 1.0 / math.sqrt(1.0 / full.final_std**2 + 1.0 / prior**2) * RPS_TO_DPH}


def stop_bound_lines(units=("nav-rlg", "premise")) -> list:
    """Markdown section: what limits the 30-minute stop (the bound of :func:`stop_bound`)."""
    rows = [stop_bound(u) for u in units]
    lines = ["## What limits the 30-minute stop (a bound independent of the filter)", "",
             "1-sigma accuracy that any unbiased estimate of a constant azimuth drift can reach from "
             f"{BOUND_STOP_S / 60:.0f} min of zero-velocity data at {BOUND_LAT_DEG:g} deg N, the initial velocity, "
             "tilt and heading errors unknown (a linear-Gaussian covariance computation, "
             "`sarins_fmu.stop_accuracy`, the Fisher information of the drift with the tilt random walk as a "
             "nuisance; the rotation modulates the horizontal biases away; Gauss-Markov bias instability left out, "
             "so the bound is optimistic), °/h:", "",
             "| unit | gyro ARW (°/√h) | VRW (µg/√Hz) | bound, all noise | horizontal gyros' ARW only | "
             "azimuth gyro ARW + VRW only | heading walk N/√T | bound with the filter's prior |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['unit']} | {r['arw_dpsh']:g} | {r['vrw_ug']:g} | {_fmt(r['full'])} | "
                     f"{_fmt(r['horizontal'])} | {_fmt(r['azimuth'])} | {_fmt(r['heading_walk'])} | "
                     f"{_fmt(r['with_prior'])} (prior {r['prior']:g}) |")
    nav = rows[0]
    lines += ["", "The azimuth drift reaches the velocity only through the Earth rate "
              "(φ_U = −ε t, φ_E = Ω cos L ε t²/2, δv_N = g Ω cos L ε t³/6: 5 mm/s for 0.002 °/h after 30 min "
              "at 40°). The horizontal gyros' random walk makes the tilt wander, and its velocity error grows as "
              "g N t^1.5/√3, which hides the drift's t³ signature: on "
              f"{nav['unit']} the horizontal gyros alone limit the drift to {_fmt(nav['horizontal'])} °/h, the "
              f"azimuth gyro's random walk and the accelerometer noise to {_fmt(nav['azimuth'])} °/h, and the "
              f"heading random walk read as N/√T would allow {_fmt(nav['heading_walk'])} °/h. It is the tilt "
              "random walk, not the heading random walk, that keeps 0.002 °/h out of reach in 30 min at the "
              "preset's noise while the azimuth gyro stays vertical (indexing the RINS during the stop changes "
              f"that, `sarins_fmu.stop_indexing`). The stop filter's own 1σ combines this bound with its prior on the drift "
              f"({nav['prior']:g} °/h): {_fmt(nav['with_prior'])} °/h.", ""]
    return lines


def indexed_stop_bound(unit: str = "nav-rlg", lat_deg: float = BOUND_LAT_DEG, duration: float = BOUND_STOP_S) -> dict:
    """The bound of :func:`stop_bound` with the RINS indexed through ``STOP_SEQUENCE`` (deg/h):
    ``full`` (every body-frame gyro drift and accelerometer bias unknown,
    :func:`sarins_fmu.stop_indexing.indexed_drift_accuracy`), ``gyrocompass`` (N_z / sqrt(T), a drift read
    from a directly observed tilt), ``with_prior`` (``full`` with the filter's prior on the drift)."""
    import math

    from sarins_fmu.experiments.online_rls import imu_unit
    from sarins_fmu.experiments.online_rls_indexed import STOP_SEQUENCE
    from sarins_fmu.kalman import StopFilterSettings
    from sarins_fmu.stop_indexing import indexed_drift_accuracy, indexing_schedule, rotation_samples
    from sarins_fmu.units import DEG_TO_RAD, RPS_TO_DPH

    model = imu_unit(unit)
    n = int(round(duration))
    rotations = rotation_samples(indexing_schedule(STOP_SEQUENCE, float(n)), n, substeps=4)
    acc = indexed_drift_accuracy(lat=lat_deg * DEG_TO_RAD, rotations=rotations, arw=model.gyro.random_walk,
                                 vrw=model.accel.random_walk)
    prior = StopFilterSettings.for_model(model).azimuth_drift0_std
    return {"unit": unit, "full": acc.final_std * RPS_TO_DPH, "gyrocompass": acc.gyrocompass_std * RPS_TO_DPH,
            "with_prior": 1.0 / math.sqrt(1.0 / acc.final_std**2 + 1.0 / prior**2) * RPS_TO_DPH}


def _distribution(errors) -> dict:
    e = np.asarray(errors, float)
    p5, p95 = np.percentile(e, [5.0, 95.0])
    return {"runs": len(e), "median_abs": float(np.median(np.abs(e))), "p5": float(p5), "p95": float(p95),
            "within": int(np.sum(np.abs(e) < PAPER_STOP_DPH)), "rms": float(np.sqrt(np.mean(e**2)))}


def indexed_stop_lines(results: dict, unit: str = "nav-rlg") -> list:
    """Markdown section: the 30-min stop with and without indexing, the error distributions beside the bounds."""
    from sarins_fmu.experiments.online_rls_indexed import STOP_SEQUENCE

    plain, indexed = _group(results, f"stop-{unit}-"), _group(results, f"stop-indexed-{unit}-")
    if not indexed:
        return []
    seq = STOP_SEQUENCE
    positions = ", ".join(f"({o:g}°, {i:g}°)" for o, i in seq.positions_deg)
    b0, b1 = stop_bound(unit), indexed_stop_bound(unit)
    lines = [f"## Indexing the dual-axis RINS during the stop ({unit})", "",
             f"Sequence (outer, inner gimbal angle): {positions}; holds {', '.join(f'{h:g}' for h in seq.holds)} s "
             f"(the last to the end of the stop), moves at {seq.rate_dps:g} °/s, {seq.accel_dps2:g} °/s², one gimbal "
             "at a time: the azimuth gyro's axis horizontal to the vehicle's right, left, left, right "
             "(`sarins_fmu.experiments.online_rls_indexed.STOP_SEQUENCE`). Its drift then tilts the IMU at first "
             "order (gyrocompass-like) instead of through the Earth rate's t³ path. Same seeds and temperatures "
             "with and without indexing; without: the forward-reverse azimuth rotation and the 11-state filter; "
             "with: the 12-state `IndexedStopFilter` fed the known rotations.", "",
             "| stop | runs | median abs error (°/h) | error 5-95 % (°/h) | rms (°/h) | within 0.002 °/h | "
             "mean filter 1σ | bound (1σ) | bound with the filter's prior |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, runs, bound in (("without indexing", plain, b0), ("with indexing", indexed, b1)):
        if not runs:
            continue
        d = _distribution([r["error_dph"] for r in runs])
        lines.append(f"| {name} | {d['runs']} | {_fmt(d['median_abs'])} | {_fmt(d['p5'])} .. {_fmt(d['p95'])} | "
                     f"{_fmt(d['rms'])} | {d['within']}/{d['runs']} ({100.0 * d['within'] / d['runs']:.0f} %) | "
                     f"{_fmt(float(np.mean([r['std_dph'] for r in runs])))} | {_fmt(bound['full'])} | "
                     f"{_fmt(bound['with_prior'])} |")
    lines += ["", f"Bound with indexing: every body-frame gyro drift and accelerometer bias unknown; the "
              f"gyrocompass limit N/√T (a drift read from a directly observed tilt) is {_fmt(b1['gyrocompass'])} °/h. "
              f"Without indexing the horizontal gyros' random walk hides the t³ signature ({_fmt(b0['full'])} °/h).", ""]
    return lines


def zupt_stop_lines(results: dict, unit: str = "nav-rlg") -> list:
    """Markdown section: the same stops through the stop filter (eqs 4-6) and through the aided navigation
    filter with a zero-velocity update at every step (``stop-zupt-<unit>-*``), paired by seed."""
    zupt = {k.rsplit("-", 1)[1]: results[k] for k in results if k.startswith(f"stop-zupt-{unit}-")}
    pairs = [(results[f"stop-{unit}-{i}"], zupt[i]) for i in sorted(zupt) if f"stop-{unit}-{i}" in results]
    if not pairs:
        return []
    b0 = stop_bound(unit)
    lines = [f"## The stop through the aided filter's zero-velocity updates ({unit})", "",
             "The same stops (seeds, temperatures, IMU records, initial INS errors) through the paper's stop filter "
             "(eqs 4-6: 11 states, static error model, open loop on the free INS) and through the aided navigation "
             "filter a vehicle runs at every stop (`sarins_fmu.aided`: 15 states, a zero-velocity update at every "
             "1 s step, fed back into its INS; `sarins_fmu.experiments.online_rls_zupt`), given the same noise "
             "densities, velocity-measurement std and priors (one gyro-bias prior for the three axes: the azimuth "
             "prior).", "",
             "| filter | runs | median abs error (°/h) | error 5-95 % (°/h) | rms (°/h) | within 0.002 °/h | "
             "mean filter 1σ (°/h) |", "|---|---|---|---|---|---|---|"]
    for name, key in (("stop filter (eqs 4-6)", 0), ("aided filter, ZUPT", 1)):
        runs = [pair[key] for pair in pairs]
        d = _distribution([r["error_dph"] for r in runs])
        lines.append(f"| {name} | {d['runs']} | {_fmt(d['median_abs'])} | {_fmt(d['p5'])} .. {_fmt(d['p95'])} | "
                     f"{_fmt(d['rms'])} | {d['within']}/{d['runs']} | "
                     f"{_fmt(float(np.mean([r['std_dph'] for r in runs])))} |")
    diff = np.array([b["estimate_dph"] - a["estimate_dph"] for a, b in pairs])
    a_est = np.array([a["estimate_dph"] for a, _ in pairs])
    b_est = np.array([b["estimate_dph"] for _, b in pairs])
    corr = float(np.corrcoef(a_est, b_est)[0, 1]) if len(pairs) > 2 else float("nan")
    head = np.array([b["heading_error_arcsec"] for _, b in pairs])
    head_std = float(np.mean([b["heading_std_arcsec"] for _, b in pairs]))
    lines += ["", f"Paired by stop, the two estimates differ by {_fmt(float(np.sqrt(np.mean(diff**2))))} °/h rms "
              f"(correlation {corr:.3f}); the filter-independent bound is {_fmt(b0['full'])} °/h "
              f"({_fmt(b0['with_prior'])} °/h with the prior). The aided filter's INS leaves the stop with a heading "
              f"error of {float(np.sqrt(np.mean(head**2))):.1f}\" rms (its own 1σ {head_std:.1f}\"): the stop's "
              "gyrocompassing, fed back into the INS (the stop filter estimates the heading error open loop).", ""]
    return lines


FITTED_CLAIM = 2  # index of the claim ``--calibrate`` fits (mean S after FF-RLS): not a test on that unit


def comparison_claims(results: dict, unit: str = "nav-rlg") -> list:
    """Seed 002's headline claims against the headline configurations' runs (:mod:`sarins.comparison`);
    ``unit``: whose runs (default the headline nav-rlg; the calibrated unit's name for its section)."""
    from sarins.comparison import Claim

    stops = _group(results, f"stop-{unit}-")
    mc = _group(results, f"mc-markov-{unit}-filter-")
    veh = _group(results, f"veh-markov-{unit}-")
    pct = lambda a, b: 100.0 * (np.asarray(a, float) / np.asarray(b, float) - 1.0)  # noqa: E731
    return [
        Claim(f"30-min stop: abs. azimuth-drift error (°/h), {unit}", PAPER_STOP_DPH,
              [abs(r["error_dph"]) for r in stops], paper_text="< 0.002", note=f"no {unit} stops run"),
        Claim(f"30-min stop with indexing: abs. azimuth-drift error (°/h), {unit}", PAPER_STOP_DPH,
              [abs(r["error_dph"]) for r in _group(results, f"stop-indexed-{unit}-")], paper_text="< 0.002",
              note=f"no indexed {unit} stops run"),
        Claim("mean S after FF-RLS (°/h·°C), Table 2", PAPER_S_FF, [r["s_ff"] for r in mc],
              note=f"no {unit} Monte Carlo run"),
        Claim("S after FF-RLS / S without update, Table 2", PAPER_FF_OVER_NONE,
              [r["s_ff"] / r["s_none"] for r in mc], paper_text="< 0.5 (of the means)",
              note=f"no {unit} Monte Carlo run"),
        Claim("vehicle CEP, updated vs initial model (%), Table 5", PAPER_CEP_CHANGE_PCT,
              [pct(r["cep_updated"], r["cep_initial"]) for r in veh], note=f"no {unit} vehicle test run", digits=3),
        Claim("vehicle max radial error, updated vs initial (%), Table 5", PAPER_MAX_RADIAL_CHANGE_PCT,
              [pct(r["max_radial_updated"], r["max_radial_initial"]) for r in veh],
              note=f"no {unit} vehicle test run", digits=3),
    ]


def _md_table(heads: list, rows: list) -> list:
    return ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)] + ["| " + " | ".join(r) + " |" for r in rows]


def calibrated_section(results: dict, calibrated: dict | None) -> list:
    """The unit calibrated to seed 002, Table 2 (``--calibrate``), beside the sourced unit: the fitted
    sizes and the figure fitted to, the search's trials, and every claim of the comparison table on
    both units, the fitted one marked.  ``results``: the sourced campaign's runs; ``calibrated``:
    :func:`sarins.online_rls.campaign.calibrate_unit`'s {'fit', 'results'} (None: no section)."""
    from sarins.comparison import CALIBRATED_HEADER, MIN_RUNS, calibrated_rows

    from .calibrate import noise_sizes

    if not calibrated:
        return []
    fit, runs = calibrated["fit"], calibrated["results"]
    k, unit, target = fit["k"], fit["unit"], fit["target"]
    base = noise_sizes(1.0)
    sourced_mc = [r["s_ff"] for r in _group(results, HEAD_MC + "-")]
    sourced_median = f"{float(np.median(sourced_mc)):.4g}" if sourced_mc else "-"
    sizes = [["factor k on the four noise terms", "1", f"{k:g}"],
             ["gyro angle random walk (°/√h)", f"{base['gyro_arw_dpsh']:.3g}", f"{fit['gyro_arw_dpsh']:.4g}"],
             ["gyro bias instability (°/h)", f"{base['gyro_bias_instability_dph']:.3g}",
              f"{fit['gyro_bias_instability_dph']:.4g}"],
             ["accelerometer velocity random walk (µg/√Hz)", f"{base['accel_vrw_ug_rthz']:.3g}",
              f"{fit['accel_vrw_ug_rthz']:.4g}"],
             ["accelerometer bias instability (µg)", f"{base['accel_bias_instability_ug']:.3g}",
              f"{fit['accel_bias_instability_ug']:.4g}"],
             [f"median S after FF-RLS over {fit['n_runs']} 300-day runs (°/h·°C)", sourced_median,
              f"{fit['median_s']:.4g} (target {target:.4g}; mean {fit['mean_s']:.4g})"]]
    lines = ["## Calibrated unit (calibrated to seed 002, Table 2)", "",
             "Everything above is the sourced unit (nav-rlg). What sets its S after FF-RLS is the noise of the "
             "stop estimates: with exact stop estimates the sourced ageing alone gives the paper's size. The "
             "unsourced ageing sizes of a and b only add to S, so no factor on them reaches the paper's value; "
             "here the unit's four stop-noise terms (gyro angle random walk and bias instability, accelerometer "
             "velocity random walk and bias instability; the terms the hypothetical premise unit changes) are "
             "scaled together by one factor k, the stop filter tuned to the scaled unit, and k is fitted by code "
             f"(`sarins/online_rls/calibrate.py`) to one figure: the median S after FF-RLS over the {fit['n_runs']} "
             f"headline 300-day runs (markov ageing, simulated stops) equals seed 002's Table 2 value {target:g} "
             "°/h·°C (the statistic the comparison table sets against it). Search "
             "(`sarins.calibration_fit.fit_scale`): from k = 1 by factors of 3 until bracketed, then regula falsi "
             f"(Illinois) on ln k, trial k rounded to 4 digits, tolerance {100 * fit['rtol']:g} % on the median, "
             "at most 12 trials; every trial the campaign's seeded runs on the scaled unit (k = 1: the sourced "
             "runs, reused).", "",
             *_md_table(["size", "sourced unit (nav-rlg)", f"calibrated to {fit['figure']}"], sizes), "",
             "Trials (k: median S): " + ", ".join(f"{tk:g}: {tv:.4g}" for tk, tv in fit["trials"])
             + f". {'Converged' if fit['converged'] else '**Not converged**'}: median/target - 1 = "
               f"{100 * (fit['median_s'] / target - 1):+.2f} % after {len(fit['trials'])} trials "
               f"({fit['wall_seconds']:.0f} s, stored runs not rerun).", ""]
    body = calibrated_rows(comparison_claims(results), comparison_claims(runs, unit), FITTED_CLAIM,
                           rename=lambda name: name.replace(", nav-rlg", ""))
    lines += [f"The calibrated unit (`{unit}`): the sourced campaign's headline studies (stops, indexed stops, "
              "300-day runs, vehicle tests: same seeds, temperatures and days) on the calibrated unit, in process. "
              "The fitted row is the calibration's own figure; every other row is validation of the calibrated "
              "unit against the rest of the paper (paper's percentile as in the comparison table above; fewer "
              f"than {MIN_RUNS} runs: not tested).", "", *_md_table(CALIBRATED_HEADER, body), ""]
    mc = _group(runs, f"mc-markov-{unit}-filter-")
    if mc:
        means = {key: float(np.mean([r[key] for r in mc])) for key in ("s_none", "s_rls", "s_ff")}
        lines += [f"Calibrated unit, 300-day runs: mean S no update / RLS / FF-RLS {means['s_none']:.4f} / "
                  f"{means['s_rls']:.4f} / {means['s_ff']:.4f} °/h·°C, FF-RLS / no update of the means "
                  f"{means['s_ff'] / means['s_none']:.2f} (paper: 0.066, < 0.5).", ""]
    return lines


def _plots(results: dict, out: Path) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = []

    def save(fig, name):
        fig.tight_layout()
        fig.savefig(out / name, dpi=90)
        plt.close(fig)
        names.append(name)

    stops = {cfg.split("-", 1)[1]: _group(results, cfg + "-") for cfg in _configs(results, "stop")}
    if stops:
        fig, axes = plt.subplots(1, len(stops), figsize=(5 * len(stops), 3.6), squeeze=False)
        for ax, (unit, runs) in zip(axes[0], stops.items()):
            for r in runs[:5]:
                t = r["time"] / 60.0
                ax.plot(t, r["estimate_curve_dph"] - r["truth_dph"], lw=1)
            r = runs[0]
            ax.plot(t, r["std_curve_dph"], "k--", lw=1, label="filter 1σ")
            ax.plot(t, -r["std_curve_dph"], "k--", lw=1)
            ax.axhspan(-0.002, 0.002, color="g", alpha=0.15, label="±0.002 °/h")
            ax.set_ylim(*((-0.004, 0.004) if unit.startswith("indexed-") else (-0.03, 0.03)))
            title = f"aided filter, ZUPT, {unit[5:]}" if unit.startswith("zupt-") else f"stop filter, {unit}"
            ax.set(xlabel="stop time (min)", ylabel="ε_U estimate − truth (°/h)", title=title)
            ax.legend(fontsize=7)
        save(fig, "stop_convergence.png")
    mc = _configs(results, "mc")
    head = HEAD_MC if HEAD_MC in mc else (mc[0] if mc else None)
    if head:
        r = results[head + "-000"]
        fig, axes = plt.subplots(3, 1, figsize=(7, 6), sharex=True)
        for j, (ax, name) in enumerate(zip(axes, ("a (°/h/°C²)", "b (°/h/°C)", "c (°/h)"))):
            ax.plot(r["truth_days"], r["truth_dph"][:, j], "g", label="truth")
            ax.plot(r["stop_days"], r["rls_history_dph"][:, j], "bo-", ms=3, label="RLS")
            ax.plot(r["stop_days"], r["ff_history_dph"][:, j], "ro-", ms=3, label="FF-RLS")
            ax.set_ylabel(name)
        axes[0].legend(fontsize=7)
        axes[-1].set_xlabel("day")
        axes[0].set_title("Fig. 4: model parameters over time (one run)")
        save(fig, "fig4_parameters.png")
        temp = np.linspace(0.0, 50.0, 101)
        fig, ax = plt.subplots(figsize=(6, 4))
        for key, label, style in (("initial_dph", "initial (no update)", "r--"), ("rls_dph", "RLS", "b-"),
                                  ("ff_dph", "FF-RLS λ=0.8", "m-"), ("final_truth_dph", "true final model", "g-")):
            ax.plot(temp, np.polyval(r[key], temp), style, label=label)
        ax.plot(r["stop_temperature"], r["stop_estimate_dph"], "k.", label="stop estimates")
        ax.set(xlabel="gyro temperature (°C)", ylabel="azimuth drift (°/h)", title="Fig. 5: effect of model update")
        ax.legend(fontsize=7)
        save(fig, "fig5_curves.png")
        runs = _group(results, head + "-")
        fig, ax = plt.subplots(figsize=(7, 3.5))
        idx = np.arange(1, len(runs) + 1)
        for key, label, style in (("s_none", "no update", "r."), ("s_rls", "RLS", "b."), ("s_ff", "FF-RLS", "m.")):
            ax.plot(idx, [x[key] for x in runs], style, label=label)
        ax.set(xlabel="run", ylabel="S (°/h·°C)", title=f"Fig. 6: S in {len(runs)} simulations ({head[3:]})")
        ax.legend(fontsize=7)
        save(fig, "fig6_s_values.png")
    veh = _configs(results, "veh")
    if veh:
        head_veh = HEAD_VEHICLE if HEAD_VEHICLE in veh else veh[0]
        r = results[head_veh + "-000"]
        fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
        t = r["time"] / 3600.0
        for ax, comp in zip(axes, ("east", "north")):
            ax.plot(t, r[f"{comp}_initial"], "r", label="initial model")
            ax.plot(t, r[f"{comp}_updated"], "b", label="updated model")
            ax.set_ylabel(f"{comp} error (m)")
        axes[0].legend(fontsize=7)
        axes[0].set_title(f"Fig. 8: position errors ({head_veh[4:]}, run 0)")
        axes[-1].set_xlabel("navigation time (h)")
        save(fig, "fig8_position_errors.png")
        temp = np.linspace(0.0, 50.0, 101)
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(temp, np.polyval(r["initial_dph"], temp), "r", label="initial model")
        ax.plot(temp, np.polyval(r["updated_dph"], temp), "k", label="updated model")
        ax.plot(temp, np.polyval(r["final_truth_dph"], temp), "g--", label="truth on the test day")
        upd = r["event_update"] == 1
        ax.plot(r["event_temperature"][upd], r["event_drift_dph"][upd], "b.", label="stop estimates used")
        ax.set(xlabel="gyro temperature (°C)", ylabel="azimuth drift (°/h)", title="Fig. 7: drift model")
        ax.legend(fontsize=7)
        save(fig, "fig7_vehicle_model.png")
    return names


def _fmt(x, nd=4):
    return f"{x:.{nd}f}" if abs(x) >= 10.0 ** (1 - nd) or x == 0 else f"{x:.1e}"


def write_report(results: dict, out_dir, *, profile: str, wall_time: float, workers=None,
                 forgetting_factor: float = 0.8, computed: int | None = None, calibrated: dict | None = None) -> Path:
    """Write report.md, summary.json and the PNG figures; returns the report path.  ``calibrated``:
    the ``--calibrate`` unit (:func:`sarins.online_rls.campaign.calibrate_unit`), a section after the
    comparison table and its fit in summary.json."""
    from sarins.comparison import comparison_lines

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stops, mc, veh = stop_summary(results), mc_summary(results), vehicle_summary(results)
    veh_configs = _configs(results, "veh")
    engines = sorted({str(results[k].get("engine", "inprocess")) for k in results if k.startswith("veh-")})
    summary = {"profile": profile, "vehicle_engine": engines, "runs": len(results), "computed": computed, "wall_time_s": wall_time,
               "workers": workers,
               "forgetting_factor": forgetting_factor, "stop_filter": stops, "monte_carlo": mc, "vehicle": veh,
               "calibrated": calibrated["fit"] if calibrated else None}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    figures = _plots(results, out)
    lines = [f"# Seed 002 campaign ({profile} profile)", "",
             f"{len(results)} runs ({len(results) if computed is None else computed} computed in this call), "
             f"wall time {wall_time:.0f} s, workers {workers or 'all cores'}, "
             f"FF-RLS λ = {forgetting_factor} per month (m = 30 days)"
             + (f"; vehicle tests run {' and '.join(engines)} (cosim: through the FMUs of the vehicle_rins_online "
                "SSP system)." if engines else "."), "",
             *comparison_lines(comparison_claims(results), profile=profile,
                               title="## The paper against our runs (nav-rlg, the headline unit)"),
             *calibrated_section(results, calibrated),
             "## Stop Kalman filter: 30-minute azimuth-drift estimate", "",
             "| unit | runs | rms error (°/h) | mean error | max abs error | mean filter 1σ | within 0.002 °/h |",
             "|---|---|---|---|---|---|---|"]
    for unit, s in stops.items():
        lines.append(f"| {unit} | {s['runs']} | {_fmt(s['rms_error_dph'])} | {_fmt(s['mean_error_dph'])} | "
                     f"{_fmt(s['max_abs_error_dph'])} | {_fmt(s['mean_std_dph'])} | {s['within_0.002']}/{s['runs']} |")
    lines += [""] + stop_bound_lines() + indexed_stop_lines(results) + zupt_stop_lines(results)
    lines += ["## 300-day simulation: mean S over the runs (Table 2 shape, °/h·°C)", "",
              "| configuration (ageing-unit-estimate) | runs | no update | RLS | FF-RLS | FF/no update | FF better in | "
              "calibration residual rms (°/h) | stop error rms (°/h) |", "|---|---|---|---|---|---|---|---|---|"]
    for cfg, s in mc.items():
        lines.append(f"| {cfg} | {s['runs']} | {_fmt(s['mean_s_none'])} | {_fmt(s['mean_s_rls'])} | "
                     f"{_fmt(s['mean_s_ff'])} | {s['ff_over_none']:.2f} | {s['ff_better_runs']}/{s['runs']} | "
                     f"{_fmt(s['calibration_rms_dph'])} | {_fmt(s['stop_rms_error_dph'])} |")
    if mc:
        lams = next(iter(mc.values()))["lambdas"]
        lines += ["", "### Sensitivity of mean S to λ", "",
                  "| configuration | " + " | ".join(f"λ={x:g}" for x in lams) + " |",
                  "|---|" + "---|" * len(lams)]
        for cfg, s in mc.items():
            lines.append(f"| {cfg} | " + " | ".join(_fmt(v) for v in s["mean_s_lambda"]) + " |")
    head = HEAD_MC + "-000"
    if head in results:
        r = results[head]
        lines += ["", f"### One run (Table 1 shape, run 0 of {HEAD_MC[3:]})", "",
                  "| model | S (°/h·°C) |", "|---|---|",
                  f"| no update | {_fmt(r['s_none'])} |", f"| RLS | {_fmt(r['s_rls'])} |",
                  f"| FF-RLS | {_fmt(r['s_ff'])} |"]
    lines += ["", "## Vehicle test analogue (Table 5 shape)", "",
              "| configuration | runs | updates per year | CEP initial (m) | CEP updated (m) | max radial initial (m) | "
              "max radial updated (m) | CEP improved in | S initial | S updated |", "|---|---|---|---|---|---|---|---|---|---|"]
    for cfg, s in veh.items():
        lines.append(f"| {cfg} | {s['runs']} | {s['mean_updates']:.1f} | {s['mean_cep_initial']:.0f} | "
                     f"{s['mean_cep_updated']:.0f} | {s['mean_max_initial']:.0f} | {s['mean_max_updated']:.0f} | "
                     f"{s['runs_improved_cep']}/{s['runs']} | {_fmt(s['mean_s_initial'])} | {_fmt(s['mean_s_updated'])} |")
    head_veh = HEAD_VEHICLE if HEAD_VEHICLE in veh_configs else (veh_configs[0] if veh_configs else "")
    veh_runs = sorted(k for k in results if k.startswith(head_veh + "-") and k[len(head_veh) + 1:].isdigit())
    if veh_runs:
        r = results[veh_runs[0]]
        upd = r["event_update"] == 1
        lines += ["", f"### Stops of {veh_runs[0]} used for the update (Table 4 shape)", "",
                  "| day | stop (min) | T_gz (°C) | predicted by initial model (°/h) | measured (°/h) |",
                  "|---|---|---|---|---|"]
        for d, dur, t, p, m in zip(r["event_time_days"][upd], r["event_duration_s"][upd], r["event_temperature"][upd],
                                   r["event_predicted_dph"][upd], r["event_drift_dph"][upd]):
            lines.append(f"| {d:.0f} | {dur / 60:.0f} | {t:.1f} | {_fmt(p)} | {_fmt(m)} |")
        lines += ["", "| run | CEP initial | CEP updated | max radial initial | max radial updated | "
                  "max east initial / updated | max north initial / updated |", "|---|---|---|---|---|---|---|"]
        for k in veh_runs:
            r = results[k]
            lines.append(f"| {k} | {r['cep_initial']:.0f} | {r['cep_updated']:.0f} | {r['max_radial_initial']:.0f} | "
                         f"{r['max_radial_updated']:.0f} | {r['max_east_initial']:.0f} / {r['max_east_updated']:.0f} | "
                         f"{r['max_north_initial']:.0f} / {r['max_north_updated']:.0f} |")
    lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures] + [""]
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path
