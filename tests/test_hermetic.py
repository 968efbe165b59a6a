"""The test suite is hermetic: it writes only into temporary folders, and the product reads no test hook.

tests/conftest.py points HOME, the XDG folders and the FMUs' library cache into a folder made for the
session; the hooks that interrupt a run at a known point live in tests/hooks.py and are installed by the
tests (monkeypatch or the ``hooks.py`` runner), never read from the environment by the product.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import HERMETIC_ENV, HERMETIC_ROOT, SYSTEM_TMP

ROOT = Path(__file__).resolve().parents[1]
PRODUCT = ("sarins", "sarins_fmu", "orchestration", "fmus")


@pytest.mark.parametrize("name", sorted(HERMETIC_ENV))
def test_home_and_caches_point_into_the_sessions_temporary_folder(name):
    assert Path(os.environ[name]).resolve().is_relative_to(HERMETIC_ROOT.resolve())
    assert HERMETIC_ROOT.resolve().is_relative_to(SYSTEM_TMP.resolve())


def test_temporary_files_go_into_the_sessions_folder(tmp_path):
    """tempfile (FMPy's extract, pytest's tmp_path) makes its folders in the session's, removed at its end."""
    import tempfile

    made = Path(tempfile.mkdtemp())
    try:
        assert made.resolve().is_relative_to(HERMETIC_ROOT.resolve())
    finally:
        made.rmdir()
    assert tmp_path.resolve().is_relative_to(HERMETIC_ROOT.resolve())


def test_a_child_process_inherits_the_redirection():
    out = subprocess.run([sys.executable, "-c", "import pathlib; print(pathlib.Path.home())"], capture_output=True,
                         text=True, check=True).stdout.strip()
    assert Path(out).resolve().is_relative_to(HERMETIC_ROOT.resolve())


def test_the_product_reads_no_test_hook_from_the_environment():
    """No product module reads a ``*TEST*`` environment variable (hooks are injected by the tests)."""
    pattern = re.compile(r"""(environ|getenv|_ENV\s*=).*["'][A-Z0-9_]*TEST[A-Z0-9_]*["']""")
    found = []
    for package in PRODUCT:
        for path in sorted((ROOT / package).rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            if "environ" not in text:
                continue
            for number, line in enumerate(text.splitlines(), 1):
                if pattern.search(line):
                    found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert found == []

