"""``sarins cosim SYSTEM ...``: run an SSP system with the generic master (orchestration)."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from orchestration import interrupt
from orchestration.errors import OrchestrationError
from orchestration.master import SCHEMES, Master
from orchestration.recorder import write_csv

__all__ = ["register", "run", "summary", "realtime_summary"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``cosim`` subcommand to an ``argparse`` subparsers object.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers()``.

    Returns
    -------
    argparse.ArgumentParser
        The ``cosim`` parser; its ``func`` default is :func:`run`.
    """
    parser = subparsers.add_parser(
        "cosim", help="co-simulate an SSP system of FMI 2.0 co-simulation FMUs",
        description="Run an .ssp archive or SystemStructure.ssd (or its folder) with the "
                    "fixed-step master and print the final values of the recorded outputs.")
    parser.add_argument("system", help="system file: x.ssp, SystemStructure.ssd or its folder")
    parser.add_argument("--stop-time", type=float, default=None, metavar="T",
                        help="stop time, s (default: the system's DefaultExperiment)")
    parser.add_argument("--start-time", type=float, default=None, metavar="T0",
                        help="start time, s (default: the system's, else 0)")
    parser.add_argument("--step", type=float, default=None, metavar="H",
                        help="communication step, s (default: the system's, else the "
                             "FMUs' DefaultExperiment stepSize)")
    parser.add_argument("--scheme", choices=SCHEMES, default="gauss-seidel",
                        help="coupling scheme (default: gauss-seidel)")
    parser.add_argument("--record", action="append", default=None, metavar="NAME",
                        help="component.variable or pattern to record (repeatable; "
                             "default: all outputs)")
    parser.add_argument("--output-every", type=int, default=1, metavar="N",
                        help="record every Nth step (default: 1)")
    parser.add_argument("--output", default=None, metavar="CSV", help="write results to CSV")
    parser.add_argument("--realtime", type=float, default=None, metavar="FACTOR",
                        help="pace the run: wall-clock seconds per simulated second (the "
                             "clock starts after initialisation; the lag distribution is reported)")
    parser.add_argument("--no-progress", action="store_true", help="never show a progress bar")
    parser.set_defaults(func=run)
    return parser


def summary(result) -> str:
    """Text table of the last recorded value of every field of a result."""
    names = result.dtype.names
    width = max(len(n) for n in names)
    last = result[-1]
    lines = [f"{result.meta.get('system', 'system')}: {result.meta.get('steps', '?')} steps, "
             f"scheme {result.meta.get('scheme', '?')}, final values at t = "
             f"{last['time']:.9g} s"]
    lines += [f"  {name:<{width}}  {_format(last[name])}" for name in names[1:]]
    return "\n".join(lines)


def _format(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    return f"{value:.12g}" if isinstance(value, (float, np.floating)) else str(value)


def run(args: argparse.Namespace) -> int:
    """Run the ``cosim`` subcommand; return the process exit code.

    Exit codes: 0 success, 2 a system-description or schedule error (bad input), 1 an FMU
    failure, 130 / 143 stopped by SIGINT (Ctrl-C) / SIGTERM: the FMUs are terminated and
    freed and the extracted folders removed before exiting.
    """
    try:
        with interrupt.handle_signals():
            with Master(args.system, scheme=args.scheme, record=args.record) as master:
                result = master.simulate(args.stop_time, args.step,
                                         start_time=args.start_time,
                                         output_every=args.output_every,
                                         progress=False if args.no_progress else None,
                                         realtime=args.realtime)
                units = column_units(master, result.dtype.names)
            interrupt.check()
    except interrupt.Interrupted as stop:
        print(f"sarins cosim: {stop} (FMUs freed, extracted files removed)", file=sys.stderr)
        return interrupt.exit_code(stop.signum)
    except OrchestrationError as error:
        print(f"sarins cosim: {'failed' if isinstance(error, RuntimeError) else 'error'}: {error}", file=sys.stderr)
        return 1 if isinstance(error, RuntimeError) else 2
    print(summary(result))
    realtime = result.meta.get("realtime")
    if realtime is not None:
        print(realtime_summary(realtime))
    if args.output:
        path = write_csv(result, args.output)
        sidecar = Path(str(path) + ".units.json")
        sidecar.write_text(json.dumps(units, indent=1) + "\n")
        print(f"results written to {path} (units in {sidecar.name})")
    return 0


def column_units(master, columns) -> dict:
    """{column: unit} of a result's columns from the FMUs' model descriptions
    ("s" for time, "1" where a variable declares no unit)."""
    units = {"time": "s"}
    index = {name: i for i, name in enumerate(master.names)}
    for column in columns[1:]:
        component, _, variable = column.partition(".")
        found = master.variables[index[component]].get(variable) if component in index else None
        units[column] = (getattr(found, "unit", None) or "1") if found is not None else "1"
    return units


def realtime_summary(report: dict) -> str:
    """One line from ``result.meta['realtime']``: late steps, the lag distribution, the least slack."""
    head = f"real time (factor {report['factor']:g}): "
    slack = report.get("min_slack_s")
    margin = "" if slack is None else f"; least slack {slack:.6f} s"
    if not report["late_steps"]:
        return head + f"no step late in {report['steps']} steps" + margin
    return (head + f"{report['late_steps']} of {report['steps']} steps late; lag p50 "
            f"{report['lag_p50_s']:.6f} s, p99 {report['lag_p99_s']:.6f} s, p99.9 {report['lag_p999_s']:.6f} s, "
            f"max {report['max_lag_s']:.6f} s at simulated t = {report['max_lag_time']:.9g} s" + margin)
