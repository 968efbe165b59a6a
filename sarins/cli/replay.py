"""``sarins replay LOG``: alignment and navigation on a recorded IMU log.

::

    sarins replay run.csv [--align-hours 4] [--compensator model.npz] [--json]

The log format is in docs/imu-log.md (CSV or NPZ).  A bad log exits with
status 2 and one line naming the file and the line (or row).
"""

from __future__ import annotations

import json

from . import UsageError, finite


def register(sub) -> None:
    p = sub.add_parser("replay", help="align and navigate on a recorded IMU log (CSV or NPZ)",
                       description="Static alignment on the start of a recorded IMU log, then free navigation "
                                   "over the rest; optionally through a trained IMU compensator first.")
    p.add_argument("log", help="IMU log, .csv or .npz (docs/imu-log.md)")
    p.add_argument("--align-hours", type=finite, default=4.0, help="alignment at the start of the log, h (default 4)")
    p.add_argument("--compensator", default=None, metavar="MODEL",
                   help="IMU compensator model file (sarins campaign mems-calibration) applied to the increments")
    p.add_argument("--json", action="store_true", help="print one JSON object (full precision)")
    p.set_defaults(func=run)


def run(args) -> int:
    from sarins_fmu.experiments.replay import replay
    from sarins_fmu.identify import compensators
    from sarins_fmu.identify.modelfile import ModelFileError
    from sarins_fmu.imu_log import read_log

    if args.align_hours <= 0:
        raise UsageError(f"--align-hours must be positive, got {args.align_hours:g}")
    log = read_log(args.log)
    comp = None
    if args.compensator:
        try:
            comp = compensators.load(args.compensator)
        except ModelFileError as exc:
            raise UsageError(str(exc)) from None
    result = replay(log, align_hours=args.align_hours, compensator=comp)
    summary = {**result.summary(), "samples": len(log.time), "step_s": log.step, "quantity": log.quantity,
               "reference": "log" if log.ref is not None else "static start",
               "align_hours": result.info["align_hours"], "nav_hours": result.info["nav_hours"],
               "compensator": comp.kind if comp is not None else None}
    if args.json:
        print(json.dumps(summary, allow_nan=False))
    else:
        for key, value in summary.items():
            print(f"{key:>24}: {value:.6g}" if isinstance(value, float) else f"{key:>24}: {value}")
    return 0
