"""Our system container vs FMPy's: the identified static system's default run, as one FMU each.

Packs ``IdentifiedStaticSystem`` (sarins/systems ``standard_static_identified`` at its defaults: 4 h
alignment, 84 h of navigation, 1 s step) with :func:`orchestration.container.build_container_fmu` twice,
``engine=write_container_fmu`` (ours) and ``engine="fmpy"`` (FMPy 0.3.32's container binary, the baseline), runs
each through the project's C host (tests/native_host/native_fmu_host.c, logging off) under ``env -i``
for the DefaultExperiment and prints the wall times, their ratio and whether the final outputs are
bit-identical.  Both runs take the same component FMUs (``--fmu-dir``, else built here).

    PYTHONPATH=$PWD python3 benchmarks/bench_container.py [--fmu-dir DIR] [--stop SECONDS]
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fmpy import read_model_description  # noqa: E402

from fmus.native_fmu import fmi_headers_dir  # noqa: E402

COMPONENTS = ("Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier")
OUTPUTS = ["ins.lat_error", "ins.position_error", "ins.nav_time", "identifier.axial_drift"]


def run(host: Path, fmu: Path, work: Path, stop: float | None) -> tuple[float, list[str], int]:
    """(wall time s, the last OUT line's values, steps) of one container FMU's run."""
    md = read_model_description(str(fmu))
    folder = work / fmu.stem
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    identifier = md.coSimulation.modelIdentifier
    step = float(md.defaultExperiment.stepSize)
    steps = int(round((stop or float(md.defaultExperiment.stopTime)) / step))
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    binary = folder / "binaries" / "linux64" / f"{identifier}.so"
    cmd = ["env", "-i", str(host), str(binary), md.guid, str(steps), repr(step),
           f"res=file://{(folder / 'resources').resolve().as_posix()}", "out=" + ",".join(str(vrs[n]) for n in OUTPUTS)]
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    if "STATUS" in proc.stdout:
        raise RuntimeError(f"{fmu.name}: {proc.stdout[-2000:]}")
    last = [line for line in proc.stdout.splitlines() if line.startswith("OUT ")][-1]
    return wall, last.split()[2:], steps


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu-dir", type=Path, help="folder with the component FMUs (default: build them)")
    ap.add_argument("--stop", type=float, help="stop time, s (default: the DefaultExperiment's)")
    args = ap.parse_args(argv)
    from fmus.system_container import write_container_fmu
    from orchestration.container import build_container_fmu
    from sarins.systems import SYSTEM_FMUS, SYSTEMS

    with tempfile.TemporaryDirectory(prefix="bench_container_") as tmp:
        work = Path(tmp)
        if args.fmu_dir is None:
            from fmus.build import build_fmus

            build_fmus(work, list(COMPONENTS), cross=False)
        else:
            for name in COMPONENTS:
                shutil.copy2(args.fmu_dir / f"{name}.fmu", work / f"{name}.fmu")
        host = work / "host"
        subprocess.run(["gcc", "-std=c11", "-O2", f"-I{fmi_headers_dir()}",
                        str(ROOT / "tests" / "native_host" / "native_fmu_host.c"), "-ldl", "-o", str(host)], check=True)
        system = SYSTEMS[SYSTEM_FMUS["IdentifiedStaticSystem"]](work)
        results = {}
        for engine in ("fmpy", "sarins"):
            fmu = build_container_fmu(system, work / f"Identified_{engine}.fmu", step_size=1.0,
                                      engine=write_container_fmu if engine == "sarins" else engine)
            results[engine] = run(host, fmu, work, args.stop)
        (t_fmpy, v_fmpy, steps), (t_ours, v_ours, _) = results["fmpy"], results["sarins"]
        print(f"IdentifiedStaticSystem, {steps} steps of 1 s, C host under env -i")
        print(f"  FMPy's container (baseline): {t_fmpy:.2f} s")
        print(f"  our container:               {t_ours:.2f} s  (ratio {t_ours / t_fmpy:.3f})")
        print(f"  final outputs ({', '.join(OUTPUTS)}) bit-identical: {v_ours == v_fmpy}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
