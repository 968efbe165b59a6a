"""Fault injection through the CLI: files (issue 21).  Slow: about 40 subprocesses.

Each case builds a faulty input (an SSP whose component source leaves it, a
zip bomb, a FIFO where an output goes, a damaged NPZ log, a schedule option
out of range, a mistyped SSD connector, a signal mid-run, a full disk), runs
``python -m sarins ...`` in a subprocess with a timeout and classifies the
outcome:

* clean -- the expected exit status, one line on stderr naming what it must
  (the option, file or component), no traceback, and the case's own check
  (e.g. the interrupted run's CSV holds its rows and the marker);
* wrong status -- another non-zero status, or a message that is not one
  clean line or does not name what it must;
* silently accepted -- exit 0 where a refusal was due, or the case's check
  fails (rows lost);
* hang -- the timeout expired;
* crash -- killed by a signal, a traceback or an ``internal error``.

The table is printed (``-s``); the test asserts every case is clean.  Set
``FAULT_INJECTION_ROOT`` to run the same cases against another checkout
(``FAULT_INJECTION_TIMEOUT``: seconds per case, ``FAULT_INJECTION_CATEGORIES``:
a comma-separated subset).
Signals and a full disk are injected by a small wrapper that patches the
process before it calls ``sarins.cli.main`` (a callback that sends the
signal after step 5; ``open`` redirected to ``/dev/full``), so they behave
the same on any version of the code.
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import zipfile
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import pytest

from file_faults import fifo, good_log, npz_bomb, sparse_file, ssd_text, system_folder
from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from orchestration import write_ssp

pytestmark = [pytest.mark.slow, pytest.mark.integration]

ROOT = Path(os.environ.get("FAULT_INJECTION_ROOT", Path(__file__).resolve().parents[1]))
TIMEOUT = float(os.environ.get("FAULT_INJECTION_TIMEOUT", 120))  # s per case
MEMORY_LIMIT = 3 * 2**30  # address space of a case fed a bomb
OUTCOMES = ("clean", "wrong status", "silently accepted", "hang", "crash")

SIGNAL_WRAPPER = """
import os, signal, sys
from orchestration.master import Master
simulate = Master.simulate
def patched(self, *args, callback=None, **kwargs):
    done = [0]
    def hook(time, master):
        done[0] += 1
        if done[0] == 5:
            os.kill(os.getpid(), signal.{signal})
    return simulate(self, *args, callback=hook, **kwargs)
Master.simulate = patched
from sarins.cli import main
sys.exit(main(sys.argv[1:]))
"""

FULL_DISK_WRAPPER = """
import builtins, pathlib, sys
real_open, real_path_open = builtins.open, pathlib.Path.open
def full(name):
    return str(name).endswith(".csv")
def fake_open(file, mode="r", *args, **kwargs):
    return real_open("/dev/full" if "w" in mode and full(file) else file, mode, *args, **kwargs)
def fake_path_open(self, mode="r", *args, **kwargs):
    if "w" in mode and full(self):
        return real_open("/dev/full", mode, *args, **kwargs)
    return real_path_open(self, mode, *args, **kwargs)
import sarins_fmu.imu_log
sarins_fmu.imu_log.open = fake_open
pathlib.Path.open = fake_path_open
from sarins.cli import main
sys.exit(main(sys.argv[1:]))
"""


@dataclass
class Case:
    category: str
    name: str
    make: Callable[[Path], list]  # tmp folder -> argv after "sarins"
    status: int = 2
    needle: Callable[[Path], str] | str = ""  # must appear in the one stderr line
    wrapper: str | None = None  # python source run instead of "-m sarins"
    bomb: bool = False  # limit the address space
    check: Callable[[Path], bool] | None = None
    extra: dict = field(default_factory=dict)


def _ssp_with_ramp_source(tmp: Path, fmus: dict, source: str) -> Path:
    from orchestration import Component, Connection, System

    system = System("rg", [Component("ramp", fmus["Ramp"], {"slope": 2.0}), Component("gain", fmus["Gain"])],
                    [Connection.between("ramp.y", "gain.u"), Connection.between("ramp.count", "gain.n_in"),
                     Connection.between("ramp.positive", "gain.flag_in")])
    archive = write_ssp(system, tmp / "evil.ssp")
    with zipfile.ZipFile(archive) as old:
        members = {n: old.read(n) for n in old.namelist()}
    ssd = members.pop("SystemStructure.ssd").decode().replace('source="resources/Ramp.fmu"', f'source="{source}"')
    with zipfile.ZipFile(archive, "w") as new:
        new.writestr("SystemStructure.ssd", ssd)
        for name, data in members.items():
            new.writestr(name, data)
    return archive


def _outside(tmp: Path) -> Path:
    return fifo(tmp / "outside" / "Turntable.fmu")


def _cosim(system, *options) -> list:
    return ["cosim", system, "--no-progress", *options]


def _interrupted_csv(tmp: Path) -> bool:
    path = tmp / "out.csv"
    if not path.is_file():
        return False
    lines = path.read_text().splitlines()
    return len(lines) > 3 and lines[0].startswith("time,") and lines[-1].startswith("# interrupted by")


def _damaged_log(tmp: Path, how: str) -> Path:
    path = good_log(tmp / "log.npz")
    data = path.read_bytes()
    if how == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif how == "corrupted":
        third = len(data) // 3
        path.write_bytes(data[:third] + bytes(b ^ 0x5A for b in data[third:third + 64]) + data[third + 64:])
    else:
        path.write_bytes(b"not a zip" * 50)
    return path


def cases(fmus: dict) -> list[Case]:
    ssp = lambda tmp, src: _ssp_with_ramp_source(tmp, fmus, src)  # noqa: E731
    ok_ssp = lambda tmp: ssp(tmp, "resources/Ramp.fmu")  # noqa: E731
    run = ("--stop-time", "1", "--step", "0.5")
    out = []
    # security: component sources
    # the archive is extracted into $TMPDIR (the case's folder): "../outside" is the FIFO beside it
    for name, source in (("dot-dot", "../outside/Turntable.fmu"), ("absolute", "ABS"),
                         ("file URI outside", "URI"), ("/etc/passwd", "/etc/passwd"),
                         ("http URI", "http://example.org/Ramp.fmu")):
        def make(tmp, source=source):
            target = _outside(tmp)
            real = {"ABS": str(target), "URI": target.as_uri()}.get(source, source)
            return _cosim(ssp(tmp, real), *run)
        out.append(Case("ssp source", name, make, needle="component 'ramp': source '"))

    def symlink_out(tmp):
        ssd = system_folder(tmp / "system", fmus)
        (ssd.parent / "link.fmu").symlink_to(_outside(tmp))
        ssd.write_text(ssd_text(ramp="link.fmu"))
        return _cosim(ssd.parent, *run)
    out.append(Case("ssp source", "symlink leaving the folder", symlink_out, needle="component 'ramp': source '"))
    # size budgets
    for command in ("allan", "replay"):
        out.append(Case("size budget", f"8 MB NPZ log -> 8 GiB ({command})",
                        lambda tmp, c=command: ([c, "--log"] if c == "allan" else [c]) + [npz_bomb(tmp / "bomb.npz", 8192)],
                        needle="limit of 2 GiB", bomb=True))
    out.append(Case("size budget", "CSV log over 2 GiB (sparse)",
                    lambda tmp: ["allan", "--log", sparse_file(tmp / "big.csv", 2**31 + 1, b"# sarins-imu-log 1\n")],
                    needle="MAX_LOG_BYTES", bomb=True))
    out.append(Case("size budget", "SSD over 64 MiB (sparse)",
                    lambda tmp: _cosim(sparse_file(tmp / "big.ssd", 2**26 + 1, b"<?xml version='1.0'?>\n"), *run),
                    needle="MAX_XML_BYTES", bomb=True))

    def description_bomb(tmp):
        ssd = system_folder(tmp / "system", fmus)
        npz_bomb(ssd.parent / "Ramp.fmu", 1024, member="modelDescription.xml")
        return _cosim(ssd.parent, *run)
    out.append(Case("size budget", "FMU whose modelDescription.xml inflates to 1 GiB", description_bomb,
                    needle="limit of 536870912 bytes", bomb=True))
    out.append(Case("size budget", "model file JSON over 256 MiB (sparse)",
                    lambda tmp: ["replay", good_log(tmp / "log.npz"), "--identify",
                                 sparse_file(tmp / "big.json", 2**28 + 1, b"{")],
                    needle="MAX_JSON_BYTES", bomb=True))
    out.append(Case("size budget", "model file NPZ -> 1 GiB",
                    lambda tmp: ["replay", good_log(tmp / "log.npz"), "--compensator",
                                 npz_bomb(tmp / "model.npz", 1024, member="__header__.npy")],
                    needle="MAX_NPZ_BYTES", bomb=True))
    # outputs that are not regular files
    data = lambda tmp: _table(tmp)  # noqa: E731
    out += [
        Case("output", "navigate --write-log FIFO",
             lambda tmp: ["navigate", "--align-hours", "0.2", "--nav-hours", "0.01", "--write-log", fifo(tmp / "f.csv")],
             needle="--write-log"),
        Case("output", "cosim --output FIFO", lambda tmp: _cosim(ok_ssp(tmp), *run, "--output", fifo(tmp / "f.csv")),
             needle="--output"),
        Case("output", "cosim --output folder", lambda tmp: _cosim(ok_ssp(tmp), *run, "--output", tmp),
             needle="--output"),
        Case("output", "allan --plot FIFO", lambda tmp: ["allan", "--hours", "0.5", "--plot", fifo(tmp / "a.png")],
             needle="--plot"),
        Case("output", "identify train --out FIFO",
             lambda tmp: ["identify", "train", "--data", data(tmp), "--inputs", "a", "--target", "y",
                          "--out", fifo(tmp / "m.json")], needle="--out"),
    ]
    # damaged NPZ logs
    for how in ("truncated", "corrupted", "not a zip"):
        out.append(Case("npz log", f"{how} (allan)", lambda tmp, h=how: ["allan", "--log", _damaged_log(tmp, h)],
                        needle=lambda tmp: str(tmp / "log.npz")))
        out.append(Case("npz log", f"{how} (replay)", lambda tmp, h=how: ["replay", _damaged_log(tmp, h)],
                        needle=lambda tmp: str(tmp / "log.npz")))
    # schedule options
    for options, needle in ((("--stop-time", "inf", "--step", "0.5"), "--stop-time"),
                            (("--stop-time", "nan", "--step", "0.5"), "--stop-time"),
                            (("--stop-time", "1e300", "--step", "0.5"), "--stop-time 1e+300"),
                            (("--stop-time", "1", "--step", "1e-300"), "--step 1e-300"),
                            (("--stop-time", "1", "--step", "0.5", "--start-time", "inf"), "--start-time")):
        out.append(Case("cosim options", " ".join(options), lambda tmp, o=options: _cosim(ok_ssp(tmp), *o),
                        needle=needle))
    # the SSD
    out.append(Case("ssd", "two schema errors", lambda tmp: _cosim(system_folder(
        tmp / "s", fmus, ramp_connectors='<ssd:Connectors><ssd:Connector name="y" kind="sideways"/></ssd:Connectors>',
        ramp_extra="<ssd:Bogus/>").parent, *run), needle="SystemStructure.ssd"))
    for declared in ("String", "Integer"):
        out.append(Case("ssd", f"connector declared {declared} for a Real", lambda tmp, d=declared: _cosim(system_folder(
            tmp / "s", fmus, ramp_connectors=f'<ssd:Connectors><ssd:Connector name="y" kind="output"><ssc:{d}/>'
                                             '</ssd:Connector></ssd:Connectors>').parent, *run),
            needle=f"declared {declared}"))
    # interrupted co-simulation
    for signame, status in (("SIGINT", 130), ("SIGTERM", 143)):
        out.append(Case("interrupt", f"{signame} after step 5 with --output",
                        lambda tmp: _cosim(ok_ssp(tmp), "--stop-time", "100", "--step", "0.5", "--output",
                                           tmp / "out.csv"),
                        status=status, needle="interrupted at t =", check=_interrupted_csv,
                        wrapper=SIGNAL_WRAPPER.replace("{signal}", signame)))
    # a full disk
    out.append(Case("full disk", "cosim --output", lambda tmp: _cosim(ok_ssp(tmp), *run, "--output", tmp / "o.csv"),
                    status=1, needle=lambda tmp: str(tmp / "o.csv"), wrapper=FULL_DISK_WRAPPER))
    out.append(Case("full disk", "navigate --write-log",
                    lambda tmp: ["navigate", "--align-hours", "0.2", "--nav-hours", "0.01", "--write-log", tmp / "l.csv"],
                    status=1, needle=lambda tmp: str(tmp / "l.csv"), wrapper=FULL_DISK_WRAPPER))
    return out


def _table(tmp: Path) -> Path:
    path = tmp / "data.csv"
    path.write_text("a,y\n" + "".join(f"{i},{2 * i}\n" for i in range(5)))
    return path


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run_case(case: Case, tmp: Path) -> tuple[str, str]:
    """Run one case; return (outcome, detail)."""
    tmp.mkdir(parents=True)
    argv = [str(a) for a in case.make(tmp)]
    command = [sys.executable, "-c", case.wrapper, *argv] if case.wrapper else [sys.executable, "-m", "sarins", *argv]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(tmp)}
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT, env=env, cwd=tmp,
                              preexec_fn=_limit_memory if case.bomb else None)
    except subprocess.TimeoutExpired:
        return "hang", f"no exit within {TIMEOUT:g} s"
    err = done.stderr
    lines = [line for line in err.splitlines() if line.strip()]
    detail = f"exit {done.returncode}: {' | '.join(lines)[:300]}"
    if done.returncode < 0 or "Traceback" in err or "internal error" in err:
        return "crash", detail
    if done.returncode == 0 and case.status != 0:
        return "silently accepted", detail
    needle = case.needle(tmp) if callable(case.needle) else case.needle
    if done.returncode != case.status or len(lines) != 1 or needle not in lines[0]:
        return "wrong status", detail
    if case.check is not None and not case.check(tmp):
        return "silently accepted", detail + " (its output check failed)"
    return "clean", detail


def test_file_faults_through_the_cli(fixture_fmus, tmp_path):
    only = [c for c in os.environ.get("FAULT_INJECTION_CATEGORIES", "").split(",") if c]  # e.g. "ssp source"
    results = []
    for i, case in enumerate(cases(fixture_fmus)):
        if only and case.category not in only:
            continue
        outcome, detail = run_case(case, tmp_path / f"case{i:02d}")
        results.append((case, outcome, detail))
    table = Counter()
    for case, outcome, _ in results:
        table[(case.category, outcome)] += 1
    categories = list(dict.fromkeys(case.category for case, _, _ in results))
    print("\ncategory | cases | " + " | ".join(OUTCOMES))
    for category in categories + ["total"]:
        counts = [sum(table[(c, o)] for c in (categories if category == "total" else [category])) for o in OUTCOMES]
        print(f"{category} | {sum(counts)} | " + " | ".join(map(str, counts)))
    for case, outcome, detail in results:
        print(f"  [{outcome}] {case.category}: {case.name}: {detail}")
    bad = [f"{case.category}: {case.name}: {outcome} ({detail})" for case, outcome, detail in results
           if outcome != "clean"]
    assert not bad, "\n".join(bad)
