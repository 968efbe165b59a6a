"""The ``sarins`` command: argument parsing and printing only.

Each sub-command lives in a module of this package with ``register(sub)``
(adds its parser, sets ``func``) and a function that calls the library or
the application layer and prints.  Conventions for every command: exit 0 on
success, 2 for bad usage or input, 1 for a run that failed, 130 on Ctrl-C
(SIGINT, even if the process started with SIGINT ignored) and 143 on
SIGTERM; a write that fails for want of room (ENOSPC) is a failed run (1)
whose message names the file; every message is one line starting with the
command's name (``sarins <command>: error: ...`` or ``...: failed: ...``),
never a traceback (``SARINS_DEBUG=1`` re-raises unexpected errors); warnings
print as one plain line.  ``--seed`` means the same in every command: the
base random seed of the run or campaign, an integer in 0 .. 2**31-1 (the
FMUs' 32-bit Integer).
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import signal
import sys
import threading
import warnings

from sarins import __version__
from sarins_fmu.files import DISK_FULL_ERRNOS

EXIT_FAILED = 1  # the run itself failed (an FMU error, a failed fit)
EXIT_USAGE = 2  # bad command-line usage or input

COMMANDS = ("navigate", "demo", "cosim", "build_fmus", "identify", "campaign", "allan", "replay")


class UsageError(ValueError):
    """Bad command-line input: reported as one line, exit status 2."""


class RunError(RuntimeError):
    """A run that failed (not the user's input): one line, exit status 1."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is (so the clean-up of Ctrl-C runs): exit 143."""


EXIT_SIGINT = 130  # 128 + SIGINT
EXIT_SIGTERM = 143  # 128 + SIGTERM
SEED_MAX = 2**31 - 1  # random seeds reach the FMUs as fmi2Integer (32-bit)


def finite(text: str) -> float:
    """argparse type: a finite float."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def seed_value(text: str) -> int:
    """argparse type: a random seed the FMUs' 32-bit Integer can carry (0 .. 2**31 - 1)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if not 0 <= value <= SEED_MAX:
        raise argparse.ArgumentTypeError(f"must be in 0 .. 2**31-1, got {value}")
    return value


def bounded_int(low: int, high: int):
    """argparse type: an integer in [low, high] (sizes are checked before anything is allocated)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in {low} .. {high}, got {value}")
        return value

    return parse


def available_memory() -> int:
    """Bytes the kernel says are available (MemAvailable), or 4 GiB if unknown."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 4 * 2**30


def check_size(n_items: float, bytes_each: float, what: str) -> None:
    """Refuse (UsageError) before allocating ``n_items * bytes_each`` bytes if
    that is more than half the available memory."""
    need = float(n_items) * float(bytes_each)
    have = available_memory()
    if not need <= have / 2:
        raise UsageError(f"{what} needs about {need / 2**30:.3g} GiB of memory, more than half of the "
                         f"{have / 2**30:.3g} GiB available")


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
    """argparse with one-line errors (no usage dump) and exit status 2.

    The namespace it returns carries ``given``: the destinations of the
    options written on the command line (see :func:`given`), so that a
    command can refuse an option that does not apply instead of ignoring it.
    """

    def error(self, message):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")

    def parse_known_args(self, args=None, namespace=None):
        self._seen_dests = set()
        namespace, rest = super().parse_known_args(args, namespace)
        # a sub-command's parser ran inside and left its own options in namespace.given
        namespace.given = frozenset(set(getattr(namespace, "given", ())) | self._seen_dests)
        return namespace, rest

    def _parse_optional(self, arg_string):
        found = super()._parse_optional(arg_string)
        matches = found if isinstance(found, list) else [found] if found else []  # a list from Python 3.12
        for action, *_ in matches:
            if action is not None and hasattr(self, "_seen_dests"):
                self._seen_dests.add(action.dest)
        return found


def given(args, *dests: str) -> list[str]:
    """Of ``dests`` (argparse destinations), those written on the command line."""
    seen = getattr(args, "given", frozenset())
    return [d for d in dests if d in seen]


def refuse_unless(args, dests: dict, applies: bool, why: str) -> None:
    """UsageError naming the first option of ``dests`` ({dest: '--option'}) that was
    given although it does not apply (``applies`` False): ``why`` says why."""
    if applies:
        return
    written = given(args, *dests)
    if written:
        raise UsageError(f"{dests[written[0]]} {why}")


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


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _raise_terminated(signum, frame):
    raise Terminated()


def main(argv=None) -> int:
    try:
        parser = build_parser()
    except ImportError as exc:  # e.g. SARINS_CORE_LIB naming something that is not the C core
        if os.environ.get("SARINS_DEBUG"):
            raise
        print(f"sarins: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    args = parser.parse_args(argv)
    name = f"sarins {args.command}"
    if getattr(args, "campaign", None):
        name += f" {args.campaign}"
    old_warning = warnings.showwarning
    warnings.showwarning = _plain_warning
    old_term = old_int = None
    if threading.current_thread() is threading.main_thread():
        old_term = signal.signal(signal.SIGTERM, _raise_terminated)
        # Python keeps SIGINT ignored if it started so (a background job of a non-interactive shell
        # inherits SIG_IGN): install Ctrl-C -> KeyboardInterrupt whatever the inherited disposition
        old_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return int(args.func(args) or 0)
    except Terminated:
        print(f"{name}: terminated", file=sys.stderr)
        return EXIT_SIGTERM
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return EXIT_SIGINT
    except RecursionError as exc:  # a deeply nested input file that escaped its reader
        if os.environ.get("SARINS_DEBUG"):
            raise
        print(f"{name}: error: input nested too deeply ({_one_line(exc)})", file=sys.stderr)
        return EXIT_USAGE
    except ImportError as exc:  # an optional dependency the chosen options need
        missing = getattr(exc, "name", None) or _one_line(exc)
        print(f"{name}: error: this needs the package {missing!r}, which is not installed or cannot be "
              "imported", file=sys.stderr)
        return EXIT_USAGE
    except OSError as exc:
        if exc.errno in DISK_FULL_ERRNOS:  # the run failed for want of room, not the user's input
            print(f"{name}: failed: {_one_line(exc)}", file=sys.stderr)
            return EXIT_FAILED
        print(f"{name}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except (UsageError, ValueError) as exc:
        print(f"{name}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except (RunError, RuntimeError) as exc:  # incl. an FMU call that failed, a campaign task that failed
        print(f"{name}: failed: {_one_line(exc)}", file=sys.stderr)
        return EXIT_FAILED
    except MemoryError:
        print(f"{name}: failed: out of memory", file=sys.stderr)
        return EXIT_FAILED
    except Exception as exc:
        if os.environ.get("SARINS_DEBUG"):
            raise
        print(f"{name}: failed: internal error {type(exc).__name__}: {_one_line(exc)} "
              "(SARINS_DEBUG=1 shows the traceback)", file=sys.stderr)
        return EXIT_FAILED
    finally:
        warnings.showwarning = old_warning
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)
        if old_int is not None:
            signal.signal(signal.SIGINT, old_int)


if __name__ == "__main__":
    sys.exit(main())
