"""The IMU parameter fault sweep of issue 31 item 4, in process: every flat IMU parameter (every element of
the vectors and matrices, tests.test_imu_param_bounds and ``python tests/imu_bound_cases.py``).

A case is one parameter of a preset set to one value.  Its outcome:

* ``refused``: the IMU's construction raises ValueError naming the parameter (clean);
* ``finite``: the IMU is built and its first step (static, 20 degC) and three steps on a two-gimbal table
  turning at the largest rate the model supports, with the ambient at the ends of its allowed range, give
  finite increments and temperatures (clean);
* ``non-finite``: built, but a step gives NaN or infinity;
* ``unnamed``: refused with a message that does not name the parameter;
* ``crash``: any other exception;
* ``silently accepted``: a value just above its derived bound, built (only for the bound cases).
"""

from __future__ import annotations

import math
import sys
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sarins_fmu import imu, imu_params  # noqa: E402
from sarins_fmu.core import imu as core_imu  # noqa: E402
from sarins_fmu.site import SITE_LAT  # noqa: E402

NAMES = [name for name, _, _ in imu_params.PARAMETERS]
EXTREMES = (math.nan, math.inf, -math.inf, 1e300, -1e300, 5e-324)  # (5e-324: the smallest positive double)
INTERNAL_RATE = 200.0  # Hz
AXES = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0))  # outer z, inner x
AMBIENT_LOW = -273.15  # degC: absolute zero
AMBIENT_HIGH = getattr(core_imu, "AMBIENT_MAX", 500.0)  # degC: the highest ambient the IMU accepts


def max_rate(internal_rate: float = INTERNAL_RATE) -> float:
    """The largest body rate per axis the model supports (rad/s): core_imu.max_rate when the core has it."""
    if hasattr(core_imu, "max_rate"):
        return core_imu.max_rate(internal_rate)
    return math.pi / 8.0 * internal_rate


def run_steps(model) -> bool:
    """True when the first step and three steps at the largest rate give finite outputs; ValueError from
    the construction or a step passes through."""
    base = imu.StaticBase(SITE_LAT, 0.0, 0.0, 0.0)
    sensor = imu.IMU(model, base, AXES, output_interval=1.0, internal_rate=INTERNAL_RATE, seed=0)
    sensor.reset(ambient0=20.0)
    zero = np.zeros((1, 2))
    rate = max_rate() / math.sqrt(2.0)  # each gimbal: the body rate's components stay within max_rate
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        outputs = [sensor.step(zero, zero, zero, ambient=[20.0])]
        angle = np.zeros((1, 2))
        for ambient in (AMBIENT_HIGH, AMBIENT_LOW, 20.0):
            outputs.append(sensor.step(angle, np.full((1, 2), rate), zero, ambient=[ambient]))
            angle = angle + rate
    return all(np.all(np.isfinite(x)) for out in outputs for x in out)


def overrides(name: str, value: float) -> dict:
    """The case's parameter values: a periodic amplitude comes with a 1 Hz frequency (the pair rule refuses
    an amplitude without one), so that its own bound is what the case tests."""
    if "periodic_amplitude" in name:
        return {name: value, name.replace("amplitude", "frequency"): 1.0}
    return {name: value}


def outcome(preset: str, name: str, value: float) -> str:
    """The outcome of one case (see the module docstring); ``above`` cases call an accepted value
    ``silently accepted``."""
    try:
        model = imu_params.apply_overrides(imu.preset(preset), overrides(name, value))
        finite = run_steps(model)
    except ValueError as exc:
        return "refused" if names_it(name, str(exc)) else "unnamed"
    except Exception:  # noqa: BLE001 - any other exception is the outcome
        return "crash"
    return "finite" if finite else "non-finite"


def bound_values(preset: str, name: str) -> tuple | None:
    """(the largest magnitude accepted, the next double above it) for a bounded parameter, or None."""
    if not hasattr(core_imu, "param_bound"):
        return None
    par = core_imu.preset_params(preset)
    bound = core_imu.param_bound(par, INTERNAL_RATE, NAMES.index(name))
    if bound is None:
        return None
    return bound, float(np.nextafter(bound, math.inf))


CATEGORIES = (  # (category, substring test on the name), first match wins
    ("gyro/accel scale factor", lambda n: "_scale_factor_" in n and "_tc_" not in n and "dtdt" not in n),
    ("temperature coefficients", lambda n: any(k in n for k in ("_tc1_", "_tc2_", "_scale_factor_tc_",
                                                                "rate_hysteresis_tc", "_dtdt"))),
    ("misalignment", lambda n: "misalignment" in n),
    ("g-sensitivity", lambda n: n.startswith("g_sensitivity")),
    ("lowrate gain/width", lambda n: n.startswith("lowrate")),
    ("axial drift a/b/c, ageing", lambda n: n.startswith(("axial_drift_", "aging_sigma"))),
    ("noise densities", lambda n: any(k in n for k in ("random_walk", "bias_instability", "flicker_",
                                                       "turn_on_bias"))),
    ("biases, hysteresis, quadratic", lambda n: any(k in n for k in ("_bias_", "hysteresis", "quadratic"))),
    ("lever arm", lambda n: "lever_arm" in n),
    ("time constants, widths, thermal", lambda n: True),
)


def category(name: str) -> str:
    return next(c for c, test in CATEGORIES if test(name))


def sweep(presets=("mems", "nav-rlg")) -> list:
    """Every case: (preset, name, value label, outcome)."""
    rows = []
    for preset in presets:
        for name in NAMES:
            for value in EXTREMES:
                rows.append((preset, name, repr(value), outcome(preset, name, value)))
            bounds = bound_values(preset, name)
            if bounds is not None:
                rows.append((preset, name, "bound", outcome(preset, name, bounds[0])))
                above = outcome(preset, name, bounds[1])
                rows.append((preset, name, "above", "silently accepted" if above in ("finite", "non-finite")
                             and above == "finite" else above))
    return rows


def combination_outcome(preset: str, values: dict) -> str:
    """The outcome of setting several parameters at once: ``refused`` when the refusal names one of them."""
    try:
        model = imu_params.apply_overrides(imu.preset(preset), values)
        finite = run_steps(model)
    except ValueError as exc:
        return "refused" if any(names_it(name, str(exc)) for name in values) else "unnamed"
    except Exception:  # noqa: BLE001 - any other exception is the outcome
        return "crash"
    return "finite" if finite else "non-finite"


def _with(par: np.ndarray, name: str, value: float) -> np.ndarray:
    out = par.copy()
    out[NAMES.index(name)] = value
    return out


def combinations(preset: str, count: int, seed: int, size: int = 6) -> list:
    """``count`` random combinations of ``size`` bounded parameters, each at a random sign (where the parameter
    may be negative) and a magnitude
    log-uniform between 1e-3 and 2 times its own bound (the bound with the others at the preset): many
    combinations overrun a shared budget that no single value does.  Returns (values, outcome) pairs."""
    rng = np.random.default_rng(seed)
    par = core_imu.preset_params(preset)
    bounded = [(name, core_imu.param_bound(par, INTERNAL_RATE, k)) for k, name in enumerate(NAMES)]
    bounded = [(name, b) for name, b in bounded if b is not None and b > 0.0]
    signed = {name for name, b in bounded if core_imu.check_params(_with(par, name, -0.5 * b)) is None}
    rows = []
    for _ in range(count):
        picked = rng.choice(len(bounded), size=size, replace=False)
        values = {}
        for k in picked:
            name, b = bounded[k]
            sign = float(rng.choice((-1.0, 1.0))) if name in signed else 1.0
            values.update(overrides(name, sign * b * 10.0 ** float(rng.uniform(-3.0, math.log10(2.0)))))
        rows.append((values, combination_outcome(preset, values)))
    return rows


CLEAN = {"refused", "finite"}


def failing(rows) -> list:
    """The cases that fail: a bound value refused or not finite, anything else neither refused by name nor
    finite."""
    bad = []
    for row in rows:
        label, result = row[2], row[3]
        if label == "bound":
            if result != "finite":
                bad.append(row)
        elif label == "above":
            if result != "refused":
                bad.append(row)
        elif result not in CLEAN:
            bad.append(row)
    return bad


def names_it(name: str, message: str) -> bool:
    """The refusal names the parameter, or for a periodic amplitude set without a frequency the frequency
    it needs (a pair rule: the amplitude alone is valid)."""
    return name in message or ("periodic_amplitude" in name and name.replace("amplitude", "frequency") in message)


if __name__ == "__main__":
    rows = sweep()
    bad = failing(rows)
    print(f"{len(rows)} cases, {len(bad)} failing")
    table = Counter((category(name), result) for _, name, _, result in bad)
    for (cat, result), n in sorted(table.items()):
        print(f"{cat} | {result} | {n}")
    if "-v" in sys.argv:
        for row in bad:
            print(*row)
    combos = [outcome for preset in ("mems", "nav-rlg") for size in (2, 6, 20)
              for _, outcome in combinations(preset, 300, seed=size, size=size)]
    print(f"{len(combos)} combinations: " + ", ".join(f"{o} {n}" for o, n in sorted(Counter(combos).items())))
