"""An IMU preset fitted to a static record's Allan curves: "simulate this unit".

Each of the six channels' overlapping Allan variance at octave averaging times (from 0.1 s, or one
sample, to a tenth of the record) is fitted, by non-negative least squares on its relative error,
with the noise terms the simulator has (:mod:`sarins_fmu.imu`, :mod:`sarins_fmu.imu_correlated`)::

    sigma^2(tau) = N^2 / tau + B^2 F(tau) + s^2 G(tau; T) + K^2 tau / 3

* N: white noise (angle / velocity random walk, ``random_walk``);
* bias instability as a sum of Gauss-Markov terms: a flicker band B (``flicker``: equal-std terms,
  three per decade over [``flicker_tau_min``, ``flicker_tau_max``], one band for the model, chosen
  among a few), whose Allan variance F is the sum of the terms' closed forms, plus one more term of
  std s and correlation time T (``bias_instability``, ``bias_corr_time``), T chosen on a grid per
  channel;
* K: rate random walk (``rate_random_walk``).

G is the Gauss-Markov Allan variance of IEEE Std 952 annex C (:func:`sarins_fmu.allan.gauss_markov_avar`).
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
FLICKER_BANDS = ((0.1, 10.0), (1.0, 1.0), (10.0, 1.0), (0.1, 1.0), (1.0, 10.0), (0.1, 100.0))  # (tau_min s, tau_max / record)


@dataclass(frozen=True)
class ChannelFit:
    """The terms fitted to one channel (SI): white N, flicker B, Gauss-Markov std s and time T, K,
    and the largest relative deviation of the fitted deviation from the curve over the fitted octaves."""

    random_walk: float
    flicker: float
    gauss_markov: float
    gauss_markov_time: float
    rate_random_walk: float
    worst: float


def fitted_taus(curve: OctaveCurve, record_s: float) -> np.ndarray:
    """Mask of the octaves fitted: FIT_FROM s (or one sample) to FIT_TO of the record."""
    first = max(FIT_FROM, float(curve.taus[0]))
    return (curve.taus >= first * (1 - 1e-9)) & (curve.taus <= FIT_TO * record_s * (1 + 1e-9))


def flicker_avar(taus, tau_min: float, tau_max: float) -> np.ndarray:
    """Allan variance of the flicker synthesis for B = 1: the sum of its equal-std Gauss-Markov terms."""
    terms = core_imu.flicker_taus(tau_min, tau_max)
    q = flicker_term_std(1.0, terms)
    return sum(gauss_markov_avar(taus, q, t) for t in terms)


def model_avar(taus, fit: ChannelFit, band: tuple[float, float]) -> np.ndarray:
    """The Allan variance the fitted terms put at ``taus`` (closed forms)."""
    taus = np.asarray(taus, float)
    out = fit.random_walk ** 2 / taus + fit.rate_random_walk ** 2 * taus / 3.0
    if fit.flicker > 0:
        out = out + fit.flicker ** 2 * flicker_avar(taus, *band)
    if fit.gauss_markov > 0:
        out = out + gauss_markov_avar(taus, fit.gauss_markov, fit.gauss_markov_time)
    return out


def fit_channel(curve: OctaveCurve, record_s: float, band: tuple[float, float]) -> ChannelFit:
    """The terms of one channel for a given flicker band (see the module docstring)."""
    h = float(curve.taus[0])
    use = fitted_taus(curve, record_s)
    t, var = curve.taus[use], curve.adev[use] ** 2
    if t.size < 2 or not np.all(var > 0):
        return ChannelFit(0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    flick = flicker_avar(t, *band)
    best = None
    shortest = max(t[0] / 2, GM_MIN_SAMPLES * h)  # a shorter correlation time is not a sampled Gauss-Markov
    grid = np.geomspace(shortest, 10 * record_s, int(GM_GRID_PER_DECADE * math.log10(10 * record_s / shortest)) + 1)
    for tc in grid:
        basis = np.column_stack([1.0 / t, flick, gauss_markov_avar(t, 1.0, tc), t / 3.0]) / var[:, None]
        coef, _ = nnls(basis, np.ones_like(t))
        model = basis @ coef  # fitted / measured variance
        worst = float(np.max(np.abs(np.sqrt(model) - 1.0)))
        if best is None or worst < best[0]:
            best = (worst, coef, tc)
    worst, coef, tc = best
    n, b, s, k = (math.sqrt(max(c, 0.0)) for c in coef)
    return ChannelFit(n, b, s, float(tc), k, worst)


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
                     f"{triad}_rate_random_walk_{ax}": fit.rate_random_walk, f"{triad}_bias_{ax}": float(bias[j])})
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
