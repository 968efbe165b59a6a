"""The ``sarins`` command: argument parsing and printing only.

Each sub-command lives in a module of this package with ``register(sub)``
(adds its parser, sets ``func``) and a function that calls the library or
the application layer and prints.  Conventions for every command: exit 0 on
success, 2 for bad usage or input, 1 for a run that failed; every message is
one line starting with the command's name; warnings print as one plain line.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import warnings

from sarins import __version__

EXIT_FAILED = 1  # the run itself failed (an FMU error, a failed fit)
EXIT_USAGE = 2  # bad command-line usage or input

COMMANDS = ("navigate", "demo", "cosim", "build_fmus", "identify", "campaign", "allan")


class UsageError(ValueError):
    """Bad command-line input: reported as one line, exit status 2."""


class RunError(RuntimeError):
    """A run that failed (not the user's input): one line, exit status 1."""


def finite(text: str) -> float:
    """argparse type: a finite float."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage dump) and exit status 2."""

    def error(self, message):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="sarins", description="Rotating-INS simulation, gyro-drift identification and "
                                               "FMI co-simulation (sarins-fmu).")
    parser.add_argument("--version", action="version", version=f"sarins {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"sarins.cli.{name}").register(sub)
    return parser


def _plain_warning(message, category, filename, lineno, file=None, line=None):
    print(f"sarins: warning: {message}", file=sys.stderr if file is None else file)


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    name = f"sarins {args.command}"
    warnings.showwarning = _plain_warning
    try:
        return int(args.func(args) or 0)
    except (UsageError, ValueError, OSError) as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except RunError as exc:
        print(f"{name}: failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
