"""An IMU preset fitted to a static record's Allan curves: "simulate this unit".

Each of the six channels' overlapping Allan variance at octave averaging times (from 0.1 s, or one
sample, to a tenth of the record) is fitted, by non-negative least squares on its relative error,
with the noise terms the simulator has (:mod:`sarins_fmu.imu`, :mod:`sarins_fmu.imu_correlated`)::

    sigma^2(tau) = N^2 / tau + B^2 F(tau) + s^2 G(tau; T) + K^2 tau / 3 + a^2 P(tau; f)

* N: white noise (angle / velocity random walk, ``random_walk``);
* bias instability as a sum of Gauss-Markov terms: a flicker band B (``flicker``: equal-std terms,
  three per decade over [``flicker_tau_min``, ``flicker_tau_max``], one band for the model, chosen
  among a few), whose Allan variance F is the sum of the terms' closed forms, plus one more term of
  std s and correlation time T (``bias_instability``, ``bias_corr_time``), T chosen on a grid per
  channel;
* K: rate random walk (``rate_random_walk``);
* a periodic disturbance of amplitude a and frequency f (``periodic_amplitude``,
  ``periodic_frequency``), whose Allan variance is P = sin^4(pi f tau) / (pi f tau)^2 (a sinusoid's
  closed form), f chosen on a grid per channel (SINE_GRID_PER_DECADE per decade over the f whose
  deviation peaks, at tau = SINE_PEAK / f, within the fitted taus; at most the Nyquist frequency);
  kept only where it lowers the channel's worst deviation by more than SINE_MIN_GAIN (5 points: the
  1-sigma scatter of a 10^4 s record's octave estimates, 1 / sqrt(2 edf), reaches 5 % at 64 s, so a
  smaller gain is no evidence of a periodic term).  The ADIS16405 accelerometers' curves carry such a
  bump (0.3 - 2 s, falling as 1 / tau after it: a disturbance near 0.5 Hz), which the term takes up
  (their worst deviation falls by 11 - 20 points, benchmarks/allan_real_units.py); the gyros'
  candidates gain less than 5 points and are left out.

For each T (and f) the coefficients come from NNLS; the channel keeps the T (and f) whose fit has the
smallest worst deviation.  G is the Gauss-Markov Allan variance of IEEE Std 952 annex C
(:func:`sarins_fmu.allan.gauss_markov_avar`).
The quantisation of the outputs (a rate output on a grid of step d is white noise of density
d sqrt(h / 12)) is inside N; the output step is reported beside the fit.  The bias is the record's
mean (gyros: less the Earth rate's vertical part when the latitude is known; accelerometers: less
gravity's magnitude along the measured vertical) -- the horizontal parts of both cannot be told
from the heading and the tilt of one static record.  Everything else of the model (thermal terms,
scale factors, misalignment) is zero: the preset is the ``ideal`` one with these terms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from . import earth, imu, imu_params
from .allan import gauss_markov_avar
from .allan_readout import OctaveCurve
from .core import imu as core_imu
from .imu_correlated import flicker_term_std

FIT_FROM = 0.1  # s: the shortest averaging time fitted (or one sample)
FIT_TO = 0.1  # of the record: the longest averaging time fitted
GM_GRID_PER_DECADE = 4
GM_MIN_SAMPLES = 10  # shortest Gauss-Markov correlation time fitted, in samples
SINE_GRID_PER_DECADE = 30  # frequencies of the periodic term tried per decade
SINE_PEAK = 0.3710  # f tau at the peak of a sinusoid's Allan deviation sin^2(pi f tau) / (pi f tau)
SINE_MIN_GAIN = 0.05  # kept when it lowers the worst deviation by more than this (see the module docstring)
FLICKER_BANDS = ((0.1, 10.0), (1.0, 1.0), (10.0, 1.0), (0.1, 1.0), (1.0, 10.0), (0.1, 100.0))  # (tau_min s, tau_max / record)


@dataclass(frozen=True)
class ChannelFit:
    """The terms fitted to one channel (SI): white N, flicker B, Gauss-Markov std s and time T, K,
    the largest relative deviation of the fitted deviation from the curve over the fitted octaves, and
    the periodic term's amplitude a (rad/s or m/s^2; 0: none) and frequency f (Hz; 0: none)."""

    random_walk: float
    flicker: float
    gauss_markov: float
    gauss_markov_time: float
    rate_random_walk: float
    worst: float
    periodic_amplitude: float = 0.0
    periodic_frequency: float = 0.0


def fitted_taus(curve: OctaveCurve, record_s: float) -> np.ndarray:
    """Mask of the octaves fitted: FIT_FROM s (or one sample) to FIT_TO of the record."""
    first = max(FIT_FROM, float(curve.taus[0]))
    return (curve.taus >= first * (1 - 1e-9)) & (curve.taus <= FIT_TO * record_s * (1 + 1e-9))


def flicker_avar(taus, tau_min: float, tau_max: float) -> np.ndarray:
    """Allan variance of the flicker synthesis for B = 1: the sum of its equal-std Gauss-Markov terms."""
    terms = core_imu.flicker_taus(tau_min, tau_max)
    q = flicker_term_std(1.0, terms)
    return sum(gauss_markov_avar(taus, q, t) for t in terms)


def sine_avar(taus, frequency: float) -> np.ndarray:
    """Allan variance of a sinusoid of amplitude 1 and ``frequency`` (Hz) at ``taus`` (s), averaged over its
    phase: sin^4(pi f tau) / (pi f tau)^2 (exact for an output that integrates it over each interval, at
    multiples of the interval)."""
    x = math.pi * float(frequency) * np.asarray(taus, float)
    return np.sin(x) ** 4 / x ** 2


def sine_grid(taus, step: float) -> np.ndarray:
    """The periodic term's frequencies tried (Hz) for the fitted ``taus`` (s) of a record sampled every
    ``step`` s: SINE_GRID_PER_DECADE per decade over the frequencies whose Allan deviation peaks
    (at tau = SINE_PEAK / f) within the fitted taus, at most the Nyquist frequency 1 / (2 step)."""
    low, high = SINE_PEAK / float(taus[-1]), min(SINE_PEAK / float(taus[0]), 0.5 / step)
    if not high > low:
        return np.empty(0)
    return np.geomspace(low, high, int(SINE_GRID_PER_DECADE * math.log10(high / low)) + 1)


def model_avar(taus, fit: ChannelFit, band: tuple[float, float]) -> np.ndarray:
    """The Allan variance the fitted terms put at ``taus`` (closed forms)."""
    taus = np.asarray(taus, float)
    out = fit.random_walk ** 2 / taus + fit.rate_random_walk ** 2 * taus / 3.0
    if fit.flicker > 0:
        out = out + fit.flicker ** 2 * flicker_avar(taus, *band)
    if fit.gauss_markov > 0:
        out = out + gauss_markov_avar(taus, fit.gauss_markov, fit.gauss_markov_time)
    if fit.periodic_amplitude > 0:
        out = out + fit.periodic_amplitude ** 2 * sine_avar(taus, fit.periodic_frequency)
    return out


def _best_fit(t, var, flick, grid, fifth) -> tuple:
    """(worst, coefficients, T, f) of the NNLS fit with the smallest worst deviation over the Gauss-Markov
    times ``grid`` and the candidate fifth columns ``fifth`` [(f, periodic column / var)]; ``flick`` is the
    flicker column / var."""
    ones = np.ones_like(t)
    best = None
    for tc in grid:
        basis = np.column_stack([1.0 / t / var, flick, gauss_markov_avar(t, 1.0, tc) / var, t / 3.0 / var, ones])
        for f, column in fifth:
            basis[:, 4] = column
            coef, _ = nnls(basis, ones)
            worst = float(np.max(np.abs(np.sqrt(basis @ coef) - 1.0)))  # basis @ coef: fitted / measured variance
            if best is None or worst < best[0]:
                best = (worst, coef, tc, f)
    return best


def fit_channel(curve: OctaveCurve, record_s: float, band: tuple[float, float], *,
                periodic: bool = True) -> ChannelFit:
    """The terms of one channel for a given flicker band (see the module docstring); ``periodic=False``:
    without the periodic term."""
    h = float(curve.taus[0])
    use = fitted_taus(curve, record_s)
    t, var = curve.taus[use], curve.adev[use] ** 2
    if t.size < 2 or not np.all(var > 0):
        return ChannelFit(0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    flick = flicker_avar(t, *band) / var
    shortest = max(t[0] / 2, GM_MIN_SAMPLES * h)  # a shorter correlation time is not a sampled Gauss-Markov
    grid = np.geomspace(shortest, 10 * record_s, int(GM_GRID_PER_DECADE * math.log10(10 * record_s / shortest)) + 1)
    best = plain = _best_fit(t, var, flick, grid, [(0.0, np.zeros_like(t))])
    if periodic:
        sines = [(f, sine_avar(t, f) / var) for f in sine_grid(t, h)]
        with_sine = _best_fit(t, var, flick, grid, sines) if sines else None
        if with_sine is not None and with_sine[0] < plain[0] - SINE_MIN_GAIN:
            best = with_sine
    worst, coef, tc, f = best
    n, b, s, k, a = (math.sqrt(max(c, 0.0)) for c in coef)
    return ChannelFit(n, b, s, float(tc), k, worst, a if f > 0 else 0.0, float(f) if a > 0 else 0.0)


@dataclass(frozen=True)
class PresetFit:
    """The six channels' fits, the flicker band, the bias (6,) SI and the output steps, and the model."""

    channels: tuple
    band: tuple
    bias: np.ndarray
    spread: np.ndarray
    model: imu.ImuModel


def fit_preset(curves: dict, record_s: float, means: np.ndarray | None = None, lat: float | None = None,
               height: float = 0.0) -> PresetFit:
    """Fit every channel (curves: channel name -> :class:`OctaveCurve`, gyro x, y, z, accel x, y, z in
    that order) for each flicker band of FLICKER_BANDS; keep the band whose worst channel is best.
    ``means`` (M, 6) 1 s means give the bias (and its in-run spread, the std of the means over tenths
    of the record)."""
    names = list(curves)
    best = None
    for lo, hi_rel in FLICKER_BANDS:
        band = (lo, max(hi_rel * record_s, 2 * lo))
        fits = tuple(fit_channel(curves[ch], record_s, band) for ch in names)
        score = max(f.worst for f in fits)
        if best is None or score < best[0]:
            best = (score, fits, band)
    _, fits, band = best
    bias, spread = _bias(means, lat, height)
    return PresetFit(fits, band, bias, spread, build_model(fits, band, bias))


def _bias(means, lat, height) -> tuple[np.ndarray, np.ndarray]:
    if means is None or len(means) == 0:
        return np.zeros(6), np.zeros(6)
    means = np.asarray(means, float)
    mean = means.mean(axis=0)
    up = mean[3:] / np.linalg.norm(mean[3:])
    bias = mean.copy()
    if lat is not None:
        bias[:3] -= earth.RATE * math.sin(lat) * up  # the Earth rate's vertical part
        g = float(np.linalg.norm(earth.gravity_n(lat, height)))
    else:
        g = float(np.linalg.norm(mean[3:]))  # latitude unknown: the magnitude stays with gravity
    bias[3:] -= g * up
    tenths = np.array_split(means, 10) if len(means) >= 10 else [means]
    spread = np.std([m.mean(axis=0) for m in tenths], axis=0)
    return bias, spread


def build_model(fits, band, bias) -> imu.ImuModel:
    """The ``ideal`` preset with the fitted noise terms and the bias (gyro x, y, z then accel x, y, z)."""
    over = {"flicker_tau_min": band[0], "flicker_tau_max": band[1]}
    for j, fit in enumerate(fits):
        triad, ax = ("gyro", "accel")[j // 3], "xyz"[j % 3]
        over.update({f"{triad}_random_walk_{ax}": fit.random_walk, f"{triad}_flicker_{ax}": fit.flicker,
                     f"{triad}_bias_instability_{ax}": fit.gauss_markov,
                     f"{triad}_bias_corr_time_{ax}": fit.gauss_markov_time,
                     f"{triad}_rate_random_walk_{ax}": fit.rate_random_walk, f"{triad}_bias_{ax}": float(bias[j]),
                     f"{triad}_periodic_amplitude_{ax}": fit.periodic_amplitude,
                     f"{triad}_periodic_frequency_{ax}": fit.periodic_frequency})
    return imu_params.apply_overrides(imu.preset("ideal"), over)


def simulate_rates(model: imu.ImuModel, duration: float, rate_hz: float, seed: int = 0,
                   chunk: int = 2**20) -> np.ndarray:
    """A static record of ``model`` as (K, 6) rates (rad/s, m/s^2), simulated in chunks of ``chunk``
    intervals (the same numbers as one call: the IMU's streams do not depend on how a run is cut)."""
    h = 1.0 / rate_hz
    n = int(round(duration * rate_hz))
    sensor = imu.IMU(model, imu.StaticBase(math.radians(45.0)), ((0.0, 0.0, 1.0),), output_interval=h,
                     internal_rate=rate_hz, seed=seed)
    out = np.empty((n, 6))
    for k0 in range(0, n, chunk):
        k = min(chunk, n - k0)
        zero = np.zeros((k, 1))
        dtheta, dv, _ = sensor.step(zero, zero, zero)
        out[k0:k0 + k, :3], out[k0:k0 + k, 3:] = dtheta / h, dv / h
    return out
