"""The azimuth gyro drift's quadratic temperature model ε(T) = a T² + b T + c (seed 002 eq. 7).

One evaluation, shared by the forgetting-factor RLS
(:mod:`sarins_fmu.identify.rls`), the vehicle test and the INS FMU, so that
they agree bit for bit.  Coefficients [a, b, c] in a drift unit (rad/s
inside) per °C², per °C and plain; temperatures in °C.
"""

from __future__ import annotations

import numpy as np


def drift_model_value(coefficients, temperature):
    """ε(T) = (a T + b) T + c of the model ``coefficients`` [a, b, c] at ``temperature`` (°C).

    A scalar temperature gives a float; an array gives an array of its shape.
    """
    a, b, c = coefficients[0], coefficients[1], coefficients[2]
    if not isinstance(temperature, np.ndarray) and np.ndim(temperature) == 0:
        t = float(temperature)
        return (float(a) * t + float(b)) * t + float(c)
    t = np.asarray(temperature, dtype=float)
    return (a * t + b) * t + c
