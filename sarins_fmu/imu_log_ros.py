"""ROS 1 and ROS 2 bags of ``sensor_msgs/Imu`` as IMU logs, through the ``rosbags`` package.

A bag (a ROS 1 ``.bag`` file, or a ROS 2 bag folder or its ``.db3`` / ``.mcap`` file) is read with
``rosbags.highlevel.AnyReader`` (pure Python, no ROS installation; the optional extra ``[ros]``).
Each message gives the sample time (``header.stamp``, ns), the angular velocity (rad/s) and the
linear acceleration (m/s^2, the specific force) in the message's frame, which REP 103 makes
forward-left-up (``--axes flu``, the default here).  The messages are taken in stamp order as a
rate log on the nominal grid of :mod:`sarins_fmu.imu_log_stream` (jitter up to 10 % of the interval
with a warning, gaps refused naming the message).  The orientation and covariances are not used.

Size budget: the bag's files together at most ``MAX_LOG_BYTES``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

IMU_TYPES = ("sensor_msgs/msg/Imu", "sensor_msgs/Imu")
BLOCK_MESSAGES = 65536  # messages converted per block


def _rosbags():
    try:
        from rosbags.highlevel import AnyReader
    except ImportError:
        from .imu_log import LogError

        raise LogError("reading a ROS bag needs the package 'rosbags' (pip install 'sarins-fmu[ros]')") from None
    return AnyReader


def _bag_size(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def read_bag(path, opts):
    """The ``sensor_msgs/Imu`` messages of a bag as an :class:`~sarins_fmu.imu_log.ImuLog` (see the module
    docstring); ``opts`` is a :class:`~sarins_fmu.imu_log.ReadOptions` (topic, axes, site)."""
    from .files import format_bytes
    from .imu_log import MAX_LOG_BYTES, LogError, _axes, _finish, _where_row
    from .imu_log_stream import LogBuilder

    path = Path(path)
    if not path.exists():
        raise LogError(f"{path}: no such bag")
    size = _bag_size(path)
    if size > MAX_LOG_BYTES:
        raise LogError(f"{path}: {format_bytes(size)} is more than the limit of {format_bytes(MAX_LOG_BYTES)} "
                       f"({MAX_LOG_BYTES} bytes) for an IMU log (MAX_LOG_BYTES); refused")
    if opts.rate_hz is not None:
        raise LogError(f"{path}: a ROS bag has its time stamps; --rate-hz applies to a log without time")
    axes, code, given = _axes(path, opts, "ros")
    reader_cls = _rosbags()
    bag_path = path.parent if path.suffix in (".db3", ".mcap") and (path.parent / "metadata.yaml").exists() else path
    try:
        with reader_cls([bag_path]) as reader:
            imu = [c for c in reader.connections if c.msgtype in IMU_TYPES]
            topics = sorted({c.topic for c in imu})
            if not topics:
                raise LogError(f"{path}: no sensor_msgs/Imu messages (topics: "
                               f"{', '.join(sorted({c.topic for c in reader.connections})) or 'none'})")
            if opts.topic is None and len(topics) > 1:
                raise LogError(f"{path}: sensor_msgs/Imu on several topics ({', '.join(topics)}); choose one with "
                               "--topic")
            topic = opts.topic or topics[0]
            if topic not in topics:
                raise LogError(f"{path}: --topic {topic}: no sensor_msgs/Imu messages there (found "
                               f"{', '.join(topics)})")
            conns = [c for c in imu if c.topic == topic]
            builder = LogBuilder(path, _where_row("message"), strict=False, quantity="rates", axes=axes,
                                 has_temps=False, has_ref=False, accept_units=opts.accept_units)
            builder.names = {"time_s": ["header.stamp"], "imu": [f"{q}.{a}" for q in ("angular_velocity",
                                                                                       "linear_acceleration")
                                                                  for a in "xyz"]}
            stamps = np.empty(BLOCK_MESSAGES, np.int64)
            values = np.empty((BLOCK_MESSAGES, 6))
            k, t0 = 0, None
            for conn, _, raw in reader.messages(connections=conns):
                msg = reader.deserialize(raw, conn.msgtype)
                stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
                w, f = msg.angular_velocity, msg.linear_acceleration
                stamps[k] = stamp
                values[k] = (w.x, w.y, w.z, f.x, f.y, f.z)
                k += 1
                if k == BLOCK_MESSAGES:
                    t0 = stamps[0] if t0 is None else t0
                    builder.feed((stamps - t0) * 1e-9, values.copy())
                    k = 0
            if k:
                t0 = stamps[0] if t0 is None else t0
                builder.feed((stamps[:k] - t0) * 1e-9, values[:k].copy())
    except LogError:
        raise
    except Exception as exc:  # rosbags raises its own errors for a damaged or unknown bag
        raise LogError(f"{path}: not a readable ROS bag ({type(exc).__name__}: "
                       f"{' '.join(str(exc).split())[:160]})") from None
    meta = {"source_format": "ROS bag", "topic": topic}
    return _finish(path, builder, meta, opts, "ros", code, given, "rates")
