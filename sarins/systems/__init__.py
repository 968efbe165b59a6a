"""The project's own co-simulation systems, written as SSP files.

``standard_static(fmu_dir)`` is the standard static single-axis RINS:
Turntable -> IMUThermal -> StrapdownINS, 1 s communication step, Gauss-Seidel
order Turntable, IMUThermal, StrapdownINS.  ``write_systems(fmu_dir)`` packs
each system as ``<name>.ssp`` (FMUs in ``resources/``) beside the FMUs; the
SSD alone is shipped in ``sarins/systems/<name>/SystemStructure.ssd``
(sources ``resources/<FMU>.fmu``, the SSP layout).
"""

from __future__ import annotations

from pathlib import Path

from fmus.slave_support import NO_TAG
from orchestration import Component, Connection, System, write_ssd, write_ssp

GIMBAL_LINKS = [f"{q}_{j}" for j in (1, 2, 3) for q in ("angle", "rate", "accel")] + [
    "ambient_temp", "ambient_temp_rate", "motion_time"]
RAW_LINKS = [(f"dtheta_{a}", f"raw_dtheta_{a}") for a in "xyz"] + [(f"dv_{a}", f"raw_dv_{a}") for a in "xyz"]  # IMU -> IMUCompensator
TEMPS = ["temp_gyro_x", "temp_gyro_y", "temp_gyro_z", "temp_accel_x", "temp_accel_y", "temp_accel_z"]
INCREMENT_LINKS = ["dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z", "temp_gyro_z", "increment_end_time"]
# K-second steps (FMI 3.0): the motion and the increments of every second of a step in arrays
GIMBAL_SUB_LINKS = [f"{name}_sub" for name in GIMBAL_LINKS if name != "motion_time"] + ["motion_time"]
INCREMENT_SUB_LINKS = [f"{name}_sub" for name in INCREMENT_LINKS if name != "increment_end_time"] + [
    "increment_end_time"]
SHIPPED = Path(__file__).resolve().parent


def standard_static(fmu_dir: Path | str = "resources", *, hours: float = 88.0, turntable=None, imu=None,
                    ins=None, seconds_per_step: int = 1, threads: int | None = None) -> System:
    """Turntable -> IMUThermal -> StrapdownINS on a static base (seed 000 set-up).

    Parameters
    ----------
    fmu_dir : folder of the FMUs (relative paths stay relative in the SSD)
    hours : default stop time of the system, h
    turntable, imu, ins : dict of extra start values per component
    seconds_per_step : K > 1 needs the FMI 3.0 FMUs (``sarins build-fmus --fmi 3``): a communication step
        of K s, every 1 s sub-interval of it in arrays (the Turntable's motion of each second to the IMU,
        the IMU's increments of each second to the INS, all three with ``n_sub`` = K): the numbers of the
        1 s system, bit for bit, with K times fewer FMI calls
    threads : the IMU's threads for the minor loops of a step's K seconds (K > 1; the same numbers); default
        the in-process run's (``SARINS_THREADS``, else the machine's cores), at most 64
    """
    fmu_dir = Path(fmu_dir)
    k = _seconds_per_step(seconds_per_step)
    sub = {"n_sub": k} if k > 1 else {}
    imu_sub = {**sub, "sub_inputs": 1, "threads": _imu_threads(threads), **SUB_SCALARS_HELD_IMU} if k > 1 else {}
    ins_sub = {**sub, "sub_inputs": 1, **SUB_SCALARS_HELD_INS} if k > 1 else {}
    components = [
        Component("turntable", fmu_dir / "Turntable.fmu", {**sub, **dict(turntable or {})}),
        Component("imu", fmu_dir / "IMUThermal.fmu", {**STATIC_BASE_HELD, **imu_sub, **dict(imu or {})}),
        Component("ins", fmu_dir / "StrapdownINS.fmu", {**NO_CORRECTION, **ins_sub, **dict(ins or {})}),
    ]
    if k > 1:  # the arrays carry every second; the scalars they replace stay unconnected (held start values)
        connections = [Connection("turntable", v, "imu", v) for v in GIMBAL_SUB_LINKS]
        connections += [Connection("imu", v, "ins", v) for v in INCREMENT_SUB_LINKS]
    else:
        connections = [Connection("turntable", v, "imu", v) for v in GIMBAL_LINKS]
        connections += [Connection("imu", v, "ins", v) for v in INCREMENT_LINKS]
    return System(name="standard_static", components=components, connections=connections,
                  start_time=0.0, stop_time=hours * 3600.0, step_size=float(k))


def _imu_threads(value) -> int:
    """The IMU FMU's thread count: ``value``, or the in-process run's (at most the FMU's 64)."""
    if value is None:
        from sarins_fmu.core.imu import thread_count

        return min(thread_count(), 64)
    return int(value)


def _seconds_per_step(value) -> int:
    """K of a K-second communication step: a whole number of seconds, 1 .. the FMUs' array limit."""
    from fmus.native_fmu import MAX_DIM

    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value) \
            or not 1 <= int(value) <= MAX_DIM:
        raise ValueError(f"seconds_per_step must be a whole number of seconds in 1 .. {MAX_DIM}, got {value!r}")
    return int(value)


# the FMUs of standard_static_identified (standard_static: the first three)
IDENTIFIED_STATIC_FMUS = ("Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier")


def standard_static_identified(fmu_dir: Path | str = "resources", *, hours: float = 88.0, turntable=None,
                               imu=None, ins=None, identifier=None, seconds_per_step: int = 1,
                               threads: int | None = None) -> System:
    """The standard static system with seed 000's RBFIdentifier closing the loop.

    Turntable -> IMUThermal -> StrapdownINS -> RBFIdentifier -> (axial drift
    correction) StrapdownINS.  The identifier reads the INS latitude error,
    navigation time, alignment temperature change and azimuth gyro
    temperature (all tagged nav_time); at its trigger time (default 12 h of
    navigation) it outputs the identified drift, held, with the navigation
    time ``apply_from`` (trigger + the identifier's latency) from which the
    INS subtracts it: ``run_static``'s ``correction_from_hours``.  Every
    output is a state output, so the loop INS -> identifier -> INS has no
    direct feedthrough; the result is the same under Gauss-Seidel and
    Jacobi.  Default stop: 4 h alignment + 84 h.  A JSON/npz ``model_file`` in ``identifier`` is
    converted into the binary model file the FMU reads, in ``fmu_dir/identifier_models``.
    ``seconds_per_step``, ``threads``: as :func:`standard_static` (the identifier then reads the INS every
    K s, so its trigger_time must be a navigation time the INS reports at a communication point; apply_from
    may fall inside a step).
    """
    base = standard_static(fmu_dir, hours=hours, turntable=turntable, imu=imu, ins=ins,
                           seconds_per_step=seconds_per_step, threads=threads)
    for name in IDENTIFIED_CORRECTION:  # fed by the identifier here
        base.components[2].parameters.pop(name, None)
    params = dict(identifier or {})
    if params.get("model_file"):  # the native FMU reads binary model files: a JSON/npz one is converted
        from sarins_fmu.identify.axial import fmu_model_file

        params["model_file"] = str(fmu_model_file(params["model_file"], Path(fmu_dir) / "identifier_models"))
    identifier_fmu = Component("identifier", Path(fmu_dir) / "RBFIdentifier.fmu", params)
    loop = [Connection("ins", "lat_error", "identifier", "lat_error"),
            Connection("ins", "nav_time", "identifier", "nav_time"),
            Connection("ins", "temp_change_align", "identifier", "temp_change"),
            Connection("ins", "temp_azimuth_gyro", "identifier", "temperature"),
            Connection("identifier", "axial_drift", "ins", "axial_drift_correction"),
            Connection("identifier", "apply_from", "ins", "axial_drift_apply_from")]
    return System(name="standard_static_identified", components=[*base.components, identifier_fmu],
                  connections=[*base.connections, *loop], start_time=base.start_time,
                  stop_time=base.stop_time, step_size=base.step_size)


VEHICLE_LINKS = [f"vehicle_{a}{q}" for q in ("", "_rate", "_accel") for a in ("yaw", "pitch", "roll")] + [
    f"base_{kind}_{ax}" for kind in ("rate", "force") for ax in "enu"] + ["base_motion_time"]


# On a static base IMUThermal (base = static) does not read its moving-base inputs: the
# static systems hold them at their declared start values explicitly, so no input is left
# unconnected by accident (and the master has nothing to warn about).
# Without an identifier the INS's axial-drift correction inputs are held at zero explicitly.
NO_CORRECTION = {"axial_drift_correction": 0.0, "axial_drift_apply_from": 0.0, "axial_drift_correction_b": 0.0,
                 "axial_drift_correction_a": 0.0}
IDENTIFIED_CORRECTION = ("axial_drift_correction", "axial_drift_apply_from")  # the RBFIdentifier sends a constant
STATIC_BASE_HELD = {name: (NO_TAG if name == "base_motion_time" else 0.0) for name in VEHICLE_LINKS}
# K-second steps: the scalar inputs the arrays replace (unread with sub_inputs = 1) held at their declared
# start values, so that no input is left unconnected by accident
SUB_SCALARS_HELD_IMU = {name: (20.0 if name == "ambient_temp" else 0.0) for name in GIMBAL_LINKS
                        if name != "motion_time"}
SUB_SCALARS_HELD_INS = {name: (20.0 if name == "temp_gyro_z" else 0.0) for name in INCREMENT_LINKS
                        if name != "increment_end_time"}


def vehicle_rins(fmu_dir: Path | str = "resources", *, hours: float = 2.0, vehicle=None, turntable=None, imu=None,
                 ins=None) -> System:
    """VehicleMotion -> IMUThermal (base = input) <- Turntable, IMUThermal -> StrapdownINS.

    The RINS's turntable rides on a land vehicle (seed 002): the vehicle's
    attitude, base rate and specific force reach the IMU as a time-tagged
    start-of-step set like the turntable's.  The vehicle stands still for its
    ``lead_time`` (default 900 s), the INS aligns over the same time.
    """
    fmu_dir = Path(fmu_dir)
    vehicle = dict(vehicle or {})
    lead = float(vehicle.get("lead_time", 900.0))
    start = {k: vehicle[v] for k, v in (("lat0", "lat0"), ("lon0", "lon0")) if v in vehicle}
    components = [
        Component("vehicle", fmu_dir / "VehicleMotion.fmu", vehicle),
        Component("turntable", fmu_dir / "Turntable.fmu", {"align_time": 0.0, **dict(turntable or {})}),
        Component("imu", fmu_dir / "IMUThermal.fmu", {"base": "input", **dict(imu or {})}),
        Component("ins", fmu_dir / "StrapdownINS.fmu", {"align_time": lead, **NO_CORRECTION, **start, **dict(ins or {})}),
    ]
    connections = [Connection("vehicle", v, "imu", v) for v in VEHICLE_LINKS]
    connections += [Connection("turntable", v, "imu", v) for v in GIMBAL_LINKS]
    connections += [Connection("imu", v, "ins", v) for v in INCREMENT_LINKS]
    return System(name="vehicle_rins", components=components, connections=connections,
                  start_time=0.0, stop_time=hours * 3600.0, step_size=1.0)


# DriftModelUpdater <-> StrapdownINS (seed 002's online update): the INS row it reads (all tagged
# solution_time), the vehicle's speed (tagged base_motion_time) and the model it sends back (tagged apply_from)
INS_TO_UPDATER = [("v_e", "v_e"), ("v_n", "v_n"), ("yaw", "yaw"), ("pitch", "pitch"), ("roll", "roll"), ("lat", "lat"),
                  ("temp_azimuth_gyro", "temp_gyro_z"), ("nav_time", "nav_time"), ("solution_time", "solution_time")]
# the updater's ins_phase input is held at 2 (navigating): the row's nav_time (>= 0 in navigation) tells the
# phase, and an Integer connection is one libcosimpy 0.0.6 cannot make
UPDATER_HELD = {"ins_phase": 2}
VEHICLE_TO_UPDATER = [("speed", "vehicle_speed"), ("base_motion_time", "speed_time")]
UPDATER_TO_INS = [("drift_a", "axial_drift_correction_a"), ("drift_b", "axial_drift_correction_b"),
                  ("drift_c", "axial_drift_correction"), ("apply_from", "axial_drift_apply_from")]
ONLINE_LEGS = "drive 300 10; turn 90; drive 300 12; stop 1920; drive 180 10; stop 60"  # a stop long enough to update


def vehicle_rins_online(fmu_dir: Path | str = "resources", *, hours: float = 1.25, vehicle=None, turntable=None,
                        imu=None, ins=None, updater=None) -> System:
    """Seed 002's vehicle test: ``vehicle_rins`` with the DriftModelUpdater closing the loop.

    VehicleMotion -> IMUThermal <- Turntable, IMUThermal -> StrapdownINS ->
    DriftModelUpdater (stop Kalman filter at the vehicle's stops, FF-RLS
    update of the azimuth drift model when it moves off after at least 30
    min) -> (the model a, b, c from ``apply_from``) StrapdownINS, which
    evaluates it at each interval's gyro temperature.  The updater pairs each
    INS row (``solution_time``) with the vehicle's speed of the same time
    (``speed_time``) and sends the model with one step of latency
    (``latency`` = 1 s), the least any scheme allows, so the run is the same
    under Gauss-Seidel and Jacobi.  Default legs: a 32-min stop after 15 min
    of alignment and 10 min of driving, which updates the model once.
    """
    fmu_dir = Path(fmu_dir)
    base = vehicle_rins(fmu_dir, hours=hours, vehicle={"legs": ONLINE_LEGS, **dict(vehicle or {})},
                        turntable=turntable, imu=imu, ins=ins)
    ins_component = base.components[3]
    for name in NO_CORRECTION:  # fed by the updater here
        ins_component.parameters.pop(name, None)
    component = Component("updater", fmu_dir / "DriftModelUpdater.fmu",
                          {"latency": 1.0, **UPDATER_HELD, **dict(updater or {})})
    loop = [Connection("ins", a, "updater", b) for a, b in INS_TO_UPDATER]
    loop += [Connection("vehicle", a, "updater", b) for a, b in VEHICLE_TO_UPDATER]
    loop += [Connection("updater", a, "ins", b) for a, b in UPDATER_TO_INS]
    return System(name="vehicle_rins_online", components=[*base.components, component],
                  connections=[*base.connections, *loop], start_time=base.start_time, stop_time=base.stop_time,
                  step_size=base.step_size)


# vehicle_gnss's default drive (120 s at 100 Hz) and GNSS outage
GNSS_DRIVE = {"start": {"lat_deg": 32.0, "lon_deg": 118.8, "height": 20.0, "heading_deg": 0.0},
              "segments": [{"kind": "stop", "duration": 10}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
                           {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 50},
                           {"kind": "turn", "radius": 150, "angle_deg": -90},
                           {"kind": "accelerate", "to_speed": 0, "accel": 1.5}, {"kind": "stop", "duration": 10}]}
GNSS_OUTAGES = ((60.0, 80.0),)
TRUTH_TO_RECEIVER = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "omega_ib_x", "omega_ib_y",
                     "omega_ib_z", "truth_time"]
IMU_TO_AIDED = [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"] + ["increment_end_time"]
ODOMETER_TO_AIDED = ["odo_valid", "odo_speed"]  # TrajectoryIMU -> AidedINS, tagged with the increments
UNUSED_AIDING = {"zaru": 0, "zupt": 0, "zupt_v_e": 0.0, "zupt_v_n": 0.0, "zupt_v_u": 0.0, "nhc": 0, "nhc_v_x": 0.0,
                 "nhc_v_z": 0.0}  # AidedINS inputs these systems leave off (their values are read under a flag only)
STILL_TO_AIDED = [("zupt", "zupt"), ("zupt", "zaru")] + [(v, v) for v in ("zupt_v_e", "zupt_v_n", "zupt_v_u", "nhc",
                                                                    "nhc_v_x", "nhc_v_z")]  # TrajectoryIMU -> AidedINS
ODOMETER_SETTINGS = ["odo_scale_factor", "odo_noise_std", "odo_resolution"]  # aided.OdometerConfig's (odo.h)
RECEIVER_TO_AIDED = ["fix_valid", "fix_lat", "fix_lon", "fix_height", "fix_v_e", "fix_v_n", "fix_v_u", "fix_count",
                     "fix_time", "fix_horizon"]
AIDED_SETTINGS = ["step", "arw", "vrw", "gyro_rw", "accel_rw", "pos0_std", "vel0_std", "tilt0_std", "heading0_std",
                  "gyro_bias0_std", "accel_bias0_std", "lever_x", "lever_y", "lever_z", "latency", "zupt_std",
                  "cov_every", "nhc_std", "odo_std", "zaru_std"]  # aided._config's order (eskf.h)
RECEIVER_SETTINGS = ["lever_x", "lever_y", "lever_z", "pos_white_e", "pos_white_n", "pos_white_u", "pos_gm_e",
                     "pos_gm_n", "pos_gm_u", "pos_gm_tau", "vel_white_e", "vel_white_n", "vel_white_u", "vel_gm_e",
                     "vel_gm_n", "vel_gm_u", "vel_gm_tau"]  # GNSSConfig.array's order (gnss.h)


def vehicle_gnss(fmu_dir: Path | str = "resources", *, trajectory=None, seed: int = 0, gnss="sps",
                 gnss_rate_hz: float = 1.0, imu_noise: str = "tactical", imu_rate_hz: float = 100.0,
                 outages=GNSS_OUTAGES, odometer=None, zupt: bool = False, zupt_detect: str = "truth",
                 vibration=None, detector=None) -> System:
    """TrajectoryIMU -> GNSSReceiver -> AidedINS, TrajectoryIMU -> AidedINS: the aided run of
    ``sarins navigate --trajectory FILE --aiding gnss`` as a system; with ``odometer`` (an
    :class:`sarins_fmu.aided.OdometerConfig`) TrajectoryIMU's odometer feeds AidedINS too: the run of
    ``--aiding gnss,odometer`` (odometer seed ``seed``, as navigate draws it); with ``zupt`` TrajectoryIMU's
    ZUPT and NHC rows (``zupt_enable``, ``nhc_enable``, ``jitter_seed`` = ``seed``, the filter's stds) feed
    AidedINS's ``zupt``, ``zupt_v_*``, ``nhc``, ``nhc_v_*``, and its still flag ``zupt`` also ``zaru``: with the
    odometer the run of ``--aiding gnss,zupt,zaru,nhc,odometer --imu-stream core`` (system
    ``vehicle_gnss_zupt``).  With ``zupt`` and ``zupt_detect='imu'`` the stops are AidedINS's own, detected from
    the increments (``zupt_source`` 1, the detector of :mod:`sarins_fmu.zero_velocity` with ``detector``, a
    ``DetectorSettings``, default its defaults; inputs ``zupt`` and ``zaru`` held at 1, TrajectoryIMU's
    ``zupt_enable`` 2 giving the ZUPT jitter of every step) and ``vibration`` (a ``Vibration``, or None)
    shakes TrajectoryIMU's increments while moving (``vib_accel_rms``, ``vib_rate_rms``): the run of
    ``navigate(..., zupt_detect='imu', vibration=vibration, detector=detector, imu_stream='core')``.

    ``trajectory``: a :class:`sarins_fmu.trajectory.Trajectory`, a dict or a JSON file (default
    ``GNSS_DRIVE``, 120 s); ``gnss``: a preset name or a GNSSConfig; ``outages``: windows [start, end) s.
    The parameters are those ``aided.navigate`` runs with (``FilterSettings()``, seed ``seed``; the filter's
    initial state drawn as navigate draws it); the IMU's errors are the core's stream
    (``aided.corrupt(stream='core')``).  Every link carries a time tag (truth_time, increment_end_time,
    fix_time, fix_horizon), so the rows at each ``nav_time`` are the same under Gauss-Seidel and Jacobi
    (Jacobi two steps later).  Communication step = the IMU step.  The odometer's readings travel with the
    increments (same FMU, same tag).
    """
    import numpy as np

    from sarins_fmu import aided, gnss as gnss_mod, trajectory as tr, zero_velocity as zv

    if zupt_detect not in aided.ZUPT_DETECT:
        raise ValueError(f"zupt_detect must be one of {', '.join(aided.ZUPT_DETECT)}, got {zupt_detect!r}")
    detected = zupt and zupt_detect == "imu"

    if trajectory is None or isinstance(trajectory, dict):
        trajectory = tr.Trajectory.from_dict(trajectory or GNSS_DRIVE)
    elif not isinstance(trajectory, tr.Trajectory):
        trajectory = tr.load_trajectory(trajectory)
    receiver = gnss_mod.preset(gnss, rate_hz=gnss_rate_hz) if isinstance(gnss, str) else gnss
    noise, settings, step = aided.IMU_NOISE[imu_noise], aided.FilterSettings(), 1.0 / imu_rate_hz
    truth = tr.generate(trajectory, step)
    fmu_dir = Path(fmu_dir)
    table = trajectory.table(step)
    motion = {"segments": "; ".join(" ".join(repr(float(x)) for x in row) for row in table), "step": step,
              "seed": int(seed), **dict(zip(["lat0", "lon0", "height0", "speed0", "yaw0", "pitch0"],
                                            trajectory.start.array().tolist())),
              **dict(zip(["arw", "vrw", "gyro_bias_std", "accel_bias_std", "gyro_rw", "accel_rw"],
                         noise.array().tolist()))}
    rx = {"rate_hz": float(receiver.rate_hz), "seed": int(seed), "outages": ";".join(f"{float(a)!r}:{float(b)!r}" for a, b in
                                                                                    np.asarray(outages, float)),
          **dict(zip(RECEIVER_SETTINGS, receiver.array().tolist()))}
    nav0 = aided._initial_state(truth, settings, np.random.default_rng([seed, 3018]))
    if odometer is not None:
        motion.update({"odo_rate_hz": float(odometer.rate_hz), "odo_seed": int(seed),
                       **dict(zip(ODOMETER_SETTINGS, [float(odometer.scale_factor), float(odometer.noise_std),
                                                      float(odometer.resolution)]))})
    ins = {**dict(zip(AIDED_SETTINGS, aided._config(noise, settings, receiver, step, odometer).tolist())),
           **{f"{n}0": float(v) for n, v in zip(["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"],
                                                nav0)},
           **{f"gnss_{k}_std_{a}": float(v) for k, std in (("pos", receiver.pos_std()), ("vel", receiver.vel_std()))
              for a, v in zip("enu", std)}, "use_velocity": 1,
           **({} if zupt else UNUSED_AIDING),
           **({} if odometer is not None else {"odo_valid": 0, "odo_speed": 0.0})}
    if zupt:
        motion.update({"zupt_enable": 2 if detected else 1, "nhc_enable": 1, "zupt_std": float(settings.zupt_std),
                       "nhc_std": float(settings.nhc_std), "jitter_seed": int(seed)})
    if vibration is not None:
        motion.update({"vib_accel_rms": float(vibration.accel_rms), "vib_rate_rms": float(vibration.rate_rms)})
    if detected:
        samples = (detector or zv.DetectorSettings()).samples(step)
        ins.update({"zupt_source": 1, "zvd_window": samples, "zupt": 1, "zaru": 1,
                    "zvd_gamma": zv.threshold(samples, (detector or zv.DetectorSettings()).alpha),
                    "zvd_vrw": float(noise.vrw), "zvd_arw": float(noise.arw)})
    components = [Component("motion", fmu_dir / "TrajectoryIMU.fmu", motion),
                  Component("receiver", fmu_dir / "GNSSReceiver.fmu", rx),
                  Component("ins", fmu_dir / "AidedINS.fmu", ins)]
    connections = [Connection("motion", v, "receiver", v) for v in TRUTH_TO_RECEIVER]
    connections += [Connection("motion", v, "ins", v) for v in IMU_TO_AIDED]
    connections += [Connection("receiver", v, "ins", v) for v in RECEIVER_TO_AIDED]
    if odometer is not None:
        connections += [Connection("motion", v, "ins", v) for v in ODOMETER_TO_AIDED]
    if zupt:
        connections += [Connection("motion", a, "ins", b) for a, b in STILL_TO_AIDED
                        if not (detected and a == "zupt")]  # detected: the inputs zupt, zaru held at 1
    name = "vehicle_gnss_zupt" if zupt else "vehicle_gnss" if odometer is None else "vehicle_gnss_odometer"
    return System(name=name, components=components, connections=connections, start_time=0.0,
                  stop_time=truth.n_steps * step, step_size=step)


def vehicle_gnss_odometer(fmu_dir: Path | str = "resources", **kwargs) -> System:
    """:func:`vehicle_gnss` with the default wheel odometer (``aided.OdometerConfig()``: 10 Hz) from
    TrajectoryIMU into AidedINS: ``sarins navigate --trajectory FILE --aiding gnss,odometer`` as a system
    (``kwargs`` go to :func:`vehicle_gnss`)."""
    from sarins_fmu.aided import OdometerConfig

    return vehicle_gnss(fmu_dir, **{"odometer": OdometerConfig(), **kwargs})


def vehicle_gnss_zupt(fmu_dir: Path | str = "resources", **kwargs) -> System:
    """:func:`vehicle_gnss` with the default wheel odometer and TrajectoryIMU's ZUPT / NHC rows (ZARU from the
    same still flag) into AidedINS: ``sarins navigate --trajectory FILE --aiding gnss,zupt,zaru,nhc,odometer
    --imu-stream core`` as a system (``kwargs`` go to :func:`vehicle_gnss`)."""
    from sarins_fmu.aided import OdometerConfig

    return vehicle_gnss(fmu_dir, **{"odometer": OdometerConfig(), "zupt": True, **kwargs})


SYSTEMS = {"standard_static": standard_static, "standard_static_identified": standard_static_identified,
           "vehicle_rins": vehicle_rins, "vehicle_rins_online": vehicle_rins_online, "vehicle_gnss": vehicle_gnss,
           "vehicle_gnss_odometer": vehicle_gnss_odometer, "vehicle_gnss_zupt": vehicle_gnss_zupt}


def write_systems(fmu_dir: Path | str) -> list[Path]:
    """Write ``<fmu_dir>/<name>.ssp`` for every system; returns the paths."""
    from sarins_fmu.files import refuse_links

    fmu_dir = Path(fmu_dir)
    refuse_links([fmu_dir / f"{name}.ssp" for name in SYSTEMS], "system file")
    return [write_ssp(make(fmu_dir), fmu_dir / f"{name}.ssp") for name, make in SYSTEMS.items()]


# The FMI 3.0 systems stepped at K s (``sarins build-fmus --fmi 3`` writes them beside its FMUs)
SECONDS_PER_STEP = 60
SYSTEMS3 = {f"standard_static_{SECONDS_PER_STEP}s": standard_static,
            f"standard_static_identified_{SECONDS_PER_STEP}s": standard_static_identified}


def write_systems3(fmu_dir: Path | str) -> list[Path]:
    """Write ``<fmu_dir>/<name>.ssp`` for the FMI 3.0 systems of :data:`SYSTEMS3` (FMI 3.0 FMUs in ``fmu_dir``,
    ``SECONDS_PER_STEP``-second steps, the IMU's threads the in-process run's count); returns the paths."""
    from sarins_fmu.files import refuse_links

    fmu_dir = Path(fmu_dir)
    refuse_links([fmu_dir / f"{name}.ssp" for name in SYSTEMS3], "system file")
    return [write_ssp(make(fmu_dir, seconds_per_step=SECONDS_PER_STEP), fmu_dir / f"{name}.ssp")
            for name, make in SYSTEMS3.items()]


def write_shipped_ssds(root: Path = SHIPPED) -> list[Path]:
    """(Re)write the shipped SSD files (sources resources/<FMU>.fmu); the
    writer reads the FMUs, so they are built into a scratch folder first."""
    import shutil
    import tempfile

    from fmus.build import build_fmus

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        build_fmus(Path(tmp) / "resources")
        for name, make in SYSTEMS.items():
            ssd = write_ssd(make(Path(tmp) / "resources"), Path(tmp) / "SystemStructure.ssd")
            folder = root / name
            folder.mkdir(parents=True, exist_ok=True)
            out.append(Path(shutil.copy2(ssd, folder / "SystemStructure.ssd")))
    return out


SYSTEM_FMUS = {"StandardStaticSystem": "standard_static", "IdentifiedStaticSystem": "standard_static_identified"}


def build_system_fmu(fmu_dir: Path | str, name: str = "StandardStaticSystem") -> Path:
    """A shipped static system (FMUs in ``fmu_dir``) packed as one FMU (our system container, FMI 2.0:
    :func:`orchestration.container.build_container_fmu` with ``engine=write_container_fmu``)
    ``<fmu_dir>/<name>.fmu``: ``StandardStaticSystem`` (turntable -> IMU -> INS) or
    ``IdentifiedStaticSystem`` (seed 000's loop, the RBF identifier feeding the INS)."""
    from fmus.build import fix_fmu_description
    from fmus.system_container import write_container_fmu
    from orchestration.container import build_container_fmu

    if name not in SYSTEM_FMUS:
        raise ValueError(f"unknown system FMU {name!r}; known: {', '.join(SYSTEM_FMUS)}")
    system = SYSTEMS[SYSTEM_FMUS[name]](Path(fmu_dir))
    from sarins_fmu.files import refuse_links

    refuse_links([Path(fmu_dir) / f"{name}.fmu"], "system FMU")
    path = build_container_fmu(system, Path(fmu_dir) / f"{name}.fmu", step_size=1.0, engine=write_container_fmu)
    fix_fmu_description(path, [(c.name, c.source) for c in system.components])
    return path


def compensated_chain(fmu_dir: str | Path, compensator_fmu: str | Path, *, turntable=None, imu=None, ins=None,
                      step: float = 0.05, stop: float = 3600.0):
    """System Turntable -> IMUThermal -> IMUCompensator -> StrapdownINS.

    ``fmu_dir`` holds Turntable.fmu, IMUThermal.fmu and StrapdownINS.fmu;
    the compensator takes the IMU's raw increments with their tag and
    temperatures, the INS reads the compensated increments with the same tag
    and the z-gyro temperature of their interval (all from the compensator),
    so the chain gives the same solution at the same nav_time under any
    scheme.  The IMU stands on a static base and the INS gets no axial-drift
    correction (both held at their start values explicitly).
    """
    fmu_dir = Path(fmu_dir)
    components = [Component("turntable", fmu_dir / "Turntable.fmu", dict(turntable or {})),
                  Component("imu", fmu_dir / "IMUThermal.fmu", {**STATIC_BASE_HELD, **dict(imu or {})}),
                  Component("comp", Path(compensator_fmu), {}),
                  Component("ins", fmu_dir / "StrapdownINS.fmu", {**NO_CORRECTION, **dict(ins or {})})]
    connections = [Connection("turntable", v, "imu", v) for v in GIMBAL_LINKS]
    connections += [Connection("imu", a, "comp", b) for a, b in RAW_LINKS]
    connections += [Connection("imu", t, "comp", t) for t in TEMPS]
    connections += [Connection("imu", "increment_end_time", "comp", "raw_increment_end_time")]
    connections += [Connection("comp", v, "ins", v) for v, _ in RAW_LINKS]
    connections += [Connection("comp", "increment_end_time", "ins", "increment_end_time"),
                    Connection("comp", "temp_azimuth_gyro", "ins", "temp_gyro_z")]
    return System(name="compensated_chain", components=components, connections=connections, start_time=0.0,
                  stop_time=stop, step_size=step)
