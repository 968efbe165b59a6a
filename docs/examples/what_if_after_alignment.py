"""A what-if branch after the alignment, with the native FMUs' FMU state, through FMPy.

Turntable -> IMUThermal -> StrapdownINS stepped Gauss-Seidel at 1 s by a plain FMPy loop (no project
code in the loop: any FMI 2.0 host does the same).  After the alignment the three FMUs' states are taken
once; navigation then runs twice from that point: branch A as it is, branch B with an azimuth drift
correction set on the INS's input.  Setting the states back replays branch A bit for bit, so the two
branches differ only by the correction, and the alignment is computed once.

    python docs/examples/what_if_after_alignment.py [--fmu-dir build/fmus] [--align 3600] [--nav 7200]
        [--correction-dph 0.002]

Units: times in s, the correction in deg/h at this edge (rad/s on the FMU), position errors in m.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

MOTION = [f"{q}_{j}" for q in ("angle", "rate", "accel") for j in (1, 2, 3)] + [
    "ambient_temp", "ambient_temp_rate", "motion_time"]
INCREMENTS = [f"dtheta_{a}" for a in "xyz"] + [f"dv_{a}" for a in "xyz"] + ["temp_gyro_z", "increment_end_time"]
DPH = math.pi / 180.0 / 3600.0  # rad/s per deg/h


class Fmu:
    """One FMU instance through FMPy's FMU2Slave, with Real access by name."""

    def __init__(self, path: Path, name: str, **params):
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        for key, value in params.items():
            if isinstance(value, str):
                self.fmu.setString([self.vr[key]], [value])
            else:
                self.fmu.setReal([self.vr[key]], [float(value)])
        self.fmu.enterInitializationMode()

    def get(self, names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def set(self, names, values):
        self.fmu.setReal([self.vr[n] for n in names], list(values))


@dataclass(frozen=True)
class Branch:
    """The end of one navigation branch: position errors (m) and the INS's last nav_time (s)."""
    north_error: float
    east_error: float
    position_error: float
    nav_time: float


@dataclass(frozen=True)
class WhatIf:
    """Branch A, its replay after setting the states back, and branch B (the correction set)."""
    branch_a: Branch
    replay_a: Branch
    branch_b: Branch
    state_bytes: int  # the three serialized states together


def _step(chain, t: float, h: float) -> None:
    table, imu, ins = chain
    table.fmu.doStep(t, h)
    imu.set(MOTION, table.get(MOTION))
    imu.fmu.doStep(t, h)
    ins.set(INCREMENTS, imu.get(INCREMENTS))
    ins.fmu.doStep(t, h)


def _navigate(chain, t0: float, seconds: int) -> Branch:
    for k in range(seconds):
        _step(chain, t0 + k, 1.0)
    ins = chain[2]
    return Branch(*ins.get(["north_error", "east_error", "position_error", "nav_time"]))


def run(fmu_dir: Path, align: int = 3600, nav: int = 7200, correction_dph: float = 0.002) -> WhatIf:
    """Align once, take the states, then branch A, replay A, branch B (see the module docstring)."""
    table = Fmu(fmu_dir / "Turntable.fmu", "table", align_time=float(align), align_dwell=align / 8.0)
    imu = Fmu(fmu_dir / "IMUThermal.fmu", "imu")
    ins = Fmu(fmu_dir / "StrapdownINS.fmu", "ins", align_time=float(align))
    chain = (table, imu, ins)
    imu.set(MOTION, table.get(MOTION))  # the turntable's initial outputs before the IMU leaves initialisation
    for fmu in chain:
        fmu.fmu.exitInitializationMode()
    for k in range(align):
        _step(chain, float(k), 1.0)
    states = [f.fmu.getFMUstate() for f in chain]
    state_bytes = sum(len(f.fmu.serializeFMUstate(s)) for f, s in zip(chain, states))
    branch_a = _navigate(chain, float(align), nav)
    for f, s in zip(chain, states):
        f.fmu.setFMUstate(s)
    replay_a = _navigate(chain, float(align), nav)
    for f, s in zip(chain, states):
        f.fmu.setFMUstate(s)
    ins.set(["axial_drift_correction"], [correction_dph * DPH])
    branch_b = _navigate(chain, float(align), nav)
    for f, s in zip(chain, states):
        f.fmu.freeFMUstate(s)
        f.fmu.terminate()
        f.fmu.freeInstance()
    return WhatIf(branch_a, replay_a, branch_b, state_bytes)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu-dir", type=Path, default=Path("build") / "fmus")
    parser.add_argument("--align", type=int, default=3600, help="alignment [s]")
    parser.add_argument("--nav", type=int, default=7200, help="navigation of each branch [s]")
    parser.add_argument("--correction-dph", type=float, default=0.002, help="branch B's correction [deg/h]")
    args = parser.parse_args(argv)
    if not (args.fmu_dir / "StrapdownINS.fmu").is_file():
        from fmus.build import build_fmus
        build_fmus(args.fmu_dir)
    result = run(args.fmu_dir, args.align, args.nav, args.correction_dph)
    print(f"states after the alignment: {result.state_bytes} bytes serialized (three FMUs)")
    for label, b in (("A", result.branch_a), ("A again", result.replay_a), ("B", result.branch_b)):
        print(f"branch {label:8s}: after {b.nav_time:.0f} s of navigation north {b.north_error:+.3f} m, "
              f"east {b.east_error:+.3f} m, horizontal {b.position_error:.3f} m")
    print("A replayed bit for bit:", result.replay_a == result.branch_a)


if __name__ == "__main__":
    main()
