"""The C core rebuilt with AddressSanitizer + UBSan and a script run against it through the binding."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from fmus.cbuild import build_line


def run(tmp_path: Path, script: str) -> None:
    """Build every core .c file with ASan + UBSan into ``tmp_path``, run ``script`` (its ``{lib}`` filled with the
    library's path) in a fresh interpreter using it, and fail on a non-zero exit, a missing "sanitized run ok" line
    or any sanitizer report."""
    root = Path(__file__).resolve().parents[1]
    core_dir = root / "sarins_fmu" / "core"
    lib = tmp_path / "_sarins_core_asan.so"
    flags = ["-std=c11", "-O1", "-g", "-fPIC", "-shared", "-Wall", "-Wextra", "-Wpedantic", "-Werror",
             "-ffp-contract=off", "-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]
    build_line(["gcc", *flags, "-I", str(core_dir), *sorted(map(str, core_dir.glob("*.c"))), "-o", str(lib)])
    libasan = subprocess.run(["gcc", "-print-file-name=libasan.so"], check=True, capture_output=True,
                             text=True).stdout.strip()
    env = {**os.environ, "SARINS_CORE_LIB": str(lib), "LD_PRELOAD": libasan, "PYTHONPATH": str(root),
           "ASAN_OPTIONS": "detect_leaks=0:abort_on_error=1", "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1"}
    done = subprocess.run([sys.executable, "-c", script.format(lib=str(lib))], env=env, capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0 and "sanitized run ok" in done.stdout, done.stderr[-4000:]
    assert "runtime error" not in done.stderr and "AddressSanitizer" not in done.stderr, done.stderr[-4000:]
