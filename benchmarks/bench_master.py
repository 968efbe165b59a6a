"""Overhead of the co-simulation master per communication step.

Baseline, measured in the same process: a bare loop of FMPy ``FMU2Slave.doStep``
calls on the same FMU instances (no data exchange, no recording).  The master
runs the same system with Gauss-Seidel and Jacobi coupling, copying every
connection and recording every output at every step.  The report gives
microseconds per communication step and the master's own overhead
(master minus bare doSteps).

Systems: the test fixtures Ramp -> Gain (pythonfmu, Real+Integer+Boolean
connections), built into a temporary folder; and, when found, the
OpenModelica mass-spring subsystems (native C FMUs, from the test cache or
``--om-dir``).

Usage: ``python benchmarks/bench_master.py [--steps N] [--om-dir DIR]``
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from fmu_fixtures.building import build_fixture_fmus  # noqa: E402
from orchestration import Component, Connection, Master, System  # noqa: E402
from orchestration.fmu import FMUInstance, UnpackedFMU  # noqa: E402


def bare_dostep(system: System, steps: int, h: float) -> float:
    """Seconds per step of a loop of FMU2Slave.doStep over all components."""
    units, instances = {}, []
    for component in system.components:
        path = system.fmu_path(component)
        units.setdefault(path, UnpackedFMU(path, component.name))
        instance = FMUInstance(component.name, units[path])
        instance.instantiate()
        slave = instance.slave
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        instance.mark_initialized()
        instances.append(instance)
    slaves = [i.slave for i in instances]
    begin = time.perf_counter()
    for n in range(steps):
        t = n * h
        for slave in slaves:
            slave.doStep(t, h)
    elapsed = time.perf_counter() - begin
    for instance in instances:
        instance.release()
    for unit in units.values():
        unit.remove()
    return elapsed / steps


def fmpy_loop(system: System, steps: int, h: float) -> float:
    """Seconds per step of a hand-written FMPy loop doing the master's work.

    Gauss-Seidel in declaration order (the systems here are ordered), inputs
    copied with ``getReal/setReal``-style list calls, every output read into a
    python list each step: what one would write with FMPy's FMU2Slave directly.
    """
    from orchestration.coupling import check_connections, group_links, value_type

    units, instances = {}, []
    for component in system.components:
        path = system.fmu_path(component)
        units.setdefault(path, UnpackedFMU(path, component.name))
        instance = FMUInstance(component.name, units[path])
        instance.instantiate()
        slave = instance.slave
        slave.setupExperiment(startTime=0.0)
        for name, value in component.parameters.items():
            var = instance.variables[name]
            getattr(slave, f"set{value_type(var)}")([var.valueReference], [value])
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        instance.mark_initialized()
        instances.append(instance)
    names = [c.name for c in system.components]
    links = group_links(check_connections(system.connections, names,
                                          [i.variables for i in instances], names))
    slaves = [i.slave for i in instances]
    into = [[(getattr(slaves[k.source], f"get{k.kind}"), list(k.source_vrs),
              getattr(slaves[k.target], f"set{k.kind}"), list(k.target_vrs))
             for k in links if k.target == i] for i in range(len(slaves))]
    reads = []
    for i, instance in enumerate(instances):
        for kind in ("Real", "Integer", "Boolean"):
            vrs = [v.valueReference for v in instance.variables.values()
                   if v.causality == "output" and value_type(v) == kind]
            if vrs:
                reads.append((getattr(slaves[i], f"get{kind}"), vrs))
    rows = []
    begin = time.perf_counter()
    for n in range(steps):
        t = n * h
        for slave, transfers in zip(slaves, into):
            for get, src, set_, dst in transfers:
                set_(dst, get(src))
            slave.doStep(t, h)
        rows.append([get(vrs) for get, vrs in reads])
    elapsed = time.perf_counter() - begin
    for instance in instances:
        instance.release()
    for unit in units.values():
        unit.remove()
    return elapsed / steps


def master_run(system: System, steps: int, h: float, scheme: str) -> float:
    """Seconds per step of Master.simulate (init excluded as far as possible)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with Master(system, scheme=scheme) as master:
            master.simulate(10 * h, h, progress=False)  # warm-up, one-off costs
            begin = time.perf_counter()
            master.simulate(steps * h, h, progress=False)
            elapsed = time.perf_counter() - begin
            begin = time.perf_counter()
            master.simulate(h, h, progress=False)  # one step: fixed cost of a run
            fixed = time.perf_counter() - begin
    return (elapsed - fixed) / (steps - 1)


def report(label: str, system: System, steps: int, h: float) -> None:
    bare = min(bare_dostep(system, steps, h) for _ in range(3))
    print(f"\n{label}: {len(system.components)} FMUs, {len(system.connections)} "
          f"connections, {steps} steps")
    loop = min(fmpy_loop(system, steps, h) for _ in range(3))
    print(f"  bare FMU2Slave.doStep loop     {bare * 1e6:8.2f} us/step")
    print(f"  hand-written FMPy loop         {loop * 1e6:8.2f} us/step   (same exchange and "
          f"recording with FMPy's list API)")
    for scheme in ("gauss-seidel", "jacobi"):
        run = min(master_run(system, steps, h, scheme) for _ in range(3))
        print(f"  master {scheme:<13}          {run * 1e6:8.2f} us/step   overhead "
              f"{(run - bare) * 1e6:7.2f} us/step  ({run / bare:4.2f} x bare, "
              f"{run / loop:4.2f} x FMPy loop)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--om-dir", type=Path,
                        default=ROOT / ".pytest_cache" / "d" / "openmodelica_fmus")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        fmus = build_fixture_fmus(Path(scratch))
        ramp_gain = System("ramp_gain",
                           [Component("ramp", fmus["Ramp"], {"slope": 2.0}),
                            Component("gain", fmus["Gain"], {"k": 3.0})],
                           [Connection.between("ramp.y", "gain.u"),
                            Connection.between("ramp.count", "gain.n_in"),
                            Connection.between("ramp.positive", "gain.flag_in")])
        report("pythonfmu Ramp -> Gain", ramp_gain, args.steps, 1e-3)
    sub1 = args.om_dir / "MassSpringSubSystem1.fmu"
    if sub1.is_file():
        mass_spring = System("mass_spring",
                             [Component("sub1", sub1, {"k2": 2.0}),
                              Component("sub2", args.om_dir / "MassSpringSubSystem2.fmu",
                                        {"k2": 2.0})],
                             [Connection.between("sub1.x1", "sub2.x1"),
                              Connection.between("sub2.x2", "sub1.x2")])
        report("OpenModelica mass-spring (native)", mass_spring, args.steps, 1e-3)
    else:
        print(f"\n(no OpenModelica FMUs in {args.om_dir}; run the tests once to fetch them)")


if __name__ == "__main__":
    main()
