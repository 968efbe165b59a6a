"""The numbers of docs/aided-navigation.md's ZARU section: a static vehicle (closed-form bias sigma, heading
drift with and without ZARU), gyrocompassing with a perfect gyro (the attitude block) and a GNSS-free drive
that starts with a stop.

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/zaru_numbers.py
Writes docs/results/aided-navigation/zaru.json and prints the Markdown tables (a few seconds).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from sarins_fmu import aided, earth
from sarins_fmu import trajectory as tr
from sarins_fmu.units import DPH_TO_RPS

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "zaru.json"
STEP, LAT, RUNS = 0.02, 32.0, 20
DEG = 180.0 / math.pi


def white_filter_noise(grade: aided.ImuNoise) -> aided.ImuNoise:
    """The grade's white noises and constant-bias stds, no bias walks (a constant to estimate)."""
    return aided.ImuNoise(arw=grade.arw, vrw=grade.vrw, gyro_bias_std=grade.gyro_bias_std,
                          accel_bias_std=grade.accel_bias_std)


def static(grade_name: str, duration: float, bias_sigmas=(0.2, -0.3, 1.5)) -> dict:
    """One stop of ``duration`` s, known constant gyro biases (multiples of the grade's std), no GNSS, RUNS
    seeds: the z gyro bias and the heading with ZUPT and with ZUPT + ZARU."""
    grade = aided.IMU_NOISE[grade_name]
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT), ({"kind": "stop", "duration": duration},)), STEP)
    bias = np.array(bias_sigmas) * grade.gyro_bias_std
    r_step = grade.arw**2 / STEP
    closed = 1.0 / math.sqrt(1.0 / grade.gyro_bias_std**2 + truth.n_steps / r_step)
    rows = {}
    for aiding in (("zupt",), ("zupt", "zaru")):
        err, sig, dhead, hsig = [], [], [], []
        for seed in range(RUNS):
            dtheta, dv, bg, ba = aided.corrupt(truth, aided.ImuNoise(arw=grade.arw, vrw=grade.vrw), seed)
            r = aided.navigate(truth, noise=white_filter_noise(grade), aiding=aiding, seed=seed,
                               imu=(dtheta + bias * STEP, dv, bg + bias, ba), settings=aided.FilterSettings(out_every=50))
            err.append(r.bias_g[-1, 2] - bias[2])
            sig.append(math.sqrt(r.cov[-1, 11, 11]))
            dhead.append(r.error[-1, 8] - r.error[0, 8])
            hsig.append(math.sqrt(r.cov[-1, 8, 8]))
        err, sig = np.array(err), np.array(sig)
        rows[",".join(aiding)] = {
            "bias_z_true_dph": bias[2] / DPH_TO_RPS,
            "bias_z_rms_error_dph": float(np.sqrt(np.mean(err**2)) / DPH_TO_RPS),
            "bias_z_max_error_over_sigma": float(np.max(np.abs(err) / sig)),
            "bias_z_sigma_dph": float(np.mean(sig) / DPH_TO_RPS),
            "heading_change_rms_deg": float(np.sqrt(np.mean(np.square(dhead))) * DEG),
            "heading_sigma_end_deg": float(np.mean(hsig) * DEG),
        }
    return {"grade": grade_name, "duration_s": duration, "runs": RUNS, "zaru_std_rps": grade.arw / math.sqrt(STEP),
            "bias_z_prior_dph": grade.gyro_bias_std / DPH_TO_RPS, "closed_form_sigma_dph": closed / DPH_TO_RPS,
            "free_heading_drift_deg": bias[2] * duration * DEG, "rows": rows}


def gyrocompass(duration: float = 60.0, zaru_std: float = 1e-7) -> dict:
    """A perfect gyro, a level vehicle heading 30 deg, ZUPT + ZARU: the heading sigma against 1 / sigma^2 =
    1 / sigma0^2 + N (Omega cos L)^2 / r (the tilt found by the ZUPT), and the heading error, over 3 seeds."""
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT, heading_deg=30.0), ({"kind": "stop", "duration": duration},)),
                        STEP)
    settings = aided.FilterSettings(zaru_std=zaru_std, out_every=50)
    om = earth.RATE * math.cos(math.radians(LAT))
    closed = 1.0 / math.sqrt(1.0 / settings.heading0_std**2 + truth.n_steps * om**2 / zaru_std**2)
    sig, err, sig0 = [], [], []
    for seed in range(3):
        for aiding in (("zupt", "zaru"), ("zupt",)):
            r = aided.navigate(truth, noise=aided.IMU_NOISE["ideal"], aiding=aiding, seed=seed, settings=settings)
            if "zaru" in aiding:
                sig.append(math.sqrt(r.cov[-1, 8, 8]))
                err.append(abs(r.error[-1, 8]))
            else:
                sig0.append(math.sqrt(r.cov[-1, 8, 8]))
    return {"duration_s": duration, "zaru_std_rps": zaru_std, "heading_sigma_rad": float(np.mean(sig)),
            "closed_form_rad": closed, "max_abs_heading_error_rad": float(max(err)),
            "heading_sigma_zupt_only_rad": float(np.mean(sig0))}


DRIVE = ({"kind": "stop", "duration": 60}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
         {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 120},
         {"kind": "turn", "rate_dps": -6, "angle_deg": 90}, {"kind": "cruise", "duration": 120},
         {"kind": "accelerate", "to_speed": 0, "accel": 1.5}, {"kind": "stop", "duration": 5})


def drive(grade_name: str) -> dict:
    """A 60 s stop, 290 s of driving, a 5 s stop (355 s), no GNSS (ZUPT, odometer, NHC), RUNS seeds of the grade's IMU:
    RMS over the runs of the heading error and the horizontal error at the end."""
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT), DRIVE), STEP)
    out = {}
    for aiding in (("zupt", "odometer", "nhc"), ("zupt", "odometer", "nhc", "zaru")):
        head, hor, bz = [], [], []
        for seed in range(RUNS):
            r = aided.navigate(truth, noise=aided.IMU_NOISE[grade_name], aiding=aiding, seed=seed,
                               settings=aided.FilterSettings(out_every=50))
            head.append(r.error[-1, 8])
            hor.append(r.horizontal_error()[-1])
            bz.append(r.bias_g[-1, 2] - r.bias_g_true[-1, 2])
        out[",".join(aiding)] = {"heading_error_rms_deg": float(np.sqrt(np.mean(np.square(head))) * DEG),
                                 "horizontal_error_rms_m": float(np.sqrt(np.mean(np.square(hor)))),
                                 "bias_z_rms_error_dph": float(np.sqrt(np.mean(np.square(bz))) / DPH_TO_RPS)}
    return {"grade": grade_name, "duration_s": float(truth.time[-1]), "runs": RUNS, "rows": out}


def main() -> None:
    result = {"static": [static("mems", 300.0), static("tactical", 600.0)], "gyrocompass": gyrocompass(),
              "drive": [drive("mems"), drive("tactical")]}
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print("| grade, stop | aiding | z bias true (deg/h) | RMS error (deg/h) | max abs error / sigma | filter sigma "
          "(deg/h) | closed form (deg/h) | RMS heading change (deg) | heading sigma at end (deg) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for s in result["static"]:
        for aiding, v in s["rows"].items():
            print(f"| {s['grade']}, {s['duration_s']:.0f} s | {aiding} | {v['bias_z_true_dph']:.2f} | "
                  f"{v['bias_z_rms_error_dph']:.3f} | {v['bias_z_max_error_over_sigma']:.2f} | {v['bias_z_sigma_dph']:.3f} | "
                  f"{s['closed_form_sigma_dph']:.3f} | {v['heading_change_rms_deg']:.3f} | {v['heading_sigma_end_deg']:.3f} |")
    g = result["gyrocompass"]
    print(f"\nperfect gyro, {g['duration_s']:.0f} s, ZUPT + ZARU (zaru_std {g['zaru_std_rps']:g} rad/s): heading sigma "
          f"{g['heading_sigma_rad']:.4e} rad, closed form {g['closed_form_rad']:.4e} rad, max |heading error| "
          f"{g['max_abs_heading_error_rad']:.1e} rad; ZUPT alone: sigma {g['heading_sigma_zupt_only_rad']:.2e} rad")
    print("\n| grade | aiding (no GNSS) | RMS heading error (deg) | RMS horizontal error (m) | RMS z bias error (deg/h) |")
    print("|---|---|---|---|---|")
    for d in result["drive"]:
        for aiding, v in d["rows"].items():
            print(f"| {d['grade']} | {aiding} | {v['heading_error_rms_deg']:.3f} | {v['horizontal_error_rms_m']:.2f} | "
                  f"{v['bias_z_rms_error_dph']:.3f} |")


if __name__ == "__main__":
    main()
