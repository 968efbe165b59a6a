"""The vehicle's legs parser and stream (sarins_fmu/core/vehicle.c, what the VehicleMotion FMU runs on its
``legs`` text) under AddressSanitizer and UBSan: the harness tests/fuzz/fuzz_vehicle_legs.c without
libFuzzer, on valid texts, every one-byte change and truncation of them, and seeded random token soups
(numbers of every size and form strtod reads: inf, nan, hex, exponents).  Any sanitizer report or a
non-finite output from a state the core calls valid fails."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import libfuzzer
import numpy as np
import pytest

from fmus.cbuild import build_line

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "sarins_fmu" / "core"
HARNESS = ROOT / "tests" / "fuzz" / "fuzz_vehicle_legs.c"
CORE_FILES = [CORE / f for f in ("vehicle.c", "schedule.c", "ambient.c", "earth.c", "rng.c", "report.c", "smath.c")]
VALID = ["drive 300 10; turn 90; drive 300 12; stop 1800; drive 180 10; stop 60",
         "drive 60 10;turn -45 ;  stop 5", "drive 1e3 0.5; turn 180; turn -180; stop 1"]
TOKENS = ["drive", "turn", "stop", "fly", ";", " ", "1", "-1", "0", "1e308", "-1e308", "1e-320", "inf", "nan",
          "0x1p6", "90", "360", "1e15", "4e15", "9007199254740993", "12.5", "+3", ".", "e5", "\t"]


def _inputs() -> list[bytes]:
    rng = np.random.default_rng(27)
    out = []
    for text in VALID:
        data = text.encode()
        for control in range(0, 256, 37):  # the grid / latitude byte
            out.append(bytes([control]) + data)
        for i in range(len(data)):
            for b in (0x00, 0x20, 0x3b, 0x39, 0x2d, 0x65, 0xff):
                out.append(b"\x00" + data[:i] + bytes([b]) + data[i + 1:])
            out.append(b"\x04" + data[:i])
    for _ in range(3000):
        words = rng.choice(TOKENS, size=int(rng.integers(1, 40)))
        out.append(bytes([int(rng.integers(0, 256))]) + " ".join(words).encode())
    return [x.replace(b"\n", b" ").replace(b"\r", b" ") for x in out]


def test_legs_parser_and_stream_hold_under_sanitizers(tmp_path):
    cc = shutil.which("gcc")
    if cc is None:
        pytest.skip("needs gcc")
    exe = tmp_path / "fuzz_vehicle_legs"
    build = subprocess.run([cc, "-std=c11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-fsanitize=address,undefined",
                            "-fno-sanitize-recover=all", "-DSARINS_FUZZ_MAIN", f"-I{CORE}", str(HARNESS),
                            *map(str, CORE_FILES), "-o", str(exe)], capture_output=True, text=True)
    if build.returncode and "asan" in build.stderr.lower():
        pytest.skip(f"gcc cannot build with AddressSanitizer here: {build.stderr[-300:]}")
    assert build.returncode == 0, build.stderr[-3000:]
    inputs = _inputs()
    corpus = tmp_path / "corpus.txt"
    corpus.write_bytes(b"\n".join(inputs) + b"\n")
    run = subprocess.run([str(exe), str(corpus)], capture_output=True, text=True, timeout=600,
                         env={"ASAN_OPTIONS": "detect_leaks=0", "UBSAN_OPTIONS": "halt_on_error=1"})
    report = run.stdout + run.stderr
    assert run.returncode == 0, report[-4000:]
    assert f"fuzz harness: {len(inputs)} inputs" in run.stdout, report[-2000:]
    for marker in ("AddressSanitizer", "runtime error:", "UndefinedBehaviorSanitizer"):
        assert marker not in report, report[-4000:]


@pytest.mark.slow
def test_libfuzzer_finds_nothing_in_the_legs_parser(tmp_path):
    """The same harness under clang's libFuzzer (ASan + UBSan) for SARINS_FUZZ_SECONDS (default 5; .ci/run
    gives 60), seeded with the valid texts and a sample of the token soups."""
    clang = libfuzzer.clang_or_skip()
    exe = tmp_path / "fuzz"
    build_line([clang, "-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-Werror",
                    "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all", f"-I{CORE}", str(HARNESS),
                    *map(str, CORE_FILES), "-o", str(exe)])
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    for k, data in enumerate(_inputs()[::25]):
        (corpus / f"seed{k:04d}").write_bytes(data)
    print("vehicle legs", libfuzzer.run(exe, corpus, libfuzzer.budget(5), "-max_len=4096", "-timeout=20"))
