"""Time-correlated sensor errors: thermal gradient, hysteresis, flicker, RRW, turn-on bias.

Terms added, per output interval k and sensor j (gyro x, y, z, accel x, y, z),
to the bias and scale factor of :mod:`sarins_fmu.imu` (all SI; T is the *die*
temperature of :func:`sarins_fmu.thermal.die_temperatures`, degC, at the
interval midpoint, Tdot its rate over the interval, degC/s)::

    b += c_g Tdot + c_h (T - P_w[T]) / w + x_flicker + x_rrw + b_on
    sf += s_g Tdot

* **Thermal gradient** ``c_g Tdot``, ``s_g Tdot`` (``bias_dtdt``,
  ``scale_factor_dtdt``).  In a lumped body warmed through its surface the
  temperature difference across the sensor is proportional to the rate of
  change, dT_across = Tdot L^2 / (2 alpha) for a slab of thickness L and
  diffusivity alpha (steady ramp solution of the heat equation); a gradient
  across a vibrating structure or a pendulum shifts its bias and scale
  factor linearly (IEEE Std 952-1997 annex B lists the "temperature
  gradient / rate" sensitivity; seed 000 models the axial drift with dT/dt
  for the same reason).
* **Thermal hysteresis** ``c_h (T - P_w[T]) / w``: P_w is the play
  (backlash) operator of half-width w degC,
      P_k = max(T_k - w, min(T_k + w, P_{k-1})),  P_0 = T_0,
  the elementary hysteron of the Prandtl-Ishlinskii model (Brokate &
  Sprekels, *Hysteresis and Phase Transitions*, 1996, ch. 2).  T - P is +w
  after heating by more than 2w and -w after cooling, so the bias-vs-
  temperature curve is a loop whose branches are 2 c_h apart; a reversal
  moves along a flat segment until the play is taken up.
* **Flicker bias instability** (coefficient B, ``flicker``): a flicker
  (1/f) bias has the two-sided PSD S(f) = B^2 / (2 pi f) of IEEE Std
  952-1997 annex C (one-sided B^2 / (pi f)) and the flat Allan deviation
  sqrt(2 ln 2 / pi) B = 0.664 B.  It is synthesised as a sum of first-order
  Gauss-Markov terms with correlation times T_i log-spaced by a ratio r
  over [tau_min, tau_max] (``flicker_tau_min``, ``flicker_tau_max``), all
  with the same std q.  Derivation of q: a GM term of std q has the
  one-sided PSD 4 q^2 T_i / (1 + (2 pi f T_i)^2); summed over log-spaced
  T_i, sum_i ~ (1/ln r) int S dlnT = (4 q^2 / ln r) int_0^inf dT / (1 +
  (2 pi f T)^2) = q^2 / (f ln r), equal to B^2 / (pi f) for
  q = B sqrt(ln r / pi).  The spectrum is 1/f for 1/(2 pi tau_max) << f <<
  1/(2 pi tau_min); the Allan floor spans about 20 tau_min < tau <
  tau_max / 5 (measured, see tests/test_imu_correlated.py).  Three terms
  per decade keep the ripple of the floor at about 1 % (Keshner, Proc. IEEE
  70(3), 1982, builds 1/f noise the same way).  Each term advances one
  exact step per interval, x <- phi x + q sqrt(1 - phi^2) w,
  phi = exp(-h / T_i), from a stationary start.
* **Rate random walk** K (``rate_random_walk``): x <- x + K sqrt(h) w; its
  Allan deviation is K sqrt(tau / 3) (IEEE Std 952).
* **Turn-on bias** (``turn_on_bias``, std): a constant drawn once per seed
  (run-to-run repeatability), from its own stream.

The terms are evaluated per interval in the C core
(``sarins_fmu/core/correlated.c``), which also builds their parameters
(``sarins_imu_build`` in ``imu_build.c``) and draws their random numbers
(``sarins_imu_seed`` and the step); this module documents them and gives
their helpers to Python.

Every random term draws from its own stream of the IMU seed (flicker, rate
random walk, turn-on: ``SARINS_IMU_STREAM_*`` in ``sarins_fmu/core/imu.h``),
so these terms never change the noise of the other terms, and a model that
has them all at zero (``ideal``, ``nav-rlg``) draws nothing for them.
"""

from __future__ import annotations

import math

import numpy as np

from .core import imu as core_imu

TERMS_PER_DECADE = 3  # SARINS_IMU_FLICKER_PER_DECADE in sarins_fmu/core/imu_build.h


def flicker_taus(tau_min: float, tau_max: float) -> np.ndarray:
    """Log-spaced correlation times (s) of the Gauss-Markov sum, endpoints included (the C core's
    ``sarins_imu_flicker_taus``: max(2, ceil(3 log10(tau_max / tau_min)) + 1) terms)."""
    return core_imu.flicker_taus(tau_min, tau_max)


def flicker_term_std(coefficient: float, taus) -> float:
    """Std of every Gauss-Markov term for flicker coefficient B: B sqrt(ln r / pi)."""
    return float(coefficient) * math.sqrt(math.log(taus[1] / taus[0]) / math.pi)


def _stack(model, name):
    return np.concatenate([getattr(model.gyro, name), getattr(model.accel, name)])


def turn_on_bias(model, seed: int) -> np.ndarray:
    """The turn-on bias an IMU of ``model`` draws at power-up with ``seed``: (6,) gyro x, y, z (rad/s),
    accelerometer x, y, z (m/s^2) (the C core's ``sarins_imu_turn_on``, the draw the IMU's step uses)."""
    return core_imu.turn_on(seed, _stack(model, "turn_on_bias"))
