"""One factor k fitted so that a campaign quantity f(k) equals a figure of a paper (:func:`fit_scale`).

Shared by the calibrated units: ``sarins campaign axial-rbf --calibrate`` (seed 000, Table 4;
:mod:`sarins.axial_rbf.calibrate`), ``sarins campaign online-rls --calibrate`` (seed 002, Table 2;
:mod:`sarins.online_rls.calibrate`) and ``sarins campaign mems-calibration --calibrate`` (seed 003,
Table 3; :mod:`sarins.mems_calibration.calibrate`).  Deterministic: f(k) is a seeded campaign
computation, so the same call gives the same trials.  Start at k0 (the campaign's unit, k = 1), step by a
fixed factor until the target is bracketed, then regula falsi (Illinois variant) on
g(u) = ln f(e^u) - ln target, u = ln k.  Trial values of k are rounded to :data:`DIGITS` significant
digits (task ids and unit names carry k).  It stops when |f/target - 1| <= rtol, when the bracket's two
ends round to the same k, or after ``max_trials`` evaluations, and returns the trial closest to the
target in log.  f is assumed to grow with k (the bracketing steps up while f < target).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

RTOL = 0.02  # accepted |f / target - 1|
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
