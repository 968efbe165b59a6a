"""``sarins build-fmus``: build the FMUs (and, with --system, the standard system as one FMU)."""

from __future__ import annotations

from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser("build-fmus", help="build the FMI 2.0 co-simulation FMUs")
    p.add_argument("--out", type=Path, default=Path("build") / "fmus", help="output folder (default build/fmus)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="build only these FMUs")
    p.set_defaults(func=run)


def run(args) -> int:
    from .build import build_fmus

    for path in build_fmus(args.out, args.only):
        print(path)
    return 0
