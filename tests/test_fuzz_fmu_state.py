"""The native glue's FMU-state reader under sanitizers (tests/fuzz/fuzz_fmu_state.c), FMI 2.0 and 3.0, for every
native model (with the files it needs: tests/fuzz_fmus.py): built as a plain program with AddressSanitizer + UBSan (the state
checksum skipped, so that changes reach the fields behind it), fed the model's own states and every one-byte
change of one of them (two model/version pairs by default, all with SARINS_FUZZ_ALL=1); then (slow), with clang,
libFuzzer for SARINS_FUZZ_STATE_SECONDS (else SARINS_FUZZ_SECONDS, default 5) per model and version (.ci/run
gives 25).  A finding is any sanitizer report, or a step returning OK with a non-finite output."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import libfuzzer
import pytest

from fmus.cbuild import build_line

from fuzz_fmus import MODELS, prepare

pytestmark = pytest.mark.integration

HARNESS = Path(__file__).resolve().parent / "fuzz" / "fuzz_fmu_state.c"
REGRESSIONS = HARNESS.parent / "regressions"
FLAGS = ["-std=c11", "-g", "-O1", "-fno-sanitize-recover=all", "-DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION"]


def _compile(cc: str, src: Path, fmi: int, out: Path, sanitize: str, main: bool) -> Path:
    cmd = [cc, *FLAGS, f"-fsanitize={sanitize}", *(["-DFMI3"] if fmi == 3 else []),
           *(["-DSARINS_FUZZ_MAIN"] if main else []), f"-I{src}", str(HARNESS),
           *sorted(str(p) for p in src.glob("*.c")), "-o", str(out)]
    build_line(cmd)
    return out


QUICK = {("Turntable", 2), ("StrapdownINS", 3)}  # in the default run; the rest are slow


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", MODELS)
def test_state_reader_under_sanitizers(tmp_path, name, fmi):
    found = any(REGRESSIONS.glob(f"{name}_fmi{fmi}_*.bin"))  # a pair with a finding of its own always runs
    if (name, fmi) not in QUICK and not found and not os.environ.get("SARINS_FUZZ_ALL"):
        pytest.skip("slow variant: set SARINS_FUZZ_ALL=1 (.ci/run does)")
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    src, env = prepare(name, fmi, tmp_path)
    exe = _compile(cc, src, fmi, tmp_path / "main", "address,undefined", main=True)
    seeds = tmp_path / "seeds"
    seeds.mkdir()
    subprocess.run([str(exe), "--seeds", str(seeds)], check=True, env=env, timeout=300)
    files = sorted(seeds.iterdir())
    assert files
    blob = files[-1].read_bytes()
    variants = tmp_path / "variants"
    variants.mkdir()
    step = max(1, len(blob) // 150)  # about 150 positions over the blob, header and payload
    for i in range(0, len(blob), step):
        bad = bytearray(blob)
        bad[i] ^= 0xFF
        (variants / f"{i:07d}").write_bytes(bytes(bad))
    (variants / "truncated").write_bytes(blob[:-1])
    # findings of earlier fuzzing runs (tests/fuzz/regressions/<model>_fmi<n>_*.bin), their GUID made this build's
    guid = blob[24:88]
    for k, found in enumerate(sorted(REGRESSIONS.glob(f"{name}_fmi{fmi}_*.bin"))):
        data = bytearray(found.read_bytes())
        data[24:88] = guid
        (variants / f"regression{k}").write_bytes(bytes(data))
    inputs = [str(p) for p in files] + sorted(str(p) for p in variants.iterdir())
    proc = subprocess.run([str(exe), *inputs], capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0 and "runtime error" not in proc.stderr, proc.stderr[-3000:]


@pytest.mark.slow
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", MODELS)
def test_libfuzzer_finds_nothing(tmp_path, name, fmi):
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    seconds = int(os.environ.get("SARINS_FUZZ_STATE_SECONDS", os.environ.get("SARINS_FUZZ_SECONDS", "5")))
    src, env = prepare(name, fmi, tmp_path)
    seeder = _compile(clang, src, fmi, tmp_path / "main", "address,undefined", main=True)
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    subprocess.run([str(seeder), "--seeds", str(corpus)], check=True, env=env, timeout=300)
    fuzz = _compile(clang, src, fmi, tmp_path / "fuzz", "fuzzer,address,undefined", main=False)
    print(name, fmi, libfuzzer.run(fuzz, corpus, seconds, "-max_len=200000", env=env, headroom_mb=2560))
