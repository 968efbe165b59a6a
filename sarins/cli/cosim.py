"""``sarins cosim SYSTEM ...``: run an SSP system with the generic master (orchestration)."""
from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path

import numpy as np

from orchestration import interrupt
from orchestration.errors import OrchestrationError, ScheduleError
from orchestration.master import SCHEMES, Master
from orchestration.recorder import write_csv
from sarins_fmu.files import check_output_path

from . import finite

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
        "cosim", help="co-simulate an SSP system of FMI 2.0 / 3.0 co-simulation FMUs",
        description="Run an .ssp archive or SystemStructure.ssd (or its folder) with the "
                    "fixed-step master and print the final values of the recorded outputs.")
    parser.add_argument("system", help="system file: x.ssp, SystemStructure.ssd or its folder")
    parser.add_argument("--stop-time", type=finite, default=None, metavar="T",
                        help="stop time, s (default: the system's DefaultExperiment)")
    parser.add_argument("--start-time", type=finite, default=None, metavar="T0",
                        help="start time, s (default: the system's, else 0)")
    parser.add_argument("--step", type=finite, default=None, metavar="H",
                        help="communication step, s (default: the system's, else the "
                             "FMUs' DefaultExperiment stepSize)")
    parser.add_argument("--scheme", choices=SCHEMES, default="gauss-seidel",
                        help="coupling scheme (default: gauss-seidel)")
    parser.add_argument("--record", action="append", default=None, metavar="NAME",
                        help="component.variable or pattern to record (repeatable; "
                             "default: all outputs)")
    parser.add_argument("--output-every", type=int, default=1, metavar="N",
                        help="record every Nth step (default: 1)")
    parser.add_argument("--output", default=None, metavar="CSV",
                        help="write results to CSV (a regular file or a new path; an interrupted "
                             "run writes the rows so far and ends the file with a line "
                             "'# interrupted by SIG... at t = T s')")
    parser.add_argument("--realtime", type=finite, default=None, metavar="FACTOR",
                        help="pace the run: wall-clock seconds per simulated second (the "
                             "clock starts after initialisation; the lag distribution is reported)")
    parser.add_argument("--no-progress", action="store_true", help="never show a progress bar")
    parser.add_argument("--profile", action="store_true",
                        help="print where a step's time goes: each FMU's doStep, gets and sets, the "
                             "conversions, recording and the master's own work (not with --realtime)")
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


OPTIONS = {"start_time": "--start-time", "stop_time": "--stop-time", "step_size": "--step",
           "output_every": "--output-every", "realtime": "--realtime"}  # Master.simulate's arguments -> this command's options
INTERRUPTED_MARK = "# interrupted by"  # first words of the last line of an interrupted run's CSV


def _schedule_message(error: ScheduleError, args: argparse.Namespace) -> str:
    """The schedule error prefixed by the options (or the system file) that set the values at fault."""
    given = [f"{OPTIONS[n]} {_option_value(args, n):g}" for n in error.names
             if n in OPTIONS and _option_value(args, n) is not None]
    if given:
        return f"{', '.join(given)}: {error}"
    if error.names:
        return f"the system file's DefaultExperiment: {error}"
    return str(error)


def _option_value(args: argparse.Namespace, name: str):
    value = getattr(args, {"step_size": "step"}.get(name, name))
    return None if name == "output_every" and value == 1 else value  # 1: the default


def run(args: argparse.Namespace) -> int:
    """Run the ``cosim`` subcommand; return the process exit code.

    Exit codes: 0 success, 2 a system-description or schedule error (bad input, naming the
    option or file), 1 an FMU failure or a write that failed for want of room, 130 / 143
    stopped by SIGINT (Ctrl-C) / SIGTERM: the FMUs are terminated and freed and the
    extracted folders removed before exiting; with ``--output`` the rows recorded so far
    are written, the file's last line saying where the run was interrupted.
    """
    if args.profile and args.realtime is not None:
        print("sarins cosim: error: --profile measures the compiled loop, which --realtime does not use; "
              "give one of them", file=sys.stderr)
        return 2
    if args.output:
        check_output_path(args.output, "--output")
        check_output_path(str(args.output) + ".units.json", "--output (its units sidecar)")
    masters = []
    try:
        with interrupt.handle_signals():
            with Master(args.system, scheme=args.scheme, record=args.record) as master:
                masters.append(master)
                result = master.simulate(args.stop_time, args.step,
                                         start_time=args.start_time,
                                         output_every=args.output_every,
                                         progress=False if args.no_progress else None,
                                         realtime=args.realtime, profile=args.profile)
                units = column_units(master, result.dtype.names)
            _check_late_signal(result)
    except interrupt.Interrupted as stop:
        units = column_units(masters[0], stop.partial.dtype.names) if stop.partial is not None else {}
        print(f"sarins cosim: {_interrupted(stop, args.output, units)} (FMUs freed, extracted "
              "files removed)", file=sys.stderr)
        return interrupt.exit_code(stop.signum)
    except ScheduleError as error:
        print(f"sarins cosim: error: {_schedule_message(error, args)}", file=sys.stderr)
        return 2
    except OrchestrationError as error:
        # a run that failed (an FMU error while running) is 1; a bad file (incl. an FMU that refuses to be
        # instantiated: FMUInstantiateError is a ValueError) is 2
        failed = isinstance(error, RuntimeError) and not isinstance(error, ValueError)
        print(f"sarins cosim: {'failed' if failed else 'error'}: {error}", file=sys.stderr)
        return 1 if failed else 2
    print(summary(result))
    realtime = result.meta.get("realtime")
    if realtime is not None:
        print(realtime_summary(realtime))
    if "profile" in result.meta:
        print(profile_summary(result.meta["profile"]))
    if args.output:
        path, sidecar = write_output(result, args.output, units)
        print(f"results written to {path} (units in {sidecar.name})")
    return 0


def write_output(result, output, units: dict, mark: str | None = None) -> tuple[Path, Path]:
    """Write the CSV (and ``mark`` as its last line) and the units sidecar, each through a
    temporary file renamed into place; return both paths."""
    from sarins.results import atomic_output

    path, sidecar = Path(output), Path(str(output) + ".units.json")
    with atomic_output(path, keep_suffix=True) as tmp:
        write_csv(result, tmp)
        if mark is not None:
            with open(tmp, "a") as stream:
                stream.write(mark + "\n")
    with atomic_output(sidecar) as tmp:
        tmp.write_text(json.dumps(units, indent=1) + "\n")
    return path, sidecar


def _check_late_signal(result) -> None:
    """A signal that came after the last step still stops the command (with every row)."""
    try:
        interrupt.check()
    except interrupt.Interrupted as stop:
        result.meta.update(interrupted_at=float(result["time"][-1]),
                           signal=signal.Signals(stop.signum).name)
        stop.partial = result
        raise


def _interrupted(stop: interrupt.Interrupted, output, units: dict) -> str:
    """What the stop message says: the time reached and, with --output, the rows written."""
    partial = stop.partial
    if partial is None:
        return f"{stop} before the first communication step"
    reached = partial.meta["interrupted_at"]
    text = f"{stop}: interrupted at t = {reached:.9g} s"
    if output:
        mark = (f"{INTERRUPTED_MARK} {partial.meta['signal']} at t = {reached:.9g} s: the rows "
                f"above are the run up to t = {partial['time'][-1]:.9g} s")
        try:
            path, _ = write_output(partial, output, units, mark)
        except OSError as error:  # the stop's status stands; say what was lost
            return text + f"; the {len(partial)} rows recorded so far could not be written: " \
                          f"{' '.join(str(error).split())}"
        text += f"; the {len(partial)} rows recorded so far are in {path}, its last line marks the stop"
    return text


def column_units(master, columns) -> dict:
    """{column: unit} of a result's columns from the FMUs' model descriptions
    ("s" for time, "1" where a variable declares no unit); each element column
    ``name[k]`` of an FMI 3.0 array gets the array's unit."""
    units = {"time": "s"}
    index = {name: i for i, name in enumerate(master.names)}
    for column in columns[1:]:
        component, _, variable = column.partition(".")
        known = master.variables[index[component]] if component in index else {}
        found = known.get(variable)
        if found is None and variable.endswith("]"):
            found = known.get(variable[:variable.rfind("[")])
        units[column] = (getattr(found, "unit", None) or "1") if found is not None else "1"
    return units


def profile_summary(profile: dict) -> str:
    """Text table of :meth:`orchestration.Master.simulate`'s profile, in microseconds per step."""
    steps = max(1, profile["steps"])
    per_step = 1e6 / steps
    rows = [(f"{name}.{part}", seconds) for name, parts in profile["components"].items()
            for part, seconds in parts.items() if seconds > 0.0]
    rows += [("conversions", profile["conversions_s"]), ("recording", profile["record_s"]),
             ("master (the rest)", profile["master_s"])]
    width = max(len(label) for label, _ in rows)
    lines = [f"profile: {profile['wall_s']:.3f} s for {profile['steps']} steps = "
             f"{profile['wall_s'] * per_step:.2f} us/step"]
    lines += [f"  {label:<{width}}  {seconds * per_step:8.2f} us/step  {100 * seconds / profile['wall_s']:5.1f} %"
              for label, seconds in rows if seconds > 0.0 or label.startswith("master")]
    return "\n".join(lines)


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
