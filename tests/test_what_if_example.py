"""docs/examples/what_if_after_alignment.py: the FMU-state what-if branch of docs/native-layer.md runs."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "docs" / "examples" / "what_if_after_alignment.py"


def _example():
    spec = importlib.util.spec_from_file_location("what_if_after_alignment", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_branches_after_the_alignment_replay_bit_for_bit_and_differ_by_the_correction(fmu_dir):
    """States taken after a 600 s alignment: branch A replayed from them is bit-identical, branch B (a
    0.01 deg/h azimuth correction) moves the position error; every branch navigated the same 300 s."""
    result = _example().run(fmu_dir, align=600, nav=300, correction_dph=0.01)
    assert result.replay_a == result.branch_a
    assert result.branch_b != result.branch_a
    assert result.branch_a.nav_time == result.branch_b.nav_time == 300.0
    assert result.state_bytes > 0
