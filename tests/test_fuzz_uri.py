"""The fmuResourceLocation parser (fmus/c/sarins_uri.h) under libFuzzer with AddressSanitizer and UBSan:
the harness tests/fuzz/fuzz_uri.c, built as it is and with -D_WIN32 (the drive-letter branch), seeded with
tests/fuzz/corpus_uri, run for SARINS_FUZZ_SECONDS per build (default 3; .ci/run gives 60).  A finding is
any sanitizer report or a broken invariant of the harness (the output NUL-terminated within its buffer, OK
only with an absolute path, "" on every error)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HARNESS = ROOT / "tests" / "fuzz" / "fuzz_uri.c"
CORPUS = ROOT / "tests" / "fuzz" / "corpus_uri"


@pytest.mark.parametrize("defines", [[], ["-D_WIN32"]], ids=["posix", "win32"])
def test_libfuzzer_finds_nothing_in_the_uri_parser(tmp_path, defines):
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    seconds = int(os.environ.get("SARINS_FUZZ_SECONDS", "3"))
    exe = tmp_path / "fuzz_uri"
    subprocess.run([clang, "-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-Werror",
                    "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all", *defines,
                    f"-I{ROOT / 'fmus' / 'c'}", str(HARNESS), "-o", str(exe)], check=True)
    corpus = tmp_path / "corpus"  # libFuzzer adds to its corpus folder: a copy, never the repository's
    shutil.copytree(CORPUS, corpus)
    assert len(list(corpus.iterdir())) >= 5
    proc = subprocess.run([str(exe), "-max_len=4096", f"-max_total_time={seconds}", "-print_final_stats=1",
                           str(corpus)], capture_output=True, text=True, timeout=seconds + 600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    runs = [line for line in proc.stderr.splitlines() if "stat::number_of_executed_units" in line]
    assert runs, proc.stderr[-2000:]
    print(defines, runs[0])
