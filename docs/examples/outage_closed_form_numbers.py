"""The numbers of docs/aided-navigation.md's "Outages against the closed form": on the aided-nav campaign's
drive and GNSS outages (``sarins_fmu.experiments.aided_nav``: 30, 60 and 120 s during a 12 m/s cruise,
tactical IMU, white 1 Hz GNSS, GNSS + ZUPT), the RMS over the runs of the horizontal error growth over each
outage, e(end) - e(start), against the closed-form free-inertial growth (:mod:`sarins_fmu.free_inertial`)
predicted from the filter's covariance of velocity, attitude and bias errors at the outage start, without
and with the IMU's white noises and bias walks during the outage
(:func:`sarins_fmu.aided.outage_closed_form_monte_carlo`).

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/outage_closed_form_numbers.py [runs]
Writes docs/results/aided-navigation/outage_closed_form.json and prints the Markdown table.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from sarins_fmu import aided
from sarins_fmu.experiments import aided_nav

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "outage_closed_form.json"
RUNS = 50


def main(runs: int = RUNS) -> dict:
    rep = aided.outage_closed_form_monte_carlo(aided_nav.drive(), runs, [list(w) for w in aided_nav.OUTAGES],
                                               noise=aided.IMU_NOISE["tactical"], gnss=aided_nav.WHITE_GNSS,
                                               aiding=("gnss", "zupt"),
                                               settings=aided.FilterSettings(cov_every=10, out_every=20))
    rows = []
    for j, (start, end) in enumerate(aided_nav.OUTAGES):
        rms, s_state, s_all = (float(v[j]) for v in (rep.rms_growth, rep.state_sigma, rep.sigma))
        rows.append({"start_s": start, "end_s": end, "rms_growth_m": rms, "closed_form_state_sigma_m": s_state,
                     "closed_form_sigma_m": s_all, "ratio": rms / s_all, "ratio_state_only": rms / s_state})
    return {"runs": runs, "imu": "tactical", "outages": rows,
            "script": "docs/examples/outage_closed_form_numbers.py"}


if __name__ == "__main__":
    result = main(int(sys.argv[1]) if len(sys.argv) > 1 else RUNS)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print("| outage (s) | RMS growth (m) | closed form, state at start (m) | closed form + noise in the outage (m) "
          "| ratio |")
    print("|---|---|---|---|---|")
    for row in result["outages"]:
        print(f"| {row['start_s']:.0f}-{row['end_s']:.0f} ({row['end_s'] - row['start_s']:.0f} s) | "
              f"{row['rms_growth_m']:.3f} | {row['closed_form_state_sigma_m']:.3f} | {row['closed_form_sigma_m']:.3f} "
              f"| {row['ratio']:.2f} |")
