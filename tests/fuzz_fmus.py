"""What the FMU fuzzing harnesses (tests/fuzz/fuzz_fmu_state.c, tests/fuzz/fuzz_fmi_calls.c) need of a native
model: its FMU's unzipped ``sources/`` and the environment naming the files it runs on (SARINS_FUZZ_RESOURCES:
the unzipped resources folder; SARINS_FUZZ_PARAMS: "name=value" lines set before initialisation), all in the
test's temporary folder.  Every native model runs on what this gives it."""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

from fmus import SLAVES
from fmus.native_fmu import NATIVE, build_native_fmu

MODELS = list(NATIVE)  # every native model
BASE_ENV = {"PATH": os.environ.get("PATH", ""), "ASAN_OPTIONS": "detect_leaks=1"}


def _resources(name: str) -> dict[str, bytes] | None:
    """Files the FMU carries that the plain build does not: IMUCompensator's trained model (a small GRU with
    random weights, tests/test_nets.py)."""
    if name != "IMUCompensator":
        return None
    from fmus.imu_compensator_slave import MODEL_IN_RESOURCES
    from test_nets import fitted

    return {MODEL_IN_RESOURCES: fitted("gru").binary()}


def _params(name: str, tmp: Path) -> str:
    """SARINS_FUZZ_PARAMS for a model that reads a file a parameter names: IMULog a 1 s log of 40 samples."""
    if name != "IMULog":
        return ""
    from file_faults import good_log

    return f"log_file={good_log(tmp / 'imu.csv', samples=40, step=1.0)}"


def prepare(name: str, fmi: int, tmp: Path) -> tuple[Path, dict[str, str]]:
    """Build ``name`` for FMI ``fmi``.0 (linux64 only) into ``tmp``; its sources/ folder and the environment
    for the harness."""
    fmu = build_native_fmu(name, SLAVES[name], tmp / "fmu", fmi=fmi, win64=False, aarch64=False,
                           resources=_resources(name))
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tmp / "unzipped")
    env = dict(BASE_ENV)
    res = tmp / "unzipped" / "resources"
    if res.is_dir():
        env["SARINS_FUZZ_RESOURCES"] = str(res.resolve())
    params = _params(name, tmp)
    if params:
        env["SARINS_FUZZ_PARAMS"] = params
    return tmp / "unzipped" / "sources", env
