"""The numbers of docs/aided-navigation.md: ideal-IMU closed-form check, NEES and outage Monte Carlo,
the GNSS presets, and one aided run per receiver preset.

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/aided_navigation_numbers.py
Writes docs/results/aided-navigation/numbers.json and prints the Markdown tables (about a minute).
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from sarins_fmu import aided, earth, gnss
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided as core
from sarins_fmu.rotations import euler_to_mat, mat_to_quat

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "numbers.json"
CHECK_SEGMENTS = (
    {"kind": "stop", "duration": 10}, {"kind": "accelerate", "to_speed": 15, "accel": 1.0},
    {"kind": "cruise", "duration": 30}, {"kind": "turn", "rate_dps": 3, "angle_deg": 90},
    {"kind": "climb", "to_pitch_deg": 5, "duration": 5}, {"kind": "cruise", "duration": 60},
    {"kind": "climb", "to_pitch_deg": 0, "duration": 5}, {"kind": "turn", "rate_dps": -6, "duration": 30},
    {"kind": "accelerate", "to_speed": 0, "accel": 1.5}, {"kind": "stop", "duration": 20})
WHITE_GNSS = gnss.WHITE


def ideal_check() -> dict:
    """End position error (m) of the ideal IMU through the 3-D mechanization at three rates."""
    traj = tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0, height=50.0), CHECK_SEGMENTS)
    out = {}
    for step in (0.02, 0.01, 0.005):
        truth = tr.generate(traj, step, 4)
        q = mat_to_quat(euler_to_mat(*truth.attitude[0])).copy()
        rows = core.nav3_steps(q, truth.velocity_n[0].copy(), truth.nav_rows()[0, :3].copy(), truth.dtheta, truth.dv,
                               step)
        t, o = truth.nav_rows()[-1], rows[-1]
        r_m, r_n = earth.radii(t[0])
        e = [(o[1] - t[1]) * (r_n + t[2]) * math.cos(t[0]), (o[0] - t[0]) * (r_m + t[2]), o[2] - t[2]]
        out[step] = {"duration_s": float(truth.time[-1]), "error_enu_m": e,
                     "velocity_error_max_mps": float(np.abs(rows[:, 3:6] - truth.velocity_n[1:]).max())}
    e1, e2 = np.array(out[0.01]["error_enu_m"]), np.array(out[0.02]["error_enu_m"])
    residual = e1 - (e2 - e1) / 3.0
    return {"runs": out, "richardson_residual_m": float(np.linalg.norm(residual)),
            "richardson_residual_m_per_h": float(np.linalg.norm(residual) / (out[0.01]["duration_s"] / 3600.0))}


def drive(cruise: float, step: float):
    segments = ({"kind": "stop", "duration": 20}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
                {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": cruise},
                {"kind": "turn", "rate_dps": 6, "angle_deg": -90}, {"kind": "accelerate", "to_speed": 0, "accel": 1.5},
                {"kind": "stop", "duration": 10})
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), segments), step)


def monte_carlo() -> dict:
    settings = aided.FilterSettings(cov_every=10, out_every=10)
    truth = drive(300.0, 0.01)
    t0 = time.process_time()
    nees = aided.nees_monte_carlo(truth, 50, gnss=WHITE_GNSS, settings=settings)
    nees_cpu = time.process_time() - t0
    outage = aided.outage_monte_carlo(truth, 50, [[60, 90], [120, 180], [200, 320]], gnss=WHITE_GNSS,
                                      settings=settings)
    from scipy.stats import chi2

    interval = [math.sqrt(chi2.ppf(q, 100) / 100) for q in (0.025, 0.975)]  # ratio if consistent: chi2(2R)/2R
    return {"duration_s": float(truth.time[-1]), "runs": 50, "band": list(nees.band), "ratio_interval": interval,
            "nees_time_mean": {b: float(v.mean()) for b, v in nees.mean_nees.items()}, "nees_inside": nees.inside,
            "cpu_s_per_run": nees_cpu / 50,
            "outages": [{"window_s": list(w), "rms_error_m": e, "predicted_sigma_m": s, "ratio": e / s}
                        for w, e, s in zip(outage.windows, outage.rms_error, outage.predicted_sigma)]}


def options() -> dict:
    """GNSS-free runs: RMS over 20 seeds of the horizontal error at the end of the cruise (347 s) and the
    filter's sigma there, for each set of aiding."""
    truth = drive(300.0, 0.01)
    settings = aided.FilterSettings(cov_every=10, out_every=10)
    out = {}
    for aiding in (("zupt",), ("zupt", "odometer"), ("zupt", "nhc"), ("zupt", "odometer", "nhc")):
        err2 = var = vel2 = 0.0
        for seed in range(20):
            r = aided.navigate(truth, aiding=aiding, settings=settings, seed=seed)
            k = int(np.searchsorted(r.time, 347.0))
            err2 += r.horizontal_error()[k] ** 2
            var += r.horizontal_sigma()[k] ** 2
            vel2 += float(np.sum(r.error[k, 3:5] ** 2))
        out[",".join(aiding)] = {"rms_horizontal_error_m": math.sqrt(err2 / 20), "sigma_m": math.sqrt(var / 20),
                                 "rms_horizontal_velocity_error_mps": math.sqrt(vel2 / 20)}
    return out


def presets() -> dict:
    truth = drive(300.0, 0.01)
    out = {}
    for name in gnss.PRESETS:
        cfg = gnss.PRESETS[name]
        r = aided.navigate(truth, gnss=cfg, seed=0, outages=[[200, 260]])
        s = aided.summary(r, [[200, 260]])
        out[name] = {"pos_std_enu_m": list(cfg.pos_std()), "vel_std_enu_mps": list(cfg.vel_std()),
                     "horizontal_error_rms_m": s["horizontal_error_rms_m"], "mean_nees": s["mean_nees"],
                     "outage_60s": s["outages"][0]}
    return out


def zupt_detection(runs: int = 20) -> dict:
    """The IMU-statistics ZUPT detector (sarins_fmu.zero_velocity, window 0.5 s, alpha 1e-3, vibration
    'car') on a drive with three 30 s stops, per grade: misses over disjoint windows wholly in the stops,
    false 'stationary' over windows wholly in motion and its Chernoff bound, the delay to the first
    detection in each stop; then GNSS-free navigation (zupt, odometer, nhc): RMS over the runs of the
    horizontal error at the end with truth ZUPTs, detected ZUPTs, and detected ZUPTs without vibration."""
    from sarins_fmu import zero_velocity as zv
    from sarins_fmu.experiments.aided_nav import STOP_SEGMENTS

    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), STOP_SEGMENTS), 0.01)
    settings, car = zv.DetectorSettings(), zv.VIBRATION["car"]
    still = truth.stationary()
    out = {"duration_s": float(truth.time[-1]), "stop_steps": int(still.sum()), "runs": runs,
           "window_s": settings.window, "alpha": settings.alpha}
    for grade in ("tactical", "mems"):
        noise = aided.IMU_NOISE[grade]
        n = settings.samples(truth.step)
        inside = np.convolve(still.astype(int), np.ones(n, int))[: still.size] == n
        moving = np.convolve((~still).astype(int), np.ones(n, int))[: still.size] == n
        disjoint = np.flatnonzero(inside)[::n]
        starts = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(int)])) == 1)
        misses = false = 0
        delays = []
        t0 = time.process_time()
        for seed in range(runs):
            dtheta, dv, _, _ = aided.corrupt(truth, noise, seed)
            vt, vv = zv.vibrate(truth, car, seed)
            found = zv.detect(dtheta + vt, dv + vv, truth.step, noise.vrw, noise.arw, settings)
            misses += int(np.sum(~found.stationary[disjoint]))
            false += int(np.sum(found.stationary & moving))
            delays += [int(np.argmax(found.stationary[s:])) * truth.step for s in starts]
        cpu = (time.process_time() - t0) / runs
        bound = zv.moving_window_bound(n, found.gamma, noise.vrw / math.sqrt(truth.step),
                                       noise.arw / math.sqrt(truth.step), car)
        nav = {}
        for label, kwargs in (("truth", {"zupt_detect": "truth", "vibration": car}),
                              ("imu", {"zupt_detect": "imu", "vibration": car}),
                              ("imu, no vibration", {"zupt_detect": "imu", "vibration": None})):
            err2, steps = 0.0, 0
            for seed in range(runs):
                r = aided.navigate(truth, noise=noise, aiding=("zupt", "odometer", "nhc"), seed=seed, **kwargs)
                err2 += r.horizontal_error()[-1] ** 2
                steps += r.zupt_steps
            nav[label] = {"rms_final_horizontal_error_m": math.sqrt(err2 / runs), "mean_zupt_steps": steps / runs}
        out[grade] = {"samples": n, "gamma": found.gamma, "disjoint_stop_windows": int(disjoint.size) * runs,
                      "misses": misses, "moving_windows": int(moving.sum()) * runs, "false_stationary": false,
                      "bound_per_window": bound, "max_delay_s": max(delays), "mean_delay_s": float(np.mean(delays)),
                      "detector_cpu_s_per_run": cpu, "navigation": nav}
    return out


def _bound(p: float) -> str:
    return "< 1e-300 (underflows)" if p == 0.0 else f"{p:.1e}"


def print_zupt(numbers):
    z = numbers["zupt_detection"]
    print(f"\nZUPT detection, {z['runs']} runs of {z['duration_s']:.0f} s, window {z['window_s']} s, alpha {z['alpha']}")
    print("| grade | N | gamma | missed stop windows | false 'stationary' (moving windows) | bound per window | "
          "delay mean / max (s) |")
    print("|---|---|---|---|---|---|---|")
    for grade in ("tactical", "mems"):
        g = z[grade]
        print(f"| {grade} | {g['samples']} | {g['gamma']:.1f} | {g['misses']} / {g['disjoint_stop_windows']} | "
              f"{g['false_stationary']} / {g['moving_windows']} | {_bound(g['bound_per_window'])} | "
              f"{g['mean_delay_s']:.2f} / {g['max_delay_s']:.2f} |")
    print("\n| grade | ZUPTs from | RMS final horizontal error (m) | mean ZUPT steps |")
    print("|---|---|---|---|")
    for grade in ("tactical", "mems"):
        for label, v in z[grade]["navigation"].items():
            print(f"| {grade} | {label} | {v['rms_final_horizontal_error_m']:.2f} | {v['mean_zupt_steps']:.0f} |")
    print(f"(truth stop steps: {z['stop_steps']})")


def main():
    numbers = {"ideal_check": ideal_check(), "monte_carlo": monte_carlo(), "presets": presets(), "options": options(),
               "zupt_detection": zupt_detection()}
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(numbers, indent=1, default=float))
    ic = numbers["ideal_check"]
    print("| IMU step (s) | end error E, N, U (m) | max velocity error (m/s) |")
    print("|---|---|---|")
    for step, r in ic["runs"].items():
        e = ", ".join(f"{x:.2e}" for x in r["error_enu_m"])
        print(f"| {step} | {e} | {r['velocity_error_max_mps']:.2e} |")
    print(f"\nRichardson residual {ic['richardson_residual_m']:.2e} m = {ic['richardson_residual_m_per_h']:.2e} m/h\n")
    mc = numbers["monte_carlo"]
    print(f"NEES, {mc['runs']} runs of {mc['duration_s']:.0f} s at 100 Hz; band {mc['band'][0]:.3f} .. {mc['band'][1]:.3f}")
    print("| block | time-mean of mean NEES | inside the band |")
    print("|---|---|---|")
    for b in ("position", "velocity", "attitude"):
        print(f"| {b} | {mc['nees_time_mean'][b]:.3f} | {100 * mc['nees_inside'][b]:.1f} % |")
    print("\n| outage (s) | RMS horizontal error (m) | predicted sigma (m) | ratio |")
    print("|---|---|---|---|")
    for o in mc["outages"]:
        w = o["window_s"]
        print(f"| {w[0]:.0f}-{w[1]:.0f} ({w[1] - w[0]:.0f} s) | {o['rms_error_m']:.3f} | {o['predicted_sigma_m']:.3f} | "
              f"{o['ratio']:.2f} |")
    print(f"ratio if consistent (95 %): {mc['ratio_interval'][0]:.2f} .. {mc['ratio_interval'][1]:.2f}")
    print(f"\nCPU per run: {mc['cpu_s_per_run']:.3f} s\n")
    print("| preset | position std E, N, U (m) | horizontal RMS (m) | mean NEES pos / vel / att | 60 s outage error / sigma (m) |")
    print("|---|---|---|---|---|")
    for name, p in numbers["presets"].items():
        std = ", ".join(f"{x:.4g}" for x in p["pos_std_enu_m"])
        n = p["mean_nees"]
        o = p["outage_60s"]
        print(f"| {name} | {std} | {p['horizontal_error_rms_m']:.3g} | {n['position']:.1f} / {n['velocity']:.1f} / "
              f"{n['attitude']:.1f} | {o['horizontal_error_m']:.3g} / {o['predicted_sigma_m']:.3g} |")
    print_options(numbers)
    print_zupt(numbers)



def print_options(numbers):
    print("\n| aiding (no GNSS) | RMS horizontal error (m) | filter sigma (m) | RMS horizontal velocity error (m/s) |")
    print("|---|---|---|---|")
    for name, o in numbers["options"].items():
        print(f"| {name} | {o['rms_horizontal_error_m']:.2f} | {o['sigma_m']:.2f} | "
              f"{o['rms_horizontal_velocity_error_mps']:.3f} |")


if __name__ == "__main__":
    main()
