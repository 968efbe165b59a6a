"""The IMULog FMU's log reader under sanitizers (tests/fuzz/fuzz_imu_log_file.c, FMI 2.0): built as a plain
program with AddressSanitizer + UBSan from the FMU's sources/ and fed valid logs of the project's format and
hand-made damaged ones (cut lines, bad numbers, out-of-range values, CRLF, odd headers); then (slow), with clang,
libFuzzer for SARINS_FUZZ_SECONDS (default 5; .ci/run gives 60) from those files.  A finding is any sanitizer
report, an accepted log without a positive finite interval, or a step returning OK with a non-finite output."""

from __future__ import annotations

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import libfuzzer
import pytest

from fmus.cbuild import build_line
from fmus import SLAVES
from fmus.native_fmu import build_native_fmu
from sarins_fmu.imu_log import write_log

pytestmark = pytest.mark.integration

HARNESS = Path(__file__).resolve().parent / "fuzz" / "fuzz_imu_log_file.c"
FLAGS = ["-std=c11", "-g", "-O1", "-fno-sanitize-recover=all"]
ENV = {"PATH": os.environ.get("PATH", ""), "ASAN_OPTIONS": "detect_leaks=1"}


def _sources(tmp: Path) -> Path:
    fmu = build_native_fmu("IMULog", SLAVES["IMULog"], tmp / "fmu", fmi=2, win64=False, aarch64=False)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tmp / "unzipped")
    return tmp / "unzipped" / "sources"


def _compile(cc: str, src: Path, out: Path, sanitize: str, main: bool) -> Path:
    cmd = [cc, *FLAGS, f"-fsanitize={sanitize}", *(["-DSARINS_FUZZ_MAIN"] if main else []), f"-I{src}",
           str(HARNESS), *sorted(str(p) for p in src.glob("*.c")), "-o", str(out)]
    build_line(cmd)
    return out


def _seeds(folder: Path) -> list[Path]:
    """Valid logs (with and without temperatures, 1 Hz and 100 Hz) and damaged variants of them."""
    folder.mkdir()
    rng = np.random.default_rng(5)
    k = np.arange(1, 9, dtype=float)
    dtheta, dv = 1e-5 * rng.standard_normal((8, 3)), 9.8 * np.array([0, 0, 1.0]) + rng.standard_normal((8, 3))
    good = [write_log(folder / "temps.csv", k, dtheta, dv, lat_deg=28.2, temps=20 + rng.standard_normal((8, 6))),
            write_log(folder / "plain.csv", k / 100.0, dtheta / 100.0, dv / 100.0, lat_deg=-33.9, lon_deg=151.2, height_m=40.0)]
    text = good[0].read_text()
    lines = text.splitlines(keepends=True)

    def field(value: str, column: int = 4) -> str:  # the first sample's column replaced by value
        cells = lines[5].rstrip("\n").split(",")
        cells[column] = value
        return "".join(lines[:5]) + ",".join(cells) + "\n" + "".join(lines[6:])

    damaged = {
        "empty": "", "header_only": "".join(lines[:5]), "cut_line": "".join(lines[:7]) + lines[7][:20],
        "crlf": text.replace("\n", "\r\n"), "nan": field("nan"), "inf": field("inf"), "huge": field("1e400"),
        "long_digits": text.replace("1.0", "1.000000000000000000000001"),
        "back_in_time": "".join(lines[:6] + [lines[7], lines[6]] + lines[8:]),
        "no_magic": "".join(lines[1:]), "extra_column": text.replace("\n", ",1\n"),
        "latitude_out": text.replace("lat_deg: 28.2", "lat_deg: 128.2"), "nul": text[:200] + "\0" + text[200:],
        "long_line": "".join(lines[:5]) + "1," + "9" * 5000 + "\n",
    }
    for name, body in damaged.items():
        (folder / f"{name}.csv").write_bytes(body.encode("latin-1", "replace"))
    return sorted(folder.iterdir())


def test_log_reader_under_sanitizers(tmp_path):
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    exe = _compile(cc, _sources(tmp_path), tmp_path / "main", "address,undefined", main=True)
    files = _seeds(tmp_path / "seeds")
    env = dict(ENV, FUZZ_LOG_PATH=str(tmp_path / "played.csv"))
    proc = subprocess.run([str(exe), *map(str, files)], capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0 and "runtime error" not in proc.stderr, proc.stderr[-3000:]
    verdict = dict(reversed(line.split(" ", 1)) for line in proc.stdout.splitlines())
    accepted = {Path(f).stem for f, v in verdict.items() if v == "ACCEPTED"}
    assert {"temps", "plain", "crlf"} <= accepted, verdict  # the valid logs were played
    assert not accepted & {"empty", "header_only", "nan", "inf", "huge", "back_in_time", "no_magic"}, verdict


@pytest.mark.slow
def test_libfuzzer_finds_nothing_in_the_log_reader(tmp_path):
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    seconds = int(os.environ.get("SARINS_FUZZ_SECONDS", "5"))
    fuzz = _compile(clang, _sources(tmp_path), tmp_path / "fuzz", "fuzzer,address,undefined", main=False)
    corpus = tmp_path / "corpus"
    _seeds(corpus)
    env = dict(ENV, FUZZ_LOG_PATH=str(tmp_path / "played.csv"))
    print("IMULog log reader", libfuzzer.run(fuzz, corpus, seconds, "-max_len=8192", "-timeout=20", env=env))
