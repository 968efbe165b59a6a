"""Export a trained seed 003 compensator as a self-contained native IMUCompensator FMU.

``export_compensator(model_file, out_dir)`` checks the model file (any kind
of :mod:`sarins_fmu.identify.compensators`, JSON or npz), writes it as the
binary model file the C model reads (:mod:`sarins_fmu.identify.netfile`) into
the FMU's ``resources/compensator.bin`` and builds
``<out_dir>/IMUCompensator.fmu`` (native: no Python at run time, FMI 2.0 or
3.0).

The system that uses it (Turntable -> IMUThermal -> IMUCompensator ->
StrapdownINS) is :func:`sarins.systems.compensated_chain`.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from sarins_fmu.identify import compensators

from . import SLAVES
from .imu_compensator_slave import MODEL_IN_RESOURCES
from .native_fmu import build_native_fmu


def export_compensator(model_file: str | Path, out_dir: str | Path, name: str | None = None, fmi: int = 2,
                       win64: bool | None = None, aarch64: bool | None = None) -> Path:
    """Build an IMUCompensator FMU carrying ``model_file``.

    Parameters
    ----------
    model_file : a compensator model file (JSON or npz) written by ``Compensator.save``
    out_dir : folder for the FMU (created)
    name : file name of the FMU (default ``IMUCompensator.fmu``; the model
        identifier stays IMUCompensator)
    fmi : 2 or 3, the FMI version
    win64 : also the Windows binary (default: when mingw-w64 is on PATH)

    Raises
    ------
    ModelFileError (ValueError) when the model file is missing or invalid.
    """
    model = compensators.load(model_file)
    out_dir = Path(out_dir)
    with tempfile.TemporaryDirectory(prefix="sarins_compensator_") as tmp:
        fmu = build_native_fmu("IMUCompensator", SLAVES["IMUCompensator"], Path(tmp) / "out", fmi=fmi,
                               win64=win64, aarch64=aarch64, resources={MODEL_IN_RESOURCES: model.binary()})
        target = out_dir / (name or fmu.name)
        out_dir.mkdir(parents=True, exist_ok=True)
        shutil.move(str(fmu), target)
    return target
