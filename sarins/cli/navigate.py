"""``sarins navigate``: one static turntable -> IMU -> INS run, or (``--trajectory``) an aided run along a
trajectory, in process."""

from __future__ import annotations

import json
import math
import time

import numpy as np

from sarins_fmu import imu as imu_mod
from sarins_fmu.files import check_output_path
from sarins_fmu.site import SITE_LAT_DEG
from sarins_fmu.turntable import ROTATION_SCHEMES

from . import UsageError, check_size, finite, given, refuse_unless, seed_value  # noqa: F401  (seed_value: reused by other commands)
from .log_options import imu_choice


def add_run_options(p, nav_hours: float) -> None:
    """Options shared by ``navigate`` and ``demo`` (papers' units at the edge)."""
    p.add_argument("--lat-deg", type=finite, default=SITE_LAT_DEG,
                   help=f"latitude of the static base, deg (default {SITE_LAT_DEG}, seed 000's site)")
    p.add_argument("--align-hours", type=finite, default=4.0, help="alignment duration, h (default 4)")
    p.add_argument("--nav-hours", type=finite, default=nav_hours, help=f"navigation duration, h (default {nav_hours:g})")
    p.add_argument("--axial-drift-dph", type=finite, default=None,
                   help="replace the azimuth gyro drift by this constant, deg/h")
    p.add_argument("--imu", type=imu_choice, default="nav-rlg", metavar="PRESET",
                   help=f"IMU error preset: {', '.join(sorted(imu_mod.PRESETS))} or a preset file (.json, sarins allan --write-preset)")
    p.add_argument("--rotation", choices=ROTATION_SCHEMES, default="forward-reverse", help="rotation scheme")
    p.add_argument("--start", choices=("hot", "cold"), default="hot", help="thermal start (default hot)")
    p.add_argument("--seed", type=seed_value, default=0, help="base random seed of the run (the IMU noise), 0 .. 2**31-1 (default 0)")


def check_run_args(args) -> None:
    if abs(args.lat_deg) > 89.9:
        raise UsageError(f"--lat-deg {args.lat_deg} is outside +-89.9 deg")
    if args.align_hours < 0:
        raise UsageError(f"--align-hours must not be negative, got {args.align_hours:g}")
    if args.nav_hours <= 0:
        raise UsageError(f"--nav-hours must be positive, got {args.nav_hours:g}")
    if getattr(args, "identify_hours", 1.0) <= 0:
        raise UsageError(f"--identify-hours must be positive, got {args.identify_hours:g}")
    if args.align_hours * 3600 < 600:
        raise UsageError("--align-hours must be at least 1/6 h (coarse + fine alignment)")
    if args.nav_hours * 3600 < 1:
        raise UsageError(f"--nav-hours {args.nav_hours:g} is shorter than one 1 s navigation step")
    if args.axial_drift_dph is not None and abs(args.axial_drift_dph) > 1e3:
        raise UsageError(f"--axial-drift-dph {args.axial_drift_dph:g} deg/h is not a gyro drift (|drift| <= 1000)")
    parts = ["--align-hours", "--nav-hours"] + (["--identify-hours"] if hasattr(args, "identify_hours") else [])
    hours = sum(getattr(args, p[2:].replace("-", "_")) for p in parts)
    named = " + ".join(parts)
    if hours > 24 * 3650:
        raise UsageError(f"{named} = {hours:g} h: runs longer than 10 years are refused")
    check_size(hours * 3600.0, BYTES_PER_STEP, f"{named} = {hours:g} h (1 s steps)")


BYTES_PER_STEP = 400  # stored per 1 s step by a run (INS outputs, temperatures, errors, recorder)


def register(sub) -> None:
    p = sub.add_parser("navigate", help="one static turntable -> IMU -> INS run, in process",
                       description="One static run in process: 4 h alignment, then free navigation.")
    add_run_options(p, nav_hours=72.0)
    p.add_argument("--correction-dph", type=finite, default=0.0,
                   help="axial drift the INS subtracts from --correction-from-hours on, deg/h")
    p.add_argument("--correction-from-hours", type=finite, default=0.0,
                   help="navigation time at which the correction starts, h (needs --correction-dph)")
    p.add_argument("--json", action="store_true", help="print one JSON object (full precision)")
    p.add_argument("--write-log", metavar="PATH", default=None,
                   help="also write the IMU output as a log (.csv or .npz, docs/imu-log.md) for sarins replay")
    g = p.add_argument_group("aided navigation along a trajectory (docs/aided-navigation.md)")
    g.add_argument("--trajectory", metavar="FILE", default=None,
                   help="trajectory file (JSON: start and segments); runs the aided INS instead of the static run")
    g.add_argument("--aiding", default="gnss,zupt", metavar="LIST",
                   help="comma-separated aiding: gnss, zupt, odometer, nhc, zaru (zero angular rate at the stops), or none "
                        "(default gnss,zupt)")
    g.add_argument("--gnss-outage", action="append", default=[], metavar="START:END",
                   help="GNSS outage window, s from the start of the trajectory (repeatable)")
    g.add_argument("--gnss", default="sps", metavar="PRESET", help="GNSS receiver preset: sps, sbas, rtk (default sps)")
    g.add_argument("--gnss-rate-hz", type=finite, default=1.0, help="GNSS fix rate, 1 .. 20 Hz (default 1)")
    g.add_argument("--gnss-pos-std", type=finite, default=None,
                   help="replace the preset's horizontal position std (white part, m; vertical twice it)")
    g.add_argument("--imu-rate-hz", type=finite, default=100.0, help="IMU output rate, Hz (default 100)")
    g.add_argument("--imu-noise", default="tactical", metavar="GRADE",
                   help="IMU noise grade of the aided run: ideal, tactical, mems (default tactical)")
    g.add_argument("--imu-stream", choices=("numpy", "core"), default=None,
                   help="where the IMU's errors, the ZUPT / NHC jitter and the vibration are drawn: core (default: "
                        "the C core's streams, as the TrajectoryIMU FMU and the vehicle_gnss* systems draw them, so "
                        "the command and the systems give the same numbers) or numpy (aided.navigate's default, with "
                        "which docs/aided-navigation.md's in-process numbers are made)")
    g.add_argument("--zupt-std", type=finite, default=0.01, help="zero-velocity update std, m/s (default 0.01)")
    g.add_argument("--zaru-std", type=finite, default=None,
                   help="zero-angular-rate update std per IMU step, rad/s (default: the gyro's white rate noise "
                        "arw / sqrt(h) of --imu-noise at --imu-rate-hz)")
    g.add_argument("--zupt-detect", choices=("truth", "imu"), default=None,
                   help="where ZUPTs come from: truth (the trajectory's stops, default) or imu (a chi-square test on "
                        "the IMU's increments, sarins_fmu.zero_velocity)")
    g.add_argument("--zupt-window", type=finite, default=None, help="detector window, s (default 0.5; --zupt-detect imu)")
    g.add_argument("--zupt-alpha", type=finite, default=None,
                   help="probability that a stationary window is declared moving, 0 .. 1 exclusive (default 0.001; "
                        "--zupt-detect imu)")
    g.add_argument("--filter-states", default=None, metavar="LIST",
                   help="optional filter states beyond the 15 (comma-separated): sf (gyro and accelerometer scale "
                        "factors), lever (GNSS antenna lever arm), gnss-gm (the receiver's Gauss-Markov position and "
                        "velocity errors), or none (default none; docs/aided-navigation.md)")
    g.add_argument("--vibration", default=None, metavar="PRESET",
                   help="vehicle vibration while moving: none, car (default car with --zupt-detect imu, else none)")
    p.set_defaults(func=run)


_STATIC_ONLY = {"lat_deg": "--lat-deg", "align_hours": "--align-hours", "nav_hours": "--nav-hours",
                "axial_drift_dph": "--axial-drift-dph", "imu": "--imu", "rotation": "--rotation", "start": "--start",
                "correction_dph": "--correction-dph", "correction_from_hours": "--correction-from-hours",
                "write_log": "--write-log"}
_AIDED_ONLY = {"aiding": "--aiding", "gnss_outage": "--gnss-outage", "gnss": "--gnss", "gnss_rate_hz": "--gnss-rate-hz",
               "gnss_pos_std": "--gnss-pos-std", "imu_rate_hz": "--imu-rate-hz", "imu_noise": "--imu-noise",
               "imu_stream": "--imu-stream", "zupt_std": "--zupt-std", "zaru_std": "--zaru-std",
               "zupt_detect": "--zupt-detect", "zupt_window": "--zupt-window",
               "zupt_alpha": "--zupt-alpha", "vibration": "--vibration", "filter_states": "--filter-states"}


def _outage(text: str) -> tuple:
    parts = text.split(":")
    try:
        start, end = (float(x) for x in parts)
    except ValueError:
        raise UsageError(f"--gnss-outage {text}: give START:END in seconds") from None
    if not (math.isfinite(start) and math.isfinite(end) and start < end):
        raise UsageError(f"--gnss-outage {text}: START must be below END")
    return start, end


def run_aided(args) -> int:
    """The aided run of ``--trajectory``: parse, call sarins_fmu.aided, print."""
    from sarins_fmu import aided, gnss
    from sarins_fmu import trajectory as tr

    refuse_unless(args, _STATIC_ONLY, False, "does not apply to an aided run (--trajectory)")
    aiding = [] if args.aiding.strip() == "none" else [a.strip() for a in args.aiding.split(",")]
    bad = [a for a in aiding if a not in aided.AIDING]
    if bad or not args.aiding.strip():
        raise UsageError(f"--aiding {args.aiding}: choose from {', '.join(aided.AIDING)} (comma-separated) or none")
    if args.imu_noise not in aided.IMU_NOISE:
        raise UsageError(f"--imu-noise {args.imu_noise}: choose one of {', '.join(aided.IMU_NOISE)}")
    if args.gnss not in gnss.PRESETS:
        raise UsageError(f"--gnss {args.gnss}: choose one of {', '.join(gnss.PRESETS)}")
    if not 1.0 <= args.imu_rate_hz <= 2000.0:
        raise UsageError(f"--imu-rate-hz {args.imu_rate_hz:g} is outside 1 .. 2000 Hz")
    if args.gnss_rate_hz > args.imu_rate_hz:
        raise UsageError(f"--gnss-rate-hz {args.gnss_rate_hz:g} is above the IMU rate (--imu-rate-hz {args.imu_rate_hz:g})")
    if not 1.0 <= args.gnss_rate_hz <= 20.0:
        raise UsageError(f"--gnss-rate-hz {args.gnss_rate_hz:g} is outside 1 .. 20 Hz")
    if args.gnss_pos_std is not None and args.gnss_pos_std < 0:
        raise UsageError(f"--gnss-pos-std must not be negative, got {args.gnss_pos_std:g}")
    if not args.zupt_std > 0:
        raise UsageError(f"--zupt-std must be positive, got {args.zupt_std:g}")
    if args.zaru_std is not None and not args.zaru_std > 0:
        raise UsageError(f"--zaru-std must be positive, got {args.zaru_std:g}")
    if args.zaru_std is not None and "zaru" not in aiding:
        raise UsageError("--zaru-std needs zaru in --aiding")
    detect, vibration, detector = _zupt_detection(args, aiding)
    filter_states = _filter_states(args.filter_states, aiding)
    outages = [_outage(t) for t in args.gnss_outage]
    if outages and "gnss" not in aiding:
        raise UsageError("--gnss-outage needs --aiding gnss")
    step = 1.0 / args.imu_rate_hz
    try:
        trajectory = tr.load_trajectory(args.trajectory)
        duration = trajectory.duration(step)
    except tr.TrajectoryError as exc:
        raise UsageError(f"--trajectory {exc}") from None
    check_size(duration / step, BYTES_PER_AIDED_STEP, f"--trajectory {args.trajectory} ({duration:g} s)")
    for start, end in outages:
        if not (0 <= start and end <= duration):
            raise UsageError(f"--gnss-outage {start:g}:{end:g} is outside the run (0 .. {duration:g} s)")
    changes = {"rate_hz": args.gnss_rate_hz}
    if args.gnss_pos_std is not None:
        s = args.gnss_pos_std
        changes["pos_white_std"] = (s, s, 2 * s)
    try:
        receiver = gnss.preset(args.gnss, **changes)
        gnss.epochs_on_grid(receiver.rate_hz, step, duration)
        truth = tr.generate(trajectory, step)
    except ValueError as exc:
        raise UsageError(f"--trajectory {args.trajectory}: {exc}") from None
    t0 = time.perf_counter()
    result = aided.navigate(truth, noise=aided.IMU_NOISE[args.imu_noise], gnss=receiver if "gnss" in aiding else None,
                            aiding=aiding, outages=outages, settings=aided.FilterSettings(zupt_std=args.zupt_std, zaru_std=args.zaru_std),
                            seed=args.seed, zupt_detect=detect, vibration=vibration, detector=detector,
                            imu_stream=args.imu_stream or "core", filter_states=filter_states)
    out = aided.summary(result, outages)
    out.update({"wall_seconds": time.perf_counter() - t0, "seed": args.seed, "aiding": aiding, "gnss": args.gnss,
                "imu_noise": args.imu_noise, "imu_stream": args.imu_stream or "core",
                "imu_rate_hz": args.imu_rate_hz, "gnss_rate_hz": args.gnss_rate_hz,
                "zupt_detect": detect, "vibration": args.vibration or ("car" if detect == "imu" else "none"),
                "filter_states": list(filter_states)})
    if args.json:
        print(json.dumps(out, allow_nan=False))
    else:
        for key, value in out.items():
            shown = f"{value:.6g}" if isinstance(value, float) else value
            print(f"{key:>26}: {shown}")
    return 0


def _filter_states(text, aiding) -> tuple:
    """The --filter-states list, or UsageError naming a bad entry."""
    from sarins_fmu import aided

    if text is None or text.strip() == "none":
        return ()
    states = [a.strip() for a in text.split(",")]
    bad = [a for a in states if a not in aided.FILTER_STATES]
    if bad or not text.strip():
        raise UsageError(f"--filter-states {text}: {', '.join(repr(b) for b in bad) or 'empty'} unknown; choose from "
                         f"{', '.join(aided.FILTER_STATES)} (comma-separated) or none")
    if len(set(states)) != len(states):
        raise UsageError(f"--filter-states {text}: a state is named twice")
    try:
        return aided.check_filter_states(states, aiding)
    except ValueError as exc:
        raise UsageError(f"--filter-states {text}: {exc} (--aiding)") from None


def _zupt_detection(args, aiding):
    """(zupt_detect, Vibration or None, DetectorSettings or None) of the options, or UsageError naming one."""
    from sarins_fmu import aided, zero_velocity

    detect = args.zupt_detect or "truth"
    if detect == "truth":
        refuse_unless(args, {"zupt_window": "--zupt-window", "zupt_alpha": "--zupt-alpha"}, False,
                      "applies with --zupt-detect imu only")
    if detect == "imu" and "zupt" not in aiding and "zaru" not in aiding:
        raise UsageError("--zupt-detect imu needs zupt or zaru in --aiding")
    noise = aided.IMU_NOISE[args.imu_noise]
    if detect == "imu" and not (noise.vrw > 0 and noise.arw > 0):
        raise UsageError(f"--zupt-detect imu needs an IMU with noise (--imu-noise {args.imu_noise} has none to test "
                         "against)")
    name = args.vibration or ("car" if detect == "imu" else "none")
    if name not in zero_velocity.VIBRATION:
        raise UsageError(f"--vibration {name}: choose one of {', '.join(zero_velocity.VIBRATION)}")
    vibration = zero_velocity.VIBRATION[name] if name != "none" else None
    detector = None
    if detect == "imu":
        window = 0.5 if args.zupt_window is None else args.zupt_window
        alpha = 1e-3 if args.zupt_alpha is None else args.zupt_alpha
        if not window > 0:
            raise UsageError(f"--zupt-window must be positive, got {window:g}")
        if not 0 < alpha < 1:
            raise UsageError(f"--zupt-alpha must be between 0 and 1 (exclusive), got {alpha:g}")
        detector = zero_velocity.DetectorSettings(window=window, alpha=alpha)
        try:
            detector.check(1.0 / args.imu_rate_hz)
        except ValueError as exc:
            raise UsageError(f"--zupt-window {window:g} s at --imu-rate-hz {args.imu_rate_hz:g}: {exc}") from None
    return detect, vibration, detector


BYTES_PER_AIDED_STEP = 400  # per IMU step: truth rows, increments, filter output rows


def run(args) -> int:
    from sarins_fmu.experiments import run_static

    if args.trajectory is not None:
        return run_aided(args)
    refuse_unless(args, _AIDED_ONLY, False, "applies to an aided run only (give --trajectory)")
    check_run_args(args)
    refuse_unless(args, {"correction_from_hours": "--correction-from-hours"}, bool(given(args, "correction_dph")),
                  "needs --correction-dph (the drift the INS subtracts from that time on)")
    if args.correction_from_hours < 0 or args.correction_from_hours > args.nav_hours:
        raise UsageError("--correction-from-hours must lie within the navigation time")
    if abs(args.correction_dph) > 1e3:
        raise UsageError(f"--correction-dph {args.correction_dph:g} deg/h is not a drift correction")
    if args.write_log and not str(args.write_log).endswith((".csv", ".npz")):
        raise UsageError(f"--write-log {args.write_log}: the file must end in .csv or .npz")
    if args.write_log:
        check_output_path(args.write_log, "--write-log")  # before the run: a FIFO there would block
    t0 = time.perf_counter()
    chunks = []
    result = run_static(lat_deg=args.lat_deg, align_hours=args.align_hours, nav_hours=args.nav_hours,
                        rotation=args.rotation, imu=args.imu, axial_drift_dph=args.axial_drift_dph,
                        start=args.start, seed=args.seed, correction_dph=args.correction_dph,
                        correction_from_hours=args.correction_from_hours,
                        on_increments=(lambda *chunk: chunks.append(chunk)) if args.write_log else None)
    if args.write_log:
        from sarins.results import atomic_output
        from sarins_fmu.imu_log import write_log

        with atomic_output(args.write_log, keep_suffix=True) as tmp:
            write_log(tmp, *(np.concatenate([c[j] for c in chunks]) for j in range(3)),
                      temps=np.concatenate([c[3] for c in chunks]), lat_deg=args.lat_deg,
                      meta={"source": f"sarins navigate --imu {args.imu} --seed {args.seed}"})
    summary = result.summary()
    summary.update({"wall_seconds": time.perf_counter() - t0, **{
        k: v for k, v in result.info.items() if k in ("imu", "rotation", "start", "seed")}})
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        for key, value in summary.items():
            shown = f"{value:.6g}" if isinstance(value, float) else value
            print(f"{key:>24}: {shown}")
    return 0
