"""Our aided navigation against KF-GINS (github:i2Nav-WHU/KF-GINS, a peer GNSS/INS filter built outside
the project) on the same simulated IMU and GNSS data: RMS position, velocity and attitude errors against
the truth, and run times.  Used by ``benchmarks/kfgins_compare.py`` and the aided-nav campaign's report.

One drive (stops, accelerations, turns at a rate and a radius, climbs), one IMU record (preset of
``sarins_fmu.aided.IMU_NOISE``) and one set of GNSS fixes (same seed) are made once.  Our
``aided.navigate`` (GNSS position aiding only, as KF-GINS; no ZUPT) runs on them in process; the same
increments, fixes, initial state (with the same initial errors) and noise figures are written in
KF-GINS's formats (:mod:`sarins_fmu.kfgins`) and KF-GINS runs as a subprocess.  Errors are taken at our
output times (every ``out_every`` IMU steps) against the trajectory's truth.  Ours keeps at those times
the navigation, the bias estimates and the variances (P's diagonal, ``covariance="diagonal"``), as
KF-GINS writes its navigation, IMU errors and the states' stds.  Times are wall-clock and CPU of this
process: ours for ``navigate`` alone (data generation excluded), KF-GINS's for its subprocess (reading
the text files, filtering, writing its result files); the two run alternately, so a load on the
machine weighs on both.
"""

from __future__ import annotations

import math
import os
import subprocess
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import aided, earth, kfgins
from .. import gnss as gnss_mod
from .. import trajectory as tr

ENV = "SARINS_KFGINS"  # the environment variable naming KF-GINS's binary


def find_binary(path=None) -> tuple:
    """KF-GINS's binary: ``path`` if given, else ``$SARINS_KFGINS``.  Returns (path, None) when it is an
    executable (and readable: the campaign records its digest) file, else (None, one-line reason)."""
    given = path if path is not None else os.environ.get(ENV)
    if not given:
        return None, (f"no KF-GINS binary given (${ENV} is not set; build it from github:i2Nav-WHU/KF-GINS as "
                      "docs/aided-navigation.md says)")
    if not (os.path.isfile(given) and os.access(given, os.X_OK | os.R_OK)):
        return None, f"{given} is not an executable file"
    return str(given), None


START_SOW = 345600.0  # s of GPS week (Thursday 00:00) at the trajectory's t = 0
WHITE_GNSS = gnss_mod.WHITE
GNSS_CHOICES = {"white": WHITE_GNSS, **gnss_mod.PRESETS}


def drive(minutes: float, step: float) -> tr.Truth:
    """A drive of about ``minutes``: a 60 s stop, then laps of cruising, turns (6 deg/s; radius 150 m),
    a climb and a descent and a stop, until the duration is reached; last a stop."""
    segments = [{"kind": "stop", "duration": 60}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0}]
    lap = [{"kind": "cruise", "duration": 60}, {"kind": "turn", "rate_dps": 6, "angle_deg": 90},
           {"kind": "accelerate", "to_speed": 18, "accel": 0.5}, {"kind": "climb", "to_pitch_deg": 3, "duration": 5},
           {"kind": "cruise", "duration": 30}, {"kind": "climb", "to_pitch_deg": 0, "duration": 5},
           {"kind": "turn", "radius": 150, "angle_deg": -120}, {"kind": "cruise", "duration": 40},
           {"kind": "accelerate", "to_speed": 0, "accel": 1.5}, {"kind": "stop", "duration": 20},
           {"kind": "accelerate", "to_speed": 12, "accel": 1.0}, {"kind": "turn", "rate_dps": -4, "angle_deg": 150}]
    traj = tr.Trajectory(tr.Start(lat_deg=30.5, lon_deg=114.4, height=20.0, heading_deg=30.0), segments)
    while traj.duration(step) < minutes * 60.0 - 1e-9:
        segments = segments + lap
        traj = tr.Trajectory(traj.start, segments)
    traj = tr.Trajectory(traj.start, segments + [{"kind": "accelerate", "to_speed": 0, "accel": 1.5},
                                                 {"kind": "stop", "duration": 10}])
    return tr.generate(traj, step)


@dataclass(frozen=True)
class Errors:
    """RMS errors over the output times: position north, east, down, horizontal, vertical and 3-D (m);
    velocity 3-D (m/s); attitude tilt (roll and pitch), heading and 3-D (deg)."""

    pos_n: float
    pos_e: float
    pos_d: float
    horizontal: float
    vertical: float
    position: float
    velocity: float
    tilt_deg: float
    heading_deg: float
    attitude_deg: float


def rms_errors(error: np.ndarray) -> Errors:
    """:class:`Errors` of (n, 9) errors (position ENU m, velocity ENU m/s, attitude phi ENU rad)."""
    def rms(x):
        return float(np.sqrt(np.mean(np.sum(x.reshape(len(x), -1) ** 2, axis=1))))
    deg = 180.0 / math.pi
    return Errors(pos_n=rms(error[:, 1]), pos_e=rms(error[:, 0]), pos_d=rms(error[:, 2]), horizontal=rms(error[:, :2]),
                  vertical=rms(error[:, 2]), position=rms(error[:, :3]), velocity=rms(error[:, 3:6]),
                  tilt_deg=deg * rms(error[:, 6:8]), heading_deg=deg * rms(error[:, 8]),
                  attitude_deg=deg * rms(error[:, 6:9]))


@dataclass(frozen=True)
class Case:
    """The data both filters get."""

    truth: tr.Truth
    imu: tuple
    fixes: gnss_mod.GNSSFixes
    nav0: np.ndarray
    noise: aided.ImuNoise
    gnss: gnss_mod.GNSSConfig
    settings: aided.FilterSettings
    seed: int


def make_case(minutes: float, *, rate_hz: int = 100, imu: str = "tactical", gnss: str = "white", seed: int = 0,
              cov_every: int = 10) -> Case:
    """Trajectory, IMU errors, GNSS fixes and the initial state (with the filter's initial errors), once."""
    truth = drive(minutes, 1.0 / rate_hz)
    noise = aided.IMU_NOISE[imu]
    settings = aided.FilterSettings(cov_every=cov_every, out_every=10)
    nav0 = aided._initial_state(truth, settings, np.random.default_rng([seed, 3018]))  # as navigate draws it
    return Case(truth=truth, imu=aided.corrupt(truth, noise, seed), fixes=gnss_mod.simulate(truth, GNSS_CHOICES[gnss],
                seed), nav0=nav0, noise=noise, gnss=GNSS_CHOICES[gnss], settings=settings, seed=seed)


def run_ours(case: Case, cov_every: int | None = None, covariance: str = "diagonal"):
    """``aided.navigate`` on the case (GNSS positions only; the result keeps ``covariance`` of P);
    (result, wall s, CPU s)."""
    settings = case.settings if cov_every is None else aided.FilterSettings(cov_every=cov_every, out_every=10)
    t0, c0 = time.perf_counter(), time.process_time()
    res = aided.navigate(case.truth, noise=case.noise, gnss=case.gnss, aiding=("gnss",), settings=settings,
                         seed=case.seed, gnss_velocity=False, imu=case.imu, fixes=case.fixes, covariance=covariance)
    return res, time.perf_counter() - t0, time.process_time() - c0


def write_case(case: Case, folder: Path) -> Path:
    """The case in KF-GINS's formats in ``folder``; the configuration file's path."""
    truth, step = case.truth, case.truth.step
    dtheta, dv = case.imu[0], case.imu[1]
    # record 0 at the start time carries the first step's increments (at rest before the start): KF-GINS
    # starts its state there and uses that record only as the 'previous' sample of the first step
    times = START_SOW + np.arange(truth.n_steps + 1) * step
    imu_path = kfgins.write_imu(folder / "imu.txt", times, np.vstack([dtheta[:1], dtheta]), np.vstack([dv[:1], dv]))
    f = case.fixes
    ok = f.valid
    gnss_path = kfgins.write_gnss(folder / "gnss.txt", START_SOW + f.time[ok], f.lat[ok], f.lon[ok], f.height[ok],
                                  case.gnss.pos_std())
    out = folder / "out"
    out.mkdir(exist_ok=True)
    s = case.settings
    return kfgins.write_config(folder / "kf-gins.yaml", imu_path=imu_path, gnss_path=gnss_path, output_dir=out,
                               rate_hz=round(1.0 / step), start_sow=START_SOW, nav_row=case.nav0,
                               pos_std_enu=[s.pos0_std] * 3, vel_std_enu=[s.vel0_std] * 3,
                               att_std=(s.tilt0_std, s.heading0_std), noise=kfgins.noise_from_imu(case.noise),
                               lever_rfu=case.gnss.lever_arm)


def run_kfgins(binary, case: Case, folder: Path):
    """KF-GINS on the case written to ``folder``: our output steps (n,) found in its result, its rows
    there (n, 9), wall s, CPU s of the child, bytes of its result files."""
    config = write_case(case, folder)
    t0 = time.perf_counter()
    before = os.times()
    proc = subprocess.run([str(binary), str(config)], cwd=folder, capture_output=True, text=True, timeout=3600)
    wall = time.perf_counter() - t0
    after = os.times()
    if proc.returncode != 0:
        raise RuntimeError(f"KF-GINS exited {proc.returncode}: {proc.stdout[-500:]} {proc.stderr[-500:]}")
    nav = kfgins.read_nav(folder / "out" / kfgins.NAV_FILE)
    out_bytes = sum(f.stat().st_size for f in (folder / "out").iterdir())
    k = np.rint((nav.time - START_SOW) / case.truth.step).astype(np.int64)
    want = np.arange(1, case.truth.n_steps // case.settings.out_every + 1) * case.settings.out_every
    pos = np.searchsorted(k, want)
    found = (pos < k.size) & (k[np.minimum(pos, k.size - 1)] == want)
    cpu = after.children_user + after.children_system - before.children_user - before.children_system
    return want[found], nav.nav[pos[found]], wall, cpu, out_bytes


def gravity_difference(lat: float, height: float) -> float:
    """Our normal gravity minus KF-GINS's series (its Earth::gravity, rewritten from its documented
    coefficients), m/s^2."""
    s2 = math.sin(lat) ** 2
    g0 = 9.7803267715 * (1 + 0.0052790414 * s2 + 0.0000232718 * s2**2 + 0.0000001262 * s2**3 + 0.0000000007 * s2**4)
    g = g0 - (3.0877e-6 - 4.3e-9 * s2) * height + 0.72e-12 * height**2
    return float(earth.gravity(lat, height)) - g


def compare(binary, minutes: float = 30.0, *, rate_hz: int = 100, imu: str = "tactical", gnss: str = "white",
            seed: int = 0, workdir=None, repeats: int = 1, commit: str | None = None) -> dict:
    """The comparison's numbers (JSON-ready).  Each filter runs ``repeats`` times on the same data
    (identical results); the times are the fastest run's (wall and CPU s)."""
    case = make_case(minutes, rate_hz=rate_hz, imu=imu, gnss=gnss, seed=seed)
    k_wall = k_cpu = wall = cpu = wall1 = cpu1 = math.inf
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(dir=workdir) as tmp:
            idx, k_nav, w, c, out_bytes = run_kfgins(binary, case, Path(tmp))
        k_wall, k_cpu = min(k_wall, w), min(k_cpu, c)
        ours, w, c = run_ours(case)
        wall, cpu = min(wall, w), min(cpu, c)
        ours1, w, c = run_ours(case, cov_every=1)
        wall1, cpu1 = min(wall1, w), min(cpu1, c)
    truth_rows = case.truth.nav_rows(idx)
    ours_idx = np.arange(1, ours.time.size + 1) * case.settings.out_every
    sel = np.isin(ours_idx, idx)
    e_k = rms_errors(aided.nav_errors(k_nav, truth_rows))
    e_o = rms_errors(ours.error[sel])
    e_o1 = rms_errors(ours1.error[sel])
    return {
        "kfgins_commit": commit, "repeats": repeats,
        "duration_s": float(case.truth.time[-1]), "imu_rate_hz": rate_hz, "imu": imu, "gnss": gnss,
        "gnss_rate_hz": case.gnss.rate_hz, "gnss_fixes": int(case.fixes.valid.sum()), "seed": seed,
        "compared_rows": int(idx.size),
        "gravity_ours_minus_kfgins_mps2": gravity_difference(float(case.truth.lat[0]), float(case.truth.height[0])),
        "ours": {"cov_every": case.settings.cov_every, "covariance": "diagonal", "rms": asdict(e_o), "wall_s": wall,
                 "cpu_s": cpu},
        "ours_cov_every_1": {"cov_every": 1, "rms": asdict(e_o1), "wall_s": wall1, "cpu_s": cpu1},
        "kfgins": {"rms": asdict(e_k), "wall_s": k_wall, "cpu_s": k_cpu, "result_bytes": out_bytes},
        "ours_over_kfgins_max": max(a / b for a, b in zip(asdict(e_o).values(), asdict(e_k).values())),
        "ours_over_kfgins_min": min(a / b for a, b in zip(asdict(e_o).values(), asdict(e_k).values())),
        "speed_ratio_wall": k_wall / wall, "speed_ratio_wall_cov_every_1": k_wall / wall1,
        "speed_ratio_cpu": k_cpu / cpu, "speed_ratio_cpu_cov_every_1": k_cpu / cpu1,
    }


def markdown(r: dict) -> str:
    """The comparison table."""
    head = ("| filter | horizontal RMS (m) | vertical RMS (m) | velocity RMS (m/s) | tilt RMS (deg) | heading RMS (deg) "
            "| run time wall / CPU (s) |\n|---|---|---|---|---|---|---|\n")
    rows = []
    for name, key in (("KF-GINS (21 states, P every IMU step)", "kfgins"),
                      (f"ours (15 states, P every {r['ours']['cov_every']} IMU steps)", "ours"),
                      ("ours (15 states, P every IMU step)", "ours_cov_every_1")):
        e = r[key]["rms"]
        rows.append(f"| {name} | {e['horizontal']:.3f} | {e['vertical']:.3f} | {e['velocity']:.4f} | "
                    f"{e['tilt_deg']:.5f} | {e['heading_deg']:.4f} | {r[key]['wall_s']:.3f} / {r[key]['cpu_s']:.3f} |")
    return head + "\n".join(rows) + (
        f"\n\nOurs / KF-GINS RMS errors (P every {r['ours']['cov_every']} steps): {r['ours_over_kfgins_min']:.4f} .. "
        f"{r['ours_over_kfgins_max']:.4f}.  KF-GINS / ours run time: {r['speed_ratio_wall']:.1f}x wall, {r['speed_ratio_cpu']:.1f}x CPU "
        f"({r['speed_ratio_wall_cov_every_1']:.1f}x / {r['speed_ratio_cpu_cov_every_1']:.1f}x with P every IMU "
        "step).\n")
