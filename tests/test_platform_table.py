"""benchmarks/platform_table.py (issue 27's acceptance table) on the Turntable: its core function runs the
FMU's case on the platforms and compile lines and compares each with the linux64 run."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import platform_table as pt  # noqa: E402


def test_turntable_row_from_a_gcc_build_of_its_sources_is_bit_identical(fmu_dir, tmp_path):
    if shutil.which("gcc") is None or shutil.which("objdump") is None:
        pytest.skip("gcc or objdump not installed")
    line = ("gcc", "-O0", "")
    row = pt.platform_row(fmu_dir / "Turntable.fmu", tmp_path, pt.Hosts(tmp_path), lines=[line], others=())
    assert row.cells["linux64"] == f"{pt.STEPS['Turntable']} steps x 12", row.cells
    major, minor = (int(x) for x in row.cells["glibc max"].split("."))
    assert (major, minor) <= (2, 17)
    assert row.cells[pt.line_name(line)] == "0", row.cells
    assert "win64" not in row.cells and "| Turntable | 2.0 | 300 steps x 12 | " in pt.markdown([row])


def test_imulog_row_plays_its_log_and_aided_ins_steps_at_a_hundredth(fmu_dir, tmp_path):
    """The IMULog case writes its own 1 Hz log (the String setting is a path); AidedINS steps 0.01 s."""
    if shutil.which("gcc") is None or shutil.which("objdump") is None:
        pytest.skip("gcc or objdump not installed")
    line = ("gcc", "-O0", "")
    rows = [pt.platform_row(fmu_dir / f"{name}.fmu", tmp_path, pt.Hosts(tmp_path), lines=[line], others=())
            for name in ("IMULog", "AidedINS")]
    assert rows[0].cells["linux64"] == f"{pt.LOG_ROWS - 1} steps x 18", rows[0].cells
    assert rows[1].cells["linux64"] == f"{pt.DEFAULT_STEPS} steps x 40", rows[1].cells  # 25 + 15 optional-state outputs
    assert [r.cells[pt.line_name(line)] for r in rows] == ["0", "0"], [r.cells for r in rows]
    assert pt.case_of("AidedINS", pt.read_model_description(str(fmu_dir / "AidedINS.fmu"))).step == 0.01


def test_a_failing_run_is_a_reason_in_its_cell(fmu_dir, tmp_path):
    """A binary the host cannot load: the cell says why instead of a number."""
    hosts = pt.Hosts(tmp_path)
    md = pt.read_model_description(str(fmu_dir / "Turntable.fmu"))
    bad = tmp_path / "bad.so"
    bad.write_bytes(b"not an ELF file")
    with pytest.raises(pt.RunFailed, match="exit 2"):
        pt.run_binary(hosts, md, pt.case_of("Turntable", md), bad, "linux64")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["Turntable", "IMULog", "AidedINS"])
def test_on_every_platform_and_compile_line_gives_the_linux64_numbers(fmu_dir, tmp_path, name):
    """win64 under wine, aarch64 under qemu, 8 compile lines: bit-identical; fmusim (when built) within its
    CSV's %.16g rounding."""
    row = pt.platform_row(fmu_dir / f"{name}.fmu", tmp_path, pt.Hosts(tmp_path),
                          fmusim=pt.os.environ.get("FMUSIM", "/work/tools/fmusim"))
    for column in ["win64", "aarch64", *map(pt.line_name, pt.LINES)]:
        assert row.cells[column] == "0" or "not installed" in row.cells[column] or "missing" in row.cells[column], \
            (column, row.cells[column])
    fmusim = row.cells["fmusim"]
    assert fmusim.startswith("fmusim absent") or float(fmusim) < 1e-15, fmusim
