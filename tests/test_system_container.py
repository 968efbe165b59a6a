"""Our own system container (fmus/c/system_container, issue 27 item 4): the identified static system as one
FMI 2.0 FMU with no Python and no FMPy binary inside.  In C hosts with an empty environment it equals the
master's Jacobi run bit for bit; its Linux binaries need glibc 2.17 at most; a bad plan is an error status
naming the line, never a crash; nothing allocates after initialisation; fmusim runs it; the slow test runs
its win64 DLL under wine and its aarch64 binary under qemu and gets the linux64 numbers."""
from __future__ import annotations

import csv
import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from fmus.cbuild import build_line
from fmus.native_fmu import AARCH64, MINGW, fmi_headers_dir

HERE = Path(__file__).resolve().parent
HOST_SRC = HERE / "native_host" / "native_fmu_host.c"
COUNTER_SRC = HERE / "native_host" / "alloc_counter.c"
ARM_SYSROOT = "/usr/aarch64-linux-gnu"
COMPONENTS = ("Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier")
OUTPUTS = ["ins.lat_error", "ins.position_error", "ins.nav_time", "identifier.axial_drift", "identifier.apply_from"]
STEPS = 2000
GLIBC_BASELINE = (2, 17)


def _cc() -> str:
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    return cc


def _system(folder: Path):
    from sarins.systems import standard_static_identified

    # the identifier fires 600 s into navigation; the INS subtracts the drift from apply_from on
    return standard_static_identified(folder, hours=0.6, turntable=dict(align_time=600.0),
                                      imu=dict(internal_rate=10.0), ins=dict(align_time=600.0),
                                      identifier=dict(trigger_time=600.0, latency=60.0))


@pytest.fixture(scope="module")
def container(fmu_dir, tmp_path_factory):
    """(the .fmu, its unzipped folder, model description, the system) of the identified system packed by our
    container."""
    from fmus.system_container import write_container_fmu
    from orchestration.container import build_container_fmu

    tmp = tmp_path_factory.mktemp("system_container")
    for name in COMPONENTS:
        shutil.copy2(fmu_dir / f"{name}.fmu", tmp / f"{name}.fmu")
    system = _system(tmp)
    fmu = build_container_fmu(system, tmp / "Identified.fmu", step_size=1.0, engine=write_container_fmu)
    folder = tmp / "unzipped"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return fmu, folder, read_model_description(str(fmu)), system


@pytest.fixture(scope="module")
def master(container):
    """The master's Jacobi run of the same system: {output: values at t = 0, 1, ..., STEPS}."""
    from orchestration import simulate_system

    return simulate_system(container[3], float(STEPS), 1.0, scheme="jacobi", record=OUTPUTS, progress=False)


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    out = tmp_path_factory.mktemp("container_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def _uri(folder: Path, windows: bool = False) -> str:
    path = (folder / "resources").resolve().as_posix()
    return f"file:///Z:{path}" if windows else f"file://{path}"


def _run(host, binary, md, folder, *args, prefix=("env", "-i"), steps=STEPS, env=None, windows=False,
         timeout=600) -> subprocess.CompletedProcess:
    cmd = [*prefix, str(host), str(binary), md.guid, str(steps), "1.0", f"res={_uri(folder, windows)}", *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc


def _out_arg(md) -> str:
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    return "out=" + ",".join(str(vrs[n]) for n in OUTPUTS)


def _rows(proc) -> dict[int, list[int]]:
    rows = {}
    for line in proc.stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == "OUT":
            rows[int(parts[1])] = [int(x, 16) for x in parts[2:]]
    return rows


def _bits(x: float) -> int:
    return int(np.array([x], dtype="<f8").view("<u8")[0])


def test_the_build_ships_our_binaries_sources_and_the_plan(container):
    fmu, folder, md, _ = container
    names = zipfile.ZipFile(fmu).namelist()
    assert md.coSimulation.modelIdentifier == "SystemContainer"
    assert md.coSimulation.canGetAndSetFMUstate is False
    assert "binaries/linux64/SystemContainer.so" in names
    for platform, compiler, binary in (("win64", MINGW, "SystemContainer.dll"),
                                       ("aarch64-linux", AARCH64, "SystemContainer.so")):
        assert (f"binaries/{platform}/{binary}" in names) == (shutil.which(compiler) is not None), platform
    assert {"sources/model.c", "sources/fmi2_glue.c", "sources/glue_core.c", "sources/variables.h"} <= set(names)
    assert "resources/container_plan.txt" in names
    assert not any("container.json" in n or "container_fmu" in n for n in names)  # nothing of FMPy's
    for name in COMPONENTS:
        assert f"resources/{name}/modelDescription.xml" in names


def test_in_a_c_host_with_an_empty_environment_it_equals_the_master_jacobi_run(container, master, host):
    """Every step's outputs (the bit patterns) equal the master's Jacobi run, from initialisation on."""
    _, folder, md, _ = container
    proc = _run(host, folder / "binaries" / "linux64" / "SystemContainer.so", md, folder, _out_arg(md))
    assert "STATUS" not in proc.stdout, proc.stdout[-3000:]
    rows = _rows(proc)
    assert sorted(rows) == list(range(STEPS + 1)) and len(master["ins.nav_time"]) == STEPS + 1
    assert master["identifier.axial_drift"][-1] != 0.0  # identified within the run
    assert master["ins.nav_time"][-1] > master["identifier.apply_from"][-1] > 600.0
    for k, name in enumerate(OUTPUTS):
        ours = [rows[s][k] for s in range(STEPS + 1)]
        assert ours == [_bits(x) for x in master[name]], name


def test_fmpy_runs_it_and_gets_the_master_jacobi_run(container, master):
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu

    fmu = container[0]
    assert validate_fmu(str(fmu)) == []
    packed = simulate_fmu(str(fmu), stop_time=float(STEPS), output_interval=1.0, output=OUTPUTS)
    for name in OUTPUTS:
        assert packed[name][-1] == master[name][-1], name


def glibc_versions(path: Path, objdump: str = "objdump") -> set[tuple[int, ...]]:
    out = subprocess.run([objdump, "-T", str(path)], capture_output=True, text=True, check=True).stdout
    return {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", out)}


def test_linux_binaries_need_nothing_newer_than_glibc_2_17(container):
    _, folder, _, _ = container
    binaries = [(folder / "binaries" / "linux64" / "SystemContainer.so", "objdump")]
    arm = folder / "binaries" / "aarch64-linux" / "SystemContainer.so"
    if arm.is_file() and shutil.which("aarch64-linux-gnu-objdump"):
        binaries.append((arm, "aarch64-linux-gnu-objdump"))
    for binary, objdump in binaries:
        versions = glibc_versions(binary, objdump)
        assert versions and max(versions) <= GLIBC_BASELINE, (binary, sorted(versions))
        dynamic = subprocess.run([objdump, "-p", str(binary)], capture_output=True, text=True, check=True).stdout
        assert "libdl.so.2" in dynamic, binary  # dlopen's home before glibc 2.34


def test_nothing_allocates_after_initialisation(container, host, tmp_path):
    _, folder, md, _ = container
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    proc = _run(host, folder / "binaries" / "linux64" / "SystemContainer.so", md, folder, "allocs",
                prefix=(), steps=300, env={"LD_PRELOAD": str(counter)})
    assert "STATUS" not in proc.stdout, proc.stdout[-3000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]


def test_fmu_state_is_refused_with_the_reason(container, host):
    _, folder, md, _ = container
    proc = _run(host, folder / "binaries" / "linux64" / "SystemContainer.so", md, folder, "roundtrip=5", steps=10)
    assert "STATUS fmi2GetFMUstate 3" in proc.stdout, proc.stdout[-2000:]
    assert "not supported (canGetAndSetFMUstate is false)" in proc.stdout


def _plan_lines(folder: Path) -> list[str]:
    return (folder / "resources" / "container_plan.txt").read_text().splitlines()


# (how the plan is spoiled, the text the error names)
BAD_PLANS = {
    "wrong header": (lambda lines: ["sarins-container-plan 2", *lines[1:]], "line 1: expected"),
    "folder outside": (lambda lines: [lines[0], lines[1].replace(" Turntable ", " ../Turntable ", 1), *lines[2:]],
                       "line 2: a name, folder or identifier that is not a plain name"),
    "absolute folder": (lambda lines: [lines[0], lines[1].replace(" Turntable ", " /etc ", 1), *lines[2:]],
                        "line 2: a name, folder or identifier"),
    "hidden folder": (lambda lines: [lines[0], lines[1].replace(" Turntable ", " .. ", 1), *lines[2:]],
                      "line 2: a name, folder or identifier"),
    "unknown line": (lambda lines: [*lines[:3], "include /etc/passwd", *lines[3:]], "line 4: unknown line"),
    "no end": (lambda lines: lines[:-1], "no 'end' line"),
    "no newline at the end": (lambda lines: ["\n".join(lines)], "does not end with a newline"),
    "component out of range": (lambda lines: [re.sub(r"^variable 0 0 ", "variable 0 9 ", x) for x in lines],
                               ": no such component"),
    "variable missing": (lambda lines: [x for x in lines if not x.startswith("variable 3 ")],
                         "the variable's value reference is not the next one"),
    "not a number": (lambda lines: [re.sub(r"^variable 0 0 (\d+)", r"variable 0 0 x\1", x) for x in lines],
                     "a bad value reference"),
    "bad type": (lambda lines: [re.sub(r"^connection R", "connection X", x) for x in lines],
                 "the type must be R, I, B or S"),
    "empty": (lambda lines: [], "line 1: expected"),
    "wrong GUID": (lambda lines: [lines[0], re.sub(r" \S+$", " 0-0-0", lines[1]), *lines[2:]],
                   "component turntable: fmi2Instantiate failed"),
    "no such binary": (lambda lines: [lines[0], re.sub(r"^(component turntable Turntable) Turntable", r"\1 Nope",
                                                       lines[1]), *lines[2:]], "component turntable: cannot load"),
    "text after end": (lambda lines: [*lines, "end"], "text after 'end'"),
}


@pytest.mark.parametrize("case", list(BAD_PLANS))
def test_a_bad_plan_is_an_error_naming_its_line(case, container, host, tmp_path):
    _, folder, md, _ = container
    copy = tmp_path / "unzipped"
    shutil.copytree(folder, copy, symlinks=True)
    spoil, expected = BAD_PLANS[case]
    lines = spoil(_plan_lines(folder))
    (copy / "resources" / "container_plan.txt").write_text("".join(x + "\n" for x in lines)[:-1]
                                                          if case == "no newline at the end" else
                                                          "".join(x + "\n" for x in lines))
    proc = _run(host, copy / "binaries" / "linux64" / "SystemContainer.so", md, copy, steps=3)
    assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout, proc.stdout[-3000:]
    assert expected in proc.stdout, proc.stdout[-3000:]


def test_a_missing_plan_is_an_error(container, host, tmp_path):
    _, folder, md, _ = container
    copy = tmp_path / "unzipped"
    shutil.copytree(folder, copy, symlinks=True)
    (copy / "resources" / "container_plan.txt").unlink()
    proc = _run(host, copy / "binaries" / "linux64" / "SystemContainer.so", md, copy, steps=3)
    assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout
    assert "cannot open resources/container_plan.txt" in proc.stdout


def test_fmusim_runs_it_with_an_empty_environment(container, master, tmp_path):
    fmusim = os.environ.get("FMUSIM") or shutil.which("fmusim")
    if fmusim is None:
        pytest.skip("fmusim not found (set FMUSIM to its path; docs/quick-start.md says how to build it)")
    out = tmp_path / "run.csv"
    cmd = ["env", "-i", fmusim, "--interface-type", "cs", "--stop-time", str(STEPS), "--output-interval", "1",
           *(a for n in OUTPUTS for a in ("--output-variable", n)), "--output-file", str(out), str(container[0])]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = list(csv.reader(out.open()))
    assert rows[0] == ["time", *OUTPUTS]
    last = {n: float(x) for n, x in zip(OUTPUTS, rows[-1][1:])}
    assert float(rows[-1][0]) == STEPS
    for name in OUTPUTS:  # fmusim prints %.16g
        assert last[name] == pytest.approx(master[name][-1], rel=4.5e-16, abs=0), name


@pytest.mark.slow
def test_win64_under_wine_and_aarch64_under_qemu_give_the_linux64_numbers(container, host, wine_env, tmp_path):
    """The container's win64 DLL (loading the components' DLLs) under wine and its aarch64 binary (loading theirs)
    under qemu-user print the linux64 binary's bit patterns at every step."""
    _, folder, md, _ = container
    missing = [t for t in (AARCH64, "qemu-aarch64") if shutil.which(t) is None]
    if missing or not Path(ARM_SYSROOT, "lib").is_dir():
        pytest.skip(f"{', '.join(missing) or ARM_SYSROOT} missing (Debian: gcc-aarch64-linux-gnu "
                    "libc6-dev-arm64-cross qemu-user)")
    for name in COMPONENTS:
        for binary in (f"win64/{name}.dll", f"aarch64-linux/{name}.so"):
            if not (folder / "resources" / name / "binaries" / binary).is_file():
                pytest.skip(f"component binary {binary} not built (the session builds every platform when slow "
                            "tests are selected)")
    out = _out_arg(md)
    linux = _rows(_run(host, folder / "binaries" / "linux64" / "SystemContainer.so", md, folder, out))
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    proc = _run(exe, folder / "binaries" / "win64" / "SystemContainer.dll", md, folder, out, prefix=("wine",),
                env=wine_env, windows=True, timeout=1800)
    assert "STATUS" not in proc.stdout, proc.stdout[-3000:]
    assert _rows(proc) == linux
    arm = tmp_path / "host_aarch64"
    build_line([AARCH64, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(arm)])
    proc = _run(arm, folder / "binaries" / "aarch64-linux" / "SystemContainer.so", md, folder, out,
                prefix=("env", "-i", "qemu-aarch64", "-L", ARM_SYSROOT), timeout=1800)
    assert "STATUS" not in proc.stdout, proc.stdout[-3000:]
    assert _rows(proc) == linux


def test_under_asan_and_ubsan_a_run_and_bad_plans_report_nothing(container, tmp_path):
    """The container's sources built with AddressSanitizer and UBSan (leaks included) in a host built the
    same way (the components as shipped): a run, then every bad plan, each one's error status and no
    sanitizer report."""
    from fmus.native_fmu import CFLAGS

    _, folder, md, _ = container
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    sources = folder / "sources"
    lib = tmp_path / "SystemContainer_san.so"
    files = sorted(str(p) for p in sources.glob("*.c"))
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}", *files,
                    "-ldl", "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"}
    proc = _run(host, lib, md, folder, _out_arg(md), prefix=(), steps=50, env=env)
    assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr, proc.stderr[-3000:]
    assert "STATUS" not in proc.stdout and len(_rows(proc)) == 51, proc.stdout[-2000:]
    for case, (spoil, expected) in BAD_PLANS.items():
        copy = tmp_path / case.replace(" ", "_")
        shutil.copytree(folder, copy, symlinks=True)
        text = "".join(x + "\n" for x in spoil(_plan_lines(folder)))
        (copy / "resources" / "container_plan.txt").write_text(text[:-1] if case == "no newline at the end" else text)
        proc = _run(host, lib, md, copy, prefix=(), steps=3, env=env)
        assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr, proc.stderr[-3000:]
        assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout and expected in proc.stdout, case


@pytest.mark.slow
def test_its_sources_compile_warning_free_at_every_compile_line(container, tmp_path):
    """The container's own sources/ (model.c, the glue) under gcc and clang, -O0/-O2/-O3, with and without
    -march=native, C11 and GNU C11, -Wall -Wextra -Wpedantic -Werror (the lines the FMUs' sources pass)."""
    from test_portable_fmus import LINES

    _, folder, _, _ = container
    sources = folder / "sources"
    failed = []
    for cc, opt, arch, std in LINES:
        if shutil.which(cc) is None:
            continue
        for c_file in sorted(sources.glob("*.c")):
            cmd = [cc, std, opt, *([arch] if arch else []), "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fPIC",
                   f"-I{sources}", "-c", str(c_file), "-o", str(tmp_path / "x.o")]
            proc = subprocess.run(cmd, capture_output=True, text=True)
            if proc.returncode != 0:
                failed.append(f"{' '.join(cmd)}\n{proc.stderr[-1500:]}")
    assert not failed, "\n".join(failed[:3])
