"""Export a trained seed 003 compensator as a self-contained IMUCompensator FMU.

``export_compensator(model_file, out_dir)`` checks the model file (any kind
of :mod:`sarins_fmu.identify.compensators`), rewrites it as plain npz into
the FMU's ``resources/compensator.npz`` and builds
``<out_dir>/IMUCompensator.fmu``.  The FMU needs only numpy at run time
(recurrent models run on numpy cells).

The system that uses it (Turntable -> IMUThermal -> IMUCompensator ->
StrapdownINS) is :func:`sarins.systems.compensated_chain`.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from sarins_fmu.identify import compensators

from . import SLAVES
from .build import build_fmu
from .imu_compensator_slave import MODEL_IN_RESOURCES

def export_compensator(model_file: str | Path, out_dir: str | Path, name: str | None = None) -> Path:
    """Build an IMUCompensator FMU carrying ``model_file``.

    Parameters
    ----------
    model_file : a compensator model file (JSON or npz) written by ``Compensator.save``
    out_dir : folder for the FMU (created)
    name : file name of the FMU (default ``IMUCompensator.fmu``; the model
        identifier stays IMUCompensator)

    Raises
    ------
    ModelFileError (ValueError) when the model file is missing or invalid.
    """
    model = compensators.load(model_file)
    out_dir = Path(out_dir)
    with tempfile.TemporaryDirectory(prefix="sarins_compensator_") as tmp:
        shipped = model.save(Path(tmp) / MODEL_IN_RESOURCES)
        fmu = build_fmu(SLAVES["IMUCompensator"], Path(tmp) / "out", extra_files=[shipped])
        target = out_dir / (name or fmu.name)
        out_dir.mkdir(parents=True, exist_ok=True)
        shutil.move(str(fmu), target)
    return target
