"""tests/libfuzzer.py itself: a harness started from a process that once held more than libFuzzer's default
2048 MB RSS limit still runs (Linux keeps the peak RSS across fork and exec, and libFuzzer reads the peak)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import libfuzzer
import pytest

HARNESS = """
#include <stddef.h>
#include <stdint.h>
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return size > 1 && data[0] == 0x7f ? 1 : 0; }
"""


@pytest.mark.slow
def test_a_harness_started_from_a_big_process_is_not_out_of_memory(tmp_path):
    clang = libfuzzer.clang_or_skip()
    (tmp_path / "h.c").write_text(HARNESS)
    exe = tmp_path / "fuzz"
    libfuzzer.build(clang, "-fsanitize=fuzzer,address", str(tmp_path / "h.c"), "-o", str(exe))
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    tests = Path(__file__).resolve().parent
    script = textwrap.dedent(f"""
        import subprocess, sys
        sys.path.insert(0, {str(tests)!r})
        import libfuzzer
        ballast = bytearray(2300 << 20)  # 2.3 GB touched: the peak RSS a child inherits
        for i in range(0, len(ballast), 4096):
            ballast[i] = 1
        del ballast
        plain = subprocess.run([{str(exe)!r}, "-max_total_time=3", {str(corpus)!r}], capture_output=True, text=True,
                               cwd={str(tmp_path)!r})
        print("plain", plain.returncode)
        print(libfuzzer.run(__import__("pathlib").Path({str(exe)!r}), __import__("pathlib").Path({str(corpus)!r}), 2))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-3000:]
    # without the limit the same harness is refused as out-of-memory: the test would catch a runner without it
    assert "plain 0" not in out.stdout, out.stdout
    assert "stat::number_of_executed_units" in out.stdout
