"""IEEE Std 952 / 1293 read-outs of an Allan deviation curve, each with its confidence interval.

The overlapping Allan deviation of a static record shows each noise term as a straight line in
log-log axes where that term dominates (IEEE Std 952-1997 annex C, IEEE Std 1293-1998 annex C;
El-Sheimy, Hou & Niu, IEEE Trans. Instrum. Meas. 57(1), 2008)::

    sigma^2(tau) = 3 Q^2 / tau^2 + N^2 / tau + (0.664 B)^2 + K^2 tau / 3 + R^2 tau^2 / 2

==========================  =======  ==========================================
term                        slope    read
==========================  =======  ==========================================
quantisation Q              -1       Q = sigma(tau) tau / sqrt(3)
random walk N               -1/2     N = sigma(tau) sqrt(tau), the line at tau = 1 s
bias instability B          0        B = sigma / 0.664 at the lowest flat point
rate random walk K          +1/2     K = sigma(tau) sqrt(3 / tau), the line at tau = 3 s
rate ramp R                 +1       R = sigma(tau) sqrt(2) / tau
==========================  =======  ==========================================

:func:`octave_curve` computes the deviation at octave-spaced averaging times anchored at 1 s
(tau = 2^k s, each a whole number of samples) with, at each, the local slope (over the octaves on
either side), the dominant noise type it implies, the equivalent degrees of freedom of the
overlapping estimator for that noise type (Howe, Allan & Barnes 1981; the simple formulas of NIST
SP 1065 table 5, after Lesage & Audoin) and the chi-square confidence interval of sigma.

:func:`read_terms` reads each term only where its slope holds (the smoothed local slope within
:data:`SLOPE_TOLERANCE` of the term's), at the averaging time of the table above nearest to where
it holds, after subtracting in variance what the other resolved terms put there (two passes).  The
interval of a term is the chi-square interval of sigma at that averaging time carried through the
same formula.  A term whose slope appears nowhere in the record is *not resolved*: its value is
None and its interval [0, upper], the upper bound being the smallest value its line can have
without passing above the curve's upper confidence limit anywhere (a bound, not a reading).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import chi2

FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # Allan floor / B for flicker noise, 0.664
CONFIDENCE = 0.95  # two-sided confidence of the intervals
MIN_CLUSTERS = 9  # fewest independent clusters (record / tau) of an averaging time used
SLOPE_TOLERANCE = 0.2  # a term holds where the local log-log slope is within this of its own
DOMINANT = 0.5  # a term is read only where it holds at least this share of the Allan variance
TERMS = ("quantization", "random_walk", "bias_instability", "rate_random_walk", "rate_ramp")
SLOPES = {"quantization": -1.0, "random_walk": -0.5, "bias_instability": 0.0, "rate_random_walk": 0.5,
          "rate_ramp": 1.0}
# sigma^2 contributed by a term of value c at tau, and the value from a variance at tau
_VAR = {"quantization": lambda c, t: 3.0 * c * c / (t * t), "random_walk": lambda c, t: c * c / t,
        "bias_instability": lambda c, t: (FLOOR * c) ** 2 + 0.0 * t, "rate_random_walk": lambda c, t: c * c * t / 3.0,
        "rate_ramp": lambda c, t: c * c * t * t / 2.0}
_VALUE = {"quantization": lambda v, t: math.sqrt(v / 3.0) * t, "random_walk": lambda v, t: math.sqrt(v * t),
          "bias_instability": lambda v, t: math.sqrt(v) / FLOOR, "rate_random_walk": lambda v, t: math.sqrt(3.0 * v / t),
          "rate_ramp": lambda v, t: math.sqrt(2.0 * v) / t}
READ_AT = {"random_walk": 1.0, "rate_random_walk": 3.0}  # s: where IEEE 952 reads the line (for the value shown)


@dataclass(frozen=True)
class OctaveCurve:
    """Overlapping Allan deviation at octave averaging times (SI units of the rate), with statistics.

    taus (T,) s; adev (T,); clusters (T,) record / tau; slope (T,) smoothed local log-log slope;
    noise (T,) the FM noise type alpha used for the edf (0 white, -1 flicker, -2 random walk, 2 white
    PM); edf (T,); low, high (T,): the CONFIDENCE interval of adev.
    """

    taus: np.ndarray
    adev: np.ndarray
    clusters: np.ndarray
    slope: np.ndarray
    noise: np.ndarray
    edf: np.ndarray
    low: np.ndarray
    high: np.ndarray


@dataclass(frozen=True)
class Term:
    """One read-out: value (None if not resolved), its CONFIDENCE interval [low, high], the averaging
    time it was read at (s; None if not resolved), in SI units of the term."""

    name: str
    value: float | None
    low: float
    high: float
    tau: float | None

    @property
    def resolved(self) -> bool:
        return self.value is not None


@dataclass(frozen=True)
class Readouts:
    """The five terms of one curve, by name (:data:`TERMS`)."""

    terms: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> Term:
        return self.terms[name]


def edf_overlapping(n_phase: int, m: int, alpha: int) -> float:
    """Equivalent degrees of freedom of the overlapping Allan variance (Howe, Allan & Barnes 1981;
    NIST SP 1065 table 5): ``n_phase`` phase points (samples + 1), averaging factor ``m``, power-law
    noise ``alpha`` (2 white PM, 1 flicker PM, 0 white FM, -1 flicker FM, -2 random-walk FM)."""
    n = float(n_phase)
    if alpha == 2:
        return (n + 1) * (n - 2 * m) / (2 * (n - m))
    if alpha == 1:
        return math.exp(math.sqrt(math.log((n - 1) / (2 * m)) * math.log((2 * m + 1) * (n - 1) / 4)))
    if alpha == 0:
        return (3 * (n - 1) / (2 * m) - 2 * (n - 2) / n) * 4 * m * m / (4 * m * m + 5)
    if alpha == -1:
        return 2 * (n - 2) / (2.3 * n - 4.9) if m == 1 else 5 * n * n / (4 * m * (n + 3 * m))
    if alpha == -2:
        return (n - 2) / (m * (n - 3) ** 2) * ((n - 1) ** 2 - 3 * m * (n - 1) + 4 * m * m)
    raise ValueError(f"alpha must be one of 2, 1, 0, -1, -2, got {alpha}")


def octave_taus(n: int, rate_hz: float) -> np.ndarray:
    """Octave averaging times 2^k s (as whole numbers of samples, repeats dropped) from one sample up to
    the record / MIN_CLUSTERS."""
    h = 1.0 / rate_hz
    top = n * h / MIN_CLUSTERS
    k = np.arange(math.floor(math.log2(h)), math.floor(math.log2(max(top, h))) + 1)
    m = np.unique(np.maximum(1, np.round(2.0 ** k / h)).astype(np.int64))
    return m[(m * h <= top + 1e-12) & (m >= 1)] * h


def octave_curve(y, rate_hz: float) -> OctaveCurve:
    """The deviation of the rate series ``y`` (K,) at :func:`octave_taus`, with slopes, edf and intervals."""
    from .allan import overlapping_adev

    y = np.asarray(y, float)
    taus, adev = overlapping_adev(y, rate_hz, octave_taus(y.size, rate_hz))
    n = y.size
    clusters = n / (taus * rate_hz)
    logt, logs = np.log(taus), np.log(np.maximum(adev, 1e-300))
    slope = np.zeros(taus.size)
    for i in range(taus.size):  # over one octave on either side (two at the ends)
        lo, hi = max(0, i - 1), min(taus.size - 1, i + 1)
        if hi > lo:
            slope[i] = (logs[hi] - logs[lo]) / (logt[hi] - logt[lo])
    noise = np.select([slope < -0.75, slope < -0.25, slope < 0.25], [2, 0, -1], -2)
    edf = np.array([max(edf_overlapping(n + 1, int(round(t * rate_hz)), int(a)), 1.0) for t, a in zip(taus, noise)])
    p = (1.0 - CONFIDENCE) / 2.0
    low = adev * np.sqrt(edf / chi2.ppf(1.0 - p, edf))
    high = adev * np.sqrt(edf / chi2.ppf(p, edf))
    return OctaveCurve(taus, adev, clusters, slope, noise, edf, low, high)


def _holds(curve: OctaveCurve, term: str) -> np.ndarray:
    return np.abs(curve.slope - SLOPES[term]) <= SLOPE_TOLERANCE


def _others(values: dict, term: str, tau: float) -> float:
    """Variance the other resolved terms put at tau."""
    return sum(_VAR[t](v, tau) for t, v in values.items() if t != term and v is not None)


def _pick(curve: OctaveCurve, term: str) -> int | None:
    """Index of the averaging time where ``term`` is read, or None if its slope holds nowhere."""
    holds = np.flatnonzero(_holds(curve, term))
    if term == "bias_instability":  # the lowest point where the curve is flat
        if holds.size == 0:
            return None
        return int(holds[np.argmin(curve.adev[holds])])
    if holds.size == 0:
        return None
    if term == "quantization":
        return int(holds[0]) if holds[0] <= 1 else None  # at the start of the curve only
    if term in READ_AT:  # nearest (in log) to where IEEE 952 reads the line
        return int(holds[np.argmin(np.abs(np.log(curve.taus[holds] / READ_AT[term])))])
    flat = np.flatnonzero(_holds(curve, "bias_instability"))
    kmin = int(flat[np.argmin(curve.adev[flat])]) if flat.size else int(np.argmin(curve.adev))
    after = holds[holds > kmin]
    return int(after[0]) if after.size else None  # the rising terms: first after the minimum (most clusters)


def _upper(curve: OctaveCurve, term: str) -> float:
    """Largest value the term can have without its line passing above the curve's upper limit."""
    return float(min(_VALUE[term](hi * hi, t) for hi, t in zip(curve.high, curve.taus)))


def read_terms(curve: OctaveCurve) -> Readouts:
    """Q, N, B, K and R of one curve (see the module docstring).

    The value subtracts in variance what the other resolved terms put at the averaging time read;
    the interval runs from the lower confidence limit less what the others can put there at most
    (their upper limits; under the floor B also the bounds of those not resolved) to the upper
    confidence limit with nothing subtracted, so it holds both the statistical
    uncertainty and that of the neighbouring lines (the graphical IEEE reading, sigma alone, is
    inside it).
    """
    values = {t: None for t in TERMS}
    picks = {t: _pick(curve, t) for t in TERMS}
    for _ in range(3):  # each term with the others' previous values subtracted
        new = {}
        for term in TERMS:
            k = picks[term]
            if k is None:
                new[term] = None
                continue
            t = float(curve.taus[k])
            var = curve.adev[k] ** 2 - _others(values, term, t)
            new[term] = _VALUE[term](var, t) if var >= DOMINANT * curve.adev[k] ** 2 else None
        values = new
    # the most each resolved term can put anywhere: its upper limit
    highs = {t: None if values[t] is None else _VALUE[t](curve.high[picks[t]] ** 2, float(curve.taus[picks[t]]))
             for t in TERMS}
    # under a floor, the terms not resolved can hide up to their bounds
    floor_highs = {t: _upper(curve, t) if values[t] is None else highs[t] for t in TERMS}
    terms = {}
    for term in TERMS:
        k = picks[term]
        if values[term] is None:
            terms[term] = Term(term, None, 0.0, _upper(curve, term), None)
            continue
        t = float(curve.taus[k])
        value = _VALUE[term](curve.adev[k] ** 2 - _others(values, term, t), t)
        most = _others(floor_highs if term == "bias_instability" else highs, term, t)
        low = _VALUE[term](max(curve.low[k] ** 2 - most, 0.0), t)
        high = _VALUE[term](curve.high[k] ** 2, t)
        terms[term] = Term(term, value, low, high, t)
    return Readouts(terms)


def record_warnings(record_s: float, n_octaves: int) -> list[str]:
    """What a record's length keeps the read-outs from showing."""
    if record_s < 3600.0:
        return [f"the record lasts {record_s:.4g} s: averaging times reach {record_s / MIN_CLUSTERS:.3g} s "
                "(record / 9), so bias instability and rate random walk, which show over hours, may not be "
                "resolved"]
    return []
