"""Calibration of the axial-rbf unit to seed 000, Table 4 (``sarins campaign axial-rbf --calibrate``).

The unit's three drift sizes beyond temperature -- block-gradient coefficient k_g, temperature-rate
coefficient d, heating/cooling hysteresis half-height H -- have no public source
(``docs/imu-presets.md``).  The campaign's sensitivity study scales them together by one factor k
(:class:`sarins_fmu.experiments.axial_rbf.Experiment` ``thermal_scale``) and redoes, for each k, the
chain downstream of the unit (:func:`sarins.axial_rbf.campaign._sensitivity`).  This module fits k to
one figure of the paper and nothing else:

    f(k) = median over the campaign's held-out cold starts of
           |table mean + identified residual - true drift|  (deg/h, 72 h window)

is the paper's Table 4 quantity (multi-temperature compensation + hot network on cold starts,
0.0005-0.0015 deg/h).  The target is the band's geometric centre sqrt(0.0005 * 0.0015) =
0.000866 deg/h: the band spans a factor 3, and its geometric centre lies a factor sqrt(3) from
either end, the same distance on the log scale the search works on.  The rest of the paper (hot
identification error, 72 h position errors, cold network) is then validation of the calibrated unit.

Search (:func:`fit_scale`), deterministic: every f(k) is a seeded campaign computation (same
experiments, noise seeds, calibration and training runs for the same k), so the same call gives the
same trials.  Start at k = 1 (the campaign's unit, whose value is the comparison table's), step by a
fixed factor until the target is bracketed, then regula falsi (Illinois variant) on
g(u) = ln f(e^u) - ln target, u = ln k.  Trial values of k are rounded to 4 significant digits (the
task ids name k).  It stops when |f/target - 1| <= rtol, when the bracket's two ends round to the
same k, or after ``max_trials`` evaluations, and returns the trial closest to the target in log.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

TABLE4_BAND_DPH = (0.0005, 0.0015)  # seed 000 Table 4: drift error after compensation + hot network, deg/h
TABLE4_CENTRE_DPH = math.sqrt(TABLE4_BAND_DPH[0] * TABLE4_BAND_DPH[1])  # geometric centre, deg/h
FIGURE = "seed 000, Table 4"
RTOL = 0.02  # accepted |median / target - 1|
MAX_TRIALS = 12  # evaluations of f(k), k = 1 included
STEP = 3.0  # factor between bracketing trials
K_RANGE = (1e-3, 1e3)  # the search stays inside this range of k
DIGITS = 4  # significant digits of a trial k


@dataclass(frozen=True)
class ScaleFit:
    """Result of :func:`fit_scale`.

    k : the fitted factor (the trial closest to the target in log); value : f(k);
    target : the value fitted to; trials : ((k, f(k)), ...) in the order run;
    converged : |value/target - 1| <= rtol; rtol : the tolerance."""

    k: float
    value: float
    target: float
    trials: tuple
    converged: bool
    rtol: float


@dataclass(frozen=True)
class ThermalCalibration:
    """The unit calibrated to seed 000, Table 4 (:func:`calibrate_thermal_scale`).

    k : factor on the three sizes beyond temperature; gradient_dph_per_c : fitted k_g (deg/h/degC);
    rate_dph_per_cph : fitted d (deg/h per degC/h); hysteresis_dph : fitted H (deg/h);
    median_dph : the final median |table mean + identified residual - true drift| (deg/h) over the
    held-out cold starts; target_dph : what it was fitted to; figure : the paper's figure;
    trials : ((k, median deg/h), ...) in the order run; converged, rtol : as :class:`ScaleFit`;
    n_runs : held-out cold starts per trial; wall_seconds : time of the fit."""

    k: float
    gradient_dph_per_c: float
    rate_dph_per_cph: float
    hysteresis_dph: float
    median_dph: float
    target_dph: float
    figure: str
    trials: tuple
    converged: bool
    rtol: float
    n_runs: int
    wall_seconds: float


def _round(k: float) -> float:
    return float(f"{k:.{DIGITS}g}")


def fit_scale(evaluate: Callable[[float], float], target: float, *, k0: float = 1.0, step: float = STEP,
              rtol: float = RTOL, max_trials: int = MAX_TRIALS, k_range: tuple = K_RANGE) -> ScaleFit:
    """Find k with evaluate(k) = target (both positive), f assumed to grow with k across the bracket.

    Bracketing from ``k0`` by factors of ``step`` (up while f < target, down while f > target),
    then regula falsi (Illinois) on ln f against ln k; every trial k rounded to :data:`DIGITS`
    significant digits.  Raises ValueError for bad settings or a non-positive or non-finite f;
    returns the best trial with ``converged`` False if the tolerance is not met (the target outside
    f over ``k_range``, a step in f, or ``max_trials`` reached)."""
    lo_k, hi_k = k_range
    if not (math.isfinite(target) and target > 0.0):
        raise ValueError(f"target must be a positive number, got {target}")
    if not (0.0 < lo_k <= k0 <= hi_k and math.isfinite(hi_k)):
        raise ValueError(f"need 0 < k_range[0] <= k0 <= k_range[1] < inf, got {k_range}, k0 = {k0}")
    if not (step > 1.0 and 0.0 < rtol < 1.0 and max_trials >= 1):
        raise ValueError(f"need step > 1, 0 < rtol < 1, max_trials >= 1 (got {step}, {rtol}, {max_trials})")
    trials: list[tuple[float, float]] = []

    def g(k: float) -> float:  # ln f - ln target, recording the trial
        value = float(evaluate(k))
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"the fitted quantity must be positive and finite, got {value} at k = {k}")
        trials.append((k, value))
        return math.log(value / target)

    def done() -> ScaleFit:
        k, value = min(trials, key=lambda t: abs(math.log(t[1] / target)))
        return ScaleFit(k, value, target, tuple(trials), abs(value / target - 1.0) <= rtol, rtol)

    def close(gk: float) -> bool:
        return abs(math.expm1(gk)) <= rtol

    k = _round(k0)
    gk = g(k)
    if close(gk):
        return done()
    # bracket: step away from k0 until g changes sign
    direction = 1.0 if gk < 0.0 else -1.0
    a, ga = k, gk
    while True:
        if len(trials) >= max_trials:
            return done()
        b = _round(min(max(a * step ** direction, lo_k), hi_k))
        if b == a:  # at the end of k_range: the target is not reached
            return done()
        gb = g(b)
        if close(gb):
            return done()
        if (gb > 0.0) != (ga > 0.0):
            break
        a, ga = b, gb
    # regula falsi, Illinois variant, on u = ln k: a keeps the sign of ga, b of gb
    ua, ub = math.log(a), math.log(b)
    side = 0
    while len(trials) < max_trials:
        u = (ua * gb - ub * ga) / (gb - ga)
        c = _round(math.exp(u))
        if c in (a, b):  # the bracket is narrower than the rounding of k
            break
        gc = g(c)
        if close(gc):
            break
        if (gc > 0.0) == (gb > 0.0):  # c replaces b; a is kept: halve its weight if it was kept before too
            b, ub, gb = c, math.log(c), gc
            if side == -1:
                ga /= 2.0
            side = -1
        else:
            a, ua, ga = c, math.log(c), gc
            if side == 1:
                gb /= 2.0
            side = 1
    return done()


def sizes_dph(k: float) -> tuple[float, float, float]:
    """(k_g deg/h/degC, d deg/h per degC/h, H deg/h) of the unit with its terms beyond temperature x k."""
    from sarins_fmu.experiments import axial_rbf as s0
    from sarins_fmu.units import DPH_TO_RPS

    terms = s0.block_terms(k)
    return (float(terms["axial_drift_grad"] / DPH_TO_RPS), float(s0.DTDT_DPH_PER_CPH * k),
            float(terms["axial_hysteresis"] / DPH_TO_RPS))


def calibrate_thermal_scale(*, seed: int, out, common: dict, multitemp: dict, sizes: tuple, nav: float,
                            target_dph: float = TABLE4_CENTRE_DPH, rtol: float = RTOL,
                            max_trials: int = MAX_TRIALS) -> ThermalCalibration:
    """Fit the unit's factor k on its drift terms beyond temperature to seed 000, Table 4.

    f(k) is the median |drift error| of the sensitivity study's row for k
    (:func:`sarins.axial_rbf.campaign._sensitivity`, run for that one k: the scaled unit's own
    multi-temperature calibration, compensated hot training runs, hot_mt network and compensated
    held-out cold starts); k = 1 is the campaign's unit and its value the comparison table's
    ``mt_hot_mt`` median.  seed, out, common (workers, scheduler, progress), multitemp, sizes
    (hot train, hot test, cold train, cold test), nav (evaluation window, h): the campaign's."""
    import numpy as np

    from .campaign import _sensitivity

    t0 = time.perf_counter()
    runs: list[int] = []

    def median_error(k: float) -> float:
        rows = _sensitivity([k], seed=seed, out=out, common=common, multitemp=multitemp, sizes=sizes,
                            nav=nav)["rows"][float(k)]
        runs.append(len(rows))
        return float(np.median(np.abs([e["error_dph"] for e in rows])))

    fit = fit_scale(median_error, target_dph, rtol=rtol, max_trials=max_trials)
    grad, rate, hyst = sizes_dph(fit.k)
    return ThermalCalibration(fit.k, grad, rate, hyst, fit.value, target_dph, FIGURE, fit.trials, fit.converged,
                              rtol, runs[0], time.perf_counter() - t0)
