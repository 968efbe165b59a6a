"""The core's worker threads (sarins_fmu/core/workers.h) under ThreadSanitizer and ASan + UBSan, and the
IMUThermal FMU that uses them under ASan + UBSan.

A C driver splits ranges of every length from 0 to 300 over 1 to 5 threads, thousands of runs on one set,
sets started and stopped in a loop: every item written once with its own value, chunks contiguous (each
chunk's first item follows the previous chunk's last), no report from the sanitizers.  Then the FMI 3.0
IMUThermal built from its sources with ASan + UBSan steps a turning table with 3 threads (sub_inputs = 1)
and gives the plain build's numbers.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from fmus.cbuild import build_line

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "sarins_fmu" / "core"
FLAGS = ["-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fno-omit-frame-pointer"]

DRIVER = r"""
#include "smath.h"
#include <stdio.h>
#include <stdlib.h>
#include "workers.h"

typedef struct { int64_t *out; int64_t *first; int64_t *count; int run; } job;

/* each item gets run * 1000 + k; the chunk's first item and size are noted by its first item */
static void fill(void *arg, int64_t k0, int64_t k1)
{
    job *j = arg;
    for (int64_t k = k0; k < k1; k++)
        j->out[k] = (int64_t)j->run * 1000 + k;
    j->first[k0] = k0;
    j->count[k0] = k1 - k0;
}

int main(void)
{
    int64_t out[300], first[300], count[300];
    for (int cycle = 0; cycle < 20; cycle++) {
        for (int threads = 1; threads <= 5; threads++) {
            int started = 0;
            sarins_workers *w = sarins_workers_start(threads, &started);
            if (w == NULL || started != threads) {
                printf("start %d: %d started\n", threads, started);
                return 1;
            }
            for (int run = 0; run < 300; run++) {
                int64_t n = run % 300;
                for (int64_t k = 0; k < 300; k++)
                    out[k] = first[k] = count[k] = -1;
                job j = {out, first, count, run};
                sarins_workers_run(w, fill, &j, n);
                int64_t next = 0;
                for (int64_t k = 0; k < n; k++) {
                    if (out[k] != (int64_t)run * 1000 + k) {
                        printf("item %lld of %lld wrong\n", (long long)k, (long long)n);
                        return 1;
                    }
                    if (first[k] == k) { /* a chunk starts here: right after the previous one */
                        if (k != next) return 1;
                        next = k + count[k];
                    }
                }
                if (next != n || (n < 300 && out[n] != -1)) { /* nothing beyond the range */
                    printf("chunks of %lld end at %lld\n", (long long)n, (long long)next);
                    return 1;
                }
            }
            sarins_workers_stop(w);
        }
    }
    if (sarins_workers_start(0, NULL) != NULL || sarins_workers_start(SARINS_WORKERS_MAX + 1, NULL) != NULL)
        return 1;
    sarins_workers_stop(NULL);
    job none = {out, first, count, 7};
    sarins_workers_run(NULL, fill, &none, 3); /* no set: the caller's thread */
    if (out[2] != 7002) return 1;
    printf("workers ok\n");
    return 0;
}
"""


def _driver(tmp_path: Path, sanitize: str) -> subprocess.CompletedProcess:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    src = tmp_path / "driver.c"
    src.write_text(DRIVER)
    exe = tmp_path / f"driver_{sanitize.replace(',', '_')}"
    build_line([cc, *FLAGS, f"-fsanitize={sanitize}", "-fno-sanitize-recover=all", f"-I{CORE}", str(src),
                str(CORE / "workers.c"), "-o", str(exe), "-lpthread"])  # (smath.c's ifunc resolvers run before TSan is up)
    return subprocess.run([str(exe)], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "TSAN_OPTIONS": "halt_on_error=1"})


def _sanitizer_runs(tmp_path: Path, sanitize: str) -> None:
    """Skip with the reason when this system cannot run a program built with the sanitizer at all (e.g.
    ThreadSanitizer on a kernel whose address-space randomisation it does not support)."""
    cc = shutil.which("gcc") or shutil.which("cc")
    src = tmp_path / "hello.c"
    src.write_text("#include <stdio.h>\nint main(void) { puts(\"hello\"); return 0; }\n")
    exe = tmp_path / "hello"
    built = subprocess.run([cc, f"-fsanitize={sanitize}", str(src), "-o", str(exe)], capture_output=True, text=True)
    if built.returncode != 0:
        pytest.skip(f"{cc} cannot build with -fsanitize={sanitize}: {built.stderr.strip()[-300:]}")
    ran = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    if ran.returncode != 0 or ran.stdout.strip() != "hello":
        pytest.skip(f"a -fsanitize={sanitize} program does not run here: {ran.stderr.strip()[-300:]}")


@pytest.mark.parametrize("sanitize", ["thread", "address,undefined"])
def test_ranges_split_over_threads_with_no_sanitizer_report(tmp_path, sanitize):
    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler (gcc/cc)")
    _sanitizer_runs(tmp_path, sanitize)
    done = _driver(tmp_path, sanitize)
    assert done.returncode == 0 and "workers ok" in done.stdout, done.stdout + done.stderr[-3000:]
    assert "WARNING: ThreadSanitizer" not in done.stderr and "runtime error" not in done.stderr, done.stderr[-3000:]


IMU_RUN = textwrap.dedent("""
    import sys
    sys.path[:0] = [{tests!r}]
    import numpy as np
    import test_native_imu_given_motion as t
    rows, ends = t.run_given({fmu!r}, threads=3, gauss_seidel=True)
    np.save({out!r}, np.array(rows))
    print("sanitized run ok")
    """)


@pytest.mark.integration
def test_the_imu_fmu_with_threads_under_address_and_undefined_sanitizers(tmp_path, fmu3_dir):
    """The FMI 3.0 IMUThermal rebuilt from its own sources with ASan + UBSan, its binary swapped into the FMU,
    stepped with 3 threads through FMPy: no report, and the plain build's numbers."""
    import zipfile

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    plain = fmu3_dir / "IMUThermal.fmu"
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(plain) as z:
        z.extractall(unpacked)
    sources = unpacked / "sources"
    binary = unpacked / "binaries" / "x86_64-linux" / "IMUThermal.so"
    build_line([cc, *FLAGS, "-fPIC", "-shared", "-fvisibility=hidden", "-fsanitize=address,undefined",
                "-fno-sanitize-recover=all", f"-I{sources}", *sorted(map(str, sources.glob("*.c"))), "-o",
                str(binary)])
    sanitized = tmp_path / "IMUThermal.fmu"
    with zipfile.ZipFile(sanitized, "w") as z:
        for path in sorted(unpacked.rglob("*")):
            if path.is_file():
                z.write(path, path.relative_to(unpacked).as_posix())
    libasan = subprocess.run([cc, "-print-file-name=libasan.so"], check=True, capture_output=True,
                             text=True).stdout.strip()
    env = {**os.environ, "LD_PRELOAD": libasan, "PYTHONPATH": str(ROOT),
           "ASAN_OPTIONS": "detect_leaks=0:abort_on_error=1", "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1"}
    results = {}
    for kind, fmu in (("sanitized", sanitized), ("plain", plain)):
        out = tmp_path / f"{kind}.npy"
        done = subprocess.run([sys.executable, "-c", IMU_RUN.format(tests=str(ROOT / "tests"), fmu=str(fmu),
                                                                   out=str(out))],
                              env=env if kind == "sanitized" else None, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0 and "sanitized run ok" in done.stdout, done.stderr[-4000:]
        assert "runtime error" not in done.stderr and "AddressSanitizer" not in done.stderr, done.stderr[-4000:]
        results[kind] = out.read_bytes()
    assert results["sanitized"] == results["plain"]
