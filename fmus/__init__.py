"""FMI 2.0 co-simulation slaves (pythonfmu) over the sarins_fmu library, and their build step.

Each slave module holds one class deriving from ``Fmi2Slave``; it declares
the variables, converts between FMI scalars and library arrays, and calls
the library.  No physics lives here.  ``fmus.build`` turns the slaves into
self-contained FMUs (the library travels in each FMU's resources).  The
native FMUs (``fmus.native_fmu.NATIVE``) keep only the declaration here; their
FMI calls are answered in C (``fmus/c``).
"""

SLAVES = {
    "Turntable": "turntable_slave.py",
    "IMUThermal": "imu_thermal_slave.py",
    "StrapdownINS": "strapdown_ins_slave.py",
    "RBFIdentifier": "rbf_identifier_slave.py",
    "DriftModelUpdater": "drift_model_updater_slave.py",
    "IMUCompensator": "imu_compensator_slave.py",
    "VehicleMotion": "vehicle_motion_slave.py",
    "IMULog": "imu_log_slave.py",
    "GNSSReceiver": "gnss_receiver_slave.py",
    "AidedINS": "aided_ins_slave.py",
    "TrajectoryIMU": "trajectory_imu_slave.py",
}
