"""Issue 27's acceptance table: every FMU ``sarins build-fmus`` writes on every platform and compile line.

For each FMU (FMI 2.0, the FMI 3.0 variants, the system FMUs of ``build-fmus --system``) a fixed short
case (the workloads of tests/test_portable_fmus.py where the FMU has one, else its default parameters and
inputs for 50 steps of 1 s, of 0.01 s for GNSSReceiver, AidedINS and TrajectoryIMU; IMULog plays a synthetic 1 Hz log of
120 samples; every scalar Real/Float64 output) runs

- linux64: the shipped x86-64 Linux binary through the project's C host (tests/native_host/) under env -i,
- glibc max: the newest ``GLIBC_`` symbol version the linux64 binary references (objdump -T),
- fmusim: the FMI project's simulator under env -i (--fmusim or $FMUSIM; skipped with the reason),
- win64: the shipped Windows DLL through the mingw-built host under wine,
- aarch64: the shipped aarch64-linux binary through the aarch64 host under qemu-user,
- its own ``sources/`` built with gcc and clang at -O0/-O3, with and without -march=native
  (``-Wall -Wextra -Wpedantic -Werror``), through the C host under env -i.

Each cell is the largest relative difference of any output at any step against the linux64 run (0: bit
identical; fmusim prints ``%.16g``, so a 1-ulp rounding there is the CSV's) or the reason it did not run.

    PYTHONPATH=$PWD python3 benchmarks/platform_table.py [--fmu-dir DIR] [--fmusim PATH] [--only NAME...]
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
for _p in (ROOT, ROOT / "tests"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

from fmpy import read_model_description  # noqa: E402

from fmus.native_fmu import AARCH64, ARM_PLATFORM, MINGW, fmi_headers_dir  # noqa: E402
from sarins.systems import SYSTEM_FMUS  # noqa: E402
from test_native_fmus import CASES, HOST_SRC, table  # noqa: E402
from test_portable_fmus import (ARM_SYSROOT, HOST3_SRC, IMU_CASE, QEMU, STEPS, VEHICLE_CASE, _compile,  # noqa: E402
                                glibc_versions)

# the workloads' parameters (tests/test_portable_fmus.py); any other FMU runs its defaults
SETTINGS = {"Turntable": CASES["dual-axis chamber"], "IMUThermal": IMU_CASE, "VehicleMotion": VEHICLE_CASE}
DEFAULT_STEPS = 50
STEP_SIZES = {"AidedINS": 0.01, "GNSSReceiver": 0.01, "TrajectoryIMU": 0.01}  # s: FMUs whose contract needs a shorter step than 1 s
LOG_ROWS = 120  # samples of the synthetic 1 Hz log the IMULog row plays
LINES = [(cc, opt, arch) for cc in ("gcc", "clang") for opt in ("-O0", "-O3") for arch in ("", "-march=native")]
PLATFORMS = {"2.0": {"linux64": ("linux64", ".so"), "win64": ("win64", ".dll"), "aarch64": (ARM_PLATFORM, ".so")},
             "3.0": {"linux64": ("x86_64-linux", ".so"), "win64": ("x86_64-windows", ".dll"),
                     "aarch64": (ARM_PLATFORM, ".so")}}
TYPE_CODES = {"Real": "r", "Float64": "r", "Integer": "i", "Int32": "i", "String": "s"}


def line_name(line) -> str:
    cc, opt, arch = line
    return f"{cc} {opt}" + (" native" if arch else "")


COLUMNS = ["linux64", "glibc max", "fmusim", "win64", "aarch64", *(line_name(l) for l in LINES)]


class RunFailed(Exception):
    """A run or a build that gave no rows; the message is the table cell."""


@dataclass
class Row:
    """One FMU's line: ``cells`` column -> text (a difference or a reason)."""

    name: str
    fmi: str
    system: bool
    cells: dict[str, str] = field(default_factory=dict)


@dataclass
class Case:
    """The fixed short case of one FMU: steps of 1 s, parameter settings, the scalar outputs compared."""

    steps: int
    settings: dict
    outputs: list[str]
    step: float = 1.0  # s, the communication step


def case_of(name: str, md, work: Path | None = None) -> Case:
    """The FMU's case; the IMULog's needs ``work``, where its log is written."""
    by_name = {v.name: v for v in md.modelVariables}
    settings = {k: v for k, v in SETTINGS.get(name, {}).items() if k in by_name}
    steps = STEPS.get(name) or DEFAULT_STEPS
    if name == "IMULog":
        if work is None:
            raise ValueError("the IMULog case writes a log: give case_of a work folder")
        settings["log_file"] = synthetic_log(work / "platform_log.csv")
        steps = LOG_ROWS - 1
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.type in ("Real", "Float64")
               and not getattr(v, "dimensions", None)]
    return Case(steps, settings, outputs, STEP_SIZES.get(name, 1.0))


def synthetic_log(path: Path) -> Path:
    """A 1 Hz log of LOG_ROWS samples (format 1, %.17g) whose increments and temperatures vary per sample:
    slow sines with incommensurate periods, so a wrong row or column shows in every output."""
    from sarins_fmu.imu_log import write_log

    k = np.arange(1, LOG_ROWS + 1, dtype=float)
    wave = np.sin(np.outer(k, [0.11, 0.13, 0.17, 0.19, 0.23, 0.29]))
    temps = 25.0 + np.sin(np.outer(k, np.arange(1.0, 7.0) * 0.05))
    return write_log(path, k, 1e-5 * wave[:, :3], 9.8 * np.array([0.0, 0.0, 1.0]) + 1e-3 * wave[:, 3:],
                     lat_deg=28.222, temps=temps)


def host_value(value, platform: str):
    """A setting as the host on ``platform`` passes it: a path under wine is seen on drive Z:."""
    if isinstance(value, Path):
        return f"Z:{value.resolve().as_posix()}" if platform == "win64" else str(value)
    return value


def host_args(md, case: Case, platform: str = "linux64") -> list[str]:
    """The C hosts' arguments (tests/native_host/): settings, then the outputs to print."""
    vr = {v.name: v for v in md.modelVariables}
    args = [f"{TYPE_CODES[vr[n].type]}{vr[n].valueReference}={host_value(value, platform)}"
            for n, value in case.settings.items()]
    args.append("out=" + ",".join(str(vr[n].valueReference) for n in case.outputs))
    if md.fmiVersion.startswith("3"):
        args.append(f"nout={len(case.outputs)}")
    return args


def _short(text: str) -> str:
    lines = [ln.strip() for ln in text.strip().splitlines() if ln.strip()]
    return (lines[-1] if lines else "no output")[:140].replace("|", "/")


def run_host(cmd: list[str], env=None, timeout=600) -> dict[int, np.ndarray]:
    """{steps done: outputs as float64} from a C host run, or RunFailed with the reason."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        raise RunFailed(f"timeout {timeout} s") from None
    status = [ln for ln in proc.stdout.splitlines() if ln.startswith("STATUS")]
    logs = [ln.split(None, 3)[-1] for ln in proc.stdout.splitlines() if ln.startswith("LOG ")]
    if proc.returncode != 0 or status:
        raise RunFailed(_short(" ".join(status[:1] + logs[-1:]) or proc.stderr or proc.stdout)
                        + ("" if proc.returncode == 0 else f" (exit {proc.returncode})"))
    rows = table(proc)
    if not rows:
        raise RunFailed("no output rows")
    return {k: np.array(v, dtype=np.uint64).view(np.float64) for k, v in rows.items()}


def max_rel(rows: dict, ref: dict) -> float:
    """Largest |x - ref| / |ref| over the steps both runs have (0 where both are equal, NaN included)."""
    if sorted(rows) != sorted(ref):
        raise RunFailed(f"{len(rows)} rows, linux64 {len(ref)}")
    x = np.array([rows[k] for k in sorted(ref)])
    y = np.array([ref[k] for k in sorted(ref)])
    same = (x == y) | (np.isnan(x) & np.isnan(y))
    rel = np.where(same, 0.0, np.abs(x - y) / np.maximum(np.abs(y), 1e-300))
    return float(np.max(rel)) if rel.size else 0.0


def fmt(value: float) -> str:
    return "0" if value == 0.0 else f"{value:.2g}"


class Hosts:
    """The C hosts, built once per table: (fmi, platform) -> (command prefix, executable) or a reason."""

    def __init__(self, work: Path):
        self.work = work
        self.cache: dict = {}
        self.wine_env: dict | str | None = None

    def _build(self, fmi: str, platform: str):
        src = HOST_SRC if fmi == "2.0" else HOST3_SRC
        headers = f"-I{fmi_headers_dir(2 if fmi == '2.0' else 3)}"
        flags = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", headers, str(src)]
        exe = self.work / f"host{fmi[0]}_{platform}"
        if platform == "linux64":
            cmd, prefix = ["gcc", *flags, "-ldl", "-o", str(exe)], ["env", "-i"]
        elif platform == "win64":
            if not shutil.which(MINGW) or not shutil.which("wine"):
                raise RunFailed(f"{MINGW} or wine not installed")
            exe = exe.with_suffix(".exe")
            cmd, prefix = [MINGW, *flags, "-static", "-o", str(exe)], ["wine"]
        else:
            if not shutil.which(AARCH64) or not shutil.which("qemu-aarch64") or not Path(ARM_SYSROOT).is_dir():
                raise RunFailed(f"{AARCH64}, qemu-aarch64 or {ARM_SYSROOT} missing")
            cmd, prefix = [AARCH64, *flags, "-ldl", "-o", str(exe)], list(QEMU)
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RunFailed("host build: " + _short(proc.stderr))
        return prefix, exe

    def get(self, fmi: str, platform: str):
        key = (fmi, platform)
        if key not in self.cache:
            try:
                self.cache[key] = self._build(fmi, platform)
            except RunFailed as err:
                self.cache[key] = str(err)
        if isinstance(self.cache[key], str):
            raise RunFailed(self.cache[key])
        return self.cache[key]

    def env(self, platform: str):
        if platform != "win64":
            return None
        if self.wine_env is None:
            env = dict(os.environ, WINEPREFIX=str(self.work / "wineprefix"), WINEDEBUG="-all")
            proc = subprocess.run(["wine", "wineboot", "--init"], env=env, capture_output=True, timeout=600)
            self.wine_env = env if proc.returncode == 0 else f"wineboot: exit {proc.returncode}"
        if isinstance(self.wine_env, str):
            raise RunFailed(self.wine_env)
        return self.wine_env


def resource_arg(md, resources: Path | None, platform: str) -> list[str]:
    """The hosts' ``res=`` op: FMI 2.0 a file URI, FMI 3.0 a path ending in a separator; under wine the
    folder is seen on drive Z:."""
    if resources is None:
        return []
    path = resources.resolve().as_posix()
    if md.fmiVersion.startswith("3"):
        return [f"res=Z:{path.replace('/', chr(92))}{chr(92)}" if platform == "win64" else f"res={path}/"]
    return [f"res=file:///Z:{path}" if platform == "win64" else f"res=file://{path}"]


def run_binary(hosts: Hosts, md, case: Case, binary: Path, platform: str, resources: Path | None = None) -> dict:
    if not binary.is_file():
        raise RunFailed(f"no {binary.parent.name}/{binary.name}")
    prefix, exe = hosts.get(md.fmiVersion, platform)
    cmd = [*prefix, str(exe), str(binary), md.guid, str(case.steps), repr(case.step), *host_args(md, case, platform),
           *resource_arg(md, resources, platform)]
    return run_host(cmd, env=hosts.env(platform))


def run_fmusim(fmusim: str | None, fmu: Path, case: Case, work: Path) -> dict:
    """The case in fmusim under env -i: {steps done: outputs}, from its CSV (``%.16g``)."""
    if not fmusim or not Path(fmusim).is_file():
        raise RunFailed("fmusim absent (--fmusim / $FMUSIM; build: shared/FACTS.md)")
    out = work / f"{fmu.stem}_fmusim.csv"
    cmd = ["env", "-i", fmusim, "--interface-type", "cs", "--stop-time", repr(case.steps * case.step),
           "--output-interval", repr(case.step), "--output-file", str(out)]
    for name, value in case.settings.items():
        cmd += ["--start-value", name, str(host_value(value, "linux64"))]
    for name in case.outputs:
        cmd += ["--output-variable", name]
    try:
        proc = subprocess.run([*cmd, str(fmu)], capture_output=True, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        raise RunFailed("fmusim timeout 600 s") from None
    if proc.returncode != 0 or not out.is_file():
        raise RunFailed(f"fmusim exit {proc.returncode}: " + _short(proc.stderr or proc.stdout))
    with open(out, newline="") as f:
        reader = csv.reader(f)
        header = [h.strip().strip('"') for h in next(reader)]
        cols = [header.index(n) for n in case.outputs]
        rows = {}
        for r in reader:
            rows[int(round(float(r[0]) / case.step))] = np.array([float(r[c]) for c in cols])
    return rows


def compile_sources(folder: Path, identifier: str, line, work: Path) -> Path:
    cc, opt, arch = line
    if not shutil.which(cc):
        raise RunFailed(f"{cc} not installed")
    if not (folder / "sources").is_dir():
        raise RunFailed("no sources/")
    out = work / line_name(line).replace(" ", "_")
    out.mkdir(parents=True, exist_ok=True)
    try:
        return _compile(folder / "sources", identifier, cc, [f for f in (opt, arch) if f], out)
    except AssertionError as err:
        raise RunFailed("build: " + _short(str(err))) from None


def platform_row(fmu: Path, work: Path, hosts: Hosts, fmusim: str | None = None, lines=LINES,
                 jobs: int = 2, others=("fmusim", "win64", "aarch64")) -> Row:
    """One FMU on every platform and compile line (the module docstring's columns); ``lines`` and
    ``others`` (of fmusim, win64, aarch64) choose the columns run, the rest stay "-"."""
    md = read_model_description(str(fmu))
    fmi = "3.0" if md.fmiVersion.startswith("3") else "2.0"
    identifier = md.coSimulation.modelIdentifier
    row = Row(md.modelName if fmu.stem not in SYSTEM_FMUS else fmu.stem, fmi, fmu.stem in SYSTEM_FMUS)
    folder = work / f"{fmu.stem}_{fmi[0]}"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    case = case_of(fmu.stem, md, folder)
    res = folder / "resources" if (folder / "resources").is_dir() else None
    binary = {p: folder / "binaries" / d / f"{identifier}{ext}" for p, (d, ext) in PLATFORMS[fmi].items()}
    try:
        ref = run_binary(hosts, md, case, binary["linux64"], "linux64", res)
        row.cells["linux64"] = f"{len(ref) - 1} steps x {len(case.outputs)}"
    except RunFailed as err:
        row.cells = {c: "-" for c in COLUMNS} | {"linux64": str(err)}
        return row
    versions = glibc_versions(binary["linux64"]) if shutil.which("objdump") else set()
    row.cells["glibc max"] = ".".join(map(str, max(versions))) if versions else "objdump missing"

    def cell(fn) -> str:
        try:
            return fmt(max_rel(fn(), ref))
        except RunFailed as err:
            return str(err)

    if "fmusim" in others:
        row.cells["fmusim"] = cell(lambda: run_fmusim(fmusim, fmu, case, folder))
    for p in [p for p in ("win64", "aarch64") if p in others]:
        row.cells[p] = cell(lambda p=p: run_binary(hosts, md, case, binary[p], p, res))

    def source_cell(line) -> str:
        return cell(lambda: run_binary(hosts, md, case, compile_sources(folder, identifier, line, folder),
                                       "linux64", res))

    with ThreadPoolExecutor(max(1, jobs)) as pool:
        for line, text in zip(lines, pool.map(source_cell, lines)):
            row.cells[line_name(line)] = text
    return row


def build_all(out: Path) -> list[Path]:
    """``sarins build-fmus --system`` into out/fmi2 and ``--fmi 3`` into out/fmi3: the FMUs they write."""
    for args in (["--system", "--out", str(out / "fmi2")], ["--fmi", "3", "--out", str(out / "fmi3")]):
        subprocess.run([sys.executable, "-m", "sarins", "build-fmus", *args], check=True, cwd=ROOT,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)), stdout=subprocess.DEVNULL)
    return find_fmus(out)


def find_fmus(folder: Path) -> list[Path]:
    """Every .fmu under ``folder``: FMI 2.0 first, system FMUs last, by name."""
    found = sorted(p for p in folder.rglob("*.fmu") if not p.name.endswith(".tmp.fmu"))
    return sorted(found, key=lambda p: (p.stem in SYSTEM_FMUS, "fmi3" in p.parts or "fmus3" in p.parts, p.stem))


def markdown(rows: list[Row]) -> str:
    head = ["FMU", "FMI", *COLUMNS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        name = f"{r.name} (system)" if r.system else r.name
        lines.append("| " + " | ".join([name, r.fmi, *(r.cells.get(c, "-") for c in COLUMNS)]) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fmu-dir", type=Path, help="take the .fmu files under this folder instead of building")
    ap.add_argument("--fmusim", default=os.environ.get("FMUSIM"), help="fmusim executable (default $FMUSIM)")
    ap.add_argument("--only", nargs="+", metavar="NAME", help="only these FMUs (file stems)")
    ap.add_argument("--jobs", type=int, default=2, help="compile lines in parallel (default 2)")
    ap.add_argument("--out", type=Path, help="also write the table to this file")
    args = ap.parse_args(argv)
    if args.fmu_dir is not None and not args.fmu_dir.is_dir():
        print(f"--fmu-dir {args.fmu_dir}: not a folder", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="platform_table_") as tmp:
        work = Path(tmp)
        fmus = find_fmus(args.fmu_dir) if args.fmu_dir else build_all(work / "fmus")
        if args.only:
            fmus = [f for f in fmus if f.stem in args.only]
        hosts = Hosts(work)
        rows = []
        for fmu in fmus:
            rows.append(platform_row(fmu, work, hosts, args.fmusim, jobs=args.jobs))
            print(f"{rows[-1].name} FMI {rows[-1].fmi}: done", file=sys.stderr, flush=True)
    text = markdown(rows)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
