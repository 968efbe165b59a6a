"""Overlapping Allan deviation of IMU rates and the IEEE Std 952 read-outs.

The overlapping Allan deviation (:func:`overlapping_adev`, rate data) of a
stationary record shows each noise term as a straight line in log-log axes
(IEEE Std 952-1997 annex C; Titterton & Weston 2004, sec. 4.4.3; El-Sheimy,
Hou & Niu, IEEE Trans. Instrum. Meas. 57(1), 2008):

    sigma^2(tau) = N^2 / tau + (0.664 B)^2 + K^2 tau / 3

* angle / velocity random walk N: slope -1/2, read at tau = 1 s
  (rad/sqrt(s) or m/s/sqrt(s));
* bias instability B: the flat floor is 0.664 B (rad/s or m/s^2);
* rate random walk K: slope +1/2, read at tau = 3 s (rad/s/sqrt(s) or
  m/s^2/sqrt(s)).

:mod:`sarins_fmu.allan_readout` reads each term where its slope holds, with
its confidence interval (quantisation and rate ramp too); a term the record
cannot show is "not resolved".  A first-order Gauss-Markov bias
(``bias_instability`` of :class:`sarins_fmu.imu.TriadErrors`) has no flat
floor: its Allan deviation peaks at 0.62 sigma near tau = 1.9 T and is not
one of the lines above; :func:`spec` states what a preset's terms imply on
the curve so that read-outs can be compared with it.
"""

from __future__ import annotations

import math
import numpy as np
from scipy.optimize import nnls

from .imu import IMU, ImuModel, StaticBase
from .units import DEG_TO_RAD

FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # Allan floor / B for flicker noise, 0.664
MIN_CLUSTERS = 9  # fewest independent clusters of length tau used in the fit
TRIADS = ("gyro", "accel")


def static_record(model: ImuModel, duration: float, rate_hz: float, *, seed: int = 0,
                  lat_deg: float = 45.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Static, level, hot-started IMU at constant ambient: rates over ``duration`` s.

    Returns (gyro (K, 3) rad/s, accel (K, 3) m/s^2, temperatures (K, 6) degC),
    the increments divided by the interval 1/rate_hz.  On a static base the
    motion is constant, so the minor loop runs at the output rate.
    """
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise ValueError(f"sample rate must be positive, got {rate_hz}")
    n = int(round(duration * rate_hz))
    if not (math.isfinite(duration) and n >= 2):
        raise ValueError(f"duration {duration} s holds fewer than 2 samples at {rate_hz} Hz")
    h = 1.0 / rate_hz
    sensor = IMU(model, StaticBase(lat_deg * DEG_TO_RAD), ((0.0, 0.0, 1.0),), output_interval=h,
                 internal_rate=rate_hz, seed=seed)
    zero = np.zeros((n, 1))
    dtheta, dv, temps = sensor.step(zero, zero, zero)
    return dtheta / h, dv / h, temps


def default_taus(n: int, rate_hz: float, per_decade: int = 10) -> np.ndarray:
    """Log-spaced averaging times from one sample to a tenth of the record, s."""
    top = max(2.0, n / 10.0)
    m = np.unique(np.round(np.geomspace(1.0, top, max(2, int(per_decade * math.log10(top)) + 1))))
    return m / rate_hz


def averaging_factors(n: int, rate_hz: float, taus) -> np.ndarray:
    """Cluster lengths m (samples) for the averaging times ``taus`` (s) of a record of ``n`` samples.

    m = round(tau * rate_hz), kept if 1 <= m <= n, sorted, without repeats (the averaging
    time used is then m / rate_hz).  A cluster length that leaves fewer than two
    second differences (m > (n - 1) / 2) is dropped by :func:`overlapping_adev`.
    """
    m = np.round(np.asarray(taus, float).ravel() * rate_hz)
    m = m[np.isfinite(m) & (m >= 1) & (m <= n)]
    return np.unique(m).astype(np.int64)


def overlapping_adev(y, rate_hz: float, taus) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of one rate series ``y`` (K,) sampled at ``rate_hz`` (Hz).

    With the integrated series x_0 = 0, x_k = (y_0 + ... + y_(k-1)) / rate_hz
    (the angle for a gyro rate) and tau = m / rate_hz,

        sigma^2(tau) = sum_(k=0)^(K-2m) (x_(k+2m) - 2 x_(k+m) + x_k)^2 / (2 (K + 1 - 2m) tau^2)

    (IEEE Std 952-1997 annex C; NIST SP 1065 eq. (11)): half the mean square
    difference of successive m-sample averages, over every start k (overlapping
    clusters).  Averaging times with fewer than two terms are dropped.

    Returns (taus used (T,) s, deviation (T,)) in the unit of ``y``.
    """
    y = np.asarray(y, float)
    if y.ndim != 1 or y.size < 3 or not np.isfinite(y).all():
        raise ValueError("Allan deviation needs at least 3 finite samples")
    x = np.concatenate(([0.0], np.cumsum(y - y.mean()))) / rate_hz  # the mean cancels; removed for precision
    n = y.size
    used, dev = [], []
    for m in averaging_factors(n, rate_hz, taus):
        terms = n + 1 - 2 * m
        if terms < 2:
            continue
        d = x[2 * m:] - 2.0 * x[m:n + 1 - m] + x[:terms]
        tau = m / rate_hz
        used.append(tau)
        dev.append(math.sqrt(float(np.dot(d, d)) / (2.0 * terms)) / tau)
    return np.asarray(used), np.asarray(dev)


def allan_deviation(rates, rate_hz: float, taus=None) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of each column of ``rates`` (K, M).

    Returns (taus (T,), adev (T, M)) in the unit of ``rates``; ``taus`` in s
    (default :func:`default_taus`).  Raises ValueError on NaN or too few samples.
    """
    rates = np.asarray(rates, float)
    if rates.ndim == 1:
        rates = rates[:, None]
    if rates.shape[0] < 3 or not np.isfinite(rates).all():
        raise ValueError("Allan deviation needs at least 3 finite samples per column")
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise ValueError(f"sample rate must be positive, got {rate_hz}")
    taus = default_taus(rates.shape[0], rate_hz) if taus is None else np.asarray(taus, float)
    out_taus, cols = None, []
    for col in rates.T:
        t, dev = overlapping_adev(col, rate_hz, taus)
        out_taus = t if out_taus is None else out_taus
        cols.append(dev)
    if out_taus.size == 0:
        raise ValueError("no averaging time fits the record (each needs at least two cluster differences)")
    return out_taus, np.column_stack(cols)


def gauss_markov_avar(taus, std, corr_time):
    """Allan variance of a first-order Gauss-Markov process (std, correlation time T):
    (std T / tau)^2 (2 tau / T - 3 + 4 exp(-tau / T) - exp(-2 tau / T))
    (IEEE Std 952-1997 annex C, correlated noise; -> 2 std^2 T / tau for tau >> T and
    (2/3) std^2 tau / T for tau << T)."""
    x = np.asarray(taus, float) / corr_time
    bracket = np.where(x < 1e-3, 2.0 / 3.0 * x**3, 2.0 * x - 3.0 + 4.0 * np.exp(-x) - np.exp(-2.0 * x))
    return std**2 * bracket / x**2


def fit_gauss_markov(taus, adev, corr_time: float, record_length: float) -> tuple[float, float]:
    """(white-noise density, Gauss-Markov std) fitted to one curve, the correlation time given.

    The read-out of a preset whose bias instability is a Gauss-Markov process
    (no flat floor): non-negative least squares on the Allan variance, each
    averaging time weighted by the square root of its cluster count over its variance.
    """
    taus, adev = np.asarray(taus, float), np.asarray(adev, float)
    use = (taus <= record_length / MIN_CLUSTERS) & (adev > 0)
    t, var = taus[use], adev[use] ** 2
    weight = np.sqrt(record_length / t) / var
    basis = np.column_stack([1.0 / t, gauss_markov_avar(t, 1.0, corr_time)]) * weight[:, None]
    coef, _ = nnls(basis, var * weight)
    return math.sqrt(coef[0]), math.sqrt(coef[1])


def spec(model: ImuModel, triad: str) -> dict:
    """What the preset's terms put on the Allan curve of ``triad``, per axis (3,) each.

    random_walk: the white noise density; bias_instability: the flicker
    coefficient B; gauss_markov: the Gauss-Markov std and correlation time
    (no floor of its own); rate_random_walk: K.
    """
    if triad not in TRIADS:
        raise ValueError(f"triad must be one of {TRIADS}, got {triad!r}")
    t = getattr(model, triad)
    return {"random_walk": t.random_walk, "bias_instability": t.flicker, "rate_random_walk": t.rate_random_walk,
            "gauss_markov": t.bias_instability, "gauss_markov_time": t.bias_corr_time}
