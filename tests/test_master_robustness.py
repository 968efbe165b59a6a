"""Archives within limits, clean stops on SIGINT/SIGTERM, the real-time lag report."""
from __future__ import annotations

import os
import signal
import struct
import subprocess
import sys
import time
import zipfile
import zlib
from pathlib import Path

import pytest

from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from orchestration import Master, SystemFileError, read_system, simulate_system, write_ssp
from sarins.cli import main

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[1]


def deflate_bomb(path: Path, gib: int = 1) -> Path:
    """A valid zip of about 1 MB per GiB whose one member inflates to ``gib`` GiB of zeros.

    Built from one repeated raw-deflate block (a full flush resets the
    compressor, so every 1 MiB of zeros compresses to the same bytes).
    """
    mib = bytes(1 << 20)
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    block = compressor.compress(mib) + compressor.flush(zlib.Z_FULL_FLUSH)
    count = 1024 * gib
    data = block * count + compressor.flush()
    crc = 0
    for _ in range(count):
        crc = zlib.crc32(mib, crc)
    size = count << 20
    name = b"resources/payload.bin"
    local = struct.pack("<IHHHHHIIIHH", 0x04034B50, 20, 0, 8, 0, 0, crc, len(data), size,
                        len(name), 0) + name
    central = struct.pack("<IHHHHHHIIIHHHHHII", 0x02014B50, 20, 20, 0, 8, 0, 0, crc,
                          len(data), size, len(name), 0, 0, 0, 0, 0, 0) + name
    end = struct.pack("<IHHHHIIH", 0x06054B50, 0, 0, 1, 1, len(central),
                      len(local) + len(data), 0)
    path.write_bytes(local + data + central + end)
    return path


def test_a_2_mb_zip_bomb_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    bomb = deflate_bomb(tmp_path / "bomb.ssp")
    assert bomb.stat().st_size < 2 << 20
    with zipfile.ZipFile(bomb) as archive:  # a well-formed archive, honest sizes
        assert archive.infolist()[0].file_size == 1 << 30
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setenv("TMPDIR", str(scratch))
    import tempfile
    monkeypatch.setattr(tempfile, "tempdir", None)
    with pytest.raises(SystemFileError, match=r"bomb\.ssp.*1073741824 bytes, more than the "
                                              r"limit of 536870912 bytes; refused"):
        read_system(bomb)
    assert list(scratch.iterdir()) == []
    assert main(["cosim", str(bomb), "--stop-time", "1", "--step", "1"]) == 2


def test_archive_members_escaping_the_folder_are_refused(ramp_gain, tmp_path):
    path = write_ssp(ramp_gain, tmp_path / "deep" / "evil.ssp")
    with zipfile.ZipFile(path, "a") as archive:
        archive.writestr("../../escaped.txt", "x")
    with pytest.raises(SystemFileError, match=r"'\.\./\.\./escaped\.txt' would be written "
                                              "outside the extraction folder"):
        read_system(path)
    assert not (tmp_path / "escaped.txt").exists()
    absolute = write_ssp(ramp_gain, tmp_path / "abs.ssp")
    with zipfile.ZipFile(absolute, "a") as archive:
        archive.writestr(zipfile.ZipInfo("/etc/evil"), "x")
    with pytest.raises(SystemFileError, match="outside the extraction folder"):
        read_system(absolute)


def test_member_count_and_size_limits(ramp_gain, tmp_path):
    path = write_ssp(ramp_gain, tmp_path / "ok.ssp")
    with pytest.raises(SystemFileError, match="3 members, more than the limit of 2"):
        read_system(path, max_members=2)
    with pytest.raises(SystemFileError, match="more than the limit of 1000 bytes"):
        read_system(path, max_bytes=1000)
    system = read_system(path)
    assert (Path(system.base_dir) / "resources" / "Gain.fmu").is_file()


def test_realtime_reports_the_worst_lag(ramp_gain, tmp_path, capsys):
    with pytest.warns(UserWarning, match="fell behind"):
        result = simulate_system(ramp_gain, 0.2, 0.05, realtime=0.01,
                                 callback=lambda t, m: time.sleep(0.02) if t == 0.1 else None)
    report = result.meta["realtime"]
    assert report["steps"] == 4 and report["factor"] == 0.01
    assert report["late_steps"] >= 1 and report["max_lag_s"] > 0.0
    assert min(abs(report["max_lag_time"] - t) for t in (0.15, 0.2)) < 1e-12  # after it
    path = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    assert main(["cosim", str(path), "--stop-time", "0.5", "--step", "0.25",
                 "--realtime", "0.001", "--no-progress"]) == 0
    assert "real time (factor 0.001):" in capsys.readouterr().out


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_stops_cosim_cleanly(ramp_gain, tmp_path, signum, code):
    path = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(scratch)}
    process = subprocess.Popen(
        [sys.executable, "-m", "sarins", "cosim", str(path), "--stop-time", "1000",
         "--step", "0.01", "--realtime", "0.01", "--no-progress"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while len(list(scratch.glob("orchestration_fmu_*"))) < 2:  # both FMUs extracted
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, "cosim did not start"
            time.sleep(0.05)
        time.sleep(0.5)
        process.send_signal(signum)
        out, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == code, err
    assert f"sarins cosim: stopped by {signal.Signals(signum).name}" in err
    assert "Traceback" not in err and "FATAL" not in err
    assert list(scratch.iterdir()) == []  # extracted .ssp and FMUs removed


def test_keyboard_interrupt_in_python_frees_and_removes(ramp_gain, tmp_path):
    """Without the CLI's handlers a KeyboardInterrupt from a callback still cleans up."""
    path = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    master = Master(path)

    def interrupt(time_now, m):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        with master:
            master.simulate(1.0, 0.25, callback=interrupt)
    assert master.instances == [] and not Path(master.system.base_dir).exists()
