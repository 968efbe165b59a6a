"""``sarins campaign axial-rbf``: seed 000's hot/cold identification campaign.

Phase 1 runs the training experiments (4 h alignment + 12 h navigation),
phase 2 trains the hot model (latitude error) and the cold model (latitude
error, temperature, temperature change), phase 3 runs the held-out
experiments (uncompensated, compensated re-runs, the paper's true drift and
the live align -> 12 h -> identify -> compensate -> 72 h run), then the
report (Markdown + PNG) is written to ``<out>/report``.  Every experiment's
result is stored as it finishes (``<out>/runs``); rerunning skips them.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

HELP = "seed 000: RBF axial-drift identification, hot and cold start (Tables 2-5, Figs 1-4)"

PROFILES = {  # (hot train, hot test, cold train, cold test)
    "quick": (8, 3, 16, 2),
    "paper": (16, 6, 24, 4),
}
DEFAULT_ENGINE = {"quick": "inprocess", "paper": "cosim"}


def add_arguments(parser) -> None:
    parser.add_argument("--engine", choices=("inprocess", "cosim"), default=None,
                        help="run the experiments in process or through the FMUs "
                             "(default: quick inprocess, paper cosim)")
    from sarins.cli import seed_value

    parser.add_argument("--seed", type=seed_value, default=0,
                        help="base random seed of the campaign (draws the experiments' conditions and noise "
                             "seeds), 0 .. 2**31-1 (default 0)")
    parser.add_argument("--truth", choices=("simulated", "paper"), default="simulated",
                        help="training target: the simulated true drift, or the paper's protocol "
                             "(drift minimising the 72 h position error of a re-run)")
    parser.add_argument("--no-live", action="store_true",
                        help="skip the live identified 88 h run of each held-out experiment")


def _digest(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:10]


def execute(*, profile: str = "quick", engine: str | None = None, seed: int = 0, out, workers=None,
            scheduler=None, progress: bool = True, truth: str = "simulated", live: bool | None = None,
            sizes=None, nav_hours: float | None = None) -> dict:
    """Run the campaign; returns the summary dict the report is written from.

    sizes : (hot train, hot test, cold train, cold test), default the profile's;
    nav_hours : evaluation window of the held-out runs (default 72 h; shorter
    only to test the campaign machinery quickly)."""
    from sarins.campaign import Task, atomic_output, build_artifacts, code_hash, run_campaign

    from sarins_fmu.experiments import axial_rbf as s0
    from . import runs

    if profile not in PROFILES:
        raise ValueError(f"profile must be one of {list(PROFILES)}")
    engine = engine or DEFAULT_ENGINE[profile]
    live = (profile == "paper") if live is None else live
    n_ht, n_hv, n_ct, n_cv = sizes or PROFILES[profile]
    out = Path(out)
    run_dir = out / "runs"
    t_start = time.perf_counter()
    fmu_dir = None
    if engine == "cosim" or profile == "quick":
        from fmus.build import DEFAULT_NAMES, build_fmus

        # built in a temporary folder and moved into place; rebuilt when the code changes
        fmu_dir = str(build_artifacts(out / "fmus", [f"{n}.fmu" for n in DEFAULT_NAMES], build_fmus,
                                      code_hash())[0].parent)
    exps = {"hot": s0.generate("hot", n_ht, n_hv, seed), "cold": s0.generate("cold", n_ct, n_cv, seed)}
    common = dict(workers=workers, scheduler=scheduler, progress=progress)
    tr = "" if truth == "simulated" else "-ptruth"
    train_tasks = [Task(f"s{seed}-{e.name}-{engine}{tr}", runs.train_task,
                        {"exp": e.to_dict(), "engine": engine, "fmu_dir": fmu_dir, "paper_truth": truth == "paper"},
                        volatile=("fmu_dir",), finite=("drift_dph", "lat_error_deg"))
                   for k in exps for e in exps[k] if e.role == "train"]
    train = run_campaign(train_tasks, run_dir, description="axial-rbf training runs", **common)
    rows = {k: [train[t.id] for t in train_tasks if t.kwargs["exp"]["start"] == k] for k in exps}
    target = "drift_dph" if truth == "simulated" else "paper_truth_dph"
    model_dir = out / "models"
    model_dir.mkdir(parents=True, exist_ok=True)
    nets = {}
    for kind, inputs in (("hot", s0.HOT_INPUTS), ("cold", s0.COLD_INPUTS)):
        with atomic_output(model_dir / f"{kind}.json", keep_suffix=True) as tmp:  # a kill never leaves half a model
            nets[kind] = s0.train_rbf(rows[kind], inputs, tmp, target=target)
    models = {k: str(model_dir / f"{k}.json") for k in nets}
    digests = {k: _digest(model_dir / f"{k}.json") for k in nets}
    tag = digests["hot"] + digests["cold"]
    nav = s0.NAV_HOURS if nav_hours is None else float(nav_hours)
    exact = profile == "paper"
    test_tasks = [Task(f"s{seed}-{e.name}-{engine}-{'live' if live else 'nolive'}-{nav:g}h-{int(exact)}-{tag}",
                       runs.test_task, {"exp": e.to_dict(), "models": models, "engine": engine, "fmu_dir": fmu_dir,
                                        "live": live, "rerun_all": exact, "nav_hours": nav},
                       volatile=("models", "fmu_dir"), identity={"models": digests})
                  for k in exps for e in exps[k] if e.role == "test"]
    if profile == "quick":
        first = exps["hot"][n_ht]
        test_tasks.append(Task(f"s{seed}-cosim-check-{tag}", runs.cosim_check_task,
                               {"exp": first.to_dict(), "model_file": models["hot"], "fmu_dir": fmu_dir},
                               volatile=("model_file", "fmu_dir"), identity={"model": digests["hot"]}))
    tests = run_campaign(test_tasks, run_dir, description="axial-rbf held-out runs", **common)
    check = tests.pop(test_tasks[-1].id) if profile == "quick" else None
    tested = {k: [tests[t.id] for t in test_tasks if t.id in tests and t.kwargs["exp"]["start"] == k]
              for k in exps}
    summary = {"profile": profile, "engine": engine, "seed": seed, "truth": truth, "live": live,
               "train": rows, "test": tested, "nets": nets, "models": models, "cosim_check": check,
               "comparison": _comparisons(rows, tested),
               "wall_seconds": time.perf_counter() - t_start,
               "workers": workers, "scheduler": scheduler}
    return summary


def _comparisons(rows: dict, tested: dict) -> dict:
    """Identification by (a) closed form, (b) linear regression, (c) Kalman filter,
    beside the RBF network, on the same held-out experiments."""
    from sarins_fmu.experiments import axial_rbf as s0

    out = {}
    for kind, inputs in (("hot", s0.HOT_INPUTS), ("cold", s0.COLD_INPUTS)):
        tests = tested[kind]
        if not tests:
            continue
        lin = s0.linear_regression(rows[kind], inputs)(tests)
        methods = {"rbf": [t["ident_dph"] for t in tests],
                   "closed_form": [float(s0.closed_form_drift_dph(t["lat_error_deg"])) for t in tests],
                   "linear": list(map(float, lin)),
                   "kalman": [s0.kalman_drift_dph(t["time_h"], t["lat_error_series_deg"]) for t in tests]}
        if kind == "cold":
            methods["rbf_hot_model"] = [t["ident_hot_dph"] for t in tests]
        table = {}
        for name, est in methods.items():
            table[name] = [{"drift_dph": float(d), "error_dph": float(d - t["drift_dph"]),
                            "max_nmi": s0.compensated_max_nmi(t, d)} for d, t in zip(est, tests)]
        out[kind] = table
    return out


def run(args) -> int:
    from .report import write_report

    summary = execute(profile=args.profile, engine=args.engine, seed=args.seed, out=args.out,
                      workers=args.workers, scheduler=args.scheduler, progress=not args.no_progress,
                      truth=args.truth, live=False if args.no_live else None)
    report = write_report(summary, Path(args.out) / "report")
    print(f"sarins campaign axial-rbf: report written to {report}")
    hot = [abs(t["ident_dph"] - t["drift_dph"]) for t in summary["test"]["hot"]]
    print(f"  hot start: max identification error {max(hot):.5f} deg/h over {len(hot)} held-out experiments; "
          f"wall time {summary['wall_seconds']:.0f} s")
    print(json.dumps({"hot_max_error_dph": max(hot)}))
    return 0
