"""``sarins build-fmus``: build the FMUs (and, with --system, the standard system as one FMU)."""

from __future__ import annotations

from pathlib import Path

from . import UsageError


def register(subparsers) -> None:
    p = subparsers.add_parser("build-fmus", help="build the FMI 2.0 co-simulation FMUs")
    p.add_argument("--out", type=Path, default=Path("build") / "fmus", help="output folder (default build/fmus)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="build only these FMUs")
    p.add_argument("--system", action="store_true",
                   help="also write the standard static system as one FMU (FMPy container, FMI 2.0)")
    p.add_argument("--compensator", type=Path, metavar="MODEL_FILE",
                   help="ship this trained seed 003 compensator (JSON/npz) in IMUCompensator.fmu")
    p.set_defaults(func=run)


def run(args) -> int:
    from fmus.build import NEEDS_MODEL, build_fmus
    from fmus.native import HOST_REQUIREMENTS
    from fmus.native_fmu import platform_note

    if args.compensator is not None:  # a bad model file fails before anything is built
        from sarins_fmu.identify.compensators import load

        load(args.compensator)
    names = None
    if args.only:
        names = [n for n in args.only if not (n == "IMUCompensator" and args.compensator is not None)]
        for name in names:
            if name in NEEDS_MODEL:
                raise UsageError(f"--only {name}: it needs a trained model: {NEEDS_MODEL[name]}")
    elif args.compensator is None:
        print("IMUCompensator not built (it needs a trained model: --compensator MODEL_FILE)")
    for path in build_fmus(args.out, names) if names != [] else []:
        print(path)
    if not args.only:
        from sarins.systems import write_systems

        for path in write_systems(args.out):
            print(path)
    if args.system:
        from sarins.systems import build_system_fmu

        print(build_system_fmu(args.out))
    if args.compensator is not None:
        from fmus.compensator_export import export_compensator

        print(export_compensator(args.compensator, args.out))
    print(platform_note())
    print(f"Python-hosted FMUs: {HOST_REQUIREMENTS}")
    return 0
