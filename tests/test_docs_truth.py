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
