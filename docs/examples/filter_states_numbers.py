"""The numbers of docs/aided-navigation.md's "Optional filter states" section: Monte Carlo runs with and
without each optional ESKF state (navigate(filter_states=...)), against the truth.

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/filter_states_numbers.py
Writes docs/results/aided-navigation/filter-states.json and prints the Markdown table (about 20 s).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr
from sarins_fmu.experiments.aided_nav import MANOEUVRES

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "filter-states.json"
RUNS = 50
STEP = 0.01
WHITE_GNSS = gnss.WHITE
# the drive of aided_navigation_numbers.py (380 s, one 90 deg turn each way) and the manoeuvring one of
# sarins_fmu.experiments.aided_nav.MANOEUVRES (162.5 s: two full turns at 10 deg/s each way, a 5 deg climb,
# accelerations; its first stop of 20.5 s keeps the turn-rate jumps off the 1 Hz fix epochs: see there)
DRIVE = ({"kind": "stop", "duration": 20}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
         {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 300},
         {"kind": "turn", "rate_dps": 6, "angle_deg": -90}, {"kind": "accelerate", "to_speed": 0, "accel": 1.5},
         {"kind": "stop", "duration": 10})
SF_NOISE = dataclasses.replace(aided.IMU_NOISE["tactical"], gyro_sf_std=1e-3, accel_sf_std=1e-3)
LEVER_GNSS = dataclasses.replace(WHITE_GNSS, lever_arm=(0.5, 1.5, 1.2))
LEVER_SETTINGS = aided.FilterSettings(lever_arm=(0.0, 1.0, 0.9), lever0_std=0.5)
ALL_GNSS = dataclasses.replace(gnss.PRESETS["sps"], lever_arm=(0.5, 1.5, 1.2))
# case: (trajectory, what is simulated, navigate's keywords, the options compared)
CASES = {
    "sps": (DRIVE, "tactical IMU, sps preset (Gauss-Markov receiver errors, tau 60 s / 10 s)",
            {"gnss": gnss.PRESETS["sps"]}, [(), ("gnss-gm",)]),
    "scale_factors": (MANOEUVRES, "tactical IMU with scale-factor errors N(0, 1000 ppm^2) per axis, white GNSS",
                      {"gnss": WHITE_GNSS, "noise": SF_NOISE}, [(), ("sf",)]),
    "lever_arm": (MANOEUVRES, "tactical IMU, white GNSS, antenna at (0.5, 1.5, 1.2) m, the filter told (0, 1, 0.9) m",
                  {"gnss": LEVER_GNSS, "settings": LEVER_SETTINGS}, [(), ("lever",)]),
    "all": (MANOEUVRES, "all three: scale-factor errors, the lever arm 0.5 m off, the sps preset",
            {"gnss": ALL_GNSS, "noise": SF_NOISE, "settings": LEVER_SETTINGS},
            [(), ("sf",), ("lever",), ("gnss-gm",), ("sf", "lever", "gnss-gm")]),
}
BLOCKS = ("position", "velocity", "attitude")


def monte_carlo(truth, states, kwargs) -> dict:
    """RUNS seeds: horizontal RMS over runs and times, the time-mean of the mean NEES per block, the 95 % band
    of the mean of RUNS chi2(3), the fraction of times inside it; the optional states' final z-scores."""
    from scipy.stats import chi2

    h2, nees, z = 0.0, None, {}
    for seed in range(RUNS):
        r = aided.navigate(truth, seed=seed, filter_states=states, **kwargs)
        h2 += float(np.mean(r.horizontal_error() ** 2))
        values = {b: r.nees(b) for b in BLOCKS}
        nees = values if nees is None else {b: nees[b] + values[b] for b in BLOCKS}
        sg, sa = aided.scale_factors(kwargs.get("noise", aided.IMU_NOISE["tactical"]), seed)
        truth_of = {"scale_g": sg, "scale_a": sa, "lever": np.array(kwargs["gnss"].lever_arm)}
        for name in r.states:
            if name in truth_of:
                z.setdefault(name, []).append(((r.states[name][-1] - truth_of[name]) / r.state_sigma(name)[-1])
                                              .tolist())
    band = (chi2.ppf(0.025, 3 * RUNS) / RUNS, chi2.ppf(0.975, 3 * RUNS) / RUNS)
    mean = {b: v / RUNS for b, v in nees.items()}
    out = {"filter_states": list(states), "horizontal_rms_m": float(np.sqrt(h2 / RUNS)),
           "mean_nees": {b: float(v.mean()) for b, v in mean.items()},
           "nees_inside": {b: float(np.mean((v >= band[0]) & (v <= band[1]))) for b, v in mean.items()},
           "band": list(band)}
    if z:
        out["final_z"] = {name: {"mean": np.mean(v, axis=0).tolist(), "rms": np.sqrt(np.mean(np.square(v), axis=0))
                                 .tolist()} for name, v in z.items()}
    return out


def main() -> None:
    result = {"runs": RUNS, "step_s": STEP, "cases": {}}
    for name, (segments, text, kwargs, options) in CASES.items():
        truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), segments), STEP)
        result["cases"][name] = {"simulated": text, "duration_s": float(truth.time[-1]),
                                 "rows": [monte_carlo(truth, states, kwargs) for states in options]}
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print("| case | filter states | horizontal RMS (m) | mean NEES pos / vel / att | inside band pos / vel / att |")
    print("|---|---|---|---|---|")
    for name, case in result["cases"].items():
        for row in case["rows"]:
            n, i = row["mean_nees"], row["nees_inside"]
            print(f"| {name} | {', '.join(row['filter_states']) or 'none (15 states)'} | {row['horizontal_rms_m']:.3f} | "
                  f"{n['position']:.2f} / {n['velocity']:.2f} / {n['attitude']:.2f} | "
                  f"{i['position']:.2f} / {i['velocity']:.2f} / {i['attitude']:.2f} |")
    for name, case in result["cases"].items():
        for row in case["rows"]:
            for state, z in row.get("final_z", {}).items():
                print(f"{name} {','.join(row['filter_states'])} {state}: final z mean "
                      f"{np.round(z['mean'], 2).tolist()}, rms {np.round(z['rms'], 2).tolist()}")


if __name__ == "__main__":
    main()
