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


def cmd_demo(args) -> int:
    """The main job: one hot-start static run, a short table of its errors."""
    t0 = time.perf_counter()
    result = _run(args)
    s = result.summary()
    rows = [
        ("latitude error at 12 h", f"{s.get('lat_error_deg_12h', float('nan')):+.5f} deg"),
        ("position error at end", f"{s['position_error_nm']:.3f} nm after {args.nav_hours:g} h"),
        ("max position error", f"{s['max_position_error_nm']:.3f} nm"),
        ("identified axial drift", "none yet (identifier not in this run)"),
        ("wall time", f"{time.perf_counter() - t0:.1f} s"),
    ]
    print(f"sarins demo: {args.imu} IMU, {args.start} start, {args.rotation} rotation, "
          f"{args.align_hours:g} h alignment + {args.nav_hours:g} h navigation at {args.lat_deg} deg")
    for name, value in rows:
        print(f"  {name:<24} {value}")
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
    p = sub.add_parser("demo", help="the main job on built-in defaults")
    _add_run_options(p, nav_hours=72.0)
    p.set_defaults(func=cmd_demo)
    for module in _plugin_modules():
        module.register(sub)
    return parser


def _plugin_modules():
    """Sub-command modules of the other packages (master, identifiers)."""
    import importlib

    found = []
    for name in ("orchestration.cli", "sarins_fmu.identify.cli", "fmus.cli"):
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
