"""The documents say what the code does: numbers written by a script are checked against a fresh run."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def _engine_table():
    spec = importlib.util.spec_from_file_location("engine_table", ROOT / "benchmarks" / "engine_table.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("row", ["| `standard_static` (7000 s)", "| `standard_static_identified`",
                                 "| `vehicle_rins` (2900 s)", "| `vehicle_rins_online`"])
def test_the_readme_engine_table_holds_the_masters_numbers(row, fmu_dir):
    """``python benchmarks/engine_table.py --write-readme`` wrote them; a fresh Gauss-Seidel run gives them."""
    table = _engine_table()
    name, unit = table.README_ROW[row]
    (line,) = [line for line in README.read_text(encoding="utf-8").splitlines() if line.startswith(row)]
    assert line.split(" | ")[1] == table.readme_value(table.reference_values(name, fmu_dir), unit)


def test_the_readme_and_build_fmus_help_say_which_fmus_are_native():
    """The README's FMU table and ``sarins build-fmus --help`` name the native FMUs as the build makes
    them (every FMU) (fmus.native_fmu.NATIVE)."""
    import argparse

    from fmus import SLAVES
    from fmus.native_fmu import NATIVE
    from sarins.cli import build_fmus as command

    rows = {line.split("|")[1].strip(" `"): line.split("|")[3].strip() for line in README.read_text().splitlines()
            if line.startswith("| `") and line.count("|") == 4}
    assert {n: rows[n] for n in SLAVES} == {n: "native C" if n in NATIVE else "Python-hosted" for n in SLAVES}
    sub = argparse.ArgumentParser().add_subparsers()
    command.register(sub)
    text = " ".join(sub.choices["build-fmus"].description.split())
    native_part = text.split("the native C FMUs ")[1].split(" every FMI call in C")[0]
    assert all(n in native_part for n in NATIVE) and set(SLAVES) == set(NATIVE)


def test_the_docs_cite_no_missing_file():
    assert "FACTS.md" not in (ROOT / "tests" / "test_native_fmus3_sub.py").read_text()
