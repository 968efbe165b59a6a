"""``sarins build-fmus``: build the FMUs (and, with --system, the static systems as one FMU each)."""

from __future__ import annotations

from pathlib import Path

from . import UsageError


def register(subparsers) -> None:
    from fmus.native_fmu import NATIVE

    p = subparsers.add_parser(
        "build-fmus", help="build the FMI 2.0 (or 3.0) co-simulation FMUs",
        description="Build the co-simulation FMUs. FMI 2.0 (default, into build/fmus): the native C FMUs "
                    f"{', '.join(n for n in NATIVE if n != 'IMUCompensator')} (and IMUCompensator with --compensator), "
                    "every FMI call in C, each with binaries/linux64, binaries/win64 and binaries/aarch64-linux (each "
                    "when its compiler is installed) and sources/; the project's systems as .ssp beside them. FMI 3.0 "
                    "(--fmi 3, into build/fmus3): the "
                    "native FMUs only, binaries/x86_64-linux, x86_64-windows and aarch64-linux the same way, and "
                    "sources/, with the static systems stepped at 60 s as .ssp beside them (standard_static_60s, "
                    "standard_static_identified_60s: every second in arrays, the 1 s systems' numbers). --system "
                    "adds the static systems as one container FMU each (FMI 2.0).")
    p.add_argument("--out", type=Path, default=None,
                   help="output folder (default build/fmus; with --fmi 3 build/fmus3)")
    p.add_argument("--fmi", type=int, choices=(2, 3), default=2,
                   help="FMI version: 2 (every FMU) or 3 (the FMI 3.0 variants of the native FMUs only)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="build only these FMUs")
    p.add_argument("--system", action="store_true",
                   help="also write the standard static system and the identified one (seed 000's loop "
                        "with the RBF identifier) as one FMU each (our system container, FMI 2.0: C, linux64, win64, "
                        "aarch64-linux and sources/)")
    p.add_argument("--compensator", type=Path, metavar="MODEL_FILE",
                   help="ship this trained seed 003 compensator (JSON/npz) in IMUCompensator.fmu (as its binary model "
                        "file, resources/compensator.bin)")
    p.set_defaults(func=run)


def run_fmi3(args) -> int:
    """``--fmi 3``: the FMI 3.0 co-simulation variants of the native (Python-free) FMUs."""
    from fmus.build import NEEDS_MODEL
    from fmus.native_fmu import DEFAULT_OUT3, NATIVE, build_native_fmus3

    if args.system:
        raise UsageError("--system: not available with --fmi 3 (only the native FMUs have FMI 3.0 variants)")
    others = [n for n in args.only or [] if n not in NATIVE]
    if others:
        raise UsageError(f"--only {' '.join(others)}: no FMI 3.0 variant (native FMUs: {', '.join(NATIVE)})")
    if args.compensator is not None:  # a bad model file fails before anything is built
        from sarins_fmu.identify.compensators import load

        load(args.compensator)
    names = None if args.only is None else [n for n in args.only if n not in NEEDS_MODEL]
    if args.only and args.compensator is None and len(names) < len(args.only):
        raise UsageError(f"--only IMUCompensator: it needs a trained model: {NEEDS_MODEL['IMUCompensator']}")
    out = args.out or DEFAULT_OUT3
    for path in build_native_fmus3(out, names) if names != [] else []:
        print(path)
    if not args.only:
        from sarins.systems import write_systems3

        for path in write_systems3(out):
            print(path)
    if args.compensator is not None:
        from fmus.compensator_export import export_compensator

        print(export_compensator(args.compensator, out, fmi=3))
    return 0


def run(args) -> int:
    if args.fmi == 3:
        return run_fmi3(args)
    from fmus.build import NEEDS_MODEL, build_fmus
    from fmus.native_fmu import platform_note

    args.out = args.out or Path("build") / "fmus"
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
        from sarins.systems import SYSTEM_FMUS, build_system_fmu

        for name in SYSTEM_FMUS:
            print(build_system_fmu(args.out, name))
    if args.compensator is not None:
        from fmus.compensator_export import export_compensator

        print(export_compensator(args.compensator, args.out))
    print(platform_note())
    return 0
