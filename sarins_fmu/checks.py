"""Argument conversion shared by the library's profile builders (turntable schedules, chamber profiles).

The range checks (finite, positive, ...) are the C core's (``sarins_fmu/core/schedule.h``); this only
turns a caller's value into a float with a message naming it.
"""


def number(name: str, value) -> float:
    """``value`` as a float, else ValueError naming ``name``."""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
