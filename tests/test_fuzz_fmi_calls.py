"""FMI call sequences on the native glue under sanitizers (tests/fuzz/fuzz_fmi_calls.c), FMI 2.0 and 3.0, for
every native model (with the files it needs: tests/fuzz_fmus.py): built as a plain program with AddressSanitizer
+ UBSan and fed the seed corpus (tests/fuzz/corpus_fmi_calls) and the findings of earlier runs
(tests/fuzz/regressions/calls_*.bin), by default for two model/version pairs and every pair with a finding of
its own, all with SARINS_FUZZ_ALL=1; then
(slow), with clang, libFuzzer for SARINS_FUZZ_CALLS_SECONDS per model and version (else SARINS_FUZZ_SECONDS,
default 5).  A finding is any sanitizer report (leaks included), a hang (-timeout), or a broken invariant
(an OK the FMI state machine forbids, an OK for an unknown value reference or a wrong count, a non-finite
output after an OK step: the harness aborts naming it)."""

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

HARNESS = Path(__file__).resolve().parent / "fuzz" / "fuzz_fmi_calls.c"
CORPUS = HARNESS.parent / "corpus_fmi_calls"
REGRESSIONS = HARNESS.parent / "regressions"
FLAGS = ["-std=c11", "-g", "-O1", "-fno-sanitize-recover=all"]
QUICK = {("StrapdownINS", 2), ("Turntable", 3)}  # in the default run; the rest are slow


def _compile(cc: str, src: Path, fmi: int, out: Path, sanitize: str, main: bool) -> Path:
    cmd = [cc, *FLAGS, f"-fsanitize={sanitize}", *(["-DFMI3"] if fmi == 3 else []),
           *(["-DSARINS_FUZZ_MAIN"] if main else []), f"-I{src}", str(HARNESS),
           *sorted(str(p) for p in src.glob("*.c")), "-o", str(out)]
    build_line(cmd)
    return out


def _inputs(name: str, fmi: int) -> list[str]:
    """The corpus, the findings on any model (calls_fmi<n>_*.bin) and those on this one
    (calls_<model>_fmi<n>_*.bin)."""
    found = [*REGRESSIONS.glob("calls_fmi*_*.bin"), *REGRESSIONS.glob(f"calls_{name}_fmi{fmi}_*.bin")]
    return sorted(str(p) for p in CORPUS.iterdir()) + sorted(str(p) for p in found)


def _has_own_regression(name: str, fmi: int) -> bool:
    return any(REGRESSIONS.glob(f"calls_{name}_fmi{fmi}_*.bin"))


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", MODELS)
def test_call_sequences_under_sanitizers(tmp_path, name, fmi):
    if (name, fmi) not in QUICK and not _has_own_regression(name, fmi) and not os.environ.get("SARINS_FUZZ_ALL"):
        pytest.skip("slow variant: set SARINS_FUZZ_ALL=1 (.ci/run does)")
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    src, env = prepare(name, fmi, tmp_path)
    exe = _compile(cc, src, fmi, tmp_path / "main", "address,undefined", main=True)
    inputs = _inputs(name, fmi)
    assert len(inputs) >= 6
    proc = subprocess.run([str(exe), *inputs], capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0 and "runtime error" not in proc.stderr, proc.stderr[-3000:]
    assert f"ran {len(inputs)} inputs" in proc.stdout


@pytest.mark.slow
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", MODELS)
def test_libfuzzer_calls_find_nothing(tmp_path, name, fmi):
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    seconds = int(os.environ.get("SARINS_FUZZ_CALLS_SECONDS", os.environ.get("SARINS_FUZZ_SECONDS", "5")))
    src, env = prepare(name, fmi, tmp_path)
    corpus = tmp_path / "corpus"
    shutil.copytree(CORPUS, corpus)
    fuzz = _compile(clang, src, fmi, tmp_path / "fuzz", "fuzzer,address,undefined", main=False)
    print(name, fmi, libfuzzer.run(fuzz, corpus, seconds, "-timeout=20", env=env, headroom_mb=2560))
