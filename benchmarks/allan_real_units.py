"""The numbers of docs/imu-log.md for the two real ADIS16405 static records (../shared/data/adis16405).

    python benchmarks/allan_real_units.py [--data ../shared/data/adis16405] [--sim-factor 10]

Prints (markdown) for each unit and gyro axis (right-front-up, read with ``--axes frd``) and each
accelerometer: the read-outs N, B, K, Q with their 95 % intervals (``sarins_fmu.allan_readout``), the
IEEE graphical readings with allantools (its overlapping deviation at 1 s, and at B's averaging
time over 0.664), and the datasheet figures; then the Allan deviation of the preset fitted to the
record (``sarins allan --write-preset``) against the real one per octave from 0.1 s to a tenth of
the record: its closed form, and a simulated record ``--sim-factor`` times as long; and the periodic
terms the fit kept, with each channel's worst deviation without one.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sarins.allan import DISPLAY  # noqa: E402
from sarins_fmu import allan_preset, allan_readout  # noqa: E402
from sarins_fmu.imu_log import ReadOptions, read_log  # noqa: E402

CHANNELS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
DATASHEET = {"gyro": "N 3 (0.05 deg/s/sqrt(Hz)); in-run stability 25 deg/h", "accel": "-"}


def _fmt(term, triad, t) -> str:
    f = DISPLAY[triad][term][0]
    if not t.resolved:
        return f"n.r. (< {t.high * f:.3g})"
    return f"{t.value * f:.3g} [{t.low * f:.3g}, {t.high * f:.3g}] @ {t.tau:g} s"


def main() -> None:
    import allantools

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data" / "adis16405")
    p.add_argument("--sim-factor", type=float, default=10.0)
    args = p.parse_args()
    ratio_rows, periodic_rows = [], []
    print("| unit | channel | N | B | K | Q | allantools sigma(1 s) | allantools sigma(tau_B)/0.664 | datasheet |")
    print("|---|---|---|---|---|---|---|---|---|")
    for unit in ("unit1", "unit2"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            log = read_log(args.data / f"{unit}.csv.gz", ReadOptions(axes="frd", lat_deg=51.08, height_m=1100.0))
        h = log.step
        rates = np.hstack([log.dtheta, log.dv]) / h
        curves = {}
        for j, ch in enumerate(CHANNELS):
            triad = ch.split("_")[0]
            c = curves[ch] = allan_readout.octave_curve(rates[:, j], 1.0 / h)
            r = allan_readout.read_terms(c)
            b = r["bias_instability"]
            taus = np.array([1.0] + ([b.tau] if b.resolved else []))
            _, theirs, _, _ = allantools.oadev(rates[:, j], rate=1.0 / h, data_type="freq", taus=taus)
            fn, fb = DISPLAY[triad]["random_walk"][0], DISPLAY[triad]["bias_instability"][0]
            floor = f"{theirs[1] / allan_readout.FLOOR * fb:.3g}" if b.resolved else "-"
            print(f"| {unit} | {ch} | {_fmt('random_walk', triad, r['random_walk'])} | "
                  f"{_fmt('bias_instability', triad, b)} | {_fmt('rate_random_walk', triad, r['rate_random_walk'])} | "
                  f"{_fmt('quantization', triad, r['quantization'])} | {theirs[0] * fn:.3g} | {floor} | "
                  f"{DATASHEET[triad]} |", flush=True)
        record = len(log.time) * h
        fit = allan_preset.fit_preset(curves, record, log.means, log.lat, log.height)
        for j, ch in enumerate(CHANNELS):
            without = allan_preset.fit_channel(curves[ch], record, fit.band, periodic=False).worst
            periodic_rows.append((unit, ch, fit.channels[j], without, fit.band))
        sim = allan_preset.simulate_rates(fit.model, args.sim_factor * record, 1.0 / h, seed=2)
        for j, ch in enumerate(CHANNELS):
            c = curves[ch]
            use = allan_preset.fitted_taus(c, record)
            model = np.sqrt(allan_preset.model_avar(c.taus[use], fit.channels[j], fit.band)) / c.adev[use]
            s = allan_readout.octave_curve(sim[:, j], 1.0 / h)
            sims = dict(zip(np.round(s.taus, 9), s.adev))
            simr = np.array([sims[round(t, 9)] for t in c.taus[use]]) / c.adev[use]
            ratio_rows.append((unit, ch, c.taus[use], model, simr))
        del sim
    print()
    taus = ratio_rows[0][2]
    print(f"Preset / real Allan deviation per octave (model: closed form; sim: a record {args.sim_factor:g} x as long)")
    print()
    print("| unit | channel | curve | " + " | ".join(f"{t:g} s" for t in taus) + " | worst |")
    print("|---|---|---|" + "---|" * (len(taus) + 1))
    for unit, ch, _, model, simr in ratio_rows:
        for label, r in (("model", model), ("sim", simr)):
            print(f"| {unit} | {ch} | {label} | " + " | ".join(f"{x:.2f}" for x in r)
                  + f" | {np.max(np.abs(r - 1)) * 100:.0f} % |")
    print()
    print(f"flicker band and fits: see sarins allan --write-preset; record {record:g} s, "
          f"octaves {taus[0]:g} .. {taus[-1]:g} s ({math.log2(taus[-1] / taus[0]):.0f} octaves)")
    print()
    print("Periodic terms kept by the fit (amplitude: gyros deg/h, accelerometers mm/s^2) and the worst "
          "deviation of the closed form with and without one")
    print()
    print("| unit | channel | flicker band s | amplitude | frequency Hz | worst | worst without |")
    print("|---|---|---|---|---|---|---|")
    for unit, ch, c, without, band in periodic_rows:
        scale = 180.0 / math.pi * 3600.0 if ch.startswith("gyro") else 1e3
        term = (f"{c.periodic_amplitude * scale:.3g} | {c.periodic_frequency:.3g}" if c.periodic_amplitude > 0
                else "- | -")
        print(f"| {unit} | {ch} | {band[0]:g} .. {band[1]:g} | {term} | {c.worst * 100:.1f} % | {without * 100:.1f} % |")


if __name__ == "__main__":
    main()
