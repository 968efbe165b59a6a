"""The aided-navigation campaign's experiments: one drive, Monte Carlo runs of the 15-state
error-state Kalman filter (:func:`sarins_fmu.aided.navigate`) with GNSS and GNSS outages.

Also the comparison with KF-GINS, a peer filter, on one drive (:func:`kfgins_run`, the work of
:mod:`sarins_fmu.experiments.kfgins_compare`).

The drive (:func:`drive`): 20 s stop, accelerate to 12 m/s, 90° turn, cruise, -90° turn, brake,
10 s stop, at latitude 32° N, IMU at 100 Hz.  GNSS at 1 Hz with white errors (the filter's model:
the receiver presets' Gauss-Markov errors would make it over-confident, docs/aided-navigation.md),
outages of 30, 60 and 120 s during the cruise with GNSS between them.  Frames and units as in
:mod:`sarins_fmu.aided`: errors computed - true, position ENU m, velocity ENU m/s, attitude phi ENU rad.
"""

from __future__ import annotations

import functools

import numpy as np

from .. import aided, gnss
from .. import trajectory as tr

STEP = 0.01  # IMU step, s
LAT_DEG = 32.0  # start latitude, deg
SPEED = 12.0  # cruise speed, m/s
# 1 Hz fixes with white errors only (hypothetical, a receiver whose errors the 15-state filter models)
WHITE_GNSS = gnss.WHITE
OUTAGES = ((60.0, 90.0), (150.0, 210.0), (280.0, 400.0))  # GNSS outages [start, end) s: 30, 60, 120 s
CRUISE = 400.0  # s: the outages all fall in the cruise
BLOCKS = ("position", "velocity", "attitude")


@functools.lru_cache(maxsize=2)
def drive(cruise: float = CRUISE, step: float = STEP) -> tr.Truth:
    """Truth of the campaign's drive (see module docs) with a cruise of ``cruise`` s (cached per process:
    the runs of a worker share it; read only)."""
    segments = ({"kind": "stop", "duration": 20}, {"kind": "accelerate", "to_speed": SPEED, "accel": 1.0},
                {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": cruise},
                {"kind": "turn", "rate_dps": 6, "angle_deg": -90}, {"kind": "accelerate", "to_speed": 0, "accel": 1.5},
                {"kind": "stop", "duration": 10})
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT_DEG, lon_deg=118.0), segments), step)


# A manoeuvring drive (162.5 s) for the optional filter states (docs/aided-navigation.md, "Optional filter
# states"): two full turns each way (yaw rate 10 deg/s), a climb (pitch), accelerations.  The first stop lasts
# 20.5 s so that no 1 Hz fix falls on a jump of the turn rate: there the receiver's antenna velocity takes the
# rate of the step that starts at the epoch (gnss.h), the filter the rate of the step that ends there, a
# velocity outlier of |omega x l| (0.2 m/s with l = 1.2 m) that a random-constant lever state keeps for good.
MANOEUVRES = ({"kind": "stop", "duration": 20.5}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
              {"kind": "turn", "rate_dps": 10, "angle_deg": 360}, {"kind": "cruise", "duration": 20},
              {"kind": "climb", "to_pitch_deg": 5, "duration": 5}, {"kind": "cruise", "duration": 10},
              {"kind": "climb", "to_pitch_deg": 0, "duration": 5},
              {"kind": "turn", "rate_dps": -10, "angle_deg": 360}, {"kind": "accelerate", "to_speed": 0, "accel": 1.5},
              {"kind": "stop", "duration": 10})

def trajectory_task(cruise: float = CRUISE, out_every: int = 20) -> dict:
    """The drive's truth at the output rate: time (n,) s; east, north, up (n,) m from the start;
    speed (n,) m/s; yaw (n,) rad; stationary (n,) 1 where the vehicle stands still."""
    truth = drive(cruise)
    rows = truth.nav_rows()[::out_every]
    from .. import earth

    r_m, r_n = earth.radii(rows[0, 0])
    return {"time": truth.time[::out_every],
            "east": (rows[:, 1] - rows[0, 1]) * (r_n + rows[0, 2]) * np.cos(rows[0, 0]),
            "north": (rows[:, 0] - rows[0, 0]) * (r_m + rows[0, 2]), "up": rows[:, 2] - rows[0, 2],
            "speed": np.linalg.norm(rows[:, 3:6], axis=1), "yaw": rows[:, 6],
            "stationary": (np.linalg.norm(rows[:, 3:6], axis=1) < 1e-9).astype(float)}


def monte_carlo_run(seed: int, cruise: float = CRUISE, outages=OUTAGES, imu: str = "tactical",
                    aiding=("gnss", "zupt"), out_every: int = 20) -> dict:
    """One aided run of the drive (``seed``: IMU, initial and GNSS errors).

    Returns time (n,) s; error (n, 9) position ENU m, velocity ENU m/s, attitude ENU rad; sigma (n, 9)
    the filter's standard deviations of the same (square roots of P's diagonal); nees (n, 3) position,
    velocity, attitude NEES; outage_error, outage_sigma (m,) the horizontal error (m) at the end of each
    outage and the filter's sqrt(P_EE + P_NN) there; cpu_s the process time of the run.
    """
    import time

    truth = drive(cruise)
    settings = aided.FilterSettings(cov_every=10, out_every=out_every)
    t0 = time.process_time()
    r = aided.navigate(truth, noise=aided.IMU_NOISE[imu], gnss=WHITE_GNSS, aiding=tuple(aiding),
                       outages=[list(w) for w in outages], settings=settings, seed=seed)
    cpu = time.process_time() - t0
    table = aided.outage_table(r, outages)
    diag = np.sqrt(np.diagonal(r.cov, axis1=1, axis2=2)[:, :9])
    return {"time": r.time, "error": r.error, "sigma": diag, "nees": np.column_stack([r.nees(b) for b in BLOCKS]),
            "outage_error": np.array([row.error for row in table]),
            "outage_sigma": np.array([row.sigma for row in table]), "cpu_s": cpu}


# a drive with three 30 s stops for the zero-velocity detector (sarins_fmu.zero_velocity)
STOP_SEGMENTS = ({"kind": "stop", "duration": 30}, {"kind": "accelerate", "to_speed": 10, "accel": 1.0},
                 {"kind": "cruise", "duration": 60}, {"kind": "accelerate", "to_speed": 0, "accel": 1.0},
                 {"kind": "stop", "duration": 30}, {"kind": "accelerate", "to_speed": 8, "accel": 1.0},
                 {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 60},
                 {"kind": "accelerate", "to_speed": 0, "accel": 1.0}, {"kind": "stop", "duration": 30})


@functools.lru_cache(maxsize=1)
def stop_drive(step: float = STEP) -> tr.Truth:
    """Truth of :data:`STOP_SEGMENTS` (cached per process; read only)."""
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT_DEG, lon_deg=118.0), STOP_SEGMENTS), step)


ZUPT_WINDOW = 0.5  # detector window, s
ZUPT_ALPHA = 1e-3  # probability that a stationary window is declared moving
ZUPT_IMU = "tactical"
ZUPT_VIBRATION = "car"


def zupt_run(seed: int, imu: str = ZUPT_IMU, window: float = ZUPT_WINDOW, alpha: float = ZUPT_ALPHA,
             vibration: str = ZUPT_VIBRATION) -> dict:
    """One run of the IMU-statistics ZUPT detector on :func:`stop_drive` with the vibration preset
    ``vibration``, then GNSS-free navigation (ZUPT, odometer, NHC) with the truth's and the detected ZUPTs.

    Returns (scalars) stop_windows, misses: disjoint windows wholly inside the stops and those declared
    moving; moving_windows, false_stationary: windows wholly in motion and those declared stationary;
    delay_s: mean delay from a stop's start to its first detection; samples, gamma: the detector's N and
    threshold; error_truth_m, error_imu_m: horizontal error at the end with truth / detected ZUPTs;
    zupt_truth, zupt_imu: ZUPT steps; cpu_s.
    """
    import time

    from .. import zero_velocity as zv

    truth = stop_drive()
    noise, vib = aided.IMU_NOISE[imu], zv.VIBRATION[vibration]
    settings = zv.DetectorSettings(window=window, alpha=alpha)
    t0 = time.process_time()
    dtheta, dv, _, _ = aided.corrupt(truth, noise, seed)
    vib_theta, vib_v = zv.vibrate(truth, vib, seed)
    found = zv.detect(dtheta + vib_theta, dv + vib_v, truth.step, noise.vrw, noise.arw, settings)
    n, still = found.samples, truth.stationary()
    inside = np.convolve(still.astype(int), np.ones(n, int))[: still.size] == n
    moving = np.convolve((~still).astype(int), np.ones(n, int))[: still.size] == n
    disjoint = np.flatnonzero(inside)[::n]  # each stop is one run of whole windows: n apart, no shared sample
    starts = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(int)])) == 1)
    delays = [int(np.argmax(found.stationary[s:])) * truth.step for s in starts]
    kwargs = dict(noise=noise, aiding=("zupt", "odometer", "nhc"), seed=seed, vibration=vib, detector=settings)
    r_truth = aided.navigate(truth, zupt_detect="truth", **kwargs)
    r_imu = aided.navigate(truth, zupt_detect="imu", **kwargs)
    return {"stop_windows": disjoint.size, "misses": int(np.sum(~found.stationary[disjoint])),
            "moving_windows": int(moving.sum()), "false_stationary": int(np.sum(found.stationary & moving)),
            "delay_s": float(np.mean(delays)), "samples": n, "gamma": found.gamma,
            "error_truth_m": float(r_truth.horizontal_error()[-1]), "error_imu_m": float(r_imu.horizontal_error()[-1]),
            "zupt_truth": r_truth.zupt_steps, "zupt_imu": r_imu.zupt_steps, "cpu_s": time.process_time() - t0}


def kfgins_run(binary: str, minutes: float, seed: int = 0, repeats: int = 3) -> dict:
    """Our filter and KF-GINS (``binary``) on the same data: :func:`sarins_fmu.experiments.kfgins_compare.compare`
    on its drive of about ``minutes`` (tactical IMU, 1 Hz GNSS with white errors, ``seed``), each filter run
    ``repeats`` times (the fastest times kept).

    Returns comparison: the comparison's JSON text ('' when KF-GINS failed); failure: '' or one line saying
    how KF-GINS failed (its exit status and the end of its output, or why it could not start).
    """
    import json
    import subprocess

    from . import kfgins_compare

    try:
        r = kfgins_compare.compare(binary, minutes, seed=seed, repeats=repeats)
    except (OSError, RuntimeError, ValueError, subprocess.SubprocessError) as exc:
        return {"comparison": "", "failure": " ".join(f"{type(exc).__name__}: {exc}".split())[:300]}
    return {"comparison": json.dumps(r), "failure": ""}
