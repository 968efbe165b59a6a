"""The C core on Windows' toolchain: mingw-w64 cross-builds, wine runs.

tests/core_driver/core_driver.c runs a fixed workload through the core's
public functions and prints every output's bit pattern.  It is built with the
system gcc (linux64, glibc) and with x86_64-w64-mingw32-gcc (win64, msvcrt,
statically linked), the .exe is run under wine, and the outputs are compared
group by group.

What is asserted: every output of every group is bit-identical.  The core calls
no libm (its math is smath.c: plain IEEE binary64 + - * / and integer
operations, sqrt and fma correctly rounded in hardware or software) and fixes
its floating-point contract in the source, so the two toolchains and C
runtimes cannot differ; any difference is a compiler or ABI fault.

The printed table (run with -s) gives per group the outputs, how many are
bit-identical, the largest relative difference and the largest ulp distance.
"""

import ast
import math
import re
import shutil
import struct
import subprocess
from pathlib import Path

import pytest

from sarins_fmu.core.exports import public_functions

ROOT = Path(__file__).resolve().parent.parent
CORE = ROOT / "sarins_fmu" / "core"
DRIVER = ROOT / "tests" / "core_driver" / "core_driver.c"
MINGW = "x86_64-w64-mingw32-gcc"
MINGW_OBJDUMP = "x86_64-w64-mingw32-objdump"

GROUPS = ["turntable", "earth", "rotations", "thermal", "interval_terms", "correlated", "filter",
          "imu_increments", "ins_coarse", "ins_align", "ins_nav", "stop_filter"]
SYSTEM_DLLS = {"kernel32.dll", "msvcrt.dll"}


def _setup_flags():
    """setup.py's UNIX_FLAGS, read from its source (importing it would run setup())."""
    tree = ast.parse((ROOT / "setup.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "UNIX_FLAGS" for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError("setup.py defines no UNIX_FLAGS")


FLAGS = [f for f in _setup_flags() if f != "-fPIC"]  # -fPIC only for the shared library
SOURCES = sorted(str(p) for p in CORE.glob("*.c"))


def _need(*tools):
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64; "
                    ".ci/run installs them)")


def _run(cmd, **kw):
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kw)
    assert res.returncode == 0, f"{cmd[0]} exited {res.returncode}:\n{res.stderr[-3000:]}"
    return res


@pytest.fixture(scope="session")
def win64_tools(wine_env):
    """The session's wine environment (tests/conftest.py), once gcc is known to be there too."""
    _need("gcc", MINGW, "wine")
    return wine_env


def _parse(stdout):
    """{group: [bit pattern as int]} in output order."""
    out = {}
    for line in stdout.splitlines():
        group, bits = line.split()
        out.setdefault(group, []).append(int(bits, 16))
    return out


def _value(bits):
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


def _ordered(bits):
    """Bit pattern mapped to a monotonic integer line, so that ulp distance is a difference."""
    return bits if bits < 1 << 63 else (1 << 63) - bits


def _compare(lin, win):
    """Per group: outputs, bit-identical, largest relative difference, largest ulp distance."""
    rows = {}
    for group, a in lin.items():
        b = win[group]
        same, rel, ulp = 0, 0.0, 0
        for x, y in zip(a, b):
            if x == y:
                same += 1
                continue
            u, v = _value(x), _value(y)
            rel = max(rel, abs(u - v) / max(abs(u), abs(v)))
            ulp = max(ulp, abs(_ordered(x) - _ordered(y)))
        rows[group] = (len(a), same, rel, ulp)
    return rows


@pytest.mark.slow  # 20 s with the wine prefix
def test_win64_core_matches_linux64(tmp_path, win64_tools):
    _need("gcc", MINGW, "wine")
    lin_exe, win_exe = tmp_path / "core_driver", tmp_path / "core_driver.exe"
    common = [*FLAGS, f"-I{CORE}", str(DRIVER), *SOURCES]
    _run(["gcc", *common, "-o", str(lin_exe)])
    _run([MINGW, *common, "-static", "-o", str(win_exe)])

    lin = _parse(_run([str(lin_exe)]).stdout)
    win = _parse(_run(["wine", str(win_exe)], env=win64_tools).stdout)
    assert list(lin) == GROUPS
    assert list(win) == GROUPS
    assert {g: len(v) for g, v in win.items()} == {g: len(v) for g, v in lin.items()}
    assert all(math.isfinite(_value(x)) for v in lin.values() for x in v)

    rows = _compare(lin, win)
    print(f"\n{'group':16s} {'outputs':>7s} {'bit-identical':>13s} {'largest rel. diff':>17s} {'ulp':>4s}")
    for group, (n, same, rel, ulp) in rows.items():
        print(f"{group:16s} {n:7d} {same:13d} {rel:17.3g} {ulp:4d}")
    for group, (n, same, rel, _) in rows.items():
        assert same == n, f"{group}: {n - same} of {n} outputs differ (largest relative difference {rel:.3g})"


def _dll_imports_exports(dll):
    dump = _run([MINGW_OBJDUMP, "-p", str(dll)]).stdout
    imports = {m.lower() for m in re.findall(r"DLL Name: (\S+)", dump)}
    table = dump.split("[Ordinal/Name Pointer] Table", 1)[1]
    exports = set(re.findall(r"^\s*\[\s*\d+\] (\w+)$", table, flags=re.M))
    return imports, exports


@pytest.mark.slow
def test_core_builds_as_win64_dll(tmp_path):
    _need("gcc", "nm", MINGW, MINGW_OBJDUMP)
    dll, so = tmp_path / "sarins_core.dll", tmp_path / "libsarins_core.so"
    _run([MINGW, *FLAGS, "-shared", f"-I{CORE}", *SOURCES, "-o", str(dll)])
    _run(["gcc", *FLAGS, "-fPIC", "-shared", f"-I{CORE}", *SOURCES, "-o", str(so)])
    imports, exports = _dll_imports_exports(dll)
    # needs nothing beyond Windows' own DLLs (the C runtime is msvcrt, libgcc linked in)
    assert imports <= SYSTEM_DLLS, imports
    # the same public functions as the linux library
    nm = _run(["nm", "-D", "--defined-only", str(so)]).stdout
    linux = {line.split()[-1] for line in nm.splitlines() if line.split()[1] in ("T", "i")}  # i: an ifunc (target_clones)
    assert "sarins_core_abi" in linux
    assert exports == linux


@pytest.mark.slow
def test_core_dll_from_the_msvc_export_list_exports_every_public_function(tmp_path):
    # what MSVC's linker does with setup.py's list: export those names and nothing else; mingw's ld does the
    # same with auto-export off and a module-definition file
    _need(MINGW, MINGW_OBJDUMP)
    names = public_functions(CORE)
    definition = tmp_path / "sarins_core.def"
    definition.write_text("EXPORTS\n" + "".join(f"    {name}\n" for name in names))
    dll = tmp_path / "sarins_core.dll"
    _run([MINGW, *FLAGS, "-shared", f"-I{CORE}", *SOURCES, "-Wl,--exclude-all-symbols", str(definition),
          "-o", str(dll)])
    _, exports = _dll_imports_exports(dll)
    assert exports == set(names)
    # every function the Python binding declares is among them
    bound = set()
    for module in (ROOT / "sarins_fmu").rglob("*.py"):
        bound.update(re.findall(r"\bfunction\(\s*\"(sarins_\w+)\"", module.read_text(encoding="utf-8")))
    assert bound and bound <= exports, sorted(bound - exports)
