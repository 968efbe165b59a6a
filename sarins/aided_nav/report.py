"""Tables, figures (PNG) and the Markdown report of ``sarins campaign aided-nav``.

Takes the campaign's ``{task id: result dict}`` (see :mod:`sarins.aided_nav.campaign`) and writes
``report.md``, ``summary.json`` and the figures into the output folder.  Units: m, m/s, deg (attitude
at this edge only), s.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from sarins.campaign import write_text
from sarins_fmu.experiments.aided_nav import BLOCKS, OUTAGES

RATIO_BAND = (0.7, 1.4)  # issue 30's acceptance band of RMS error / predicted sigma at an outage's end
AXES = ("E", "N", "U")


def _runs(results: dict) -> list:
    return [results[k] for k in sorted(results) if k.startswith("run-")]


def nees_summary(runs: list) -> dict:
    """Mean NEES over the runs per output time and its two-sided 95 % band: the mean of R chi-square(3)
    values is chi-square(3R) / R; ``inside`` is the fraction of output times with the mean in the band."""
    from scipy.stats import chi2

    r = len(runs)
    mean = np.mean([run["nees"] for run in runs], axis=0)  # (n, 3)
    band = (float(chi2.ppf(0.025, 3 * r) / r), float(chi2.ppf(0.975, 3 * r) / r))
    inside = (mean >= band[0]) & (mean <= band[1])
    t = runs[0]["time"]
    return {"runs": r, "band": list(band),
            "longest_excursions": {b: excursions(t, mean[:, i], band)[:2] for i, b in enumerate(BLOCKS)},
            "time_mean": {b: float(mean[:, i].mean()) for i, b in enumerate(BLOCKS)},
            "inside": {b: float(inside[:, i].mean()) for i, b in enumerate(BLOCKS)}, "mean": mean}


def excursions(time, mean, band) -> list:
    """Intervals where ``mean`` (n,) leaves ``band``: [start s, end s, 'above' or 'below', extreme value],
    longest first."""
    side = np.where(mean > band[1], 1, np.where(mean < band[0], -1, 0))
    out, k = [], 0
    while k < side.size:
        if side[k] == 0:
            k += 1
            continue
        j = k
        while j + 1 < side.size and side[j + 1] == side[k]:
            j += 1
        seg = mean[k:j + 1]
        out.append([float(time[k]), float(time[j]), "above" if side[k] > 0 else "below",
                    float(seg.max() if side[k] > 0 else seg.min())])
        k = j + 1
    return sorted(out, key=lambda e: e[0] - e[1])


def outage_summary(runs: list) -> list:
    """Per outage window: RMS over the runs of the horizontal error at its end (m), RMS of the filter's
    predicted sigma_h = sqrt(P_EE + P_NN) there (m), their ratio, and the ratio's 95 % interval for a
    consistent filter (horizontal error Gaussian with variance sigma_h^2 split equally on E and N:
    R runs give 2R squared components, ratio^2 ~ chi-square(2R) / 2R)."""
    from scipy.stats import chi2

    err = np.array([run["outage_error"] for run in runs])
    sig = np.array([run["outage_sigma"] for run in runs])
    r = len(runs)
    lo, hi = (math.sqrt(chi2.ppf(q, 2 * r) / (2 * r)) for q in (0.025, 0.975))
    rows = []
    for j, (start, end) in enumerate(OUTAGES):
        e, s = float(np.sqrt(np.mean(err[:, j] ** 2))), float(np.sqrt(np.mean(sig[:, j] ** 2)))
        rows.append({"start_s": start, "end_s": end, "length_s": end - start, "rms_error_m": e, "predicted_sigma_m": s,
                     "ratio": e / s, "consistent_interval": [lo, hi],
                     "in_acceptance": bool(RATIO_BAND[0] <= e / s <= RATIO_BAND[1])})
    return rows


def error_summary(runs: list) -> dict:
    """RMS over the runs and time of the horizontal / vertical position error (m), the velocity error
    norm (m/s), the tilt and heading errors (deg), and the filter's RMS sigma for the same."""
    err = np.concatenate([run["error"] for run in runs])
    sig = np.concatenate([run["sigma"] for run in runs])
    deg = 180.0 / math.pi
    rms = lambda a: float(np.sqrt(np.mean(a**2)))  # noqa: E731
    return {"horizontal_m": rms(np.hypot(err[:, 0], err[:, 1])), "horizontal_sigma_m": rms(np.hypot(sig[:, 0], sig[:, 1])),
            "vertical_m": rms(err[:, 2]), "vertical_sigma_m": rms(sig[:, 2]),
            "velocity_mps": rms(np.linalg.norm(err[:, 3:6], axis=1)),
            "velocity_sigma_mps": rms(np.linalg.norm(sig[:, 3:6], axis=1)),
            "tilt_deg": deg * rms(np.linalg.norm(err[:, 6:8], axis=1)),
            "tilt_sigma_deg": deg * rms(np.linalg.norm(sig[:, 6:8], axis=1)),
            "heading_deg": deg * rms(err[:, 8]), "heading_sigma_deg": deg * rms(sig[:, 8])}


def zupt_summary(results: dict) -> dict | None:
    """Totals of the ZUPT-detector runs (``zupt-*``): windows, misses against alpha (expected count and the
    binomial 99.9 % point), false 'stationary' against the Chernoff bound, mean delay, and the RMS over the
    runs of the final horizontal error with truth / detected ZUPTs (m); None without such runs."""
    from scipy.stats import binom

    from sarins_fmu import aided
    from sarins_fmu import zero_velocity as zv
    from sarins_fmu.experiments.aided_nav import STEP, ZUPT_ALPHA, ZUPT_IMU, ZUPT_VIBRATION, ZUPT_WINDOW

    runs = [results[k] for k in sorted(results) if k.startswith("zupt-")]
    if not runs:
        return None
    total = lambda key: int(sum(int(r[key]) for r in runs))  # noqa: E731
    rms = lambda key: float(np.sqrt(np.mean([float(r[key]) ** 2 for r in runs])))  # noqa: E731
    noise = aided.IMU_NOISE[ZUPT_IMU]
    n, gamma = int(runs[0]["samples"]), float(runs[0]["gamma"])
    bound = zv.moving_window_bound(n, gamma, noise.vrw / math.sqrt(STEP), noise.arw / math.sqrt(STEP),
                                   zv.VIBRATION[ZUPT_VIBRATION])
    m = total("stop_windows")
    return {"runs": len(runs), "imu": ZUPT_IMU, "vibration": ZUPT_VIBRATION, "window_s": ZUPT_WINDOW,
            "alpha": ZUPT_ALPHA, "samples": n, "gamma": gamma, "stop_windows": m, "misses": total("misses"),
            "expected_misses": ZUPT_ALPHA * m, "misses_999": int(binom.ppf(0.999, m, ZUPT_ALPHA)),
            "moving_windows": total("moving_windows"), "false_stationary": total("false_stationary"),
            "bound_per_window": bound, "mean_delay_s": float(np.mean([float(r["delay_s"]) for r in runs])),
            "rms_error_truth_m": rms("error_truth_m"), "rms_error_imu_m": rms("error_imu_m"),
            "mean_zupt_truth": total("zupt_truth") / len(runs), "mean_zupt_imu": total("zupt_imu") / len(runs)}


def _zupt_lines(z: dict | None) -> list:
    if z is None:
        return []
    bound = "< 1e-300 (underflows)" if z["bound_per_window"] == 0.0 else f"{z['bound_per_window']:.1e}"
    return ["## Zero-velocity detection from the IMU", "",
            f"{z['runs']} runs on a drive with three 30 s stops (`sarins_fmu.experiments.aided_nav.STOP_SEGMENTS`), "
            f"IMU `{z['imu']}` with vibration `{z['vibration']}` while moving; the detector of "
            f"`sarins_fmu.zero_velocity` (window {z['window_s']:g} s, N = {z['samples']}, α = {z['alpha']:g}, "
            f"γ = {z['gamma']:.1f}, the (1 − α) point of χ²(6(N − 1))). Misses are counted on disjoint windows "
            "wholly inside the stops (independent, Binomial(m, α)); false 'stationary' on windows wholly in motion.",
            "", "| stop windows | missed | expected α·m | binomial 99.9 % point | moving windows | false 'stationary' | "
            "Chernoff bound per window | mean delay to detection (s) |", "|---|---|---|---|---|---|---|---|",
            f"| {z['stop_windows']} | {z['misses']} | {z['expected_misses']:.2f} | {z['misses_999']} | "
            f"{z['moving_windows']} | {z['false_stationary']} | {bound} | {z['mean_delay_s']:.2f} |", "",
            "GNSS-free navigation (ZUPT, odometer, non-holonomic constraint) on the same runs, RMS over the runs "
            "of the horizontal error at the end:", "",
            "| ZUPTs from | RMS final horizontal error (m) | mean ZUPT steps |", "|---|---|---|",
            f"| truth (the trajectory's stops) | {z['rms_error_truth_m']:.3f} | {z['mean_zupt_truth']:.0f} |",
            f"| IMU detector | {z['rms_error_imu_m']:.3f} | {z['mean_zupt_imu']:.0f} |", ""]


def kfgins_summary(results: dict, skipped: str | None = None) -> dict:
    """The KF-GINS comparison (the ``kfgins`` task's JSON: see
    :func:`sarins_fmu.experiments.kfgins_compare.compare`), or {"skipped": reason} when the task did not run
    (``skipped``: why, from the campaign) or KF-GINS failed in it."""
    task = results.get("kfgins")
    if task is None:
        return {"skipped": skipped or "no KF-GINS binary was given"}
    if str(task["failure"]):
        return {"skipped": f"KF-GINS failed: {task['failure']}"}
    return json.loads(str(task["comparison"]))


def _kfgins_lines(k: dict) -> list:
    from sarins_fmu.experiments.kfgins_compare import markdown

    head = ["## Against KF-GINS on the same data", ""]
    if "skipped" in k:
        return head + [f"KF-GINS comparison skipped: {k['skipped'].rstrip('.')}.", ""]
    return head + [
        f"[KF-GINS](https://github.com/i2Nav-WHU/KF-GINS), a peer GNSS/INS filter built outside the project, and "
        f"ours on the same data (`sarins_fmu.experiments.kfgins_compare`): a {k['duration_s']:.0f} s drive with "
        f"stops, turns and climbs, IMU `{k['imu']}` at {k['imu_rate_hz']} Hz, {k['gnss_fixes']} GNSS position fixes "
        f"({k['gnss']}, {k['gnss_rate_hz']:g} Hz), seed {k['seed']}; ours with GNSS positions only, as KF-GINS. "
        f"RMS errors against the truth at {k['compared_rows']} output times. Run times: the fastest of "
        f"{k['repeats']} runs, ours `navigate` alone, KF-GINS its process (reading its text files, writing its "
        f"results); the two alternate, so a load on the machine (header) weighs on both.", "",
        markdown(k).rstrip(), ""]


def _shade_outages(ax) -> None:
    for start, end in OUTAGES:
        ax.axvspan(start, end, color="0.85", lw=0)


def _plots(results: dict, runs: list, nees: dict, out: Path) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = []

    def save(fig, name):
        fig.tight_layout()
        fig.savefig(out / name, dpi=90)
        plt.close(fig)
        names.append(name)

    traj = results.get("trajectory")
    if traj is not None:
        fig, ax = plt.subplots(figsize=(6, 4.5))
        ax.plot(traj["east"] / 1e3, traj["north"] / 1e3, color="0.4", lw=1, label="drive")
        for start, end in OUTAGES:
            sel = (traj["time"] >= start) & (traj["time"] < end)
            ax.plot(traj["east"][sel] / 1e3, traj["north"][sel] / 1e3, lw=3, label=f"GNSS outage {end - start:g} s")
        still = traj["stationary"] > 0
        ax.plot(traj["east"][still] / 1e3, traj["north"][still] / 1e3, "ko", ms=5, label="stops (ZUPT)")
        ax.set_xlabel("east (km)")
        ax.set_ylabel("north (km)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize=8)
        ax.set_title("trajectory")
        save(fig, "trajectory.png")
    run0 = runs[0]
    t = run0["time"]
    scale = {"position": (1.0, "m"), "velocity": (1.0, "m/s"), "attitude": (180.0 / math.pi, "deg")}
    for i, block in enumerate(BLOCKS):
        k, unit = scale[block]
        fig, axes = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
        for j, ax in enumerate(axes):
            _shade_outages(ax)
            e, s = run0["error"][:, 3 * i + j] * k, run0["sigma"][:, 3 * i + j] * k
            ax.plot(t, e, lw=0.8, label="error (run 0)")
            ax.plot(t, 3 * s, "r", lw=0.8, label="±3σ (filter)")
            ax.plot(t, -3 * s, "r", lw=0.8)
            ax.set_ylabel(f"{AXES[j]} ({unit})")
        axes[0].legend(fontsize=8, loc="upper left")
        axes[0].set_title(f"{block} error and the filter's ±3σ (grey: GNSS outages)")
        axes[-1].set_xlabel("time (s)")
        save(fig, f"errors_{block}.png")
    fig, axes = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
    lo, hi = nees["band"]
    for i, (ax, block) in enumerate(zip(axes, BLOCKS)):
        _shade_outages(ax)
        ax.plot(t, nees["mean"][:, i], lw=0.8, label=f"mean NEES over {nees['runs']} runs")
        ax.axhline(3.0, color="k", lw=0.6)
        ax.axhspan(lo, hi, color="g", alpha=0.2, label="95 % χ² band")
        ax.set_ylabel(block)
    axes[0].legend(fontsize=8, loc="upper left")
    axes[0].set_title("normalised estimation error squared (3 dof)")
    axes[-1].set_xlabel("time (s)")
    save(fig, "nees.png")
    fig, ax = plt.subplots(figsize=(8, 3.6))
    _shade_outages(ax)
    h = np.sqrt(np.mean([r["error"][:, 0] ** 2 + r["error"][:, 1] ** 2 for r in runs], axis=0))
    s = np.sqrt(np.mean([r["sigma"][:, 0] ** 2 + r["sigma"][:, 1] ** 2 for r in runs], axis=0))
    ax.plot(t, h, lw=0.8, label="RMS horizontal error over the runs")
    ax.plot(t, s, "r", lw=0.8, label="RMS predicted σ_h")
    ax.set_yscale("log")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("m")
    ax.legend(fontsize=8)
    save(fig, "outage_growth.png")
    return names


def summarise(results: dict, kfgins_skipped: str | None = None) -> dict:
    """Every number of the report from the results (the report prints these); ``kfgins_skipped``: why
    the KF-GINS comparison did not run, when it did not."""
    runs = _runs(results)
    nees = nees_summary(runs)
    return {"runs": len(runs), "nees": {k: v for k, v in nees.items() if k != "mean"},
            "outages": outage_summary(runs), "errors": error_summary(runs), "zupt_detection": zupt_summary(results),
            "kfgins": kfgins_summary(results, kfgins_skipped),
            "cpu_s_per_run": float(np.mean([r["cpu_s"] for r in runs]))}


def write_report(results: dict, out_dir, *, profile: str, wall_time: float, workers=None, computed: int | None = None,
                 parent_cpu: float | None = None, kfgins_skipped: str | None = None) -> Path:
    """Write report.md, summary.json and the PNG figures; returns the report path.  ``kfgins_skipped``: why
    the KF-GINS comparison did not run (printed in its section), when it did not."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    runs = _runs(results)
    if len(runs) < 2:
        raise ValueError("the aided-nav report needs at least 2 runs")
    summary = summarise(results, kfgins_skipped)
    load = os.getloadavg()
    summary.update({"profile": profile, "computed": computed, "wall_time_s": wall_time, "workers": workers,
                    "campaign_process_cpu_s": parent_cpu, "load_average_1_5_15": list(load)})
    write_text(out / "summary.json", json.dumps(summary, indent=2))
    nees = nees_summary(runs)
    figures = _plots(results, runs, nees, out)
    lo, hi = nees["band"]
    e = summary["errors"]
    lines = [f"# Aided navigation campaign ({profile} profile)", "",
             f"{len(runs)} Monte Carlo runs ({computed if computed is not None else len(runs)} tasks computed in this "
             f"call), wall time {wall_time:.1f} s, workers {workers or 'all cores'}, load average "
             f"{load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} (1 / 5 / 15 min) when the report was written; the "
             f"filter's own CPU time {summary['cpu_s_per_run']:.3f} s per run.", "",
             "The drive (`sarins_fmu.experiments.aided_nav.drive`): 20 s stop, accelerate to 12 m/s, 90° turn, "
             "cruise, −90° turn, brake, 10 s stop, 32° N, IMU at 100 Hz (grade `tactical`, "
             "`sarins_fmu.aided.IMU_NOISE`). GNSS at 1 Hz with white errors (1, 1, 2 m; 0.05, 0.05, 0.1 m/s), "
             "ZUPT at the stops, the 15-state error-state Kalman filter of the C core (`eskf.h`). Run k uses "
             "seed k for the IMU, initial and GNSS errors.", "",
             "## GNSS outages", "",
             "RMS over the runs of the horizontal error at the end of each outage against the RMS of the filter's "
             "predicted σ_h = √(P_EE + P_NN) there. For a consistent filter the ratio lies in the 95 % interval "
             "√(χ²(2R)/2R) (R runs, two horizontal components per run); issue 30 asks for 0.7 .. 1.4.", "",
             "| outage (s) | length (s) | RMS horizontal error (m) | predicted σ_h (m) | ratio | 95 % interval if "
             "consistent | in 0.7 .. 1.4 |", "|---|---|---|---|---|---|---|"]
    for row in summary["outages"]:
        a, b = row["consistent_interval"]
        lines.append(f"| {row['start_s']:g}-{row['end_s']:g} | {row['length_s']:g} | {row['rms_error_m']:.3f} | "
                     f"{row['predicted_sigma_m']:.3f} | {row['ratio']:.2f} | {a:.2f} .. {b:.2f} | "
                     f"{'yes' if row['in_acceptance'] else 'no'} |")
    lines += ["", "## Consistency (NEES)", "",
              f"Mean over the {len(runs)} runs of the normalised estimation error squared (3 degrees of freedom per "
              f"block) at each output time; the mean of {len(runs)} χ²(3) values lies in {lo:.3f} .. {hi:.3f} with "
              "95 % probability (χ²(3R)/R).", "",
              "| block | time-mean of mean NEES | fraction of time inside the band |", "|---|---|---|"]
    for b in BLOCKS:
        lines.append(f"| {b} | {summary['nees']['time_mean'][b]:.3f} | {100 * summary['nees']['inside'][b]:.1f} % |")
    lines += ["", "For a consistent filter the mean NEES lies in its band 95 % of the time on average. It is correlated "
              "over seconds to tens of seconds, so an excursion is one event, not many: the two longest per block "
              "(start - end of the outside samples, side, extreme mean NEES):", "",
              "| block | longest excursions |", "|---|---|"]
    for b in BLOCKS:
        ex = summary["nees"]["longest_excursions"][b]
        text = "; ".join(f"{e[0]:.1f}-{e[1]:.1f} s {e[2]} ({e[3]:.2f})" for e in ex) or "none"
        lines.append(f"| {b} | {text} |")
    lines += ["", "## Errors against the filter's σ", "",
              "RMS over all runs and output times (σ: the filter's, the same RMS).", "",
              "| quantity | RMS error | RMS filter σ |", "|---|---|---|",
              f"| horizontal position (m) | {e['horizontal_m']:.3f} | {e['horizontal_sigma_m']:.3f} |",
              f"| vertical position (m) | {e['vertical_m']:.3f} | {e['vertical_sigma_m']:.3f} |",
              f"| velocity (m/s) | {e['velocity_mps']:.4f} | {e['velocity_sigma_mps']:.4f} |",
              f"| tilt (deg) | {e['tilt_deg']:.5f} | {e['tilt_sigma_deg']:.5f} |",
              f"| heading (deg) | {e['heading_deg']:.4f} | {e['heading_sigma_deg']:.4f} |",
              ""] + _zupt_lines(summary["zupt_detection"]) + _kfgins_lines(summary["kfgins"]) + ["## Figures", "",
              "Trajectory; position, velocity and attitude errors of run 0 with the filter's ±3σ envelope; mean "
              "NEES with its band; RMS horizontal error against the predicted σ_h (grey: GNSS outages).", ""]
    lines += [f"![{f}]({f})" for f in figures] + [""]
    path = out / "report.md"
    write_text(path, "\n".join(lines))
    return path
