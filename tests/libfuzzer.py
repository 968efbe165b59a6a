"""Running a libFuzzer harness from a test: clang (or a skip with the install line), the time budget from the
environment, and the run itself, which fails the test on any finding and returns the run's execution count."""

from __future__ import annotations

import os
import resource
import shutil
import subprocess
from pathlib import Path

import pytest


def clang_or_skip() -> str:
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    return clang


def build(clang: str, *args: str) -> None:
    """``clang args``: a skip with clang's reason when it cannot link libFuzzer here, else it must succeed."""
    proc = subprocess.run([clang, *args], capture_output=True, text=True)
    if proc.returncode != 0 and "fuzzer" in proc.stderr:
        pytest.skip(f"clang cannot link libFuzzer here: {proc.stderr[-300:]}")
    assert proc.returncode == 0, proc.stderr


def budget(default: int, variable: str = "SARINS_FUZZ_SECONDS") -> int:
    """Seconds of fuzzing: ``variable`` if set (.ci/run gives 60), else ``default``."""
    return int(os.environ.get(variable, str(default)))


def rss_limit(headroom_mb: int = 2048) -> str:
    """libFuzzer's ``-rss_limit_mb`` for a harness started from this process.

    libFuzzer reads its RSS as the peak RSS of getrusage, and Linux keeps that peak across fork and exec: a
    fuzzer started from a pytest worker that once held 2 GB starts "at" 2 GB and, with libFuzzer's 2048 MB
    default, reports out-of-memory on its first inputs.  The limit is therefore this process's peak plus
    ``headroom_mb`` for the harness itself."""
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024  # Linux: KiB
    return f"-rss_limit_mb={peak_mb + headroom_mb}"


def run(exe: Path, corpus: Path, seconds: int, *flags: str, env: dict | None = None,
        headroom_mb: int = 2048) -> str:
    """``exe -max_total_time=seconds flags corpus`` in the corpus's parent folder (crash files land there);
    asserts exit 0 and returns libFuzzer's ``stat::number_of_executed_units`` line."""
    proc = subprocess.run([str(exe), f"-max_total_time={seconds}", "-print_final_stats=1", rss_limit(headroom_mb),
                           *flags, str(corpus)],
                          capture_output=True, text=True, env=env, timeout=seconds + 900, cwd=corpus.parent)
    assert proc.returncode == 0, proc.stderr[-3000:]
    runs = [line for line in proc.stderr.splitlines() if "stat::number_of_executed_units" in line]
    assert runs, proc.stderr[-2000:]
    return runs[0]
