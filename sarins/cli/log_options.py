"""Options shared by the commands that read a recorded IMU log (``sarins replay``, ``sarins allan --log``).

They say what a log cannot say about itself (docs/imu-log.md): its format, the sensor's axes, the
sample rate of a log without time, the site, the ROS topic, and the override of the unit checks.
"""

from __future__ import annotations

import argparse

from sarins_fmu import imu as imu_mod

from . import finite

FORMAT_CHOICES = ("auto", "sarins", "csv", "i2nav", "ros")


def add_log_options(p, *, rate: bool = True, site: bool = True) -> None:
    """The reading options; ``rate``: add --rate-hz (a command that has its own adds it itself);
    ``site``: add --lat-deg, --lon-deg, --height-m."""
    p.add_argument("--format", choices=FORMAT_CHOICES, default="auto",
                   help="log format (default auto: by the file's content and suffix)")
    p.add_argument("--axes", default=None, metavar="XYZ",
                   help="the sensor's x, y, z directions, three of r/l f/b u/d (e.g. frd: x forward, y right, z down); "
                        "rotated to right-front-up (default: the format's own, rfu for CSV, frd for i2Nav, flu for ROS)")
    if rate:
        p.add_argument("--rate-hz", type=finite, default=None, help="sample rate of a log without a time_s column, Hz")
    if site:
        p.add_argument("--lat-deg", type=finite, default=None, help="latitude of the static start, deg (a log without lat_deg)")
        p.add_argument("--lon-deg", type=finite, default=None, help="longitude of the static start, deg (default 0)")
        p.add_argument("--height-m", type=finite, default=None, help="height of the static start, m (default 0)")
    p.add_argument("--topic", default=None, help="ROS bag: the topic of the sensor_msgs/Imu messages")
    p.add_argument("--accept-units", action="store_true",
                   help="read a log whose units look wrong (its mean specific force is not gravity, a sample is beyond "
                        "any full scale): those refusals become warnings")


def read_options(args, rate_hz: float | None):
    """The :class:`~sarins_fmu.imu_log.ReadOptions` of the parsed options (``rate_hz``: the log's rate
    when the user gave it)."""
    from sarins_fmu.imu_log import ReadOptions

    if rate_hz is not None and not rate_hz > 0:
        from . import UsageError

        raise UsageError(f"--rate-hz must be positive, got {rate_hz:g}")
    return ReadOptions(format=args.format, axes=args.axes, rate_hz=rate_hz,
                       lat_deg=getattr(args, "lat_deg", None), lon_deg=getattr(args, "lon_deg", None),
                       height_m=getattr(args, "height_m", None), topic=args.topic, accept_units=args.accept_units)


def imu_choice(text: str) -> str:
    """argparse type: a built-in IMU preset or a preset file (.json), checked now."""
    if text in imu_mod.PRESETS:
        return text
    from sarins_fmu.imu_preset_file import is_preset_file, read_preset

    if not is_preset_file(text):
        raise argparse.ArgumentTypeError(f"{text!r} is neither a preset ({', '.join(sorted(imu_mod.PRESETS))}) nor a "
                                         "preset file (.json)")
    try:
        read_preset(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text
