"""Build the fixture slaves into FMUs with ``pythonfmu build`` (once per session)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
SLAVES = ("Ramp", "Gain", "Faulty", "Feed")


def build_fixture_fmus(destination: Path) -> dict[str, Path]:
    """Build every fixture slave into ``destination``; reuse FMUs already there.

    Returns
    -------
    dict
        ``{slave name: FMU path}``, plus ``'RampFixedStep'``: the Ramp built
        with ``canHandleVariableCommunicationStepSize=false``.
    """
    destination.mkdir(parents=True, exist_ok=True)
    fmus = {}
    for name in SLAVES:
        fmu = destination / f"{name}.fmu"
        if not fmu.is_file():
            subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f",
                            str(HERE / f"{name}.py"), "-d", str(destination)],
                           check=True, capture_output=True, cwd=destination)
        fmus[name] = fmu
    fixed = destination / "fixed_step" / "Ramp.fmu"
    if not fixed.is_file():
        fixed.parent.mkdir(exist_ok=True)
        subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f",
                        str(HERE / "Ramp.py"), "-d", str(fixed.parent), "--no-variable-step"],
                       check=True, capture_output=True, cwd=fixed.parent)
    fmus["RampFixedStep"] = fixed
    return fmus
