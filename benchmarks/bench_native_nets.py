"""Cost of a step of the native IMUCompensator and RBFIdentifier FMUs, against the in-process library.

For each compensator kind at seed 003's sizes (RBF 30 neurons, GRNN 2000 patterns, recurrent 60 units),
the FMU (through FMPy: setReal of the inputs, doStep, getReal of the outputs) runs ``--steps`` steps; the
baseline, measured in the same process, is the library's one-sample compensation (``Compensator.stream``,
the same C function through ctypes).  Prints microseconds per step and the ratio FMU / library.

    PYTHONPATH=. python3 benchmarks/bench_native_nets.py [--steps 2000] [--save-models DIR]

``--save-models DIR`` also writes the models as npz (to time another build of the FMU on the same models).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def models(hidden: int = 60) -> dict:
    """{kind: fitted compensator} at seed 003's sizes; recurrent weights random (inference cost only)."""
    from sarins_fmu.identify import compensators, recurrent

    rng = np.random.default_rng(0)
    n = 4000
    y = np.column_stack([rng.normal(0, 0.5, (n, 3)), rng.normal(0, 3.0, (n, 3))])
    temp = np.linspace(-10, 40, n)
    x = np.column_stack([y * (1 + 1e-3) + 1e-3 * np.sin(temp)[:, None], temp])
    out = {"traditional": compensators.make("traditional").fit(x, y),
           "rbf": compensators.make("rbf", max_neurons=30).fit(x, y),
           "grnn": compensators.make("grnn", max_patterns=2000).fit(x, y)}
    for kind, (cell, layers) in compensators.RECURRENT_KINDS.items():
        g = 4 if cell == "lstm" else 3
        arrays = {}
        for k in range(layers):
            sfx = "" if k == 0 else f"_l{k}"
            arrays |= {f"w_ih{sfx}": rng.normal(0, 0.2, (g * hidden, 7 if k == 0 else hidden)),
                       f"w_hh{sfx}": rng.normal(0, 0.2, (g * hidden, hidden)),
                       f"b_ih{sfx}": rng.normal(0, 0.1, g * hidden), f"b_hh{sfx}": rng.normal(0, 0.1, g * hidden)}
        arrays |= {"w_out": rng.normal(0, 0.2, (6, hidden)), "b_out": rng.normal(0, 0.1, 6)}
        comp = compensators.make(kind, hidden=hidden)
        comp.weights = recurrent.RecurrentWeights(cell, arrays)
        comp.input_mean, comp.input_scale = x.mean(axis=0), x.std(axis=0)
        comp.target_mean, comp.target_scale = np.zeros(6), np.full(6, 1e-3)
        out[kind] = comp
    return out


def fmu_us_per_step(fmu: Path, rows: np.ndarray, h: float) -> float:
    """Wall time per step of the FMU through FMPy (set inputs, doStep, get outputs), us."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    ins = [vr[f"raw_{q}_{a}"] for q in ("dtheta", "dv") for a in "xyz"] + [
        vr[f"temp_{s}"] for s in ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")]
    outs = [vr[f"{q}_{a}"] for q in ("dtheta", "dv") for a in "xyz"]
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="bench")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    values = [list(r[:6] * h) + [r[6]] * 6 for r in rows]
    t0 = time.perf_counter()
    for k, v in enumerate(values):
        s.setReal(ins, v)
        s.doStep(k * h, h)
        s.getReal(outs)
    elapsed = time.perf_counter() - t0
    s.terminate()
    s.freeInstance()
    return elapsed / len(rows) * 1e6


def library_us_per_step(model, rows: np.ndarray) -> float:
    stream = model.stream()
    t0 = time.perf_counter()
    for r in rows:
        stream.step(r)
    return (time.perf_counter() - t0) / len(rows) * 1e6


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--save-models", type=Path, default=None)
    args = p.parse_args(argv)
    from fmus.compensator_export import export_compensator

    h = 0.05
    rng = np.random.default_rng(1)
    rows = np.column_stack([rng.normal(0, 0.5, (args.steps, 3)), rng.normal(0, 3, (args.steps, 3)),
                            np.linspace(0, 30, args.steps)])
    print(f"{'kind':12s} {'FMU us/step':>12s} {'library us/step':>16s} {'ratio':>7s}")
    with tempfile.TemporaryDirectory() as tmp:
        for kind, model in models().items():
            path = model.save(Path(tmp) / f"{kind}.npz")
            if args.save_models:
                args.save_models.mkdir(parents=True, exist_ok=True)
                model.save(args.save_models / f"{kind}.npz")
            fmu = export_compensator(path, Path(tmp), name=f"{kind}.fmu", win64=False)
            lib = library_us_per_step(model, rows)
            fmu_us = fmu_us_per_step(fmu, rows, h)
            print(f"{kind:12s} {fmu_us:12.1f} {lib:16.1f} {fmu_us / lib:7.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
