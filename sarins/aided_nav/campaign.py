"""``sarins campaign aided-nav``: GNSS/INS aided navigation along a drive, Monte Carlo.

Tasks (each one campaign task, stored as it finishes, resumable):

* ``trajectory``: the drive's truth (for the trajectory plot);
* ``run-<seed>``: one aided run (tactical IMU, 1 Hz GNSS with white errors, ZUPT at the stops,
  GNSS outages of 30, 60 and 120 s), :func:`sarins_fmu.experiments.aided_nav.monte_carlo_run`;
* ``zupt-<seed>``: the IMU-statistics ZUPT detector on a drive with three stops and GNSS-free
  navigation with its ZUPTs against the truth's, :func:`sarins_fmu.experiments.aided_nav.zupt_run`;
* ``kfgins``: our filter against KF-GINS on the same data, when its binary is given (``--kfgins`` or
  ``$SARINS_KFGINS``), :func:`sarins_fmu.experiments.aided_nav.kfgins_run`; without one the report says
  the comparison was skipped and why.

The report (:mod:`sarins.aided_nav.report`) takes the consistency (mean NEES against its 95 % χ²
band) and the outage table (RMS over the runs of the horizontal error at each outage's end against
the filter's predicted σ) from the runs, and the ±3σ error plots from run 0.
"""

from __future__ import annotations

import time
from pathlib import Path

HELP = "aided navigation: GNSS/INS error-state Kalman filter along a drive, NEES and GNSS-outage Monte Carlo"

# profile -> settings: Monte Carlo runs, cruise length (s), output decimation (IMU steps per row), ZUPT-detector runs,
# length of the KF-GINS comparison's drive (min; the paper profile's is the one of docs/aided-navigation.md)
PROFILES = {
    "quick": {"runs": 10, "cruise": 400.0, "out_every": 20, "zupt_runs": 4, "kfgins_minutes": 5.0},
    "paper": {"runs": 100, "cruise": 400.0, "out_every": 10, "zupt_runs": 20, "kfgins_minutes": 30.0},
}
KFGINS_REPEATS = 3  # runs of each filter in the KF-GINS comparison; the fastest times are reported
ZUPT_KEYS = ("stop_windows", "misses", "moving_windows", "false_stationary", "samples", "zupt_truth", "zupt_imu")


def add_arguments(parser) -> None:
    from sarins.cli.navigate import seed_value

    parser.add_argument("--runs", type=_runs, default=None,
                        help="Monte Carlo runs (default: the profile's, quick 10, paper 100)")
    parser.add_argument("--zupt-runs", type=lambda t: _runs(t, 0), default=None,
                        help="runs of the ZUPT-detector study (default: the profile's, quick 4, paper 20; 0: none)")
    parser.add_argument("--seed", type=seed_value, default=0,
                        help="first random seed: run k uses seed + k (default 0)")
    parser.add_argument("--kfgins", default=None, metavar="PATH",
                        help="KF-GINS binary for the comparison with a peer filter (default $SARINS_KFGINS; without "
                             "one the report says the comparison was skipped)")


def _runs(text: str, low: int = 2) -> int:
    import argparse

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
    if not low <= value <= 10000:
        raise argparse.ArgumentTypeError(f"must be in {low} .. 10000, got {text!r}")
    return value


def run_schema(n: int, m: int) -> dict:
    """What one run returns: n output rows, m outage windows."""
    from sarins.campaign import Field

    return {"time": Field((n,)), "error": Field((n, 9)), "sigma": Field((n, 9)), "nees": Field((n, 3)),
            "outage_error": Field((m,)), "outage_sigma": Field((m,)), "cpu_s": Field()}


def build_tasks(profile: str, runs: int | None = None, seed: int = 0, zupt_runs: int | None = None,
                kfgins: str | None = None) -> list:
    """The campaign's tasks for ``profile``: the trajectory, ``runs`` Monte Carlo runs (seeds seed ..),
    ``zupt_runs`` runs of the ZUPT detector (seeds seed ..) and, with ``kfgins`` (the path of an
    executable KF-GINS binary), the comparison with KF-GINS (seed ``seed``; its record holds the
    binary's SHA-256, not its path)."""
    from sarins.campaign import Field, Task
    from sarins_fmu.experiments import aided_nav

    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r}")
    p = PROFILES[profile]
    runs = p["runs"] if runs is None else runs
    zupt_runs = p["zupt_runs"] if zupt_runs is None else zupt_runs
    most = max(runs, zupt_runs)
    if not 0 <= seed <= 2**31 - most:
        raise ValueError(f"--seed must be in 0 .. {2**31 - most} for {most} runs, got {seed}")
    truth = aided_nav.drive(p["cruise"])
    n = truth.n_steps // p["out_every"]
    rows = len(range(0, truth.n_steps + 1, p["out_every"]))
    tasks = [Task("trajectory", aided_nav.trajectory_task, {"cruise": p["cruise"], "out_every": p["out_every"]},
                  schema={k: Field((rows,)) for k in ("time", "east", "north", "up", "speed", "yaw", "stationary")})]
    kwargs = {"cruise": p["cruise"], "outages": [list(w) for w in aided_nav.OUTAGES], "out_every": p["out_every"]}
    tasks += [Task(f"run-{k:04d}", aided_nav.monte_carlo_run, {"seed": seed + k, **kwargs},
                   schema=run_schema(n, len(aided_nav.OUTAGES))) for k in range(runs)]
    zupt_schema = {**{k: Field(kind="iu") for k in ZUPT_KEYS},
                   **{k: Field() for k in ("delay_s", "gamma", "error_truth_m", "error_imu_m", "cpu_s")}}
    tasks += [Task(f"zupt-{k:04d}", aided_nav.zupt_run, {"seed": seed + k}, schema=zupt_schema)
              for k in range(zupt_runs)]
    if kfgins is not None:
        tasks.append(Task("kfgins", aided_nav.kfgins_run, {"binary": kfgins, "minutes": p["kfgins_minutes"], "seed": seed,
                                                           "repeats": KFGINS_REPEATS},
                          volatile=("binary",), identity={"kfgins_sha256": _sha256(kfgins)},
                          schema={"comparison": Field(kind="U"), "failure": Field(kind="U")}))
    return tasks


def _sha256(path: str) -> str:
    import hashlib

    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def run(args) -> int:
    from sarins.campaign import run_campaign
    from sarins_fmu.experiments.kfgins_compare import find_binary

    from .report import write_report

    out = Path(args.out)
    binary, why = find_binary(args.kfgins)
    tasks = build_tasks(args.profile, args.runs, args.seed, args.zupt_runs, kfgins=binary)
    start, cpu0 = time.perf_counter(), time.process_time()
    results = run_campaign(tasks, out / "runs", workers=args.workers, scheduler=args.scheduler,
                           progress=not args.no_progress, description="aided-nav")
    wall = time.perf_counter() - start
    report = write_report(results, out, profile=args.profile, wall_time=wall, workers=args.workers,
                          computed=len(results.computed), parent_cpu=time.process_time() - cpu0, kfgins_skipped=why)
    print(f"sarins campaign aided-nav: {len(tasks)} tasks ({len(results.computed)} computed now) in {wall:.0f} s; "
          f"report {report}")
    return 0
