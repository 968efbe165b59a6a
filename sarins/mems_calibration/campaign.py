"""``sarins campaign mems-calibration``: seed 003's dynamic calibration, end to end.

1. Build the Turntable and IMUThermal FMUs (into ``<out>/fmus``).
2. Co-simulate the dynamic, tumble and rate-test recordings through the
   master, as a resumable campaign (``<out>/recordings/<kind>.npz``).
3. Fit the traditional model (tumble + rate test) and the RBFNN, GRNN,
   LSTM and GRU compensators (dynamic training set); save them as plain
   model files (``<out>/models``).
4. Evaluate on the held-out dynamic test set; write ``summary.json``, the
   Markdown report and the figures (``<out>`` or ``--report-dir``).

The recurrent models need PyTorch (``pip install 'sarins-fmu[deep]'``);
without it they are skipped with that message and the others still run.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from sarins.cli import bounded_int, seed_value

HELP = "seed 003: MEMS IMU dynamic calibration on a 3-axis thermal rate table (traditional, RBFNN, GRNN, LSTM, GRU)"

MODEL_DEFAULTS = {  # per profile: recurrent training steps, GRNN patterns, RBF training samples
    "quick": dict(rnn_steps=60, grnn_patterns=5000, rbf_samples=10000),
    "paper": dict(rnn_steps=4000, grnn_patterns=20000, rbf_samples=50000),
}


def add_arguments(parser) -> None:
    parser.add_argument("--models", default="traditional,rbf,grnn,lstm,gru",
                        help="comma-separated subset of traditional,rbf,grnn,lstm,gru")
    parser.add_argument("--rnn-steps", type=bounded_int(1, 1_000_000), default=None,
                        help="recurrent training steps, 1 .. 10**6 (default: quick 60, paper 4000 as the paper)")
    parser.add_argument("--grnn-patterns", type=bounded_int(1, 200_000), default=None,
                        help="GRNN pattern-layer size, evenly spaced training samples, 1 .. 200000 "
                             "(quick 5000, paper 20000)")
    parser.add_argument("--rbf-samples", type=bounded_int(1, 1_000_000), default=None,
                        help="RBF training samples, evenly spaced, 1 .. 10**6 (quick 10000, paper 50000)")
    parser.add_argument("--seed", type=seed_value, default=3,
                        help="base random seed of the campaign: the IMU noise of the recordings, 0 .. 2**31-1 "
                             "(default 3; the networks' initialisation has its own fixed seed)")
    parser.add_argument("--report-dir", default=None, help="write report.md and the PNGs here (default: --out)")
    parser.add_argument("--refit", action="store_true",
                        help="fit the models again even if <out>/models holds them from a run with the same options")


def run(args) -> int:
    from sarins_fmu.identify import compensators, recurrent

    kinds = [k.strip() for k in args.models.split(",") if k.strip()]
    unknown = [k for k in kinds if k not in compensators.KINDS]
    if unknown or not kinds:
        raise ValueError(f"unknown model(s) {unknown}; choose from {', '.join(compensators.KINDS)}")
    options = dict(MODEL_DEFAULTS[args.profile])
    for key in ("rnn_steps", "grnn_patterns", "rbf_samples"):
        if getattr(args, key) is not None:
            options[key] = getattr(args, key)
    skipped = []
    if any(k in ("lstm", "gru") for k in kinds) and not recurrent.torch_available():
        skipped = [k for k in kinds if k in ("lstm", "gru")]
        kinds = [k for k in kinds if k not in skipped]
        print(f"skipping {', '.join(skipped)}: {recurrent.INSTALL_HINT}", file=sys.stderr)
    summary = run_mems_calibration(args.profile, Path(args.out), kinds=kinds, workers=args.workers, scheduler=args.scheduler,
                        progress=not args.no_progress, seed=args.seed, report_dir=args.report_dir, skipped=skipped,
                        refit=args.refit, **options)
    for name, red in summary["reductions"].items():
        print(f"{name:12s} mean {red['mean']:6.1f} %  std {red['std']:6.1f} %  mean-abs {red['mae']:6.1f} %")
    print(f"report: {summary['report']}")
    return 0


def record_all(profile_name: str, out: Path, *, workers=None, scheduler=None, progress=True, seed=3) -> dict:
    """Build the FMUs and run the three recordings as a resumable campaign."""
    from fmus.build import build_fmus
    from sarins.campaign import Task, build_artifacts, code_hash, run_campaign

    from sarins_fmu.experiments import mems_calibration as mc

    from .recording import record_task

    names = ("Turntable", "IMUThermal")
    fmu_dir = out / "fmus"  # built in a temporary folder, moved into place, rebuilt when the code changes
    build_artifacts(fmu_dir, [f"{n}.fmu" for n in names], lambda tmp: build_fmus(tmp, list(names)), code_hash())
    tasks = [Task(kind, record_task, dict(kind=kind, profile_name=profile_name, fmu_dir=str(fmu_dir), seed=seed),
                  volatile=("fmu_dir",)) for kind in mc.KINDS]
    return run_campaign(tasks, out / "recordings", workers=workers, scheduler=scheduler, progress=progress,
                        description="mems-calibration recordings")


def fit_models(kinds, train, fit, *, rnn_steps: int, grnn_patterns: int, rbf_samples: int, seed: int = 0,
               log=None) -> dict:
    """Fitted compensators by name (the traditional one from the calibration fit).

    ``log``: optional callable taking one line of progress text.
    """
    from sarins_fmu.identify import compensators

    models = {}
    for kind in kinds:
        if log:
            log(f"mems-calibration: fitting {kind} on {len(train)} samples")
        if kind == "traditional":
            t0 = time.perf_counter()
            model = compensators.TraditionalCompensator(fit.gyro, fit.accel)
            model.fit_seconds = time.perf_counter() - t0
        else:
            opts = {"rbf": dict(max_samples=rbf_samples), "grnn": dict(max_patterns=grnn_patterns)}.get(
                kind, dict(steps=rnn_steps, seed=seed))
            model = compensators.make(kind, **opts).fit(train.X, train.Y)
        models[kind] = model
    return models


def _stored_models(out: Path, kinds, models_key: str) -> dict:
    """Models of an earlier run made from the same recordings, options and code
    (``models_key``, fit times from its summary); an unreadable model file is
    fitted again with a notice."""
    from sarins_fmu.identify import compensators

    try:
        old = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    if not isinstance(old, dict) or old.get("models_key") != models_key:
        return {}
    stored = {}
    for kind in kinds:
        path = out / "models" / f"{kind}.npz"
        if path.exists():
            try:
                model = compensators.load(path)
            except (ValueError, OSError) as exc:
                print(f"mems-calibration: refitting {path}: {' '.join(str(exc).split())}", file=sys.stderr)
                continue
            if model.fit_seconds is None:
                model.fit_seconds = old.get("models", {}).get(kind, {}).get("fit_s")
            stored[kind] = model
    return stored


def run_mems_calibration(profile_name: str, out: Path, *, kinds, workers=None, scheduler=None, progress=True, seed=3,
              report_dir=None, rnn_steps=60, grnn_patterns=5000, rbf_samples=10000, skipped=(),
              refit=False) -> dict:
    """The whole campaign; returns the summary (also written to ``<out>/summary.json``).

    Like the recordings, fitted models are reused: ``<out>/models/<kind>.npz``
    from an earlier run with the same options (``<out>/summary.json``) is
    loaded instead of fitted again, unless ``refit``.
    """
    import numpy as np

    from sarins.campaign import atomic_output, write_text
    from sarins_fmu import imu
    from sarins_fmu.experiments import mems_calibration as mc
    from . import report as rep

    out = Path(out)
    wall = {}
    t0 = time.perf_counter()
    recs = record_all(profile_name, out, workers=workers, scheduler=scheduler, progress=progress, seed=seed)
    wall["recording campaign (this call; 0 when resumed)"] = time.perf_counter() - t0
    for kind in mc.KINDS:
        wall[f"co-simulation {kind}"] = float(recs[kind].get("wall_s", float("nan")))
    prof = mc.profile(profile_name)
    train, test = mc.dynamic_dataset(recs["dynamic"], prof)
    fit = mc.traditional_calibration(recs["tumble"], recs["rates"], prof)

    log = (lambda text: print(text, file=sys.stderr, flush=True)) if progress else None  # noqa: E731
    options = dict(rnn_steps=rnn_steps, grnn_patterns=grnn_patterns, rbf_samples=rbf_samples)
    model_dir = out / "models"
    model_dir.mkdir(parents=True, exist_ok=True)
    models_key = _models_key(recs, options)
    stored = {} if refit else _stored_models(out, kinds, models_key)
    models = fit_models([k for k in kinds if k not in stored], train, fit, log=log, **options)
    models = {k: stored.get(k) or models[k] for k in kinds}
    residuals = {"raw": test.X[:, :6] - test.Y}
    info = {}
    t0 = time.perf_counter()
    for name, model in models.items():
        if log:
            log(f"mems-calibration: evaluating {name} on {len(test)} samples")
        t1 = time.perf_counter()
        residuals[name] = model.predict(test.X) - test.Y
        info[name] = dict(n_parameters=int(model.n_parameters), fit_s=float(model.fit_seconds or 0.0),
                          predict_s=time.perf_counter() - t1)
        with atomic_output(model_dir / f"{name}.npz", keep_suffix=True) as tmp:
            model.save(tmp)
    wall["model evaluation"] = time.perf_counter() - t0
    wall["model fitting (sum of the fit times)"] = sum(i["fit_s"] for i in info.values())
    stats = {name: rep.residual_stats(r) for name, r in residuals.items()}
    red = {name: rep.reductions(s, stats["raw"]) for name, s in stats.items() if name != "raw"}

    report_dir = Path(report_dir) if report_dir else out
    report_dir.mkdir(parents=True, exist_ok=True)
    figures = [rep.residual_figure(report_dir / "fig4_gyro_x_residual.png", test.time, residuals, 0,
                                   "Fig. 4 analogue: X gyro residual after each model").name,
               rep.residual_figure(report_dir / "fig5_accel_x_residual.png", test.time, residuals, 3,
                                   "Fig. 5 analogue: X accelerometer residual after each model").name]
    summary = dict(
        profile=profile_name, step=prof.step, cal_step=prof.cal_step, tumble_dwell=prof.tumble_dwell,
        n_train=len(train), n_test=len(test), gyro_fit_rms_dps=fit.gyro_rms_residual * 180 / np.pi,
        accel_fit_rms_mg=fit.accel_rms_residual / rep.G_MG, models=info, wall_s=wall,
        reductions=red, table3=rep.table3(stats, red),
        stats={n: {k: v.tolist() for k, v in s.items()} for n, s in stats.items()},
        options=options, seed=seed, reused_models=sorted(stored), models_key=models_key)
    summary["notes"] = (
        f"GRNN pattern layer: {min(grnn_patterns, len(train))} of the {len(train)} training samples (evenly "
        f"spaced; the evaluation costs one exp per test-pattern pair). RBF trained on {min(rbf_samples, len(train))} "
        f"evenly spaced samples (2000 centre candidates). Recurrent models: {rnn_steps} NAdam steps on windows of "
        "100 samples read by 32 parallel streams, state carried; prediction runs the test series statefully "
        "from a zero state. All networks learn the correction y - x (standardised), see docs/mc.md.")
    if skipped:
        from sarins_fmu.identify.recurrent import INSTALL_HINT

        summary.update(skipped=list(skipped), skip_reason=INSTALL_HINT)
    text = rep.markdown(summary, rep.calibration_tables(fit, imu.preset("mems")), figures)
    summary["report"] = str((report_dir / "report.md").resolve())
    write_text(report_dir / "report.md", text)
    write_text(out / "summary.json", json.dumps(summary, indent=1))
    return summary


def _models_key(recs: dict, options: dict) -> str:
    """Identity of fitted models: the recordings they were fitted on, the
    fitting options and the code."""
    import hashlib

    import numpy as np

    from sarins.campaign import canonical_json, code_hash

    digest = hashlib.sha256(canonical_json(options).encode())
    digest.update(code_hash([__file__]).encode())
    for kind in sorted(recs):
        for key in sorted(recs[kind]):
            if key != "wall_s":
                digest.update(key.encode())
                digest.update(np.ascontiguousarray(recs[kind][key]).tobytes())
    return digest.hexdigest()
