"""A minimal Gauss-Seidel driver over FMPy's FMU2Slave, for the FMU tests
(independent of the project's master, so the FMUs are checked on their own)."""

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from orchestration import fmilog


def unpack(path):
    """(model description, extracted folder) of the FMU at ``path``."""
    return read_model_description(str(path)), extract(str(path))


class Slave:
    def __init__(self, path, name, log=None, unpacked=None):
        """``unpacked``: (model description, folder) of ``path`` read and extracted once by :func:`unpack`
        for many instances (default: read and extracted for this one)."""
        self.md, self.dir = unpacked or unpack(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.log = [] if log is None else log
        self.name = fmilog.register(name, lambda status, category, text: self.log.append((status, category, text)))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=self.name)
        self.fmu.instantiate(loggingOn=True, callbacks=fmilog.callbacks())
        self.fmu.setupExperiment(startTime=0.0)

    def set(self, **values):
        for name, value in values.items():
            if isinstance(value, str):
                self.fmu.setString([self.vr[name]], [value])
            elif isinstance(value, int) and not isinstance(value, bool):
                self.fmu.setInteger([self.vr[name]], [value])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def free(self):
        try:
            self.fmu.terminate()
        except Exception:
            pass
        self.fmu.freeInstance()
        fmilog.unregister(self.name)


# the time-tagged motion set and increments: sarins.systems' GIMBAL_LINKS and INCREMENT_LINKS, written out
# (this driver also runs in a host without the project, test_fmu_runs_in_a_host_without_this_project)
TT_TO_IMU = [f"{q}_{j}" for j in (1, 2, 3) for q in ("angle", "rate", "accel")] + [
    "ambient_temp", "ambient_temp_rate", "motion_time"]
IMU_TO_INS = ["dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z", "temp_gyro_z", "increment_end_time"]


def check_parameter_error(fmu_path, params: dict, text: str) -> None:
    """Bad parameters: fmi2ExitInitializationMode returns fmi2Error and the
    logged error names ``text``; the host frees the instance."""
    import pytest
    from fmpy.fmi1 import FMICallException

    slave = Slave(fmu_path, "bad")
    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.exitInitializationMode()
        errors = [message for status, _, message in slave.log if status == 3]
        assert any(text in message for message in errors), slave.log
    finally:
        slave.free()


def run_chain(fmu_dir, n_steps, *, step=1.0, tt_params=None, imu_params=None, ins_params=None,
              record=("lat_error",), correction=None):
    """Turntable -> IMUThermal -> StrapdownINS, Gauss-Seidel, fixed step."""
    tt = Slave(fmu_dir / "Turntable.fmu", "turntable")
    imu = Slave(fmu_dir / "IMUThermal.fmu", "imu")
    ins = Slave(fmu_dir / "StrapdownINS.fmu", "ins")
    try:
        tt.set(**(tt_params or {}))
        imu.set(**(imu_params or {}))
        ins.set(**(ins_params or {}))
        for s in (tt, imu, ins):
            s.fmu.enterInitializationMode()
        imu.fmu.setReal([imu.vr[n] for n in TT_TO_IMU], tt.get(*TT_TO_IMU))
        ins.fmu.setReal([ins.vr[n] for n in IMU_TO_INS], imu.get(*IMU_TO_INS))
        for s in (tt, imu, ins):
            s.fmu.exitInitializationMode()
        rows = []
        for k in range(n_steps):
            t = k * step
            tt.fmu.doStep(t, step)
            imu.fmu.setReal([imu.vr[n] for n in TT_TO_IMU], tt.get(*TT_TO_IMU))
            imu.fmu.doStep(t, step)
            ins.fmu.setReal([ins.vr[n] for n in IMU_TO_INS], imu.get(*IMU_TO_INS))
            if correction is not None:
                ins.set(axial_drift_correction=correction(t))
            ins.fmu.doStep(t, step)
            rows.append(ins.get(*record))
        return rows
    finally:
        for s in (ins, imu, tt):
            s.free()
