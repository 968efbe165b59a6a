"""Seed 003 results: residual statistics (Table 3), calibration tables (1-2),
residual figures (Figs 4-5) and the Markdown report.

Residual = compensated (or raw) output - truth, per channel, on the
held-out test set.  Units at this edge: gyro deg/s, accelerometer mg.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sarins_fmu.units import RAD_TO_DEG
from sarins_fmu.experiments.mems_calibration import OUTPUT_NAMES

G_MG = 9.80665e-3  # m/s^2 per mg (standard gravity / 1000)
CHANNEL_SCALE = np.array([RAD_TO_DEG] * 3 + [1.0 / G_MG] * 3)  # SI -> deg/s, mg
CHANNEL_UNIT = ["deg/s"] * 3 + ["mg"] * 3


def residual_stats(residual: np.ndarray) -> dict:
    """Per-channel mean, std and mean |.| of (n, 6) residuals, SI units."""
    r = np.asarray(residual, float)
    return {"mean": r.mean(axis=0), "std": r.std(axis=0), "mae": np.abs(r).mean(axis=0)}


def reductions(stats: dict, raw: dict) -> dict:
    """Overall reduction vs raw output, %: the mean over the six channels of
    1 - |mean| / |mean_raw|, 1 - std / std_raw and 1 - mae / mae_raw."""
    out = {}
    for key in ("mean", "std", "mae"):
        ratio = np.abs(stats[key]) / np.abs(raw[key])
        out[key] = float(100.0 * np.mean(1.0 - ratio))
    return out


def _fmt(x: float) -> str:
    return f"{x:.3g}" if abs(x) >= 1e-3 else f"{x:.2e}"


def table3(stats: dict, red: dict) -> str:
    """Markdown Table 3 analogue: per model, per channel mean / std, and the reductions."""
    head = "| model | " + " | ".join(f"{n} mean / std ({u})" for n, u in zip(OUTPUT_NAMES, CHANNEL_UNIT))
    head += " | mean red. % | std red. % | mean-abs red. % |\n|" + "---|" * (len(OUTPUT_NAMES) + 4) + "\n"
    rows = []
    for name, s in stats.items():
        cells = [f"{_fmt(m)} / {_fmt(d)}" for m, d in zip(s["mean"] * CHANNEL_SCALE, s["std"] * CHANNEL_SCALE)]
        r = red.get(name)
        tail = ["-", "-", "-"] if r is None else [f"{r['mean']:.1f}", f"{r['std']:.1f}", f"{r['mae']:.1f}"]
        rows.append(f"| {name} | " + " | ".join(cells + tail) + " |")
    return head + "\n".join(rows) + "\n"


def calibration_tables(fit, model) -> str:
    """Tables 1-2 analogues: fitted bias, scale factors and misalignment of both triads,
    beside the simulated preset's nominal values (at 25 degC, linear part only)."""
    from sarins_fmu.units import DPH_TO_RPS

    lines = []
    for title, cal, triad, bias_unit, bias_scale in (
            ("Table 1 analogue: accelerometer calibration coefficients", fit.accel, model.accel, "mg", 1 / G_MG),
            ("Table 2 analogue: gyro calibration coefficients", fit.gyro, model.gyro, "deg/h", 1 / DPH_TO_RPS)):
        lines += [f"**{title}** (fitted / preset nominal)", "",
                  f"| axis | bias ({bias_unit}) | scale factor (ppm) | K row: x | y | z |", "|---|---|---|---|---|---|"]
        k_nom = np.eye(3) + np.diag(triad.scale_factor) + triad.misalignment
        for i, ax in enumerate("xyz"):
            krow = " | ".join(f"{cal.matrix[i, j]:.6f} / {k_nom[i, j]:.6f}" for j in range(3))
            lines.append(f"| {ax} | {cal.bias[i] * bias_scale:.2f} / {triad.bias[i] * bias_scale:.2f} | "
                         f"{cal.scale_factor[i] * 1e6:.0f} / {triad.scale_factor[i] * 1e6:.0f} | {krow} |")
        lines.append("")
    lines += ["Fitted and nominal coefficients are not the same quantity. The *nominal* bias is the preset's "
              "constant term at the 25 degC reference; the *fitted* bias is everything constant during the "
              "tumble and rate tests: nominal bias + linear and quadratic temperature terms at the sensor "
              "temperature of the calibration (the chamber is not at 25 degC and the sensors self-heat), the "
              "g-sensitivity averaged over the positions (gyros), and the bias-instability state at the time. "
              "The scale factors and the K matrix are compared likewise (temperature terms of the scale factor "
              "included). A fitted bias far from the nominal one is therefore expected for the mems preset, whose "
              "temperature coefficients are large; what matters is the residual after compensation (Table 3).", ""]
    return "\n".join(lines)


def residual_figure(path: Path, time: np.ndarray, residuals: dict, channel: int, title: str,
                    max_points: int = 4000) -> Path:
    """Figs 4/5 analogue: one channel's residual after each model (and raw), one panel per model."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(residuals)
    step = max(1, len(time) // max_points)
    fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.6 * len(names)), sharex=True, sharey=True)
    axes = np.atleast_1d(axes)
    t_min = (time[::step] - time[0]) / 60.0
    for ax, name in zip(axes, names):
        ax.plot(t_min, residuals[name][::step, channel] * CHANNEL_SCALE[channel], lw=0.5)
        ax.set_ylabel(f"{name}\n({CHANNEL_UNIT[channel]})", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time into the test set (min)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)


PAPER = {"traditional": (9.2, 4.7), "shallow (RBFNN, GRNN)": (30.0, 33.0), "recurrent (LSTM, GRU)": (55.0, 38.0)}


def markdown(summary: dict, fit_tables: str, figures: list[str]) -> str:
    """The whole report as Markdown (numbers from ``summary``, see sarins.mems_calibration.campaign)."""
    s = summary
    lines = [
        "# Seed 003: dynamic calibration of a MEMS IMU (co-simulation)", "",
        f"Profile **{s['profile']}**; recordings co-simulated through the project's master "
        "(Turntable FMU -> IMUThermal FMU, preset `mems`, 200 Hz minor loop, Gauss-Seidel); "
        f"dynamic step {s['step']} s, calibration step {s['cal_step']} s. "
        f"Training set {s['n_train']} samples (first chamber cycle), test set {s['n_test']} samples (held out).", "",
        "## Traditional calibration (eqs (1)-(2))", "",
        f"24-position tumble ({s['tumble_dwell']:.0f} s per position) and rate test (22 rates per axis, "
        f"whole revolutions); fit RMS residual: gyro {s['gyro_fit_rms_dps']:.3g} deg/s, "
        f"accelerometer {s['accel_fit_rms_mg']:.3g} mg.", "", fit_tables,
        "## Table 3 analogue: residuals on the test set", "",
        "Residual = output - truth. Mean and std per channel; reductions are the mean over the six "
        "channels of the relative reduction against the raw output (|mean|, std, mean |residual|).", "",
        s["table3"], "",
        "Paper (Table 3 text): traditional -9.2 % mean / -4.7 % std; shallow networks about -30 % / -33 %; "
        "recurrent about -55 % / -38 %.", "",
        "## Model sizes and times", "",
        "| model | parameters | fit (s) | predict test set (s) |", "|---|---|---|---|",
    ]
    for name, info in s["models"].items():
        lines.append(f"| {name} | {info['n_parameters']} | {info['fit_s']:.1f} | {info['predict_s']:.1f} |")
    if "lstm" in s["models"] and "gru" in s["models"]:
        a, b = s["models"]["lstm"]["n_parameters"], s["models"]["gru"]["n_parameters"]
        lines += ["", f"GRU has {100 * (1 - b / a):.1f} % fewer parameters than LSTM (paper: 24 %)."]
    if s.get("skipped"):
        lines += ["", f"Not run: {', '.join(s['skipped'])} ({s.get('skip_reason', '')})."]
    if s.get("reused_models"):
        lines += ["", f"Fitted models reused from an earlier run with the same options (their fit times are from "
                      f"that run): {', '.join(s['reused_models'])}."]
    lines += ["", "Wall times: " + ", ".join(f"{k} {v:.0f} s" for k, v in s["wall_s"].items()) + ".", "",
              "## Figures", ""]
    lines += [f"![{f}]({f})" for f in figures]
    if s.get("notes"):
        lines += ["", "## Notes", "", s["notes"]]
    return "\n".join(lines) + "\n"
