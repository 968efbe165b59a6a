"""``sarins replay LOG``: alignment and navigation on a recorded IMU log.

::

    sarins replay run.csv [--align-hours 4] [--compensator model.npz]
                          [--identify {hot,cold,MODEL.json} [--no-compensate]] [--json]
    sarins replay unit1.csv.gz --axes frd --lat-deg 51.08 --heading-deg 0 --json

The log formats are in docs/imu-log.md (the project's CSV or NPZ, a vendor CSV
with units in its header, gzip, i2Nav text, ROS bags; ``--axes``, ``--lat-deg``,
... say what the file does not).  A bad log exits with status 2 and one line
naming the file and the line (or row).  When the gyros cannot see the Earth
rate over the alignment (a MEMS bias far above it), the replay levels with the
accelerometers and takes the heading from ``--heading-deg`` (clockwise from
north), or exits 2 naming that option; ``--heading-deg`` also replaces
gyrocompassing on any log.  The aligned ``roll_deg``, ``pitch_deg`` and
``heading_deg`` are printed; an attitude whose tilt disagrees with the
accelerometers' levelling by more than an accelerometer bias allows is refused.
``--imu PRESET`` also replays a simulated static record of that preset (a name
or a preset file) of the log's length, rate and site, and prints its numbers
beside the log's (``simulated_*``).  ``--identify``
runs seed 000's RBF axial-drift identifier after the model's alignment and
12 h of navigation, prints the drift and (unless ``--no-compensate``)
subtracts it over the rest of the log; a log the model does not fit (too
short, other sample interval, other alignment, other site, no temperatures
for a cold model) exits with status 2 and says why.
"""

from __future__ import annotations

import json
import math

from . import UsageError, finite, refuse_unless
from .log_options import add_log_options, imu_choice, read_options
from .navigate import seed_value


def register(sub) -> None:
    p = sub.add_parser("replay", help="align and navigate on a recorded IMU log (CSV or NPZ)",
                       description="Static alignment on the start of a recorded IMU log, then free navigation "
                                   "over the rest; optionally through a trained IMU compensator first.")
    p.add_argument("log", help="IMU log: CSV (.gz), NPZ, i2Nav text or a ROS bag (docs/imu-log.md)")
    p.add_argument("--align-hours", type=finite, default=None,
                   help="alignment at the start of the log, h (default 4 to gyrocompass; with --heading-deg 1/6, "
                        "at most half the log)")
    p.add_argument("--heading-deg", type=finite, default=None,
                   help="heading of the static start, deg clockwise from north: level with the accelerometers and "
                        "take this heading (needed when the gyros cannot see the Earth rate)")
    add_log_options(p)
    p.add_argument("--imu", type=imu_choice, default=None, metavar="PRESET",
                   help="also replay a simulated static record of this preset (name or .json file) of the log's "
                        "length, rate and site, for comparison")
    p.add_argument("--seed", type=seed_value, default=0, help="with --imu: the random seed of the simulated record")
    p.add_argument("--compensator", default=None, metavar="MODEL",
                   help="IMU compensator model file (sarins campaign mems-calibration) applied to the increments")
    p.add_argument("--identify", default=None, metavar="MODEL",
                   help="identify the axial gyro drift with seed 000's RBF network after the alignment and 12 h "
                        "of navigation: 'hot' or 'cold' (the shipped models) or a model file (JSON)")
    p.add_argument("--no-compensate", action="store_true",
                   help="with --identify: print the identified drift, but do not subtract it from the rest of the log")
    p.add_argument("--json", action="store_true", help="print one JSON object (full precision)")
    p.set_defaults(func=run)


def run(args) -> int:
    from sarins_fmu.experiments.replay import ModelFitError, replay
    from sarins_fmu.identify import compensators
    from sarins_fmu.identify.modelfile import ModelFileError
    from sarins_fmu.imu_log import read_log

    if args.align_hours is not None and args.align_hours <= 0:
        raise UsageError(f"--align-hours must be positive, got {args.align_hours:g}")
    if args.no_compensate and args.identify is None:
        raise UsageError("--no-compensate needs --identify")
    refuse_unless(args, {"seed": "--seed"}, args.imu is not None, "needs --imu (the seed of the simulated record)")
    log = read_log(args.log, read_options(args, args.rate_hz))
    comp = None
    if args.compensator:
        try:
            comp = compensators.load(args.compensator)
        except ModelFileError as exc:
            raise UsageError(str(exc)) from None
    ident = _identifier(args.identify) if args.identify is not None else None
    heading = None if args.heading_deg is None else math.radians(args.heading_deg)
    try:
        result = replay(log, align_hours=args.align_hours, compensator=comp, identifier=ident,
                        compensate_drift=not args.no_compensate, heading=heading, path=args.log)
    except ModelFitError as exc:
        raise UsageError(f"{args.log}: {exc}") from None
    info = result.info
    summary = {**result.summary(), "samples": len(log.time), "step_s": log.step, "quantity": log.quantity,
               "format": log.format, "axes": log.axes,
               "reference": "log" if log.ref is not None else "static start",
               "align_hours": info["align_hours"], "nav_hours": info["nav_hours"],
               "alignment": info["alignment"], "roll_deg": info["roll_deg"], "pitch_deg": info["pitch_deg"],
               "heading_deg": info["heading_deg"], "gyro_bias_dph": info["gyro_comp_dph"],
               "accel_bias_mps2": info["accel_comp"],
               "compensator": comp.kind if comp is not None else None,
               "warnings": log.warnings + info["warnings"]}
    if args.imu is not None:
        summary.update(_simulated(args, log, heading))
    if ident is not None:
        summary.update(identifier=info["identifier_model"], identified_drift_dph=info["identified_drift_dph"],
                       identify_at_hours=info["identify_at_s"] / 3600.0,
                       identify_lat_error_deg=info["identify_lat_error_deg"],
                       drift_compensated_from_hours=(None if info["compensation_from_s"] is None
                                                     else info["compensation_from_s"] / 3600.0))
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        for key, value in summary.items():
            print(f"{key:>28}: {value:.6g}" if isinstance(value, float) else f"{key:>28}: {value}")
    return 0


def _identifier(choice: str):
    """The drift model of ``--identify``: a shipped kind or a model file."""
    from sarins_fmu.identify.axial import DriftIdentifier, default_model_path
    from sarins_fmu.identify.modelfile import ModelFileError

    path = default_model_path(choice) if choice in ("hot", "cold") else choice
    try:
        return DriftIdentifier(path)
    except ModelFileError as exc:
        raise UsageError(str(exc)) from None


def _simulated(args, log, heading) -> dict:
    """A static record of the --imu preset with the log's length, rate and site, replayed the same way."""
    import numpy as np

    from sarins_fmu import imu as imu_mod
    from sarins_fmu.allan import static_record
    from sarins_fmu.experiments.replay import replay
    from sarins_fmu.imu_log import ImuLog

    h = log.step
    n = len(log.time)
    gyro, accel, temps = static_record(imu_mod.preset(args.imu), n * h, 1.0 / h, seed=args.seed,
                                       lat_deg=math.degrees(log.lat))
    sim = ImuLog(time=np.arange(1, n + 1) * h, dtheta=gyro * h, dv=accel * h, temps=temps, ref=None, lat=log.lat,
                 lon=log.lon, height=log.height, interval=h)
    out = replay(sim, align_hours=args.align_hours, heading=0.0 if heading is not None else None,
                 path=f"the simulated record of --imu {args.imu}")
    return {f"simulated_{k}": v for k, v in {**out.summary(), "alignment": out.info["alignment"],
                                              "roll_deg": out.info["roll_deg"], "pitch_deg": out.info["pitch_deg"],
                                              "heading_deg": out.info["heading_deg"],
                                              "imu": args.imu, "seed": args.seed}.items()}
