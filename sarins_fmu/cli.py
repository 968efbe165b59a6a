"""The ``sarins`` command line.

Sub-commands register themselves with :func:`build_parser`; every command
turns bad input into a one-line message on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings

from . import imu as imu_mod
from .turntable import ROTATION_SCHEMES
from .units import NM, RAD_TO_DEG


class UsageError(ValueError):
    """Bad command-line input: reported as one line, exit status 2."""


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def _add_run_options(p: argparse.ArgumentParser, nav_hours: float) -> None:
    p.add_argument("--lat-deg", type=_finite, default=28.222, help="latitude of the static base, deg")
    p.add_argument("--align-hours", type=_finite, default=4.0, help="alignment duration, h")
    p.add_argument("--nav-hours", type=_finite, default=nav_hours, help="navigation duration, h")
    p.add_argument("--axial-drift-dph", type=_finite, default=None,
                   help="replace the azimuth gyro drift by this constant, deg/h")
    p.add_argument("--imu", choices=sorted(imu_mod.PRESETS), default="nav-rlg")
    p.add_argument("--rotation", choices=ROTATION_SCHEMES, default="forward-reverse")
    p.add_argument("--start", choices=("hot", "cold"), default="hot", help="thermal start")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--correction-dph", type=_finite, default=0.0,
                   help="axial drift the INS subtracts from --correction-from-hours on, deg/h")
    p.add_argument("--correction-from-hours", type=_finite, default=0.0,
                   help="navigation time at which the correction starts, h")


def _check_run_args(args) -> None:
    if abs(args.lat_deg) > 89.9:
        raise UsageError(f"--lat-deg {args.lat_deg} is outside +-89.9 deg")
    if args.align_hours < 0 or args.nav_hours <= 0 or args.correction_from_hours < 0:
        raise UsageError("hours must be positive (alignment may be 0 only with an aligned start)")
    if args.align_hours * 3600 < 600:
        raise UsageError("--align-hours must be at least 1/6 h (coarse + fine alignment)")


def _run(args):
    from .experiments import run_static

    _check_run_args(args)
    return run_static(lat_deg=args.lat_deg, align_hours=args.align_hours, nav_hours=args.nav_hours,
                      rotation=args.rotation, imu=args.imu, axial_drift_dph=args.axial_drift_dph,
                      start=args.start, seed=args.seed, correction_dph=args.correction_dph,
                      correction_from_hours=args.correction_from_hours)


def cmd_navigate(args) -> int:
    """Run one static experiment in process and print its end-of-run errors."""
    t0 = time.perf_counter()
    result = _run(args)
    summary = result.summary()
    summary.update({"wall_seconds": round(time.perf_counter() - t0, 3), **{
        k: v for k, v in result.info.items() if k in ("imu", "rotation", "start", "seed")}})
    if args.json:
        print(json.dumps(summary))
    else:
        for key, value in summary.items():
            print(f"{key:>24}: {value}")
    return 0


def demo_parameters(args) -> dict:
    """FMU start values of the standard system for the run options (SI)."""
    from .units import DEG_TO_RAD, DPH_TO_RPS

    lat = args.lat_deg * DEG_TO_RAD
    align = args.align_hours * 3600.0
    imu = {"preset": args.imu, "lat": lat, "thermal_start": args.start, "seed": args.seed}
    if args.axial_drift_dph is not None:  # a constant azimuth drift, no thermal terms (ImuModel.with_axial_drift)
        imu.update({"axial_drift_a": 0.0, "axial_drift_b": 0.0, "axial_drift_c": args.axial_drift_dph * DPH_TO_RPS,
                    "axial_drift_dtdt": 0.0, "gyro_bias_z": 0.0, "gyro_bias_tc1_z": 0.0, "gyro_bias_tc2_z": 0.0,
                    "aging_sigma_a": 0.0, "aging_sigma_b": 0.0, "aging_sigma_c": 0.0})
    return {"turntable": {"scheme": args.rotation, "align_time": align},
            "imu": imu, "ins": {"lat0": lat, "align_time": align}}


def cmd_demo(args) -> int:
    """The main job: the identified static system co-simulated by the FMPy master
    (Turntable -> IMUThermal -> StrapdownINS -> RBFIdentifier FMUs): align,
    navigate ``--identify-hours``, identify the axial drift, subtract it and
    navigate ``--nav-hours`` more; prints the identified drift and the position
    error with and (from the same run in process, without correction) without
    compensation."""
    import numpy as np

    from fmus.build import build_fmus
    from fmus.systems import standard_static_identified
    from orchestration import AlgebraicLoopWarning, simulate_system

    from .experiments import run_static
    from .identify.axial import default_model_path
    from .units import DPH_TO_RPS

    _check_run_args(args)
    if args.identify_hours <= 0:
        raise UsageError("--identify-hours must be positive")
    t0 = time.perf_counter()
    fmu_dir = build_fmus(args.fmu_dir)[0].parent
    params = demo_parameters(args)
    model = args.model_file or str(default_model_path(args.model))
    ident = {"model_file": model, "trigger_time": args.identify_hours * 3600.0}
    hours = args.align_hours + args.identify_hours + args.nav_hours
    system = standard_static_identified(fmu_dir, hours=hours, identifier=ident, **params)
    stop = hours * 3600.0
    record = ["ins.lat_error", "ins.position_error", "ins.nav_time", "imu.temp_gyro_z", "identifier.axial_drift"]
    print(f"sarins demo: co-simulating {hours:g} h of the identified static system "
          f"({args.imu} IMU, {args.start} start, {args.rotation} rotation, {args.lat_deg} deg; "
          f"identify at {args.identify_hours:g} h with {model}) in {fmu_dir}")
    with warnings.catch_warnings():  # the INS <-> identifier loop is broken at the INS input on purpose
        warnings.simplefilter("ignore", AlgebraicLoopWarning)
        result = simulate_system(system, stop, 1.0, record=record, progress=not args.no_progress)
    nav = result["ins.nav_time"]
    after = nav > args.identify_hours * 3600.0 + 0.5
    ref = run_static(lat_deg=args.lat_deg, align_hours=args.align_hours,
                     nav_hours=args.identify_hours + args.nav_hours, rotation=args.rotation, imu=args.imu,
                     axial_drift_dph=args.axial_drift_dph, start=args.start, seed=args.seed)
    ref_after = ref.time > args.identify_hours * 3600.0 + 0.5
    k_id = int(np.argmin(np.abs(nav - args.identify_hours * 3600.0)))
    rows = [
        ("latitude error at trigger", f"{result['ins.lat_error'][k_id] * RAD_TO_DEG:+.5f} deg"),
        ("identified axial drift", f"{result['identifier.axial_drift'][-1] / DPH_TO_RPS:+.5f} deg/h"),
        ("position error, compensated", f"max {np.max(result['ins.position_error'][after]) / NM:.3f} nm, "
                                        f"end {result['ins.position_error'][-1] / NM:.3f} nm "
                                        f"({args.nav_hours:g} h after identification)"),
        ("position error, uncompensated", f"max {np.max(ref.position_error[ref_after]) / NM:.3f} nm, "
                                          f"end {ref.position_error[-1] / NM:.3f} nm (same run in process)"),
        ("azimuth gyro temperature", f"{result['imu.temp_gyro_z'][1]:.1f} -> {result['imu.temp_gyro_z'][-1]:.1f} degC"),
        ("wall time", f"{time.perf_counter() - t0:.1f} s ({result.meta['steps']} steps, "
                      f"{result.meta['scheme']})"),
    ]
    for name, value in rows:
        print(f"  {name:<30} {value}")
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage dump) and exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="sarins", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p = sub.add_parser("navigate", help="one static turntable -> IMU -> INS run, in process")
    _add_run_options(p, nav_hours=72.0)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_navigate)
    p = sub.add_parser("demo", help="the main job: align, navigate 12 h, identify the axial drift (RBF FMU), "
                                    "compensate, navigate 72 h, co-simulated")
    _add_run_options(p, nav_hours=72.0)
    p.add_argument("--identify-hours", type=_finite, default=12.0,
                   help="navigation time at which the RBFIdentifier FMU identifies the drift, h (default 12)")
    p.add_argument("--model", choices=("hot", "cold"), default="hot", help="shipped identifier model")
    p.add_argument("--model-file", default=None, help="identifier model file (JSON), overrides --model")
    p.add_argument("--fmu-dir", default="build/fmus", help="where the FMUs are built (default build/fmus)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_demo)
    for module in _plugin_modules():
        module.register(sub)
    return parser


def _plugin_modules():
    """Sub-command modules of the other packages (master, identifiers)."""
    import importlib

    found = []
    for name in ("orchestration.cli", "sarins_fmu.identify.cli", "fmus.cli", "sarins_fmu.experiments.campaign_cli"):
        try:
            found.append(importlib.import_module(name))
        except ModuleNotFoundError as exc:
            if exc.name is None or not name.startswith(exc.name):
                raise
    return found


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (UsageError, ValueError, OSError) as exc:
        print(f"sarins {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"sarins {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
