"""Readers for what real sensors write: vendor CSV with units in the header (gzip), declared axes, the
KF-GINS / i2Nav IMU text, ROS bags of sensor_msgs/Imu; each replays to the numbers of the same data in
the project's format."""

import gzip
import json
import math

import numpy as np
import pytest

from sarins_fmu import allan, imu, imu_log
from sarins_fmu.experiments.replay import replay
from sarins_fmu.imu_log import LogError, ReadOptions, read_log, write_log
from sarins_fmu.imu_log_units import axes_matrix, rotate
from sarins_fmu.units import DEG_TO_RAD, G0

H = 0.01  # s, 100 Hz
N = 50000  # 500 s: a 400 s alignment and 100 s of navigation


@pytest.fixture(scope="module")
def record():
    """A level, static nav-rlg record at 100 Hz (rad/s, m/s^2, right-front-up) at 45 deg."""
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), N * H, 1.0 / H, seed=2, lat_deg=45.0)
    return gyro, accel


def _sarins_rates(tmp_path, gyro, accel, h=H):
    """The same rates in the project's format (NPZ, rate columns)."""
    cols = {"time_s": np.arange(1, len(gyro) + 1) * h}
    cols.update({f"gyro_{a}_radps": gyro[:, i] for i, a in enumerate("xyz")})
    cols.update({f"accel_{a}_mps2": accel[:, i] for i, a in enumerate("xyz")})
    np.savez(tmp_path / "ref.npz", meta=np.array(json.dumps({"lat_deg": 45.0})), **cols)
    return read_log(tmp_path / "ref.npz")


def _same_replay(a, b):
    ra, rb = replay(a, align_hours=400 / 3600), replay(b, align_hours=400 / 3600)
    for name in ("lat_error", "lon_error", "position_error", "velocity_n", "attitude"):
        np.testing.assert_array_equal(getattr(ra, name), getattr(rb, name), err_msg=name)
    assert ra.summary() == rb.summary()


def test_vendor_csv_in_deg_per_s_and_g_gzip_and_z_down(tmp_path, record):
    """The real units' kind of file: time_s, gyro in deg/s, accelerometers in g, z down (--axes frd)."""
    gyro, accel = record
    d = axes_matrix("frd")
    g_s, a_s = gyro @ d, accel @ d  # right-front-up -> the sensor's axes (D is orthogonal: v_s = D^T v)
    path = tmp_path / "vendor.csv.gz"
    with gzip.open(path, "wt") as fh:
        fh.write("time_s,gyro_x_dps,gyro_y_dps,gyro_z_dps,accel_x_g,accel_y_g,accel_z_g\n")
        np.savetxt(fh, np.column_stack([np.arange(N) * H, np.degrees(g_s), a_s / G0]), delimiter=",", fmt="%.17g")
    log = read_log(path, ReadOptions(axes="frd", lat_deg=45.0))
    assert log.format == "csv" and log.axes == "frd" and log.step == H and log.warnings == []
    np.testing.assert_allclose(log.dtheta / H, gyro, rtol=1e-13, atol=1e-18)
    np.testing.assert_allclose(log.dv / H, accel, rtol=1e-13)
    np.testing.assert_allclose(log.time, np.arange(1, N + 1) * H)  # the first sample ends at h
    out = replay(log, align_hours=400 / 3600)
    ref = replay(_sarins_rates(tmp_path, gyro, accel), align_hours=400 / 3600)
    np.testing.assert_allclose(out.position_error, ref.position_error, rtol=1e-6, atol=1e-6)


def test_units_in_the_header(tmp_path):
    n = 300
    rng = np.random.default_rng(1)
    gyro = 1e-5 * rng.standard_normal((n, 3))
    accel = np.tile([0.0, 0.0, 9.80665], (n, 1)) + 1e-4 * rng.standard_normal((n, 3))
    cases = {"dph": (gyro / (DEG_TO_RAD / 3600), "mg", accel / G0 * 1e3), "radps": (gyro, "mps2", accel)}
    for gunit, (gv, aunit, av) in cases.items():
        path = tmp_path / f"{gunit}.csv"
        header = ",".join([f"gyro_{a}_{gunit}" for a in "xyz"] + [f"accel_{a}_{aunit}" for a in "xyz"] + ["temp_c"])
        np.savetxt(path, np.column_stack([gv, av, np.full(n, 25.0)]), delimiter=",", header=header, comments="",
                   fmt="%.17g")
        log = read_log(path, ReadOptions(rate_hz=10.0))
        assert log.step == 0.1
        np.testing.assert_allclose(log.dtheta / 0.1, gyro, rtol=1e-12, atol=1e-20)
        np.testing.assert_allclose(log.dv / 0.1, accel, rtol=1e-12)
        assert np.all(log.temps == 25.0) and log.lat is None
    with pytest.raises(LogError, match="no time_s column; give the sample rate with --rate-hz"):
        read_log(tmp_path / "dph.csv")
    bad = tmp_path / "furlong.csv"
    bad.write_text("time_s,gyro_x_rpm,gyro_y_dps,gyro_z_dps,accel_x_g,accel_y_g,accel_z_g\n0,1,1,1,0,0,1\n")
    with pytest.raises(LogError, match=r"line 1: column 'gyro_x_rpm': gyro in unknown unit 'rpm' \(one of radps, dps, dph\)"):
        read_log(bad)


def test_axes_codes():
    np.testing.assert_array_equal(axes_matrix("rfu"), np.eye(3))
    v = np.array([[1.0, 2.0, 3.0]])  # x forward, y right, z down
    np.testing.assert_array_equal(rotate(axes_matrix("frd"), v), [[2.0, 1.0, -3.0]])
    np.testing.assert_array_equal(rotate(axes_matrix("flu"), v), [[-2.0, 1.0, 3.0]])
    for left in ("rfd", "lfu", "fru"):
        with pytest.raises(ValueError, match="left-handed"):
            axes_matrix(left)
    for bad in ("rrf", "xyz", "fr"):
        with pytest.raises(ValueError, match="axes"):
            axes_matrix(bad)


def test_the_project_format_keeps_its_axes_and_site(tmp_path, record):
    gyro, accel = record
    path = write_log(tmp_path / "p.csv", np.arange(1, 201) * H, gyro[:200] * H, accel[:200] * H, lat_deg=45.0)
    with pytest.raises(LogError, match="right-front-up by definition; --axes frd does not apply"):
        read_log(path, ReadOptions(axes="frd"))
    with pytest.raises(LogError, match="states lat_deg 45.0; --lat-deg applies only to a log without it"):
        read_log(path, ReadOptions(lat_deg=10.0))


def _i2nav_text(path, gyro, accel, start_sow, sep=" "):
    """KF-GINS IMU text: GNSS seconds of week, increments in rad and m/s, forward-right-down."""
    d = axes_matrix("frd")
    rows = np.column_stack([start_sow + np.arange(1, N + 1) * H, gyro @ d * H, accel @ d * H])
    np.savetxt(path, rows, delimiter=sep, fmt="%.17g")
    return path


def test_i2nav_text_replays_to_the_numbers_of_the_project_format(tmp_path, record):
    gyro, accel = record
    path = _i2nav_text(tmp_path / "imu.txt", gyro, accel, 456300.0)
    log = read_log(path, ReadOptions(lat_deg=45.0))
    assert log.format == "i2nav" and log.axes == "frd" and log.quantity == "increments" and log.step == H
    ref = write_log(tmp_path / "ref.npz", np.arange(1, N + 1) * H, gyro @ np.eye(3) * H, accel * H, lat_deg=45.0)
    _same_replay(log, read_log(ref))


def test_i2nav_week_rollover_and_separators(tmp_path, record):
    gyro, accel = record
    path = _i2nav_text(tmp_path / "wrap.txt", gyro, accel, 604800.0 - 300.0, sep=",")
    text = path.read_text().splitlines()
    wrapped = []
    for line in text:  # the clock restarts at 0 at the week's end, as GNSS receivers write it
        t, rest = line.split(",", 1)
        wrapped.append(f"{float(t) % 604800.0!r},{rest}")
    path.write_text("\n".join(wrapped) + "\n")
    log = read_log(path, ReadOptions(lat_deg=45.0))
    assert log.step == H and len(log.time) == N


def _bag(path, gyro, accel, version, h):
    """A ROS bag written with rosbags' own writer: sensor_msgs/Imu in forward-left-up (REP 103)."""
    pytest.importorskip("rosbags")
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE if version == 2 else Stores.ROS1_NOETIC)
    name = "sensor_msgs/msg/Imu"
    types = store.types
    d = axes_matrix("flu")
    w_s, f_s = gyro @ d, accel @ d
    if version == 2:
        from rosbags.rosbag2 import Writer

        writer, ser = Writer(path, version=9), store.serialize_cdr
    else:
        from rosbags.rosbag1 import Writer

        writer, ser = Writer(path), store.serialize_ros1
    with writer:
        conn = writer.add_connection("/imu/data", name, typestore=store)
        for k in range(len(gyro)):
            stamp = (k + 1) * round(h * 1e9)  # ns
            extra = {"seq": k} if version == 1 else {}
            header = types["std_msgs/msg/Header"](**extra, stamp=types["builtin_interfaces/msg/Time"](
                sec=stamp // 1_000_000_000, nanosec=stamp % 1_000_000_000), frame_id="imu")
            vec = types["geometry_msgs/msg/Vector3"]
            msg = types[name](header=header, orientation=types["geometry_msgs/msg/Quaternion"](x=0, y=0, z=0, w=1),
                              orientation_covariance=np.zeros(9), angular_velocity=vec(*w_s[k]),
                              angular_velocity_covariance=np.zeros(9), linear_acceleration=vec(*f_s[k]),
                              linear_acceleration_covariance=np.zeros(9))
            writer.write(conn, stamp, ser(msg, name))
    return path


@pytest.mark.parametrize("version", [1, 2])
def test_a_ros_bag_replays_to_the_numbers_of_the_project_format(tmp_path, version):
    """ROS 1 and ROS 2 bags of a 10 Hz record (500 s)."""
    h, n = 0.1, 5000
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), n * h, 1.0 / h, seed=4, lat_deg=45.0)
    path = _bag(tmp_path / ("imu.bag" if version == 1 else "imu_bag"), gyro, accel, version, h)
    log = read_log(path, ReadOptions(lat_deg=45.0))
    assert log.format == "ros" and log.axes == "flu" and log.quantity == "rates" and log.step == h
    _same_replay(log, _sarins_rates(tmp_path, gyro, accel, h))


def test_a_missing_rosbags_names_the_extra(tmp_path, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_rosbags(name, *args, **kw):
        if name.startswith("rosbags"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kw)

    (tmp_path / "x.bag").write_bytes(b"#ROSBAG V2.0\n")
    monkeypatch.setattr(builtins, "__import__", no_rosbags)
    with pytest.raises(LogError, match=r"needs the package 'rosbags' \(pip install 'sarins-fmu\[ros\]'\)"):
        read_log(tmp_path / "x.bag")


def test_a_gzip_whose_text_passes_the_budget_is_refused_as_it_is_read(tmp_path, monkeypatch):
    path = tmp_path / "bomb.csv.gz"
    with gzip.open(path, "wb", compresslevel=9) as fh:
        fh.write(b"time_s,gyro_x_radps,gyro_y_radps,gyro_z_radps,accel_x_mps2,accel_y_mps2,accel_z_mps2\n")
        fh.write(b"0.01,0,0,0,0,0,9.8\n" * 600000)  # 11 MB of text in a file of a few kB
    assert path.stat().st_size < 100_000
    monkeypatch.setattr(imu_log, "MAX_LOG_BYTES", 2**20)
    with pytest.raises(LogError, match=r"its text \(decompressed\) is more than the limit of 1 MiB"):
        read_log(path)
    damaged = tmp_path / "cut.csv.gz"
    damaged.write_bytes(path.read_bytes()[:2000])
    monkeypatch.setattr(imu_log, "MAX_LOG_BYTES", 2**30)
    with pytest.raises(LogError, match="not a readable gzip file"):
        read_log(damaged)


def test_jittered_stamps_are_read_on_their_grid_with_a_warning_and_gaps_refused(tmp_path, record):
    gyro, accel = record
    n = 2000
    t = np.arange(n) * H + 0.0004 * np.sin(np.arange(n))  # 4 % of h
    rows = np.column_stack([t, gyro[:n], accel[:n]])
    header = "time_s," + ",".join(f"gyro_{a}_radps" for a in "xyz") + "," + ",".join(f"accel_{a}_mps2" for a in "xyz")
    np.savetxt(tmp_path / "j.csv", rows, delimiter=",", header=header, comments="", fmt="%.17g")
    with pytest.warns(imu_log.LogWarning, match=r"timestamps deviate by up to \d.* % of the 0.01 s interval"):
        log = read_log(tmp_path / "j.csv")
    assert log.step == H
    np.savetxt(tmp_path / "gap.csv", np.delete(rows, 700, axis=0), delimiter=",", header=header, comments="",
               fmt="%.17g")
    with pytest.raises(LogError, match="line 702: time step 0.01.* s differs from the log's 0.01 s \\(a gap\\)"):
        read_log(tmp_path / "gap.csv")


def test_accept_units_turns_a_unit_refusal_into_a_warning(tmp_path, record):
    gyro, accel = record
    path = write_log(tmp_path / "g.csv", np.arange(1, 401) * H, gyro[:400] * H, accel[:400] * H / G0, lat_deg=45.0)
    with pytest.raises(LogError, match="not gravity"):
        read_log(path)
    with pytest.warns(imu_log.LogWarning, match="not gravity.*read anyway: --accept-units"):
        read_log(path, ReadOptions(accept_units=True))


def test_a_large_log_is_kept_in_a_mapped_temporary_file(tmp_path, record, monkeypatch):
    from sarins_fmu import imu_log_stream

    gyro, accel = (x[:20000] for x in record)
    path = write_log(tmp_path / "big.csv", np.arange(1, 20001) * H, gyro * H, accel * H, lat_deg=45.0)
    small = read_log(path)
    monkeypatch.setattr(imu_log_stream, "SPILL_BYTES", 2**16)
    monkeypatch.setattr("sarins_fmu.imu_log_text.BLOCK_BYTES", 2**18)
    big = read_log(path)
    assert isinstance(big.dtheta.base, np.memmap) or isinstance(big.dtheta, np.memmap)
    np.testing.assert_array_equal(big.dtheta, small.dtheta)
    np.testing.assert_array_equal(big.dv, small.dv)
    assert math.isclose(big.step, small.step)
