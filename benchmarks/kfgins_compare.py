"""Our aided navigation against KF-GINS (github:i2Nav-WHU/KF-GINS, built outside the project) on the same
simulated IMU and GNSS data: RMS position, velocity and attitude errors against the truth, and run times
(KF-GINS / ours, wall and CPU).  The work is :mod:`sarins_fmu.experiments.kfgins_compare`; this script
parses, runs and prints.

Run from the project root (KF-GINS's binary from --kfgins or $SARINS_KFGINS):
    PYTHONPATH=$PWD python3 benchmarks/kfgins_compare.py --minutes 30 --json out.json --markdown out.md
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from sarins_fmu import aided  # noqa: E402
from sarins_fmu.experiments.kfgins_compare import GNSS_CHOICES, compare, find_binary, markdown  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kfgins", default=None, help="KF-GINS binary (default $SARINS_KFGINS)")
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--rate-hz", type=int, default=100)
    ap.add_argument("--imu", default="tactical", choices=sorted(aided.IMU_NOISE))
    ap.add_argument("--gnss", default="white", choices=sorted(GNSS_CHOICES))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=3, help="runs of each filter; the fastest is reported")
    ap.add_argument("--kfgins-commit", default=None, help="the KF-GINS commit the binary was built from (recorded)")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--markdown", type=Path)
    args = ap.parse_args(argv)
    binary, why = find_binary(args.kfgins)
    if binary is None:
        print(f"kfgins_compare: {why}; give KF-GINS's binary with --kfgins or $SARINS_KFGINS", file=sys.stderr)
        return 2
    r = compare(binary, args.minutes, rate_hz=args.rate_hz, imu=args.imu, gnss=args.gnss, seed=args.seed,
                repeats=args.repeats, commit=args.kfgins_commit)
    table = markdown(r)
    if args.json:
        args.json.write_text(json.dumps(r, indent=2) + "\n")
    if args.markdown:
        args.markdown.write_text(table)
    print(json.dumps(r, indent=2))
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
