"""The core's load_slave against a malformed variable table from the bridge (issue 21): a value
reference given to two variables (it leaked the first name and ran), a value reference that is not an
integer, a row that is not a tuple. Each is refused by fmi2Instantiate (NULL, the reason logged); a
well-formed FMU in the same process still runs. In a fresh process: a crash fails the test, not the run."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

PATCH = """

def _sarins_test_reset(self, _reset=Instance.reset):
    _reset(self)
    mode = {mode!r}
    if mode == "duplicate":
        self.table = self.table + [(self.table[0][0], 0, 2, 4, "twin")]
    elif mode == "not-int":
        self.table = [("x", 0, 2, 4, "bad")] + self.table + [("y", 0, 2, 4, "bad2")]
    elif mode == "not-tuple":
        self.table = [["a"]] + self.table


Instance.reset = _sarins_test_reset
"""

SCRIPT = """
import shutil, sys
from pathlib import Path
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
sys.path[0:0] = [{tests!r}, {root!r}]
from orchestration import fmilog
log = []
name = fmilog.register("table", lambda status, category, text: log.append((status, text)))
path = {fmu!r}
md = read_model_description(path)
for mode in ("duplicate", "not-int", "not-tuple", "none"):
    folder = extract(path)
    if mode != "none":
        bridge = Path(folder, "resources", "_fmi_bridge.py")
        bridge.write_text(bridge.read_text() + {patch!r}.format(mode=mode))
    f = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName=name)
    del log[:]
    try:
        f.instantiate(loggingOn=False, callbacks=fmilog.callbacks())
        f.setString([next(v.valueReference for v in md.modelVariables if v.name == "log_file")], [{log!r}])
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.exitInitializationMode()
        f.doStep(0.0, 1.0)
        f.freeInstance()
        print(mode, "| INSTANCE | ")
    except Exception:
        print(mode, "| REFUSED |", " / ".join(t for s, t in log if s >= 3))
"""


def test_malformed_variable_tables_are_refused(bridge_fmu, tmp_path):
    from test_fmi_contract import _tiny_log

    tests = os.path.dirname(__file__)
    script = textwrap.dedent(SCRIPT).format(tests=tests, root=os.path.dirname(tests), patch=PATCH,
                                            fmu=str(bridge_fmu), log=str(_tiny_log(tmp_path)))
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr[-2000:]
    rows = {line.split(" | ")[0]: line.split(" | ")[1:] for line in proc.stdout.splitlines() if " | " in line}
    assert rows["none"][0] == "INSTANCE", rows
    assert rows["duplicate"][0] == "REFUSED" and "given to both" in rows["duplicate"][1], rows
    assert rows["not-int"][0] == "REFUSED" and "integer" in rows["not-int"][1], rows
    assert rows["not-tuple"][0] == "REFUSED" and "5-tuple" in rows["not-tuple"][1], rows
