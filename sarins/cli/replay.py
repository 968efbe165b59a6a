"""``sarins replay LOG``: alignment and navigation on a recorded IMU log.

::

    sarins replay run.csv [--align-hours 4] [--compensator model.npz]
                          [--identify {hot,cold,MODEL.json} [--no-compensate]] [--json]

The log format is in docs/imu-log.md (CSV or NPZ).  A bad log exits with
status 2 and one line naming the file and the line (or row).  ``--identify``
runs seed 000's RBF axial-drift identifier after the model's alignment and
12 h of navigation, prints the drift and (unless ``--no-compensate``)
subtracts it over the rest of the log; a log the model does not fit (too
short, other sample interval, other alignment, other site, no temperatures
for a cold model) exits with status 2 and says why.
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

    if args.align_hours <= 0:
        raise UsageError(f"--align-hours must be positive, got {args.align_hours:g}")
    if args.no_compensate and args.identify is None:
        raise UsageError("--no-compensate needs --identify")
    log = read_log(args.log)
    comp = None
    if args.compensator:
        try:
            comp = compensators.load(args.compensator)
        except ModelFileError as exc:
            raise UsageError(str(exc)) from None
    ident = _identifier(args.identify) if args.identify is not None else None
    try:
        result = replay(log, align_hours=args.align_hours, compensator=comp, identifier=ident,
                        compensate_drift=not args.no_compensate)
    except ModelFitError as exc:
        raise UsageError(f"{args.log}: {exc}") from None
    summary = {**result.summary(), "samples": len(log.time), "step_s": log.step, "quantity": log.quantity,
               "reference": "log" if log.ref is not None else "static start",
               "align_hours": result.info["align_hours"], "nav_hours": result.info["nav_hours"],
               "compensator": comp.kind if comp is not None else None}
    if ident is not None:
        info = result.info
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
