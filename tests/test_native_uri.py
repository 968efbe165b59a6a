"""The native FMUs' one fmuResourceLocation parser (fmus/c/sarins_uri.h): compiled here into a tiny driver
with the system compiler and fed a table of URIs (and, compiled as for Windows, the drive-letter cases)."""

from __future__ import annotations

import subprocess

import pytest

from fmus.native_fmu import C_DIR

OK, NULL, SCHEME, HOST, ESCAPE, TOO_LONG, EMPTY = range(7)
WARNINGS = ("-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror")


def _cc():
    from test_native_fmus import _cc as cc

    return cc()

DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sarins_uri.h"

/* driver BUFLEN URI (or -null): prints the code, a tab, the path */
int main(int argc, char **argv) {
    if (argc != 3) return 2;
    size_t len = (size_t)strtoul(argv[1], NULL, 10);
    char *out = malloc(len ? len : 1);
    if (!out) return 3;
    int code = sarins_uri_to_path(strcmp(argv[2], "-null") == 0 ? NULL : argv[2], out, len);
    printf("%d\t%s\n", code, len ? out : "");
    free(out);
    return 0;
}
"""

LONG = "/" + "a" * 30
CASES = [  # (uri, buffer length, code, path)
    ("file:///tmp/fmu/resources", 4096, OK, "/tmp/fmu/resources"),
    ("file://localhost/tmp/fmu/resources", 4096, OK, "/tmp/fmu/resources"),
    ("file://LocalHost/tmp/x", 4096, OK, "/tmp/x"),
    ("file:/tmp/x", 4096, OK, "/tmp/x"),
    ("FILE:///tmp/x", 4096, OK, "/tmp/x"),
    ("file:///tmp/a%20b/%41%62", 4096, OK, "/tmp/a b/Ab"),
    ("file:///tmp/%e4%b8%ad", 4096, OK, "/tmp/\u4e2d"),
    ("file:///tmp/x///", 4096, OK, "/tmp/x"),
    ("file:///", 4096, OK, "/"),
    ("file:///tmp/%2", 4096, ESCAPE, ""),
    ("file:///tmp/%", 4096, ESCAPE, ""),
    ("file:///tmp/%zz", 4096, ESCAPE, ""),
    ("file:///tmp/%g1", 4096, ESCAPE, ""),
    ("file:///tmp/%1g", 4096, ESCAPE, ""),
    ("file:///tmp/%00x", 4096, ESCAPE, ""),
    ("http://x/tmp/r", 4096, SCHEME, ""),
    ("http://x", 4096, SCHEME, ""),
    ("ftp:///tmp/r", 4096, SCHEME, ""),
    ("/tmp/plain/path", 4096, SCHEME, ""),
    ("file:relative/path", 4096, SCHEME, ""),
    ("", 4096, SCHEME, ""),
    ("file:", 4096, EMPTY, ""),
    ("file://", 4096, EMPTY, ""),
    ("file://otherhost/p", 4096, HOST, ""),
    ("file://localhostx/p", 4096, HOST, ""),
    ("file://local/p", 4096, HOST, ""),
    ("file://user@localhost/p", 4096, HOST, ""),
    ("-null", 4096, NULL, ""),
    ("file://" + LONG, len(LONG), TOO_LONG, ""),  # one byte short (the NUL)
    ("file://" + LONG, len(LONG) + 1, OK, LONG),  # fits exactly
    ("file:///" + "%41" * 20, 22, OK, "/" + "A" * 20),  # long when encoded, fits decoded
    ("file:///" + "%41" * 20, 21, TOO_LONG, ""),
    ("file:///x", 0, TOO_LONG, ""),
]


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    folder = tmp_path_factory.mktemp("uri")
    (folder / "driver.c").write_text(DRIVER)
    exe = folder / "driver"
    cmd = [_cc(), *WARNINGS, "-O1", f"-I{C_DIR}", "-o", str(exe), str(folder / "driver.c")]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return exe


def test_uri_table(driver):
    wrong = []
    for uri, length, code, path in CASES:
        proc = subprocess.run([str(driver), str(length), uri], capture_output=True, text=True, timeout=60)
        got_code, got_path = proc.stdout.rstrip("\n").split("\t", 1)
        if (int(got_code), got_path) != (code, path):
            wrong.append(f"{uri!r} (buffer {length}): got {got_code} {got_path!r}, expected {code} {path!r}")
    assert not wrong, "\n".join(wrong)


GLUE_HEADER_DIR = C_DIR  # fmus/c/sarins_uri.h
DRIVE_CASES = [  # (uri, path on Windows)
    ("file:///Z:/tmp/fmu/resources", "Z:/tmp/fmu/resources"),
    ("file:///c:/x%20y/", "c:/x y"),
    ("file://localhost/D:/r", "D:/r"),
    ("file:///C:", "C:"),
    ("file:///tmp/x", "/tmp/x"),  # no drive letter: unchanged
    ("file:///1:/x", "/1:/x"),
    ("file:///ZZ:/x", "/ZZ:/x"),
]


def _run_drive_cases(run):
    wrong = []
    for uri, path in DRIVE_CASES:
        got = run(uri)
        if got != f"0\t{path}":
            wrong.append(f"{uri!r}: got {got!r}, expected {path!r}")
    assert not wrong, "\n".join(wrong)


def test_glue_parser_drops_the_slash_before_a_windows_drive_letter(tmp_path):
    """Compiled as for Windows (_WIN32): file:///Z:/p is the path Z:/p, which Windows opens (/Z:/p it cannot)."""
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    cmd = [_cc(), *WARNINGS, "-D_WIN32", "-O1", f"-I{GLUE_HEADER_DIR}", "-o", str(exe),
           str(tmp_path / "driver.c")]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    _run_drive_cases(lambda uri: subprocess.run([str(exe), "4096", uri], capture_output=True, text=True,
                                                timeout=60).stdout.rstrip("\n"))


@pytest.mark.slow
def test_glue_parser_under_wine_opens_windows_paths(wine_env, tmp_path):
    """The same cases from a mingw-w64 build run under wine."""
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver.exe"
    proc = subprocess.run(["x86_64-w64-mingw32-gcc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-O1",
                           f"-I{GLUE_HEADER_DIR}", "-o", str(exe), str(tmp_path / "driver.c")],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    _run_drive_cases(lambda uri: subprocess.run(["wine", str(exe), "4096", uri], capture_output=True, text=True,
                                                env=wine_env, timeout=120).stdout.replace("\r", "").rstrip("\n"))
