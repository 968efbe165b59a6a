"""``sarins campaign online-rls``: seed 002's simulation study and vehicle test.

Tasks (each one campaign task, stored as it finishes, resumable):

* ``stop-<unit>-<seed>``: one 30-minute stop filter run (convergence, error);
* ``mc-<ageing>-<unit>-<estimate>-<seed>``: one 300-day model-update run;
* ``veh-<ageing>-<unit>-<seed>``: one vehicle test (a year of online
  updates, then a 6 h drive with the initial and the updated model).

The headline configuration is ``mc-markov-premise-filter`` (eq. 20 as the
library's ageing, the premise unit, every stop simulated); the others are
the sensitivity studies of ``docs/online-rls.md``.
"""

from __future__ import annotations

import time
from pathlib import Path

HELP = "seed 002: stop Kalman filter, FF-RLS model update (300-day Monte Carlo), vehicle test"

# ageing 3.5 times the preset's: mean S without update ~0.13 deg/h.degC, the size
# that the paper's Table 2 implies (FF-RLS 0.066 "below half" of no update)
PAPER_SCALE = 3.5

# profile -> settings.  mc: (ageing, unit, estimate, runs[, ageing scale]);
# vehicle: (ageing, unit, runs[, ageing scale])
PROFILES = {
    "quick": {
        "stops": {"premise": 4, "nav-rlg": 1},
        "mc": [("markov", "premise", "filter", 8)],
        "vehicle": [("markov", "premise", 1)],
        "vehicle_kwargs": {"n_sessions": 8, "year_days": 120.0, "test_day": 170.0, "drive_hours": 1.0},
    },
    "paper": {
        "stops": {"premise": 40, "nav-rlg": 20},
        "mc": [("markov", "premise", "filter", 100), ("integrated", "premise", "filter", 100),
               ("markov", "premise", "truth", 100), ("integrated", "premise", "truth", 100),
               ("markov", "nav-rlg", "filter", 50),
               ("markov", "premise", "filter", 100, PAPER_SCALE), ("integrated", "premise", "filter", 100, PAPER_SCALE)],
        "vehicle": [("markov", "premise", 30), ("integrated", "premise", 30), ("markov", "nav-rlg", 10),
                    ("markov", "premise", 30, PAPER_SCALE), ("integrated", "premise", 30, PAPER_SCALE)],
        "vehicle_kwargs": {},
    },
}


def _scale_tag(scale: float) -> str:
    return "" if scale == 1.0 else f"_x{scale:g}"


def add_arguments(parser) -> None:
    parser.add_argument("--lambda", dest="forgetting_factor", type=float, default=0.8,
                        help="forgetting factor of FF-RLS per month (default 0.8, the paper's)")


def build_tasks(profile: str, forgetting_factor: float = 0.8):
    """The campaign's tasks for ``profile`` ('quick' or 'paper')."""
    from sarins.campaign import Task
    from sarins_fmu.experiments import online_rls

    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r}")
    if not (0.0 < forgetting_factor <= 1.0):
        raise ValueError(f"--lambda must be in (0, 1], got {forgetting_factor}")
    p = PROFILES[profile]
    tasks = []
    for unit, n in p["stops"].items():
        tasks += [Task(f"stop-{unit}-{s:03d}", online_rls.simulate_stop,
                       {"imu": unit, "seed": s, "temperature": 5.0 + 40.0 * ((s * 0.618) % 1.0)}) for s in range(n)]
    for ageing, unit, estimate, n, *scale in p["mc"]:
        x = scale[0] if scale else 1.0
        tasks += [Task(f"mc-{ageing}{_scale_tag(x)}-{unit}-{estimate}-{s:03d}", online_rls.model_update_run,
                       {"seed": s, "unit": unit, "estimate": estimate, "ageing": ageing, "ageing_scale": x,
                        "forgetting_factor": forgetting_factor}) for s in range(n)]
    for ageing, unit, n, *scale in p["vehicle"]:
        x = scale[0] if scale else 1.0
        tasks += [Task(f"veh-{ageing}{_scale_tag(x)}-{unit}-{s:03d}", online_rls.vehicle_test,
                       {"seed": s, "unit": unit, "ageing": ageing, "forgetting_factor": forgetting_factor,
                        "ageing_scale": x, **p["vehicle_kwargs"]}) for s in range(n)]
    return tasks


def run(args) -> int:
    from sarins.campaign import run_campaign

    from .report import write_report

    from sarins.campaign import result_path

    tasks = build_tasks(args.profile, args.forgetting_factor)
    out = Path(args.out)
    computed = sum(not result_path(out / "runs", t.id).exists() for t in tasks)
    start = time.perf_counter()
    results = run_campaign(tasks, out / "runs", workers=args.workers, scheduler=args.scheduler,
                           progress=not args.no_progress, description="online-rls")
    wall = time.perf_counter() - start
    report = write_report(results, out, profile=args.profile, wall_time=wall, workers=args.workers,
                          forgetting_factor=args.forgetting_factor, computed=computed)
    print(f"sarins campaign online-rls: {len(tasks)} runs ({computed} computed now) in {wall:.0f} s; report {report}")
    return 0
