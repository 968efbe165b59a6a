"""Allan analysis of a preset's simulated static data or of a recorded IMU log.

:func:`analyse` returns the curves and the IEEE Std 952 / 1293 read-outs of the six
channels (gyro x, y, z in rad/s, accelerometer x, y, z in m/s^2; :mod:`sarins_fmu.allan_readout`:
quantisation Q, random walk N, bias instability B, rate random walk K, rate ramp R, each with its
confidence interval or "not resolved"), with the preset's spec beside them when the data are
simulated, and warnings for a record that is short or not static; :func:`plot` draws the
overlapping Allan deviation with the read-out lines.  Display units (:data:`DISPLAY`): gyro Q
arcsec, N deg/sqrt(h), B deg/h, K deg/h/sqrt(h), R deg/h/h; accelerometer Q mm/s, N ug/sqrt(Hz),
B ug, K ug/sqrt(h), R ug/h.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sarins_fmu import allan, allan_readout, imu
from sarins_fmu.imu_log_checks import motion
from sarins_fmu.units import ARCSEC_TO_RAD, DEG_TO_RAD, DPH_TO_RPS, DPSH_TO_RPSS, G0, UG_TO_MPS2

CHANNELS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
TERMS = allan_readout.TERMS
LABELS = {"quantization": "Q", "random_walk": "N", "bias_instability": "B", "rate_random_walk": "K",
          "rate_ramp": "R"}
# SI -> display, per triad and term: (factor, unit)
DISPLAY = {
    "gyro": {"quantization": (1 / ARCSEC_TO_RAD, "arcsec"), "random_walk": (1 / DPSH_TO_RPSS, "deg/sqrt(h)"),
             "bias_instability": (1 / DPH_TO_RPS, "deg/h"), "rate_random_walk": (60 / DPH_TO_RPS, "deg/h/sqrt(h)"),
             "rate_ramp": (3600 / DPH_TO_RPS, "deg/h/h")},
    "accel": {"quantization": (1e3, "mm/s"), "random_walk": (1 / UG_TO_MPS2, "ug/sqrt(Hz)"),
              "bias_instability": (1 / UG_TO_MPS2, "ug"), "rate_random_walk": (60 / UG_TO_MPS2, "ug/sqrt(h)"),
              "rate_ramp": (3600 / UG_TO_MPS2, "ug/h")},
}
SPEC_KEYS = {"random_walk": "random_walk", "bias_instability": "bias_instability",
             "rate_random_walk": "rate_random_walk"}  # read-outs a preset states (flicker B, white N, K)


@dataclass
class AllanResult:
    """Curves (SI) and read-outs of six channels.

    taus, adev : the dense curve for plots; curves : channel -> :class:`OctaveCurve` (the octave
    curve the read-outs come from); readouts : channel -> :class:`Readouts` (SI); spec : channel ->
    {term: SI value} for simulated data; warnings : what the record keeps the read-outs from showing.
    """

    source: str
    rate_hz: float
    record_length: float
    taus: np.ndarray  # (T,) s
    adev: np.ndarray  # (T, 6) rad/s, m/s^2
    curves: dict
    readouts: dict
    spec: dict | None = None
    gauss_markov: dict | None = None  # channel -> (fitted std, spec std, corr. time s), display units
    warnings: list = field(default_factory=list)
    resolution: dict | None = None  # channel -> output step (SI) when the data sit on a grid

    def rows(self) -> list[dict]:
        """One row per channel: each term's value (None: not resolved), interval, averaging time and unit
        (display units), the spec for simulated data."""
        out = []
        for ch in CHANNELS:
            triad = ch.split("_")[0]
            row = {"channel": ch}
            for term in TERMS:
                factor, unit = DISPLAY[triad][term]
                t = self.readouts[ch][term]
                row[term] = None if t.value is None else t.value * factor
                row[f"{term}_interval"] = [t.low * factor, t.high * factor]
                row[f"{term}_tau_s"] = t.tau
                row[f"{term}_unit"] = unit
                if self.spec is not None and term in self.spec[ch]:
                    row[f"{term}_spec"] = self.spec[ch][term] * factor
            if self.resolution and self.resolution.get(ch):
                row["resolution"] = self.resolution[ch] * (1 / DEG_TO_RAD if triad == "gyro" else 1 / G0)
                row["resolution_unit"] = "deg/s" if triad == "gyro" else "g"
            if self.gauss_markov and ch in self.gauss_markov:
                row["gauss_markov"], row["gauss_markov_spec"], row["gauss_markov_time_s"] = self.gauss_markov[ch]
                row["gauss_markov_unit"] = DISPLAY[triad]["bias_instability"][1]
            out.append(row)
        return out


def output_resolution(y) -> float | None:
    """The step of an output that sits on a grid (a quantised sensor), SI, or None: the smallest
    difference between the distinct values, when there are at most 1 / 20 as many as samples."""
    y = np.asarray(y, float)[:200000]
    values = np.unique(y)
    if values.size < 2 or values.size > y.size / 20:
        return None
    step = float(np.min(np.diff(values)))
    return step if np.allclose(np.round((values - values[0]) / step) * step, values - values[0], atol=step * 1e-3) \
        else None


def analyse(channels, rate_hz: float, source: str, model: imu.ImuModel | None = None,
            means=None) -> AllanResult:
    """Allan curves and read-outs of six rate series (gyro x, y, z rad/s, accel x, y, z m/s^2) at rate_hz.

    channels : a (K, 6) array, or six (K,) arrays or functions returning them (called one at a time:
    a large log is never copied whole); means : optional (M, 6) 1 s means of the record, for the check
    that it is static.
    """
    def column(j):
        if isinstance(channels, np.ndarray):
            return channels[:, j]
        return channels[j]() if callable(channels[j]) else channels[j]

    n = column(0).shape[0]
    record = n / rate_hz
    taus = allan.default_taus(n, rate_hz)
    dense, curves, reads, spec, gm, res = [], {}, {}, None if model is None else {}, {}, {}
    for j, ch in enumerate(CHANNELS):
        triad = ch.split("_")[0]
        y = np.ascontiguousarray(column(j), dtype=float)
        t, dev = allan.overlapping_adev(y, rate_hz, taus)
        dense.append(dev)
        curves[ch] = allan_readout.octave_curve(y, rate_hz)
        reads[ch] = allan_readout.read_terms(curves[ch])
        res[ch] = output_resolution(y)
        if model is not None:
            s = allan.spec(model, triad)
            spec[ch] = {term: float(s[key][j % 3]) for term, key in SPEC_KEYS.items()}
            if s["gauss_markov"][j % 3] > 0:  # a Gauss-Markov bias (nav-rlg): read with its correlation time
                tc = float(s["gauss_markov_time"][j % 3])
                _, std = allan.fit_gauss_markov(t, dev, tc, record)
                factor = DISPLAY[triad]["bias_instability"][0]
                gm[ch] = (std * factor, float(s["gauss_markov"][j % 3]) * factor, tc)
    if not dense or dense[0].size == 0:
        raise ValueError("no averaging time fits the record (each needs at least two cluster differences)")
    notes = allan_readout.record_warnings(record, len(curves[CHANNELS[0]].taus))
    if means is not None:
        why = motion(np.asarray(means))
        if why:
            notes.append(f"the record is not static ({why}): the read-outs mix motion into the noise terms")
    return AllanResult(source, float(rate_hz), record, t, np.column_stack(dense), curves, reads, spec, gm or None,
                       notes, res)


def simulate(preset, hours: float, rate_hz: float, seed: int) -> AllanResult:
    """Static, hot-started IMU at constant ambient for ``hours``, sampled at ``rate_hz``: ``preset`` is a
    preset name or an :class:`~sarins_fmu.imu.ImuModel` (with ``name`` for the source)."""
    model, name = (imu.preset(preset), preset) if isinstance(preset, str) else preset
    if not (hours > 0 and math.isfinite(hours)):
        raise ValueError(f"hours must be positive, got {hours}")
    if hours * 3600 * rate_hz > 5e7:
        raise ValueError(f"{hours:g} h at {rate_hz:g} Hz is more than 5e7 samples; lower the rate or the hours")
    gyro, accel, _ = allan.static_record(model, hours * 3600.0, rate_hz, seed=seed)
    return analyse(np.hstack([gyro, accel]), rate_hz, f"preset {name} (simulated, seed {seed})", model)


def plot(result: AllanResult, path) -> None:
    """Two-panel log-log plot (gyro deg/h, accelerometer ug) with the read-out lines annotated."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    tau = result.taus
    for ax, triad, scale, unit in ((axes[0], "gyro", 1 / DPH_TO_RPS, "deg/h"), (axes[1], "accel", 1 / UG_TO_MPS2, "ug")):
        lines = []
        line_styles = {"quantization": (lambda v, t: math.sqrt(3) * v / t, (0, (1, 1))),
                       "random_walk": (lambda v, t: v / np.sqrt(t), "--"),
                       "bias_instability": (lambda v, t: allan.FLOOR * v + 0 * t, ":"),
                       "rate_random_walk": (lambda v, t: v * np.sqrt(t / 3), "-."),
                       "rate_ramp": (lambda v, t: v * t / math.sqrt(2), (0, (5, 1)))}
        for j, ch in enumerate(CHANNELS):
            if not ch.startswith(triad):
                continue
            ax.loglog(tau, result.adev[:, j] * scale, label=ch)
            r = result.readouts[ch]
            cells = []
            for term in TERMS:
                factor, unit_t = DISPLAY[triad][term]
                t = r[term]
                cells.append(f"{LABELS[term]} {t.value * factor:.3g}" if t.resolved else f"{LABELS[term]} n.r.")
                if j % 3 == 0 and t.resolved:  # read-out lines of the x axis, where they were read
                    line, style = line_styles[term]
                    ax.loglog(tau, line(t.value, tau) * scale, color="k", ls=style, lw=0.8,
                              label=f"{ch} {LABELS[term]} (read at {t.tau:g} s)")
            lines.append(f"{ch}: " + ", ".join(cells))
        ax.set_xlabel("averaging time tau, s")
        ax.set_ylabel(f"overlapping Allan deviation, {unit}")
        ax.set_title(f"{triad}: " + result.source, fontsize=9)
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7, loc="lower left")
        ax.text(0.98, 0.98, "\n".join(lines), transform=ax.transAxes, va="top", ha="right", fontsize=7,
                bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
