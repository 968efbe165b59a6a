"""Sensor dynamics with memory at the output rate: size effect, rate hysteresis, output filter.

The C core applies them (``sarins_fmu/core/dynamics.h`` states the equations)
to every output interval's mean rate and specific force, after the minor
loop's deterministic errors and before the white noise:

* **Accelerometer size effect** (``ImuModel.accel_lever_arm``, m): each
  accelerometer sits at its own point r_j, away from the reference point,
  and senses ``e_j . (alpha x r_j + omega x (omega x r_j))`` on top of the
  specific force there -- the angular-acceleration (tangential) and
  centripetal terms of a lever arm.  ADIS1646x/1647x units remove it in the
  factory ("point of percussion" alignment); an uncompensated MIMU keeps it.
* **Rate hysteresis with relaxation** (``rate_hysteresis`` c,
  ``rate_hysteresis_width`` w, ``rate_hysteresis_time`` tau_r,
  ``rate_hysteresis_tc`` k): a play operator on the channel's own input
  whose state relaxes towards the input with time constant tau_r; the error
  c (1 + k (T - T_ref)) (x - P) / w is +-c on a sweep faster than w / tau_r,
  proportional to the sweep rate on a slower one, and decays as
  exp(-t / tau_r) when the input is held: memory of the last seconds of
  motion that no function of the current sample can remove.
* **Output low-pass filter** (``filter_time_constant`` tau_f): the
  first-order recursive filter y <- y + a (x - y), a = h / (h + tau_f), at
  the output rate, whose group delay at low frequency is tau_f at any output
  interval h (its closed forms are in tests/test_imu_dynamics.py).

All coefficients are zero for ``ideal`` and ``nav-rlg``: their outputs do
not change.
"""

from __future__ import annotations

import numpy as np

PAR_ROWS, STATE_ROWS = 8, 4  # SARINS_DYN_PAR_ROWS, SARINS_DYN_STATE_ROWS in dynamics.h


def _stack(model, name):
    return np.concatenate([getattr(model.gyro, name), getattr(model.accel, name)])


def parameters(model) -> np.ndarray:
    """(8, 6) parameter rows of the C core: filter time constant, hysteresis amplitude, width, relaxation
    time, temperature coefficient, accelerometer lever arm x, y, z (columns gyro x, y, z, accel x, y, z)."""
    par = np.zeros((PAR_ROWS, 6))
    for i, name in enumerate(("filter_time_constant", "rate_hysteresis", "rate_hysteresis_width",
                              "rate_hysteresis_time", "rate_hysteresis_tc")):
        par[i] = _stack(model, name)
    par[5:8, 3:6] = np.asarray(model.accel_lever_arm, float).T  # row 5 + a: component a of each accel's arm
    return par


def active(model) -> bool:
    """Whether any of the terms is switched on for ``model``."""
    par = parameters(model)
    return bool(np.any(par[0] != 0) or np.any(par[1] != 0) or np.any(par[5:8] != 0))
