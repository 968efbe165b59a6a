"""Seed 000's Fig. 1 remark on the sign of the longitude error, examined.

The paper (sec. 2.1): "在导航 12h 时，纬度误差输出为正时，经度误差时正时负"
-- at 12 h of navigation, when the latitude error is positive the longitude
error is sometimes positive, sometimes negative -- so the longitude error
"could give a singular solution" and only the latitude error is used.

The closed forms (:mod:`sarins_fmu.static_errors`) say that a constant
azimuth drift alone gives latitude and longitude errors of the same sign
at 12 h, dlon/dL = tan L (Wt - sin Wt)/(1 - cos Wt) (0.85 at 28.222 deg),
while the heading error left by the alignment drops out of the latitude
error at 12 h and enters the longitude error with its largest weight,
-2 sin L phi_U.  :func:`sign_analysis` checks both on simulated runs.
"""

from __future__ import annotations

import math

import numpy as np

from sarins_fmu.experiments import axial_rbf as s0
from sarins_fmu.static_errors import heading_error_errors
from sarins_fmu.units import DEG_TO_RAD, HOUR, RAD_TO_DEG


def ratio_lon_to_lat(lat_deg: float, hours: float = s0.IDENTIFY_HOURS) -> float:
    """dlon/dL at ``hours`` for a constant azimuth drift alone (closed form)."""
    from sarins_fmu.earth import RATE

    w = RATE * hours * HOUR
    return math.tan(lat_deg * DEG_TO_RAD) * (w - math.sin(w)) / (1.0 - math.cos(w))


def flip_threshold_dph(phi_u: float, hours: float = s0.IDENTIFY_HOURS) -> float:
    """Azimuth drift (deg/h) below which a heading error ``phi_u`` (rad) can
    turn the longitude error's sign against the latitude error's at ``hours``:
    |eps| (t - sin Wt / W) < (1 - cos Wt) |phi_u|."""
    from sarins_fmu.earth import RATE
    from sarins_fmu.units import DPH_TO_RPS

    t = hours * HOUR
    return (1.0 - math.cos(RATE * t)) * abs(phi_u) / (t - math.sin(RATE * t) / RATE) / DPH_TO_RPS


def sign_analysis(rows: list[dict], hours: float = s0.IDENTIFY_HOURS) -> dict:
    """Signs and closed-form decomposition of the 12 h errors of simulated runs.

    rows : run results with the experiment's fields and ``lat_error_deg``,
        ``lon_error_deg`` (at ``hours``), ``align_heading_error`` (rad; rows
        without a finite one are left out of the decomposition).

    Returns counts (n, lat positive, of which lon negative, signs differing)
    and, over rows with a heading error, the RMS of the observed longitude
    error minus the drift-only closed form and minus drift + heading terms,
    in deg, and the share of the sign mismatches the closed form with the
    heading term predicts.
    """
    lat_err = np.array([r["lat_error_deg"] for r in rows])
    lon_err = np.array([r["lon_error_deg"] for r in rows])
    out = {"n": len(rows), "lat_pos": int(np.sum(lat_err > 0)),
           "lat_pos_lon_neg": int(np.sum((lat_err > 0) & (lon_err < 0))),
           "differ": int(np.sum(np.sign(lat_err) != np.sign(lon_err)))}
    known = [r for r in rows if np.isfinite(r.get("align_heading_error", np.nan))]
    if not known:
        return out
    obs, drift_only, both, heading = [], [], [], []
    for r in known:
        e = s0.Experiment(**{k: r[k] for k in s0.Experiment.__dataclass_fields__})
        d_lat, d_lon = s0.deterministic_errors(e, hours)
        h_lat, h_lon = heading_error_errors(hours * HOUR, r["align_heading_error"], e.lat_deg * DEG_TO_RAD)
        obs.append(r["lon_error_deg"])
        drift_only.append(d_lon * RAD_TO_DEG)
        both.append((d_lon + float(h_lon)) * RAD_TO_DEG)
        heading.append(r["align_heading_error"] * RAD_TO_DEG * 3600.0)
    obs, drift_only, both = map(np.array, (obs, drift_only, both))
    lat_known = np.array([r["lat_error_deg"] for r in known])
    differ = np.sign(lat_known) != np.sign(obs)
    predicted = (np.sign(both) != 0) & (np.sign(lat_known) != np.sign(both))  # at the equator both terms vanish
    threshold = flip_threshold_dph(_rms(heading) / 3600.0 * DEG_TO_RAD, hours)
    out.update({"flip_threshold_dph": threshold,
                "below_threshold": int(sum(abs(r["drift_dph"]) < threshold for r in known)),
                "n_decomposed": len(known), "rms_lon_deg": _rms(obs),
                "rms_minus_drift_deg": _rms(obs - drift_only), "rms_minus_both_deg": _rms(obs - both),
                "heading_rms_arcsec": _rms(heading), "differ_decomposed": int(np.sum(differ)),
                "differ_predicted": int(np.sum(differ & predicted)),
                "drift_only_differ": int(np.sum((np.sign(drift_only) != 0) & (np.sign(lat_known) != np.sign(drift_only))))})
    return out


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))
