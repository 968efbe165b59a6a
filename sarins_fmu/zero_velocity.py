"""Zero-velocity / zero-angular-rate detection from the IMU's own statistics, and the vehicle
vibration that makes motion visible to it.

Detector (C core ``zvd.h``, per sample, no allocation after initialisation).  Sample k of step h:
specific force f_k = dv_k / h (m/s^2), angular rate w_k = dtheta_k / h (rad/s), body frame.  Over the
window W_k of the last N samples (means fbar, wbar)::

    T_k = sum_{j in W_k} |f_j - fbar|^2 / sigma_f^2 + |w_j - wbar|^2 / sigma_w^2,
    sigma_f^2 = vrw^2 / h,   sigma_w^2 = arw^2 / h,

vrw (m/s/sqrt(s)) and arw (rad/sqrt(s)) the IMU's white-noise densities, so sigma_f, sigma_w are the
per-axis std of one sample.  Derivation of the threshold: standing still, f_j = f0 + b_a + n_j and
w_j = w0 + b_g + m_j with gravity f0, Earth rate w0 and the biases constant over the window and
n, m white Gaussian; each sum is then sigma^2 times a sample variance of 3 axes x N samples, i.e.
chi-square with 3 (N - 1) degrees of freedom, and the two are independent, so

    T_k ~ chi-square(6 (N - 1))   (H0: stationary), independent of gravity, Earth rate and the biases.

Declaring the window stationary when T_k <= gamma = F^-1_{chi2(6(N-1))}(1 - alpha) makes ``alpha``
the probability that a stationary window is declared moving (the size of the test of H0; the
detector's false-alarm rate in the sense of a false "moving").  Windows N samples apart are disjoint
and independent, so over m disjoint stationary windows the misses are Binomial(m, alpha).  The
deviations about the window mean are used, not about gravity and zero rate: the per-axis biases
(the ``mems`` grade's 2 mg is two per-sample sigmas at 100 Hz) and the Earth rate would otherwise
shift the statistic by an unknown non-centrality.

Moving, a vehicle vibrates: :class:`Vibration` adds a bounded white velocity jitter u_k (std
``accel_rms h / sqrt(2)`` per axis) and attitude jitter theta_k (std ``rate_rms h / sqrt(2)``) at
every moving IMU point, seen as increments u_{k+1} - u_k and theta_{k+1} - theta_k, i.e. a sample
specific force of std ``accel_rms`` and a sample rate of std ``rate_rms`` per axis, with no drift of
velocity or attitude (the telescoping sum stays bounded).  A moving window then has T_k a Gaussian
quadratic form x' A x with E = tr(A S), whose lower tail :func:`moving_window_bound` bounds
(Chernoff).  Without vibration a smooth straight cruise has constant f and w and passes the test like
a stop: the detector needs the vehicle's vibration (or its manoeuvres) to see motion.  The detector
decides for the window ending at sample k (causal): a stop is detected N - 1 samples after it begins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .core import aided as _core
from .units import DEG_TO_RAD


@dataclass(frozen=True)
class DetectorSettings:
    """window: seconds of IMU samples per test (N = round(window / h)); alpha: probability that a
    stationary window is declared moving (the test's size, see module docs)."""

    window: float = 0.5
    alpha: float = 1e-3

    def __post_init__(self):
        if not (math.isfinite(self.window) and self.window > 0):
            raise ValueError(f"detector window must be positive, got {self.window!r}")
        if not (math.isfinite(self.alpha) and 0 < self.alpha < 1):
            raise ValueError(f"detector alpha must be in (0, 1), got {self.alpha!r}")

    def samples(self, step: float) -> int:
        """N, the window in samples of ``step`` s (at least 2)."""
        return max(2, int(round(self.window / step)))

    def check(self, step: float) -> None:
        """ValueError (the core's reason) unless the core takes this window at IMU step ``step`` s."""
        _core.ZvdState([self.samples(step), step, 1.0, 1.0, threshold(self.samples(step), self.alpha)])


def threshold(samples: int, alpha: float) -> float:
    """gamma = the (1 - alpha) quantile of chi-square(6 (samples - 1))."""
    from scipy.stats import chi2

    return float(chi2.isf(alpha, 6 * (samples - 1)))


@dataclass(frozen=True)
class Detection:
    """statistic (K,) T_k (-1 while the first window fills); stationary (K,) bool per IMU step;
    samples N; gamma the threshold; alpha."""

    statistic: np.ndarray
    stationary: np.ndarray
    samples: int
    gamma: float
    alpha: float


def detect(dtheta, dv, step: float, vrw: float, arw: float, settings: DetectorSettings = DetectorSettings()) -> Detection:
    """Stationary IMU steps from increments dtheta, dv (K, 3) rad, m/s of step ``step`` s, with the
    IMU's white-noise densities vrw (m/s/sqrt(s)) and arw (rad/sqrt(s)) (C core ``zvd.h``)."""
    if not (vrw > 0 and arw > 0):
        raise ValueError("zero-velocity detection needs the IMU's noise densities (vrw, arw) positive: an ideal IMU "
                         "has no noise to test against")
    n = settings.samples(step)
    gamma = threshold(n, settings.alpha)
    state = _core.ZvdState([n, step, vrw, arw, gamma])
    stat, flag = state.run(dtheta, dv)
    return Detection(statistic=stat, stationary=flag, samples=n, gamma=gamma, alpha=settings.alpha)


@dataclass(frozen=True)
class Vibration:
    """Vehicle vibration while moving: per-axis RMS of the sample specific force (m/s^2) and angular
    rate (rad/s) it adds at the IMU's rate (see module docs)."""

    accel_rms: float = 0.0
    rate_rms: float = 0.0

    def __post_init__(self):
        for name in ("accel_rms", "rate_rms"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"vibration {name} must be a non-negative number, got {value!r}")


# Hypothetical (our choice, no measured spectrum): a road vehicle's body vibration at a 100 Hz IMU
VIBRATION = {"none": Vibration(), "car": Vibration(accel_rms=0.3, rate_rms=0.5 * DEG_TO_RAD)}


def moving_points(truth) -> np.ndarray:
    """(K+1,) bool: the vehicle moves at the point (speed above 1e-9 m/s)."""
    return np.linalg.norm(truth.velocity_n, axis=1) >= 1e-9


def vibrate(truth, vibration: Vibration, seed: int, stream: str = "numpy"):
    """Increments of the vibration (dtheta, dv (K, 3) rad, m/s) to add to the IMU's: jitter
    u_k, theta_k white at the moving points, zero at rest; increments u_{k+1} - u_k.  ``stream``: 'numpy'
    (numpy's generator seeded [seed, 3019]) or 'core' (the C core's ``vibration.h``, stream 34 of ``seed``: the
    draws the TrajectoryIMU FMU makes one step at a time with ``vib_accel_rms``, ``vib_rate_rms``, bit for bit)."""
    if stream == "core":
        return _core.vibration_run(vibration.accel_rms, vibration.rate_rms, truth.step, seed, truth.velocity_n)
    if stream != "numpy":
        raise ValueError(f"vibration stream must be 'numpy' or 'core', got {stream!r}")
    rng = np.random.default_rng([seed, 3019])
    moving = moving_points(truth)[:, None]
    h = truth.step
    u = rng.standard_normal(truth.velocity_n.shape) * (vibration.accel_rms * h / math.sqrt(2.0)) * moving
    theta = rng.standard_normal(truth.velocity_n.shape) * (vibration.rate_rms * h / math.sqrt(2.0)) * moving
    return np.diff(theta, axis=0), np.diff(u, axis=0)


def moving_window_bound(samples: int, gamma: float, sigma_f: float, sigma_w: float, vibration: Vibration) -> float:
    """Chernoff bound on P(T <= gamma) for a window of ``samples`` moving samples with the vibration of
    :func:`vibrate` and white noise sigma_f (m/s^2), sigma_w (rad/s) per sample (the vehicle's own
    manoeuvres only add to T's spread and are left out).  Per axis the samples are
    x = n + (u_{j+1} - u_j) / h: covariance S = sigma^2 I + s_v^2 (2 I - shift - shift') / 2 with s_v the
    vibration's RMS; T = sum over 6 axes of x' C x / sigma^2 (C the centring matrix), a sum of
    lambda_i chi-square(1) with lambda_i the eigenvalues of C S C / sigma^2, and
    P(T <= gamma) <= min_{t > 0} exp(t gamma) prod_i (1 + 2 t lambda_i)^(-1/2)."""
    from scipy.optimize import minimize_scalar

    n = samples
    c = np.eye(n) - np.ones((n, n)) / n
    second = np.eye(n) * 2.0 - np.eye(n, k=1) - np.eye(n, k=-1)
    lams = []
    for sigma, vib in ((sigma_f, vibration.accel_rms), (sigma_w, vibration.rate_rms)):
        s = sigma**2 * np.eye(n) + vib**2 * second / 2.0
        lam = np.linalg.eigvalsh(c @ s @ c / sigma**2)
        lams += [lam[lam > 1e-9]] * 3
    lam = np.concatenate(lams)

    def log_bound(log_t):
        t = math.exp(log_t)
        return t * gamma - 0.5 * float(np.sum(np.log1p(2.0 * t * lam)))

    best = minimize_scalar(log_bound, bounds=(-30.0, 10.0), method="bounded")
    return float(min(1.0, math.exp(min(0.0, best.fun))))
