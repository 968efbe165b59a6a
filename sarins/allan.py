"""Allan analysis of a preset's simulated static data or of a recorded IMU log.

:func:`analyse` returns the curves and the IEEE Std 952 read-outs of the six
channels (gyro x, y, z in rad/s, accelerometer x, y, z in m/s^2), with the
preset's spec beside them when the data are simulated; :func:`plot` draws
the overlapping Allan deviation with the read-outs annotated.  Display
units: gyro random walk deg/sqrt(h), bias instability deg/h, rate random
walk deg/h/sqrt(h); accelerometer ug/sqrt(Hz), ug, ug/sqrt(h).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sarins_fmu import allan, imu
from sarins_fmu.units import DPH_TO_RPS, DPSH_TO_RPSS, UG_TO_MPS2

CHANNELS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
# SI -> display, per triad: (random walk, bias instability, rate random walk)
DISPLAY = {
    "gyro": ((1 / DPSH_TO_RPSS, "deg/sqrt(h)"), (1 / DPH_TO_RPS, "deg/h"), (60 / DPH_TO_RPS, "deg/h/sqrt(h)")),
    "accel": ((1 / UG_TO_MPS2, "ug/sqrt(Hz)"), (1 / UG_TO_MPS2, "ug"), (60 / UG_TO_MPS2, "ug/sqrt(h)")),
}
TERMS = ("random_walk", "bias_instability", "rate_random_walk")


@dataclass
class AllanResult:
    """Curves (SI) and read-outs (display units) of six channels."""

    source: str
    rate_hz: float
    record_length: float
    taus: np.ndarray  # (T,) s
    adev: np.ndarray  # (T, 6) rad/s, m/s^2
    readouts: dict  # channel -> {term: value in display units}
    spec: dict | None  # channel -> {term: value in display units}, simulated data only

    def rows(self) -> list[dict]:
        """One row per channel: read-outs, spec and units, for printing or JSON."""
        out = []
        for ch in CHANNELS:
            triad = ch.split("_")[0]
            row = {"channel": ch}
            for term, (_, unit) in zip(TERMS, DISPLAY[triad]):
                row[term] = self.readouts[ch][term]
                if self.spec is not None:
                    row[f"{term}_spec"] = self.spec[ch][term]
                row[f"{term}_unit"] = unit
            out.append(row)
        return out


def _display(triad, values):
    return {term: float(v * f) for term, v, (f, _) in zip(TERMS, values, DISPLAY[triad])}


def analyse(gyro, accel, rate_hz: float, source: str, model: imu.ImuModel | None = None) -> AllanResult:
    """Allan curves and read-outs of rates gyro (K, 3) rad/s and accel (K, 3) m/s^2 at rate_hz."""
    data = np.hstack([np.asarray(gyro, float), np.asarray(accel, float)])
    record = data.shape[0] / rate_hz
    taus, adev = allan.allan_deviation(data, rate_hz)
    reads, spec = {}, None if model is None else {}
    for j, ch in enumerate(CHANNELS):
        triad = ch.split("_")[0]
        r = allan.readouts(taus, adev[:, j], record)
        reads[ch] = _display(triad, (r.random_walk, r.bias_instability, r.rate_random_walk))
        if model is not None:
            s = allan.spec(model, triad)
            spec[ch] = _display(triad, [s[t][j % 3] for t in TERMS])
    return AllanResult(source, float(rate_hz), record, taus, adev, reads, spec)


def simulate(preset: str, hours: float, rate_hz: float, seed: int) -> AllanResult:
    """Static, hot-started ``preset`` IMU at constant ambient for ``hours``, sampled at ``rate_hz``."""
    model = imu.preset(preset)
    if not (hours > 0 and math.isfinite(hours)):
        raise ValueError(f"hours must be positive, got {hours}")
    if hours * 3600 * rate_hz > 5e7:
        raise ValueError(f"{hours:g} h at {rate_hz:g} Hz is more than 5e7 samples; lower the rate or the hours")
    gyro, accel, _ = allan.static_record(model, hours * 3600.0, rate_hz, seed=seed)
    return analyse(gyro, accel, rate_hz, f"preset {preset} (simulated, seed {seed})", model)


def plot(result: AllanResult, path) -> None:
    """Two-panel log-log plot (gyro deg/h, accelerometer ug) with the read-out lines annotated."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    tau = result.taus
    for ax, triad, scale, unit in ((axes[0], "gyro", 1 / DPH_TO_RPS, "deg/h"), (axes[1], "accel", 1 / UG_TO_MPS2, "ug")):
        lines = []
        for j, ch in enumerate(CHANNELS):
            if not ch.startswith(triad):
                continue
            ax.loglog(tau, result.adev[:, j] * scale, label=ch)
            r = result.readouts[ch]
            (f_n, u_n), (f_b, u_b), (f_k, u_k) = DISPLAY[triad]
            n, b, k = r["random_walk"] / f_n, r["bias_instability"] / f_b, r["rate_random_walk"] / f_k
            lines.append(f"{ch}: N {r['random_walk']:.3g} {u_n}, B {r['bias_instability']:.3g} {u_b}, "
                         f"K {r['rate_random_walk']:.3g} {u_k}")
            if j % 3 == 0:  # read-out lines of the x axis
                if n > 0:
                    ax.loglog(tau, n / np.sqrt(tau) * scale, "k--", lw=0.8, label=f"{ch} N: slope -1/2, at 1 s")
                if b > 0:
                    ax.axhline(allan.FLOOR * b * scale, color="k", ls=":", lw=0.8, label=f"{ch} 0.664 B: floor")
                if k > 0:
                    ax.loglog(tau, k * np.sqrt(tau / 3) * scale, "k-.", lw=0.8, label=f"{ch} K: slope +1/2, at 3 s")
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
