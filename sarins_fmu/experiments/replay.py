"""Alignment and navigation on a recorded IMU log (:mod:`sarins_fmu.imu_log`).

The log's increments drive the same two-speed strapdown INS as the
simulated runs (:func:`sarins_fmu.experiments.static_run.run_static`): a
static alignment over the first ``align_hours`` (coarse in the inertial
frame, then the zero-velocity Kalman filter) from the log's start position,
then free navigation to the end of the log.  Optionally a trained IMU
compensator (seed 003, :mod:`sarins_fmu.identify.compensators`) corrects
the increments first; it sees the mean rates and the mean of the six
temperatures, as the IMUCompensator FMU does.  Optionally seed 000's RBF
axial-drift identifier runs after the model's alignment + navigation time
and its drift is subtracted over the rest of the log.  Errors are taken
against the log's reference position when it has one, else against the
static start.  The INS is stepped in the chunks ``run_static`` uses, so a log
written from a simulated run replays to the same numbers, bit for bit.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .. import earth
from ..core import smath  # the C core's hypot: the FMU's position_error, bit for bit
from ..imu_log import ImuLog, LogError
from ..ins import InsConfig, StrapdownINS
from ..identify.axial import APPLY_LATENCY
from ..rotations import euler_to_mat, mat_to_euler
from ..units import DPH_TO_RPS, HOUR
from . import replay_align as align
from .replay_align import AlignmentError
from .static_run import CHUNK, StaticRunResult


def compensate(log: ImuLog, compensator) -> tuple[np.ndarray, np.ndarray]:
    """Increments corrected by a fitted compensator (needs the log's temperatures)."""
    if log.temps is None:
        raise LogError("the compensator needs the six temperature columns, which the log does not have")
    h = log.step
    x = np.column_stack([log.dtheta / h, log.dv / h, log.temps.mean(axis=1)])
    y = compensator.predict(x)
    return np.ascontiguousarray(y[:, :3] * h), np.ascontiguousarray(y[:, 3:] * h)


GYROCOMPASS_ALIGN_HOURS = 4.0  # seed 000's alignment (the RBF models are trained on it)
LEVEL_ALIGN_SECONDS = 600.0  # hypothetical default: 10 min of static data to level and to estimate the gyro bias


def default_align_hours(log: ImuLog, heading: float | None) -> float:
    """The alignment when none is given, h: 4 h of gyrocompassing, or, with a ``heading``
    (levelling), 10 min, at most half the log, in whole samples of the log."""
    if heading is None:
        return GYROCOMPASS_ALIGN_HOURS
    n = min(round(LEVEL_ALIGN_SECONDS / log.step), len(log.time) // 2)
    return max(n, 1) * log.step / HOUR


def replay(log: ImuLog, *, align_hours: float | None = None, coarse_seconds: float = 300.0,
           compensator=None, identifier=None, compensate_drift: bool = True, heading: float | None = None,
           path=None) -> StaticRunResult:
    """Align on the first ``align_hours`` of the log and navigate over the rest.

    ``align_hours`` None takes :func:`default_align_hours` (4 h to gyrocompass, 10 min to level).

    The alignment (:mod:`sarins_fmu.experiments.replay_align`): gyrocompassing (coarse in the
    inertial frame, then the zero-velocity Kalman filter) when the gyros can see the Earth rate and
    no ``heading`` is given; else levelling with the accelerometers' mean and the ``heading`` given
    (rad, clockwise from north), the gyro bias and the vertical accelerometer bias then estimated
    and removed.  With neither the sight of the Earth rate nor a heading it refuses
    (:class:`~sarins_fmu.experiments.replay_align.AlignmentError` naming ``--heading-deg``); it
    refuses an attitude whose tilt disagrees with the accelerometers' levelling by more than an
    accelerometer bias of any class allows.  ``path`` names the log in messages.

    identifier : optional :class:`sarins_fmu.identify.axial.DriftIdentifier`
        (seed 000's RBF network, gyrocompassing only).  After ``identify_hours`` of navigation (the
        model's protocol) it identifies the axial drift from the latitude
        error there (and, for a cold model, the z-gyro temperature then and
        its change over the alignment), as the RBFIdentifier FMU does; with
        ``compensate_drift`` the INS subtracts it from APPLY_LATENCY s later
        to the end of the log, exactly as ``run_static(correction_dph=drift,
        correction_from_hours=identify_hours + latency/3600)``.
        :func:`check_identifier_fit` refuses a log the model does not fit.

    Returns a :class:`StaticRunResult` (navigation phase; ``time`` since
    the end of alignment); its info holds the alignment (``alignment``, ``roll_deg``,
    ``pitch_deg``, ``heading_deg``, the estimated biases, ``warnings``) and, with an identifier,
    ``identified_drift_dph``, the features and ``compensation_from_s``.
    Raises ValueError naming the option when the log is shorter than the alignment or the
    alignment is not a whole number of samples.
    """
    path = path or "the log"
    if log.lat is None:
        raise AlignmentError(f"{path}: the log does not state the latitude of its static start; give it with "
                             "--lat-deg")
    given = align_hours is not None
    if not given:
        align_hours = default_align_hours(log, heading)
    if heading is None and not given and len(log.time) <= round(align_hours * HOUR / log.step):
        _refuse_unseen(log, path)  # a short log: say first what is missing (a heading), then the length
    n_align = _alignment_samples(log, align_hours, coarse_seconds if heading is None else 0.0, path, given)
    window = _window(log, n_align)
    seen = align.sight(window, log.lat)
    if heading is None and not seen.can_see:
        raise _unseen(seen, path)
    if heading is not None and identifier is not None:
        raise AlignmentError(f"{path}: --identify needs the gyrocompass alignment (the drift model was trained on "
                             "it); leave out --heading-deg")
    notes = []
    if heading is None:
        result = _replay_gyrocompass(log, n_align, coarse_seconds, compensator, identifier, compensate_drift)
        ins_out = result.pop("_last_align_row")
        mat = euler_to_mat(*ins_out)
        align.check_tilt(mat, window, path, np.asarray(result["info"]["accel_comp"]))
        note = align.accel_bias_note(result["info"]["accel_comp"], path)
        mode = "gyrocompass"
    else:
        mat, gyro_bias, accel_bias = align.level(window, log.lat, log.height, heading)
        result = _replay_levelled(log, n_align, mat, gyro_bias, accel_bias, compensator)
        note = align.accel_bias_note(accel_bias, path)
        mode = "levelling + given heading"
    if note:
        notes.append(note)
        warnings.warn(note, stacklevel=2)
    yaw, pitch, roll = mat_to_euler(mat)
    result["info"].update(alignment=mode, roll_deg=math.degrees(roll), pitch_deg=math.degrees(pitch),
                          heading_deg=math.degrees(-yaw) % 360.0,
                          gyro_horizontal_rate_dph=seen.horizontal_rate / DPH_TO_RPS,
                          earth_horizontal_rate_dph=seen.earth_rate / DPH_TO_RPS, warnings=notes)
    return StaticRunResult(**result)


def _refuse_unseen(log: ImuLog, path) -> None:
    """Refuse naming --heading-deg when the gyros of a log shorter than the default alignment cannot see
    the Earth rate over the whole log."""
    seen = align.sight(_window(log, len(log.time)), log.lat)
    if not seen.can_see:
        raise _unseen(seen, path)


def _unseen(seen, path) -> AlignmentError:
    """The refusal of a log whose gyros cannot see the Earth rate: it names --heading-deg."""
    return AlignmentError(f"{path}: the gyros cannot see the Earth rate ({seen.reason()}), so they cannot find "
                          "the heading; give it with --heading-deg (the replay then levels with the "
                          "accelerometers)")


def _window(log: ImuLog, n_align: int) -> np.ndarray:
    """The 1 s means (or the samples, for intervals of 1 s or more) of the alignment."""
    h = log.step
    block = max(1, int(round(1.0 / h)))
    means = log.means
    if means is None or len(means) == 0:
        n = n_align // block * block
        rates = np.hstack([log.dtheta[:n], log.dv[:n]]) / h
        return rates.reshape(-1, block, 6).mean(axis=1) if n else np.hstack([log.dtheta[:1], log.dv[:1]]) / h
    return means[:max(1, n_align // block)]


def _replay_gyrocompass(log, n_align, coarse_seconds, compensator, identifier, compensate_drift) -> dict:
    h = log.step
    n_total = len(log.time)
    n_id = n_corr = None
    if identifier is not None:
        n_id, n_corr = check_identifier_fit(log, identifier, n_align * h / HOUR)
    dtheta, dv = (log.dtheta, log.dv) if compensator is None else compensate(log, compensator)
    config = InsConfig(lat=log.lat, lon=log.lon, height=log.height, align_time=n_align * h,
                       coarse_time=coarse_seconds, step=h)
    ins = StrapdownINS(config)
    out = np.empty((n_total, 9))
    corr = np.zeros(n_total)
    info = {}
    if identifier is None:
        _navigate(ins, dtheta, dv, corr, out, 0, n_total, n_align)
    else:
        _navigate(ins, dtheta, dv, corr, out, 0, n_id, n_align)
        err_id = _errors(log, ins, out[n_id - 1:n_id], n_id - 1)
        temps_z = log.temps[:, 2] if log.temps is not None else None
        temp_c = float(temps_z[n_id - 1]) if temps_z is not None else float("nan")
        change_c = float(temps_z[n_align - 1] - temps_z[0]) if temps_z is not None else float("nan")
        drift_dph = identifier.drift_dph(float(err_id[0, 0]), temp_c, change_c)
        if compensate_drift:
            corr[n_corr:] = drift_dph * DPH_TO_RPS
        _navigate(ins, dtheta, dv, corr, out, n_id, n_total, n_align)
        info = {"identified_drift_dph": drift_dph, "identify_at_s": (n_id - n_align) * h,
                "identify_lat_error_deg": math.degrees(float(err_id[0, 0])), "identify_temp_c": temp_c,
                "identify_temp_change_c": change_c, "identifier_model": str(identifier.path),
                "compensation_from_s": (n_corr - n_align) * h if compensate_drift else None}
    nav = out[n_align:]
    err = _errors(log, ins, nav, n_align)
    result = _result(log, nav, err, n_align, compensator, ins.gyro_comp, ins.accel_comp)
    result["info"].update(info)
    result["_last_align_row"] = tuple(float(x) for x in out[n_align - 1, 6:9])  # yaw, pitch, roll
    return result


def _replay_levelled(log, n_align, mat_nb, gyro_bias, accel_bias, compensator) -> dict:
    """Navigate from the end of the alignment on the levelled attitude, the estimated biases removed."""
    h = log.step
    n_total = len(log.time)
    config = InsConfig(lat=log.lat, lon=log.lon, height=log.height, align_time=0.0, coarse_time=0.0, step=h)
    ins = StrapdownINS(config, initial_attitude=mat_nb)
    nav = np.empty((n_total - n_align, 9))
    for k0 in range(n_align, n_total, CHUNK):
        k1 = min(n_total, k0 + CHUNK)
        if compensator is None:
            dtheta, dv = np.asarray(log.dtheta[k0:k1]), np.asarray(log.dv[k0:k1])
        else:
            part = ImuLog(time=log.time[k0:k1], dtheta=log.dtheta[k0:k1], dv=log.dv[k0:k1],
                          temps=None if log.temps is None else log.temps[k0:k1], ref=None, lat=log.lat,
                          interval=h)
            dtheta, dv = compensate(part, compensator)
        nav[k0 - n_align:k1 - n_align] = ins.step(dtheta - gyro_bias * h, dv - accel_bias * h)
    err = _errors(log, ins, nav, n_align)
    return _result(log, nav, err, n_align, compensator, gyro_bias, accel_bias)


def _result(log, nav, err, n_align, compensator, gyro_comp, accel_comp) -> dict:
    h = log.step
    n_total = len(log.time)
    n_nav = n_total - n_align
    temps_all = log.temps if log.temps is not None else np.full((n_total, 6), np.nan)
    return dict(
        time=np.arange(1, n_nav + 1) * h, lat_error=err[:, 0], lon_error=err[:, 1], north_error=err[:, 2],
        east_error=err[:, 3], position_error=smath.evaluate("hypot", err[:, 2], err[:, 3]), velocity_n=nav[:, 3:6],
        attitude=nav[:, 6:9], time_all=np.arange(1, n_total + 1) * h - n_align * h, temperature=temps_all,
        info={"lat_deg": math.degrees(log.lat), "align_hours": n_align * h / HOUR, "nav_hours": n_nav * h / HOUR,
              "source": "log", "quantity": log.quantity, "compensated": compensator is not None,
              "gyro_comp_dph": (np.asarray(gyro_comp) / DPH_TO_RPS).tolist(),
              "accel_comp": np.asarray(accel_comp).tolist()})


def _alignment_samples(log: ImuLog, align_hours: float, coarse_seconds: float = 300.0, path="the log",
                       given: bool = True) -> int:
    h = log.step
    if not (math.isfinite(align_hours) and align_hours > 0):
        raise ValueError(f"--align-hours must be a positive time, got {align_hours} h")
    n_align = round(align_hours * HOUR / h)
    if abs(n_align * h - align_hours * HOUR) > 1e-6 * h:
        raise ValueError(f"--align-hours {align_hours:g} h is not a whole number of the log's {h:g} s samples "
                         f"({path})")
    if coarse_seconds and n_align * h < coarse_seconds + 2 * h:
        raise ValueError(f"--align-hours {align_hours:g} h ({n_align * h:g} s) must exceed the {coarse_seconds:g} s "
                         f"coarse alignment plus two of the log's {h:g} s samples ({path})")
    if len(log.time) <= n_align:
        raise ValueError(f"the log ({len(log.time) * h / HOUR:.4g} h, {path}) is not longer than the "
                         f"{align_hours:g} h alignment (--align-hours"
                         + ("" if given else "; without it 4 h to gyrocompass, or 10 min with --heading-deg") + ")")
    return n_align


class ModelFitError(LogError):
    """A log that the drift model does not fit (the message does not name the file: the caller does)."""


MAX_SITE_OFFSET_DEG = 1.0  # a model identifies at its training site: the latitude error's gain is cos L


def check_identifier_fit(log: ImuLog, identifier, align_hours: float) -> tuple[int, int]:
    """Refuse (:class:`ModelFitError`, one line) a log the drift model does not fit.

    The model's protocol (``identifier.protocol``: alignment, navigation
    before identification, INS step) must be the log's: the same
    alignment, the log's sample interval equal to the model's step, the
    log long enough to reach the identification and the compensation's
    start, its start latitude within MAX_SITE_OFFSET_DEG of the model's
    site, and the temperature columns present if the model reads them.
    Returns (samples to the identification, sample from which the drift is
    compensated), counted from the start of the log.
    """
    proto = identifier.protocol
    h = log.step
    if abs(align_hours - proto["align_hours"]) > 1e-9:
        raise ModelFitError(f"the drift model expects {proto['align_hours']:g} h of alignment, the replay "
                            f"aligns for {align_hours:g} h")
    if abs(h - proto["step_s"]) > 1e-9 * proto["step_s"]:
        raise ModelFitError(f"the drift model was trained on {proto['step_s']:g} s INS steps, the log's sample "
                            f"interval is {h:g} s (resample the log or train a model at its rate)")
    n_id = round((align_hours + proto["identify_hours"]) * HOUR / h)
    n_corr = n_id + round(APPLY_LATENCY / h)
    if abs(n_id * h - (align_hours + proto["identify_hours"]) * HOUR) > 1e-6 * h or \
            abs((n_corr - n_id) * h - APPLY_LATENCY) > 1e-6 * h:
        raise ModelFitError(f"the identification at {proto['identify_hours']:g} h (and the compensation "
                            f"{APPLY_LATENCY:g} s later) does not fall on the log's {h:g} s samples")
    need_h = n_corr * h / HOUR
    if len(log.time) <= n_corr:
        raise ModelFitError(f"the log lasts {len(log.time) * h / HOUR:.4g} h; the drift model identifies after "
                            f"{proto['align_hours']:g} h alignment + {proto['identify_hours']:g} h navigation and "
                            f"compensates from {need_h:.4g} h on, so the log must be longer than that")
    offset = abs(math.degrees(log.lat) - identifier.local_lat_deg)
    if offset > MAX_SITE_OFFSET_DEG:
        raise ModelFitError(f"the drift model was trained at {identifier.local_lat_deg:g} deg latitude, the log "
                            f"starts at {math.degrees(log.lat):.4g} deg (more than {MAX_SITE_OFFSET_DEG:g} deg apart)")
    if log.temps is None and {"temp_c", "temp_change_c"} & set(identifier.input_names):
        raise ModelFitError("the drift model reads the gyro temperature, and the log has no temperature "
                            "columns")
    return n_id, n_corr


def _navigate(ins, dtheta, dv, corr, out, start: int, stop: int, n_align: int) -> None:
    """Step the INS over samples [start, stop) in the chunks of ``run_static``
    (split at the end of the alignment), writing ``out`` rows."""
    for c0 in range(start - start % CHUNK, stop, CHUNK):
        k0, k1 = max(c0, start), min(stop, c0 + CHUNK)
        if k0 < n_align < k1:
            out[k0:n_align] = ins.step(dtheta[k0:n_align], dv[k0:n_align], corr[k0:n_align])
            k0 = n_align
        out[k0:k1] = ins.step(dtheta[k0:k1], dv[k0:k1], corr[k0:k1])


def _errors(log: ImuLog, ins, nav: np.ndarray, first: int) -> np.ndarray:
    """(K, 4) latitude, longitude (rad), north, east (m) errors of navigation
    rows ``nav`` (log samples ``first`` on) against the log's reference or the
    static start."""
    if log.ref is None:
        return ins.position_error(nav)
    ref = log.ref[first:first + len(nav)]
    r_m, r_n = earth.radii(log.lat)
    dlat, dlon = nav[:, 0] - ref[:, 0], nav[:, 1] - ref[:, 1]
    return np.column_stack([dlat, dlon, dlat * (r_m + log.height), dlon * (r_n + log.height) * np.cos(ref[:, 0])])
