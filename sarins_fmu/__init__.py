"""sarins-fmu: simulation of a laser-gyro rotating inertial navigation system.

Frames (used in every variable name that carries a frame suffix)
-----------------------------------------------------------------
``n``  navigation frame: local level East-North-Up (ENU) at the current
       position.
``b``  body (IMU sensor) frame: x right, y front, z up (right-front-up, as in
       seed 002).  Gyro and accelerometer triads measure along b.
``t``  turntable base frame: the frame the outermost gimbal axis is fixed in
       (the INS case / vehicle).  On a static base it is level; its yaw is a
       parameter.
``e``, ``i``  Earth-fixed and inertial frames.

Attitude matrices are named ``mat_xy`` and project frame y onto frame x, so
``mat_nb @ v_b = v_n`` (pyins' habit; the textbooks write C_b^n).  Yaw is the
rotation about the up axis, positive counter-clockwise seen from above
(towards the west), the Chinese-literature convention of the seeds.

Units
-----
SI inside: rad, rad/s, m, m/s, m/s^2, s; temperatures in degree Celsius.
Papers' units (deg/h, nautical miles, degrees) appear only at the edges (CLI,
FMU display units, reports) and the variable says so: ``drift_dph``,
``lat_deg``, ``error_nmi``.  Conversion constants live in
:mod:`sarins_fmu.units`.

Modules
-------
earth        WGS-84 constants, normal gravity, radii of curvature, Earth rate
rotations    DCM / quaternion / rotation-vector helpers
thermal      lumped thermal model of the IMU (cold and hot start)
imu          sensor error models, presets, increment generation (minor loop)
turntable    gimbal schedules: rotation schemes and rate-table profiles
ins          strapdown mechanization (ENU, two-speed) and alignment
kalman       static-base / zero-velocity Kalman filter models
experiments  the papers' protocols as scenario functions

Public API
----------
The names in ``__all__`` are re-exported here and imported on first use
(so ``import sarins_fmu`` stays cheap and an FMU that ships part of the
library imports only what it runs): ``sarins_fmu.run_static(...)``,
``sarins_fmu.IMU``, ``sarins_fmu.preset("nav-rlg")`` ...
"""

from importlib import import_module

__version__ = "0.1.0"

# public name -> submodule that defines it
_PUBLIC = {
    "IMU": "imu", "ImuModel": "imu", "StaticBase": "imu", "preset": "imu", "PRESETS": "imu",
    "ThermalModel": "thermal", "ThermalParams": "thermal", "Ambient": "thermal",
    "GimbalSchedule": "turntable", "single_axis": "turntable", "dual_axis": "turntable",
    "schedule_for": "turntable", "chain_matrix": "turntable",
    "StrapdownINS": "ins", "InsConfig": "ins",
    "StopKalmanFilter": "kalman", "StopFilterSettings": "kalman",
    "VehicleTrajectory": "vehicle",
    "run_static": "experiments", "StaticRunResult": "experiments",
    "SITE_LAT_DEG": "site",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name):
    try:
        module = _PUBLIC[name]
    except KeyError:
        raise AttributeError(f"module 'sarins_fmu' has no attribute {name!r}") from None
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value
