"""Shared by the FMU benchmarks: what each FMU needs so that its steps do real work, and
one fresh host process running an FMU (FMPy's ``FMU2Slave``, or the C host
``tests/native_host/host.c`` with no Python in the process).

Feeds (:func:`feeds`): parameters and constant inputs set before
initialisation, and time-tagged inputs set to ``t + offset`` before every
``doStep(t, h)``, so that every FMU computes from its first step on:

* StrapdownINS gets a static, level IMU's increments tagged
  ``increment_end_time = t + h`` (untagged increments only wait), with
  ``coarse_time`` 2 s and ``align_time`` 4 s so that its steps 1-2 run the
  coarse alignment, 3-4 the fine alignment and step 5 navigation;
* IMUThermal gets its turntable set tagged ``motion_time = t`` (a table at rest);
* RBFIdentifier fires on its first step (``trigger_time`` 0, ``nav_time = t``);
* DriftModelUpdater gets INS rows tagged ``nav_time = t`` of a parked,
  navigating vehicle (its stop filter runs every step);
* IMUCompensator gets the static increments (and carries a small RBF model,
  :func:`compensator_fmu`); IMULog plays a short simulated log
  (:func:`write_simulated_log`); Turntable and VehicleMotion need no input.

Run as a script, this file is the FMPy child: ``python fmu_runs.py FMU FEED_JSON
STEPS [STAMP_STEP ...]`` extracts the FMU to a new folder, runs it and prints
``STAMP k <unix time>`` after each listed step, ``VALUE vr value`` for the
Real outputs the feed JSON lists under ``print`` and ``ok`` at the end.  It imports
only FMPy and the standard library (as a third-party Python host would).
"""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HOST_C = ROOT / "tests" / "native_host" / "host.c"
STEP = 1.0  # s, communication step of every feed
INS_PHASES = {"coarse_time": 2.0, "align_time": 4.0}  # StrapdownINS: step 5 is its first navigation step
ALL_NAMES = ["Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier", "DriftModelUpdater", "VehicleMotion",
             "IMUCompensator", "IMULog"]
# environment variables that would point an FMU at a Python, or change its kernels
HOST_ENV_DROP = ("PYTHONPATH", "PYTHONHOME", "LD_PRELOAD", "LD_LIBRARY_PATH", "VIRTUAL_ENV")


@dataclass(frozen=True)
class Feed:
    """Inputs that make an FMU's steps do real work.

    values : name -> value set before initialisation (parameters, constant inputs).
    tags : name -> offset in s; the Real input is set to ``t + offset`` before ``doStep(t, h)``.
    """

    values: dict = field(default_factory=dict)
    tags: dict = field(default_factory=dict)


def static_increments(scale: float = STEP) -> dict:
    """Increments over ``scale`` s of a level IMU at rest facing north at the site (rad, m/s)."""
    from sarins_fmu import earth
    from sarins_fmu.site import SITE_LAT

    w = earth.earth_rate_n(SITE_LAT)
    g = earth.gravity(SITE_LAT, 0.0)
    return {"dtheta_x": 0.0, "dtheta_y": float(w[1]) * scale, "dtheta_z": float(w[2]) * scale, "dv_x": 0.0,
            "dv_y": 0.0, "dv_z": float(g) * scale}


def feeds(log_file: Path | None = None) -> dict:
    """{FMU name: Feed} for every FMU we build (IMULog only with ``log_file``)."""
    from sarins_fmu.site import SITE_LAT

    increments = static_increments()
    out = {
        "Turntable": Feed(),
        "IMUThermal": Feed(tags={"motion_time": 0.0}),
        "StrapdownINS": Feed(values={**increments, **INS_PHASES}, tags={"increment_end_time": STEP}),
        "RBFIdentifier": Feed(values={"trigger_time": 0.0}, tags={"nav_time": 0.0}),
        "DriftModelUpdater": Feed(values={"lat": SITE_LAT}, tags={"nav_time": 0.0}),
        "VehicleMotion": Feed(),
        "IMUCompensator": Feed(values={f"raw_{k}": v for k, v in increments.items()}),
    }
    if log_file is not None:
        out["IMULog"] = Feed(values={"log_file": str(log_file)})
    return out


def write_simulated_log(folder: Path, seconds: float = 960.0) -> Path:
    """A short IMU log (``seconds`` of a nav-rlg IMU on the turntable, 1 s increments) in ``folder``."""
    import numpy as np

    from sarins_fmu.experiments.static_run import run_static
    from sarins_fmu.imu_log import write_log
    from sarins_fmu.site import SITE_LAT_DEG

    chunks = []
    run_static(align_hours=(seconds - 60.0) / 3600.0, nav_hours=60.0 / 3600.0, step=STEP, seed=0,
               on_increments=lambda *chunk: chunks.append(chunk))
    cols = [np.concatenate([c[j] for c in chunks]) for j in range(4)]
    return write_log(Path(folder) / "imu_log.npz", *cols[:3], temps=cols[3], lat_deg=SITE_LAT_DEG)


def compensator_fmu(folder: Path) -> Path:
    """IMUCompensator carrying a small RBF compensator fitted on a synthetic series
    (the FMU needs a trained model; its size, not its accuracy, matters here)."""
    import numpy as np

    from fmus.compensator_export import export_compensator
    from sarins_fmu.identify import compensators

    rng = np.random.default_rng(0)
    t = np.arange(2000) * 0.1
    truth = np.column_stack([0.1 * np.sin(0.05 * t), 0.1 * np.cos(0.03 * t), 0.1 * np.sin(0.02 * t),
                             np.sin(0.01 * t), np.cos(0.013 * t), 9.8 + 0.1 * np.sin(0.02 * t)])
    temp = 10.0 + 20.0 * np.sin(0.002 * t)
    meas = truth * 1.001 + 1e-4 + 1e-5 * rng.standard_normal(truth.shape)
    model = compensators.make("rbf", max_samples=500).fit(np.column_stack([meas, temp]), truth)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return export_compensator(model.save(folder / "compensator_model.npz"), folder)


def build_all(folder: Path, names=ALL_NAMES) -> tuple[dict, dict]:
    """Build the named FMUs into ``folder``: ({name: .fmu path}, {name: Feed})."""
    from fmus.build import build_fmus

    folder = Path(folder)
    plain = [n for n in names if n != "IMUCompensator"]
    paths = {p.stem: p for p in build_fmus(folder, plain)}
    if "IMUCompensator" in names:
        paths["IMUCompensator"] = compensator_fmu(folder / "compensator")
    log = write_simulated_log(folder) if "IMULog" in names else None
    return paths, feeds(log)


def build_c_host(out: Path) -> Path:
    """Compile tests/native_host/host.c with the system compiler (FMPy's FMI headers)."""
    import fmpy

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise RuntimeError("no C compiler (gcc/cc) to build the native host")
    subprocess.run([cc, "-O2", "-o", str(out), str(HOST_C), f"-I{Path(fmpy.__file__).parent / 'c-code'}", "-ldl"],
                   check=True)
    return out


def host_env(base: dict, **extra) -> dict:
    """``base`` without anything that points an FMU at a Python or disables numba, plus ``extra``."""
    env = {k: v for k, v in base.items() if k not in HOST_ENV_DROP}
    env.update(extra)
    return env


def fmpy_command(fmu: Path, feed: Feed, steps: int, stamps=(1,), printed=()) -> list[str]:
    """argv of a fresh FMPy host process running ``fmu`` (this file as the child); ``printed``:
    Real variables whose values it prints after the last step."""
    spec = json.dumps({"values": feed.values, "tags": feed.tags, "print": list(printed)})
    return [sys.executable, str(Path(__file__).resolve()), str(fmu), spec, str(steps), *map(str, stamps)]


def c_host_command(host: Path, folder: Path, fmu: Path, feed: Feed, steps: int, stamps=(1,),
                   printed=()) -> list[str]:
    """argv of the C host running the FMU unzipped in ``folder`` (``printed`` as for :func:`fmpy_command`)."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    var = {v.name: v for v in md.modelVariables}
    ops = []
    for name, value in feed.values.items():
        kind = {"Real": "r", "Integer": "i", "String": "s"}[var[name].type]
        ops.append(f"{kind}{var[name].valueReference}={value!r}" if kind == "r"
                   else f"{kind}{var[name].valueReference}={value}")
    ops += [f"tag{var[name].valueReference}={offset!r}" for name, offset in feed.tags.items()]
    ops += [f"time-at={k}" for k in stamps]
    ops += [f"final-real={var[name].valueReference}" for name in printed]
    return [str(host), str(folder), md.coSimulation.modelIdentifier, md.guid, str(steps), repr(STEP), *ops]


def system_plan_lines(system, unzip_root: Path, fmu_of=lambda comp: Path(comp.source)):
    """The ``fmu``, start-value and ``link`` lines of the C master's plan (tests/native_host/system.c) for
    ``system``, each FMU unzipped once under ``unzip_root``; ``fmu_of(component)`` is its FMU file.
    Returns (lines, {component: index}, {component: {variable name: model variable}})."""
    from fmpy import read_model_description

    lines, index, variables = [], {}, {}
    for k, comp in enumerate(system.components):
        fmu = fmu_of(comp)
        folder = unzip_root / comp.name
        if not folder.exists():
            with zipfile.ZipFile(fmu) as z:
                z.extractall(folder)
        md = read_model_description(str(fmu))
        index[comp.name], variables[comp.name] = k, {v.name: v for v in md.modelVariables}
        lines.append(f"fmu {folder} {md.coSimulation.modelIdentifier} {md.guid}")
        for name, value in comp.parameters.items():
            var = variables[comp.name][name]
            kind = {"Real": "real", "Integer": "int", "String": "string"}[var.type]
            lines.append(f"{kind} {k} {var.valueReference} {value!r}" if kind == "real"
                         else f"{kind} {k} {var.valueReference} {value}")
    for c in system.connections:
        lines.append(f"link {index[c.start_component]} {variables[c.start_component][c.start_variable].valueReference}"
                     f" {index[c.end_component]} {variables[c.end_component][c.end_variable].valueReference}")
    return lines, index, variables


def unzip(fmu: Path, folder: Path) -> Path:
    """Extract ``fmu`` into ``folder`` (a native tool's fresh unpack)."""
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def run_host(argv: list[str], env: dict, t0: float, timeout: float = 900.0) -> tuple[dict, dict]:
    """Run ``argv``: ({step k: seconds from ``t0`` (unix time) to the end of doStep k},
    {value reference: printed value}).

    Raises RuntimeError when the process fails or a call does not return OK."""
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=timeout)
    out = proc.stdout
    if proc.returncode != 0 or "STATUS" in out or not ("ok" in out.split() or "DONE" in out):
        raise RuntimeError(f"{argv[1]}: exit {proc.returncode}\n{out[-1500:]}\n{proc.stderr[-1500:]}")
    stamps, values = {}, {}
    for line in out.splitlines():
        if line.startswith("STAMP "):
            _, k, when = line.split()
            stamps[int(k)] = float(when) - t0
        elif line.startswith("VALUE "):
            _, vr, value = line.split()
            values[int(vr)] = float(value)
    return stamps, values


def _child(argv: list[str]) -> None:
    """The FMPy host process: extract, instantiate, feed, step, free; print stamps."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    path, spec, steps, stamp_at = argv[0], json.loads(argv[1]), int(argv[2]), {int(k) for k in argv[3:]}
    md = read_model_description(path)
    folder = extract(path)  # a new folder, as FMPy does on every run
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="x")
    fmu.instantiate()
    var = {v.name: v for v in md.modelVariables}
    for name, value in spec["values"].items():
        setter = {"Real": fmu.setReal, "Integer": fmu.setInteger, "String": fmu.setString}[var[name].type]
        setter([var[name].valueReference], [value])
    tag_vrs = [var[name].valueReference for name in spec["tags"]]
    offsets = list(spec["tags"].values())
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    for k in range(steps):
        t = k * STEP
        if tag_vrs:
            fmu.setReal(tag_vrs, [t + off for off in offsets])
        fmu.doStep(t, STEP)  # raises on a status other than OK
        if k + 1 in stamp_at:
            print(f"STAMP {k + 1} {time.time():.6f}", flush=True)
    printed = [var[name].valueReference for name in spec["print"]]
    for vr, value in zip(printed, fmu.getReal(printed) if printed else []):
        print(f"VALUE {vr} {value!r}")
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(folder, ignore_errors=True)
    print("ok")


if __name__ == "__main__":
    _child(sys.argv[1:])
