"""The numbers of docs/quick-start.md: what a tool user sees.

* the whole-system FMU (``sarins build-fmus --system``) run by FMPy with its defaults: the first
  ``ins.nav_time`` (negative: alignment), the time navigation starts and the final position error;
* the README's MEMS example (``sarins navigate --imu mems --nav-hours 1``): its position error after 1 h.

    python benchmarks/quick_start_numbers.py [--fmu-dir DIR]
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def system_fmu_numbers(fmu_dir: Path) -> dict:
    """FMPy's default run of StandardStaticSystem.fmu built from the FMUs in ``fmu_dir``."""
    from fmpy import simulate_fmu

    from sarins.systems import build_system_fmu

    result = simulate_fmu(str(build_system_fmu(fmu_dir, "StandardStaticSystem")))
    nav = result["ins.nav_time"]
    first = int(np.argmax(nav >= 0))
    return {"rows": len(result), "stop_h": result["time"][-1] / 3600, "nav_time_first_s": nav[0],
            "navigation_starts_s": result["time"][first], "position_error_end_m": result["ins.position_error"][-1]}


def mems_hour_nmi() -> float:
    """``sarins navigate --imu mems --nav-hours 1``: position error, nmi."""
    out = subprocess.run([sys.executable, "-m", "sarins", "navigate", "--imu", "mems", "--nav-hours", "1"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    return float(re.search(r"position_error_nmi:\s*([0-9.]+)", out).group(1))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fmu-dir", type=Path, help="built FMUs (default: build them into a scratch folder)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "fmus"
        if args.fmu_dir:
            shutil.copytree(args.fmu_dir, folder)
        else:
            from fmus.build import build_fmus

            build_fmus(folder, ["Turntable", "IMUThermal", "StrapdownINS"], cross=False)
        for key, value in system_fmu_numbers(folder).items():
            print(f"system FMU {key}: {value:.6g}")
    print(f"MEMS 1 h position error: {mems_hour_nmi():.6g} nmi")
    return 0


if __name__ == "__main__":
    sys.exit(main())
