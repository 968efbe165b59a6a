"""``sarins allan``: overlapping Allan deviation of a preset's static data or of a recorded log.

::

    sarins allan --imu mems [--hours 28] [--rate-hz 1] [--seed 0] [--plot allan.png] [--json]
    sarins allan --log static.csv [--plot allan.png] [--json]

With ``--log`` the data, their sample rate and their length are the log's:
``--imu``, ``--hours``, ``--rate-hz`` and ``--seed`` describe simulated data
and are refused beside it (exit 2 naming the option), not ignored.

Prints, per channel, the random walk N, the bias instability B and the rate
random walk K read off the curve (IEEE Std 952 lines; 0 where the data do
not show the term), next to the preset's spec for simulated data.
"""

from __future__ import annotations

import json

from sarins_fmu import imu as imu_mod
from sarins_fmu.files import check_output_path

from . import UsageError, finite, refuse_unless
from .navigate import seed_value


def register(sub) -> None:
    p = sub.add_parser("allan", help="Allan deviation and noise read-outs of an IMU preset or log",
                       description="Overlapping Allan deviation of simulated static data of a "
                                   "preset, with the random-walk, bias-instability and rate-random-walk read-outs.")
    p.add_argument("--imu", choices=sorted(imu_mod.PRESETS), default="mems", help="IMU preset to simulate")
    p.add_argument("--log", default=None, metavar="PATH",
                   help="analyse this recorded static log (.csv or .npz, docs/imu-log.md) instead of a preset")
    p.add_argument("--hours", type=finite, default=28.0, help="length of the static record, h (default 28)")
    p.add_argument("--rate-hz", type=finite, default=1.0, help="sample rate, Hz (default 1)")
    p.add_argument("--seed", type=seed_value, default=0, help="base random seed of the run (the IMU noise), 0 .. 2**31-1 (default 0)")
    p.add_argument("--plot", default=None, help="write the annotated Allan plot to this PNG file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args) -> int:
    from sarins import allan as app

    if args.rate_hz <= 0:
        raise UsageError(f"--rate-hz must be positive, got {args.rate_hz:g}")
    if args.hours <= 0:
        raise UsageError(f"--hours must be positive, got {args.hours:g}")
    refuse_unless(args, {"imu": "--imu", "hours": "--hours", "rate_hz": "--rate-hz", "seed": "--seed"},
                  not args.log, "describes simulated data and does not apply with --log (the log sets the "
                                "data, its sample rate and its length)")
    if args.plot:
        check_output_path(args.plot, "--plot")
    if args.log:
        from sarins_fmu.imu_log import read_log

        log = read_log(args.log)
        result = app.analyse(log.dtheta / log.step, log.dv / log.step, 1.0 / log.step, f"log {args.log}")
    else:
        result = app.simulate(args.imu, args.hours, args.rate_hz, args.seed)
    if args.plot:
        app.plot(result, args.plot)
    rows = result.rows()
    if args.json:
        print(json.dumps({"source": result.source, "rate_hz": result.rate_hz, "record_s": result.record_length,
                          "channels": rows, "plot": args.plot}))
        return 0
    print(f"Allan read-outs of {result.source}, {result.record_length / 3600:.4g} h at {result.rate_hz:g} Hz "
          "(0: not shown by the data)")
    for r in rows:
        cells = []
        for term, label in (("random_walk", "N"), ("bias_instability", "B"), ("rate_random_walk", "K")):
            spec = f" (spec {r[term + '_spec']:.3g})" if term + "_spec" in r else ""
            cells.append(f"{label} {r[term]:.3g}{spec} {r[term + '_unit']}")
        if "gauss_markov" in r:
            cells.append(f"Gauss-Markov std {r['gauss_markov']:.3g} (spec {r['gauss_markov_spec']:.3g}, "
                         f"T {r['gauss_markov_time_s']:g} s) {r['gauss_markov_unit']}")
        print(f"  {r['channel']:8s} " + ";  ".join(cells))
    if args.plot:
        print(f"plot: {args.plot}")
    return 0
