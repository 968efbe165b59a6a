"""Export a trained seed 003 compensator as a self-contained IMUCompensator FMU.

``export_compensator(model_file, out_dir)`` checks the model file (any kind
of :mod:`sarins_fmu.identify.compensators`), rewrites it as plain npz into
the FMU's ``resources/compensator.npz`` and builds
``<out_dir>/IMUCompensator.fmu``.  The FMU needs only numpy at run time
(recurrent models run on numpy cells).

``compensated_chain(...)`` is the system Turntable -> IMUThermal ->
IMUCompensator -> StrapdownINS (the compensator between the IMU and the INS).
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from sarins_fmu.identify import compensators

from . import SLAVES
from .build import build_fmu
from .imu_compensator_slave import MODEL_IN_RESOURCES

RAW_LINKS = [(f"dtheta_{a}", f"raw_dtheta_{a}") for a in "xyz"] + [(f"dv_{a}", f"raw_dv_{a}") for a in "xyz"]
TEMPS = ["temp_gyro_x", "temp_gyro_y", "temp_gyro_z", "temp_accel_x", "temp_accel_y", "temp_accel_z"]


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


def compensated_chain(fmu_dir: str | Path, compensator_fmu: str | Path, *, turntable=None, imu=None, ins=None,
                      step: float = 0.05, stop: float = 3600.0):
    """System Turntable -> IMUThermal -> IMUCompensator -> StrapdownINS (Gauss-Seidel order).

    ``fmu_dir`` holds Turntable.fmu, IMUThermal.fmu and StrapdownINS.fmu;
    the INS reads the compensated increments and the IMU's z-gyro temperature.
    """
    from orchestration import Component, Connection, System

    from sarins.systems import GIMBAL_LINKS  # moved with the systems (issue 13)

    fmu_dir = Path(fmu_dir)
    components = [Component("turntable", fmu_dir / "Turntable.fmu", dict(turntable or {})),
                  Component("imu", fmu_dir / "IMUThermal.fmu", dict(imu or {})),
                  Component("comp", Path(compensator_fmu), {}),
                  Component("ins", fmu_dir / "StrapdownINS.fmu", dict(ins or {}))]
    connections = [Connection("turntable", v, "imu", v) for v in GIMBAL_LINKS]
    connections += [Connection("imu", a, "comp", b) for a, b in RAW_LINKS]
    connections += [Connection("imu", t, "comp", t) for t in TEMPS]
    connections += [Connection("comp", v, "ins", v) for v, _ in RAW_LINKS]
    connections += [Connection("imu", "temp_gyro_z", "ins", "temp_gyro_z")]
    return System(name="compensated_chain", components=components, connections=connections, start_time=0.0,
                  stop_time=stop, step_size=step)
