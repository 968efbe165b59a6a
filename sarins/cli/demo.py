"""``sarins demo``: the main job, seed 000's identified static system co-simulated (see :mod:`sarins.demo`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sarins_fmu.units import NM, RAD_TO_DEG

from . import RunError, UsageError, finite, refuse_unless
from .navigate import add_run_options, check_run_args


def register(sub) -> None:
    p = sub.add_parser("demo", help="the main job: align, navigate 12 h, identify the axial drift (RBF FMU), "
                                    "compensate, navigate 72 h, co-simulated",
                       description="Co-simulate Turntable -> IMUThermal -> StrapdownINS -> RBFIdentifier FMUs.")
    add_run_options(p, nav_hours=72.0)
    p.add_argument("--identify-hours", type=finite, default=12.0,
                   help="navigation time at which the RBFIdentifier FMU identifies the drift, h (default 12; "
                        "the shipped models need 12)")
    p.add_argument("--model", choices=("hot", "cold"), default="hot", help="shipped identifier model (default hot)")
    p.add_argument("--model-file", default=None, help="identifier model file (JSON), instead of --model")
    p.add_argument("--fmu-dir", default="build/fmus", help="where the FMUs are built (default build/fmus)")
    p.add_argument("--out", default="results/demo",
                   help="folder for the series (series.csv) and the figure of the position error with and without "
                        "compensation (position_error.png) (default results/demo)")
    p.add_argument("--no-progress", action="store_true", help="no phase announcements or progress on stderr")
    p.set_defaults(func=run)


def run(args) -> int:
    from orchestration.errors import FMUCallError
    from sarins.demo import NEXT_COMMANDS, run_demo, write_results

    check_run_args(args)
    refuse_unless(args, {"model": "--model"}, args.model_file is None,
                  "chooses a shipped model and does not apply with --model-file (give one of them)")
    if args.model_file is not None:  # a bad model file is refused before anything is built
        from sarins_fmu.identify.axial import DriftIdentifier

        DriftIdentifier(args.model_file)
    fmu_dir = Path(args.fmu_dir)
    if fmu_dir.exists() and not fmu_dir.is_dir():
        raise UsageError(f"--fmu-dir {fmu_dir} exists and is not a folder")
    out_dir = Path(args.out)
    if out_dir.exists() and not out_dir.is_dir():
        raise UsageError(f"--out {out_dir} exists and is not a folder")
    for name in ("series.csv", "position_error.png"):
        if (out_dir / name).exists() and not (out_dir / name).is_file():
            raise UsageError(f"--out {out_dir}: {out_dir / name} exists and is not a regular file")
    hours = args.align_hours + args.identify_hours + args.nav_hours
    print(f"sarins demo: co-simulating {hours:g} h of the identified static system "
          f"({args.imu} IMU, {args.start} start, {args.rotation} rotation, {args.lat_deg:g} deg; "
          f"identify at {args.identify_hours:g} h) in {args.fmu_dir}")
    try:
        out = run_demo(lat_deg=args.lat_deg, align_hours=args.align_hours, identify_hours=args.identify_hours,
                       nav_hours=args.nav_hours, imu=args.imu, rotation=args.rotation, start=args.start,
                       seed=args.seed, axial_drift_dph=args.axial_drift_dph, model=args.model,
                       model_file=args.model_file, fmu_dir=args.fmu_dir, progress=not args.no_progress)
    except FMUCallError as exc:  # the co-simulation failed: a failed run, not bad input
        raise RunError(str(exc)) from None
    try:
        files = write_results(out, out_dir, identify_hours=args.identify_hours)
    except OSError as exc:
        raise RunError(f"cannot write the results to {out_dir}: {exc}") from None
    res, ref = out["cosim"], out["reference"]
    nav = res["ins.nav_time"]
    after = nav > args.identify_hours * 3600.0 + 0.5
    ref_after = ref.time > args.identify_hours * 3600.0 + 0.5
    k_id = int(np.argmin(np.abs(nav - args.identify_hours * 3600.0)))
    rows = [
        ("model", out["model_file"]),
        ("latitude error at trigger", f"{res['ins.lat_error'][k_id] * RAD_TO_DEG:+.5f} deg"),
        ("true axial drift", f"{out['true_drift_dph']:+.5f} deg/h (mean over the {args.nav_hours:g} h after "
                             "identification)"),
        ("identified axial drift", f"{out['identified_drift_dph']:+.5f} deg/h"),
        ("identification error", f"{out['identification_error_dph']:+.5f} deg/h"),
        ("position error, compensated", f"max {np.max(res['ins.position_error'][after]) / NM:.3f} nmi, "
                                        f"end {res['ins.position_error'][-1] / NM:.3f} nmi"),
        ("position error, uncompensated", f"max {np.max(ref.position_error[ref_after]) / NM:.3f} nmi, "
                                          f"end {ref.position_error[-1] / NM:.3f} nmi (same run in process)"),
        ("azimuth gyro temperature", f"{res['imu.temp_gyro_z'][1]:.1f} -> {res['imu.temp_gyro_z'][-1]:.1f} degC"),
        ("wall time", f"{out['wall_seconds']:.1f} s ({res.meta['steps']} steps, {res.meta['scheme']})"),
    ]
    for name, value in rows:
        print(f"  {name:<30} {value}")
    print(f"results in {files.folder}/: {files.series.name} (the series, one row a minute), {files.figure.name} "
          "(position error with and without compensation)")
    print("to go further:")
    for what, command in NEXT_COMMANDS:
        print(f"  {command:<96} # {what}")
    return 0
