"""The native layer's one fmuResourceLocation parser (fmus/native/sarins_uri.h), used by the shim and the
core (issue 21): compiled here into a tiny driver with the system compiler and fed a table of URIs;
then the same refusals through a real FMU's fmi2Instantiate, first in the shim (core not loaded yet),
then in the core."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

from fmus import native

OK, NULL, SCHEME, HOST, ESCAPE, TOO_LONG, EMPTY = range(7)

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
    cmd = [native.compiler(), *native.WARNINGS, "-O1", f"-I{native.HERE}", "-o", str(exe), str(folder / "driver.c")]
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


def test_the_layer_compiles_both_objects_from_the_one_parser():
    for name in ("shim.c", "core.c"):
        text = (native.HERE / name).read_text()
        assert '#include "sarins_uri.h"' in text and "sarins_uri_to_path(" in text, name
        assert "strtol(" not in text and "hexval(" not in text, name  # no second decoder left behind


SCRIPT = """
import ctypes, sys
from pathlib import Path
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
sys.path[0:0] = [{tests!r}, {root!r}]
from orchestration import fmilog
log = []
name = fmilog.register("uri", lambda status, category, text: log.append((status, text)))
path = {fmu!r}
md = read_model_description(path)
folder = extract(path)
f = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName=name)
good = Path(folder, "resources").as_uri()
for uri in ["file://otherhost" + good[7:], good[:-4] + "%zzes", "http://example.com/resources", good]:
    del log[:]
    c = f.fmi2Instantiate(name.encode(), 1, md.guid.encode(), uri.encode(), ctypes.byref(fmilog.callbacks()),
                          0, 0)
    print("NULL" if not c else "INSTANCE", "|", " / ".join(t for s, t in log if s >= 3))
    if c:
        f.fmi2FreeInstance(c)
"""


def test_bad_resource_locations_are_refused_by_shim_and_core(bridge_fmu):
    """The first call goes through the shim (no core yet), the last three bad ones through the core."""
    tests = os.path.dirname(__file__)
    script = textwrap.dedent(SCRIPT).format(tests=tests, root=os.path.dirname(tests),
                                            fmu=str(bridge_fmu))  # Python-hosted
    script += "\nfor uri in ['file://otherhost' + good[7:], good[:-4] + '%zzes', 'http://x/r']:\n" \
              "    del log[:]\n" \
              "    c = f.fmi2Instantiate(name.encode(), 1, md.guid.encode(), uri.encode(), " \
              "ctypes.byref(fmilog.callbacks()), 0, 0)\n" \
              "    print('NULL' if not c else 'INSTANCE', '|', ' / '.join(t for s, t in log if s >= 3))\n"
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = [line for line in proc.stdout.splitlines() if "|" in line]
    assert len(lines) == 7, proc.stdout
    expected = ["another host", "bad percent escape", "not a file: URI", None, "another host", "bad percent escape",
                "not a file: URI"]
    for line, text in zip(lines, expected):
        if text is None:
            assert line.startswith("INSTANCE"), line
        else:
            assert line.startswith("NULL") and text in line, line
