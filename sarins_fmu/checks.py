"""Argument checks shared by the library's profile builders (turntable schedules, chamber profiles)."""

import math


def finite_number(name: str, value, *, positive: bool = False) -> float:
    """``value`` as a finite float, >= 0 (or > 0 if ``positive``), else ValueError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    if v < 0 or (positive and v == 0):
        raise ValueError(f"{name} must be {'positive' if positive else 'non-negative'}, got {v}")
    return v
