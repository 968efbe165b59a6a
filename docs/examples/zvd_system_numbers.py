"""The numbers of docs/aided-navigation.md's "Detected stops in the system" section: the systems' default drive
(sarins.systems.GNSS_DRIVE, 124.6 s with two 10 s stops, tactical IMU, 1 Hz SPS, GNSS outage 60-80 s, seed 0) with
every aiding (GNSS, ZUPT, ZARU, NHC, odometer) on the core's streams, the stops

  - from the truth (vehicle_gnss_zupt, navigate(..., imu_stream="core")),
  - detected by AidedINS from TrajectoryIMU's increments with the car's vibration (vehicle_gnss_zupt(zupt_detect=
    "imu", vibration=VIBRATION["car"]), navigate(..., zupt_detect="imu", vibration=car, imu_stream="core")),
  - detected without vibration (in process only: the cruises pass the test like stops).

For the detected case the system is built (FMUs into a temporary folder) and run through the master under
Gauss-Seidel; its rows are compared with navigate's at every output time (bit for bit: the count of equal rows).
Per case: ZUPT steps (truth's still steps, detected still steps, detected moving steps), the drive's horizontal RMS
error and the error at the outage's end (aided.outage_table).

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/zvd_system_numbers.py
Writes docs/results/aided-navigation/zvd_system.json and prints it (a minute: the FMU build and one system run).
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from sarins.systems import GNSS_DRIVE, GNSS_OUTAGES, vehicle_gnss_zupt
from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr
from sarins_fmu import zero_velocity as zv

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "zvd_system.json"
AIDING = ("gnss", "zupt", "zaru", "nhc", "odometer")
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
SEED = 0


def run(truth, **kwargs):
    return aided.navigate(truth, noise=aided.IMU_NOISE["tactical"], gnss=gnss.preset("sps", rate_hz=1.0),
                          aiding=AIDING, outages=GNSS_OUTAGES, seed=SEED, imu_stream="core", **kwargs)


def stops(truth, vibration):
    """The detector's still steps on the core stream's increments (and the vibration's, when given)."""
    noise = aided.IMU_NOISE["tactical"]
    dtheta, dv, _, _ = aided.corrupt(truth, noise, SEED, stream="core")
    if vibration is not None:
        vib_theta, vib_v = zv.vibrate(truth, vibration, SEED, stream="core")
        dtheta, dv = dtheta + vib_theta, dv + vib_v
    return zv.detect(dtheta, dv, truth.step, noise.vrw, noise.arw).stationary


def system_rows(vibration) -> tuple:
    """The detected system under Gauss-Seidel: nav_time (n,) and the navigation rows (n, 9)."""
    from fmus.native_fmu import build_native_fmu
    from orchestration import simulate_system, write_ssp

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, slave in (("TrajectoryIMU", "trajectory_imu_slave.py"), ("GNSSReceiver", "gnss_receiver_slave.py"),
                            ("AidedINS", "aided_ins_slave.py")):
            build_native_fmu(name, slave, tmp, win64=False, aarch64=False)
        system = vehicle_gnss_zupt(tmp, seed=SEED, zupt_detect="imu", vibration=vibration)
        rows = simulate_system(write_ssp(system, tmp / "zvd.ssp"), scheme="gauss-seidel",
                               record=[f"ins.{n}" for n in NAV] + ["ins.nav_time"], progress=False)
        return np.asarray(rows["ins.nav_time"]), np.column_stack([rows[f"ins.{n}"] for n in NAV])


def summary(r, truth_still, found=None) -> dict:
    out = {"zupt_steps": r.zupt_steps, "horizontal_error_rms_m": float(np.sqrt(np.mean(r.horizontal_error() ** 2))),
           "end_of_outage_error_m": aided.outage_table(r, GNSS_OUTAGES)[0].error}
    if found is not None:
        out.update({"detected_still_steps": int(np.sum(found & truth_still)),
                    "detected_moving_steps": int(np.sum(found & ~truth_still))})
    return out


def main() -> dict:
    truth = tr.generate(tr.Trajectory.from_dict(GNSS_DRIVE), 0.01)
    still = truth.stationary()
    car = zv.VIBRATION["car"]
    detected = run(truth, zupt_detect="imu", vibration=car)
    nav_time, rows = system_rows(car)
    index = np.round(detected.time / 0.01).astype(int)  # Gauss-Seidel: the row at time k h has nav_time k h
    equal = int(np.sum(np.all(rows[index] == detected.nav, axis=1) & (nav_time[index] == detected.time)))
    return {"drive": "sarins.systems.GNSS_DRIVE", "imu": "tactical", "gnss": "sps 1 Hz", "seed": SEED,
            "aiding": list(AIDING), "truth_still_steps": int(still.sum()), "detector": {
                "samples": detected.info["detector_samples"], "gamma": detected.info["detector_gamma"],
                "alpha": detected.info["detector_alpha"]},
            "truth": summary(run(truth), still),
            "detected_car_vibration": summary(detected, still, stops(truth, car)),
            "detected_no_vibration": summary(run(truth, zupt_detect="imu"), still, stops(truth, None)),
            "system_gauss_seidel_rows_equal_to_navigate": equal, "output_rows": len(detected.time)}


if __name__ == "__main__":
    numbers = main()
    OUT.write_text(json.dumps(numbers, indent=2) + "\n")
    print(json.dumps(numbers, indent=2))
