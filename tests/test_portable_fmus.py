"""The C core and the native FMUs: no libm, the glibc 2.17 baseline, the same numbers on every platform and
compile line.

The core calls its own math (sarins_fmu/core/smath.h) and fixes its floating-point contract in the source,
so every binary gives the numbers of the shipped linux64 one, bit for bit: the win64 DLL under wine, the
aarch64 binary under qemu-user, and ``sources/`` compiled by gcc or clang at any optimisation level, with or
without -march=native, in C11 or GNU C11, or by FMPy's own cmake build.  Each run goes through the C hosts
(tests/native_host/native_fmu_host.c, native_fmu3_host.c) with an empty environment.  A platform whose
tools are missing is skipped with the reason (.ci/run installs them); the full compile-line matrix and the
emulated platforms are slow tests, one compile line per FMU runs by default.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from fmus.cbuild import build_line
from fmus.native_fmu import AARCH64, ARM_PLATFORM, MINGW, NATIVE, build_native_fmu, fmi_headers_dir
from sarins_fmu.core import _lib
from test_native_fmus import CASES, HOST_SRC, ops, run_host, table

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from smath_convert import math_calls  # noqa: E402

CORE = ROOT / "sarins_fmu" / "core"
FMUS_C = ROOT / "fmus" / "c"
HOST3_SRC = Path(__file__).resolve().parent / "native_host" / "native_fmu3_host.c"
GLIBC_BASELINE = (2, 17)  # manylinux2014
ARM_SYSROOT = "/usr/aarch64-linux-gnu"
# every function of <math.h> (C11 and the GNU extensions), as a binary would import it
_LIBM = ("acos acosh asin asinh atan atan2 atanh cbrt ceil copysign cos cosh erf erfc exp exp10 exp2 expm1 fabs "
         "fdim floor fma fmax fmin fmod frexp hypot ilogb ldexp lgamma llrint llround log log10 log1p log2 logb "
         "lrint lround modf nan nearbyint nextafter nexttoward pow pow10 remainder remquo rint round scalbln "
         "scalbn sin sincos sinh sqrt tan tanh tgamma trunc").split()
LIBM = {n + s for n in _LIBM for s in ("", "f", "l")} | {f"__{n}_finite" for n in _LIBM}
IMU_OUTPUTS = [f"dtheta_{a}" for a in "xyz"] + [f"dv_{a}" for a in "xyz"] + [
    f"temp_{s}_{a}" for s in ("gyro", "accel") for a in "xyz"] + ["increment_end_time"]
# the IMU turning on two gimbals (inputs held), mems preset: every error term, sin/cos/exp in the minor loop
IMU_CASE = {"preset": "mems", "gimbals": "x,z", "seed": 2, "angle_1": 0.3, "rate_1": 0.2, "rate_2": -0.05,
            "angle_2": 1e6}
# the vehicle driving, turning and stopping with sway and vibration (sin/cos, the RNG, the Earth model)
VEHICLE_CASE = {"lead_time": 10.0, "legs": "drive 60 10; turn 90; drive 60 12; turn -45; stop 30", "body_seed": 5}
VEHICLE_OUTPUTS = [f"vehicle_{a}{q}" for q in ("", "_rate", "_accel") for a in ("yaw", "pitch", "roll")] + [
    f"base_{q}_{a}" for q in ("rate", "force") for a in "enu"] + ["lat", "lon", "v_e", "v_n", "speed"]
STEPS = {"Turntable": 300, "IMUThermal": 120, "StrapdownINS": None,  # StrapdownINS: its queued run's N
         "VehicleMotion": 250}


def _need(*tools):
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: gcc, clang, gcc-mingw-w64-x86-64 wine64, "
                    "gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user; .ci/run installs them)")


def _cc():
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    return cc


@pytest.fixture(scope="module")
def native(fmu_dir, tmp_path_factory):
    """{name: (unzipped folder, model description, the .fmu)} of the session's native FMI 2.0 FMUs."""
    out = tmp_path_factory.mktemp("portable")
    result = {}
    for name in NATIVE:
        fmu = fmu_dir / f"{name}.fmu"
        if not fmu.is_file():  # IMUCompensator: built with a trained model only
            continue
        with zipfile.ZipFile(fmu) as z:
            z.extractall(out / name)
        result[name] = (out / name, read_model_description(str(fmu)), fmu)
    return result


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    out = tmp_path_factory.mktemp("portable_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def run_fmu(name, native, host, binary, tmp_path, prefix=(), env=None) -> dict[int, list[int]]:
    """The workload of FMU ``name`` run from ``binary`` by ``host`` (under ``prefix``, e.g. wine or qemu):
    {steps done: output bit patterns}.  Turntable: a dual-axis run in a chamber; IMUThermal: the mems preset
    on two turning gimbals (one of them a million radians on); StrapdownINS: its queued temperature-model
    run, inputs before every step; VehicleMotion: drives, turns and a stop with sway and vibration."""
    env = {} if env is None else env
    folder, md, _ = native[name]
    if name == "StrapdownINS":
        from test_native_strapdown_ins import _host_run

        proc = _host_run(host, native[name][2], tmp_path, binary=binary, env=env, prefix=list(prefix), timeout=900)
    else:
        values = {"Turntable": CASES["dual-axis chamber"], "VehicleMotion": VEHICLE_CASE}.get(name, IMU_CASE)
        outputs = {"IMUThermal": IMU_OUTPUTS, "VehicleMotion": VEHICLE_OUTPUTS}.get(name)
        args = ops(md, values) if outputs is None else ops(md, values, outputs=outputs)
        proc = run_host(host, binary, md, STEPS[name], *args, env=env, prefix=list(prefix), timeout=900)
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    rows = table(proc)
    assert len(rows) > 100 and len({tuple(r) for r in rows.values()}) > 50  # it moves
    return rows


@pytest.fixture(scope="module")
def shipped(native, host, fmu_dir, tmp_path_factory):
    """{name: the workload's rows from the shipped linux64 binary}."""
    return {name: run_fmu(name, native, host, native[name][0] / "binaries" / "linux64" / f"{name}.so",
                          tmp_path_factory.mktemp(f"ref_{name}")) for name in WORKLOADS}


def _rows_differ(a: dict, b: dict) -> str:
    """'' when equal, else a one-line account (how many values differ, the largest relative difference)."""
    if a == b:
        return ""
    if sorted(a) != sorted(b):
        return f"different steps: {sorted(set(a) ^ set(b))[:5]}"
    x = np.array([a[k] for k in sorted(a)], dtype=np.uint64).view(np.float64)
    y = np.array([b[k] for k in sorted(b)], dtype=np.uint64).view(np.float64)
    rel = np.abs(x - y) / np.maximum(np.abs(y), 1e-300)
    return f"{int(np.sum(x != y))} of {x.size} values differ, largest relative difference {float(np.max(rel)):.3g}"


# ----------------------------------------------------------------- binaries: no libm, glibc 2.17


def _binaries(native) -> list[Path]:
    """The in-process core library and every Linux binary of the native FMUs."""
    found = [_lib.library_path()]
    for folder, _, _ in native.values():
        found += sorted((folder / "binaries").glob("*linux*/*.so"))
    return found


def test_no_binary_references_a_libm_symbol(native):
    _need("nm", "readelf")
    for path in _binaries(native):
        undefined = subprocess.run(["nm", "-D", "--undefined-only", str(path)], capture_output=True, text=True,
                                   check=True).stdout
        names = {line.split()[-1].split("@")[0] for line in undefined.splitlines() if line.strip()}
        assert not names & LIBM, f"{path.name} imports {sorted(names & LIBM)} from libm"
        needed = subprocess.run(["readelf", "-d", str(path)], capture_output=True, text=True, check=True).stdout
        assert "libm.so" not in needed, f"{path} needs libm"


def glibc_versions(path: Path) -> set[tuple[int, ...]]:
    """The GLIBC_ symbol versions a binary references (``objdump -T``)."""
    dump = subprocess.run(["objdump", "-T", str(path)], capture_output=True, text=True, check=True).stdout
    return {tuple(int(p) for p in v.split(".")) for v in re.findall(r"\bGLIBC_([0-9.]+)\b", dump)}


def test_linux_binaries_need_nothing_newer_than_glibc_2_17(native):
    _need("objdump")
    for path in _binaries(native):
        versions = glibc_versions(path)
        assert versions and max(versions) <= GLIBC_BASELINE, (path.name, max(versions))


# ----------------------------------------------------------------- sources: no <math.h> call, contract fixed


def _c_files():
    return sorted([*CORE.glob("*.[ch]"), *FMUS_C.glob("*.[ch]"), *FMUS_C.glob("*/*.c")])


def test_the_sources_call_no_math_h_function():
    """Only smath's functions (and <math.h>'s classification macros) in the core and the FMU glue and models."""
    calls = [f"{p.relative_to(ROOT)}:{line}: {name}" for p in _c_files() if not p.name.startswith("smath")
             for line, name in math_calls(p.read_text())]
    assert not calls, "calls into libm (tools/smath_convert.py rewrites them):\n" + "\n".join(calls)


def test_every_c_file_includes_smath_first():
    """smath.h fixes the floating-point contract of the file from where it is included: before anything."""
    first = re.compile(r'^\s*#\s*include\s*([<"][^>"]+[>"])', re.M)
    late = [str(p.relative_to(ROOT)) for p in _c_files() if p.suffix == ".c"
            and (m := first.search(p.read_text())) and m.group(1) != '"smath.h"']
    assert not late, f"first include is not \"smath.h\": {late}"


def test_the_smath_constants_are_those_the_generator_writes():
    pytest.importorskip("mpmath")
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "smath_gen.py"), "--check"], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr


# ----------------------------------------------------------------- any compile line


def _compile(sources: Path, identifier: str, cc: str, flags: list[str], out: Path) -> Path:
    target = out / f"{identifier}.so"
    cmd = [cc, *flags, "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fPIC", "-shared", "-I.",
           *sorted(p.name for p in sources.glob("*.c")), "-o", str(target)]
    return build_line(cmd, cwd=sources)  # (the core's files compiled once per line for every FMU)


# the FMUs with a workload here (run_fmu); the network FMUs' platforms: tests/test_native_nets.py
WORKLOADS = ("Turntable", "IMUThermal", "StrapdownINS", "VehicleMotion")
LINES = [(cc, opt, arch, std) for cc in ("gcc", "clang") for opt in ("-O0", "-O2", "-O3")
         for arch in ("", "-march=native") for std in ("-std=c11", "-std=gnu11")]
QUICK_LINE = ("clang", "-O3", "-march=native", "-std=gnu11")


def _check_lines(name, lines, native, host, shipped, tmp_path):
    folder, _, _ = native[name]
    report = []
    for k, (cc, *flags) in enumerate(lines):
        _need(cc)
        out = tmp_path / f"line{k}"
        out.mkdir()
        lib = _compile(folder / "sources", name, cc, [f for f in flags if f], out)
        diff = _rows_differ(run_fmu(name, native, host, lib, out), shipped[name])
        report.append((" ".join(f for f in (cc, *flags) if f), diff or "bit-identical"))
    print(f"\n{name}:\n" + "\n".join(f"  {line:40s} {result}" for line, result in report))
    assert all(result == "bit-identical" for _, result in report), report


@pytest.mark.parametrize("name", WORKLOADS)
def test_sources_with_another_compile_line_give_the_shipped_numbers(name, native, host, shipped, tmp_path):
    """clang -O3 -march=native -std=gnu11 -Wall -Wextra -Wpedantic -Werror: no warning, the shipped bits."""
    _check_lines(name, [QUICK_LINE], native, host, shipped, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", WORKLOADS)
def test_sources_with_every_compile_line_give_the_shipped_numbers(name, native, host, shipped, tmp_path):
    """gcc and clang, -O0/-O2/-O3, with and without -march=native, C11 and GNU C11: 24 lines, all warning-free
    under -Wall -Wextra -Wpedantic -Werror, all with the shipped bits."""
    _check_lines(name, LINES, native, host, shipped, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", WORKLOADS)
def test_fmpy_builds_the_sources_and_the_result_runs_with_an_empty_environment(name, native, host, shipped,
                                                                                tmp_path):
    """FMPy's own source build (fmpy.build.build_platform_binary: cmake, its CMakeLists links no libm), the
    binary loaded by the C host under env -i: the shipped numbers."""
    _need("cmake")
    from fmpy.build import build_platform_binary

    folder, _, _ = native[name]
    unzipped = tmp_path / name
    shutil.copytree(folder, unzipped)
    shutil.rmtree(unzipped / "binaries")
    build = tmp_path / "build"
    build.mkdir()
    build_platform_binary(unzipped, build_dir=build, all_warnings=True)
    lib = unzipped / "binaries" / "linux64" / f"{name}.so"
    assert lib.is_file()
    assert _rows_differ(run_fmu(name, native, host, lib, tmp_path, prefix=["env", "-i"]), shipped[name]) == ""


# ----------------------------------------------------------------- other platforms


@pytest.mark.slow
@pytest.mark.parametrize("name", WORKLOADS)
def test_win64_dll_under_wine_gives_the_linux64_numbers(name, native, shipped, wine_env, tmp_path):
    folder, _, _ = native[name]
    dll = folder / "binaries" / "win64" / f"{name}.dll"
    assert dll.is_file(), "the build had mingw but shipped no win64 DLL"
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    rows = run_fmu(name, native, exe, dll, tmp_path, prefix=["wine"], env=wine_env)
    assert _rows_differ(rows, shipped[name]) == ""


def _arm_host(tmp_path: Path, src: Path = HOST_SRC, fmi: int = 2) -> Path:
    _need(AARCH64, "qemu-aarch64")
    if not Path(ARM_SYSROOT, "lib").is_dir():
        pytest.skip(f"{ARM_SYSROOT} missing (Debian: apt-get install libc6-dev-arm64-cross)")
    exe = tmp_path / "host_aarch64"
    build_line([AARCH64, "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror",
                    f"-I{fmi_headers_dir(fmi)}", str(src), "-ldl", "-o", str(exe)])
    return exe


QEMU = ["qemu-aarch64", "-L", ARM_SYSROOT]


@pytest.mark.slow
@pytest.mark.parametrize("name", WORKLOADS)
def test_aarch64_binary_under_qemu_gives_the_linux64_numbers(name, native, shipped, tmp_path):
    folder, _, _ = native[name]
    exe = _arm_host(tmp_path)
    so = folder / "binaries" / ARM_PLATFORM / f"{name}.so"
    assert so.is_file(), f"the build had {AARCH64} but shipped no {ARM_PLATFORM} binary"
    rows = run_fmu(name, native, exe, so, tmp_path, prefix=QEMU)
    assert _rows_differ(rows, shipped[name]) == ""


def test_aarch64_turntable_under_qemu_quick(native, shipped, tmp_path):
    """The default suite's aarch64 check: the Turntable (sin of the ambient, the schedule) under qemu-user."""
    folder, _, _ = native["Turntable"]
    so = folder / "binaries" / ARM_PLATFORM / "Turntable.so"
    if not so.is_file():
        pytest.skip(f"no {ARM_PLATFORM} binary: {AARCH64} was not on PATH at the build")
    exe = _arm_host(tmp_path)
    assert _rows_differ(run_fmu("Turntable", native, exe, so, tmp_path, prefix=QEMU), shipped["Turntable"]) == ""


def _fmi3_hosts(tmp_path: Path) -> Path:
    """The FMI 3.0 C host built for x86-64 Linux (tmp_path/host), win64 (tmp_path/host.exe) and aarch64 (returned);
    a skip when a cross tool is missing."""
    _need(MINGW, "wine", AARCH64, "qemu-aarch64")
    flags = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir(3)}"]
    build_line([_cc(), *flags, str(HOST3_SRC), "-ldl", "-o", str(tmp_path / "host")])
    build_line([MINGW, *flags, str(HOST3_SRC), "-static", "-o", str(tmp_path / "host.exe")])
    return _arm_host(tmp_path, HOST3_SRC, fmi=3)


@pytest.mark.slow
def test_fmi3_binaries_of_every_platform_give_the_x86_64_linux_numbers(tmp_path, wine_env):
    """The FMI 3.0 IMUThermal (n_sub = 200: every minor interval in arrays) and Turntable from
    binaries/x86_64-windows under wine and binaries/aarch64-linux under qemu, through the FMI 3.0 C host:
    the x86_64-linux bits."""
    arm = _fmi3_hosts(tmp_path)
    env = wine_env
    for name, slave in (("IMUThermal", "imu_thermal_slave.py"), ("Turntable", "turntable_slave.py")):
        fmu = build_native_fmu(name, slave, tmp_path, fmi=3, win64=True, aarch64=True)
        folder = tmp_path / name
        zipfile.ZipFile(fmu).extractall(folder)
        md = read_model_description(str(fmu))
        vr = {v.name: v.valueReference for v in md.modelVariables}
        if name == "IMUThermal":
            outs = ["increment_end_time"] + [f"{q}_{a}_sub" for q in ("dtheta", "dv") for a in "xyz"]
            args = [f"u{vr['n_sub']}=200", f"s{vr['preset']}=mems", f"s{vr['gimbals']}=x,z",
                    f"r{vr['angle_1']}=0.3", f"r{vr['rate_1']}=0.2", f"r{vr['rate_2']}=-0.05",
                    "out=" + ",".join(str(vr[n]) for n in outs), f"nout={1 + 6 * 200}"]
        else:
            outs = [f"{q}_{j}" for j in (1, 2) for q in ("angle", "rate", "accel")] + ["ambient_temp"]
            args = [f"s{vr['scheme']}=dual-axis", f"r{vr['align_time']}=0.0",
                    "out=" + ",".join(str(vr[n]) for n in outs), f"nout={len(outs)}"]
        runs = {}
        for system, exe, binary, prefix in (
                ("x86_64-linux", tmp_path / "host", folder / "binaries" / "x86_64-linux" / f"{name}.so", []),
                ("x86_64-windows", tmp_path / "host.exe", folder / "binaries" / "x86_64-windows" / f"{name}.dll",
                 ["wine"]),
                (ARM_PLATFORM, arm, folder / "binaries" / ARM_PLATFORM / f"{name}.so", QEMU)):
            proc = subprocess.run([*prefix, str(exe), str(binary), md.guid, "30", "1.0", *args], capture_output=True,
                                  text=True, timeout=900, env=env)
            assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:] + proc.stderr[-2000:]
            runs[system] = table(proc)
        for system in ("x86_64-windows", ARM_PLATFORM):
            assert _rows_differ(runs[system], runs["x86_64-linux"]) == "", (name, system)


@pytest.mark.slow
def test_fmi3_imu_on_its_own_threads_on_every_platform(tmp_path, wine_env):
    """The FMI 3.0 IMUThermal reading every second's motion from arrays (sub_inputs = 1, 8 s steps) on 2
    threads (pthreads; the Windows API under wine) from binaries/x86_64-windows and binaries/aarch64-linux:
    the x86_64-linux bits of its 1 thread run."""
    from test_native_imu_given_motion import K, MOTION, PARAMS, SUB_OUT, arrays_of

    arm = _fmi3_hosts(tmp_path)
    fmu = build_native_fmu("IMUThermal", "imu_thermal_slave.py", tmp_path, fmi=3, win64=True, aarch64=True)
    folder = tmp_path / "IMUThermal"
    zipfile.ZipFile(fmu).extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    steps = 12
    ins = ["motion_time"] + [f"{name}_sub" for name in MOTION]
    rows = tmp_path / "rows.bin"  # Jacobi: before the step from k K s, the set tagged k K
    np.array([[j * K] + [x for name in ins[1:] for x in arrays_of(j)[name]] for j in range(steps)],
             dtype=np.float64).tofile(rows)
    common = [f"u{vr['n_sub']}={K}", f"i{vr['sub_inputs']}=1", f"s{vr['gimbals']}={PARAMS['gimbals']}",
              "in=" + ",".join(str(vr[n]) for n in ins), f"nin={1 + 11 * K}", f"rows={rows}",
              "out=" + ",".join(str(vr[n]) for n in ["increment_end_time", *SUB_OUT]), f"nout={1 + 7 * K}"]
    runs = {}
    for system, exe, binary, prefix, threads in (
            ("one thread", tmp_path / "host", folder / "binaries" / "x86_64-linux" / "IMUThermal.so", [], 1),
            ("x86_64-linux", tmp_path / "host", folder / "binaries" / "x86_64-linux" / "IMUThermal.so", [], 2),
            ("x86_64-windows", tmp_path / "host.exe", folder / "binaries" / "x86_64-windows" / "IMUThermal.dll",
             ["wine"], 2),
            (ARM_PLATFORM, arm, folder / "binaries" / ARM_PLATFORM / "IMUThermal.so", QEMU, 2)):
        proc = subprocess.run([*prefix, str(exe), str(binary), md.guid, str(steps), f"{K:.1f}", *common,
                               f"i{vr['threads']}={threads}"], capture_output=True, text=True, timeout=900,
                              env=wine_env)
        assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:] + proc.stderr[-2000:]
        runs[system] = table(proc)
    one = runs["one thread"]
    assert len(one) == steps + 1 and len({tuple(row) for row in one.values()}) == steps + 1  # every step differs
    for system in ("x86_64-linux", "x86_64-windows", ARM_PLATFORM):
        assert _rows_differ(runs[system], runs["one thread"]) == "", system
