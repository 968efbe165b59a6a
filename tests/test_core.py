"""The C physics core: built by pip install, loaded through its ctypes binding."""

import ctypes
import shutil
import subprocess

import pytest

from sarins_fmu import core
from sarins_fmu.core.exports import public_functions


def test_core_is_built_and_of_this_abi():
    path = core.library_path()
    assert path.is_file() and path.parent.name == "core"
    assert core.LIB.sarins_core_abi() == core.ABI


def test_core_links_no_python():
    # a plain C library: it loads with no Python module init and exports none
    lib = ctypes.CDLL(str(core.library_path()))
    assert not hasattr(lib, "PyInit__sarins_core")


def test_the_msvc_export_list_names_every_function_the_library_exports():
    # setup.py hands MSVC's linker (which exports nothing unless told) core/exports.py's list; GNU ld exports
    # every public function by itself, so the built library's dynamic symbols are the reference
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm (binutils) not installed")
    out = subprocess.run([nm, "-D", "--defined-only", str(core.library_path())], capture_output=True, text=True,
                         check=True).stdout
    exported = {line.split()[-1] for line in out.splitlines() if line.split()[1] in ("T", "i")}  # i: an ifunc (target_clones)
    assert "sarins_core_abi" in exported
    assert public_functions() == sorted(exported)


def test_the_export_list_skips_static_helpers_and_comments(tmp_path):
    (tmp_path / "a.h").write_text(
        "/* sarins_in_comment(x) is not a function\n"
        " * sarins_in_comment_too(y) */\n"
        "double sarins_one(const double *x);\n"
        "int64_t *sarins_two(int n,\n    double y);\n"
        "static inline int sarins_helper(int x) { return x; }\n"
        "typedef struct sarins_state { double x; } sarins_state;\n"
        "#define SARINS_MACRO(x) sarins_one(x)\n")
    assert public_functions(tmp_path) == ["sarins_one", "sarins_two"]
