"""Accuracy of the core's portable math (sarins_fmu/core/smath.h) against mpmath, and its exact functions
against numpy.

For each function: random arguments over its whole range (log-uniform magnitudes from the subnormals to
the largest doubles, both signs where defined, plus uniform sets where it is used: angles, exp's and log's
ordinary ranges, arguments near the quadrant limits and near 1), evaluated by ``sarins_smath_eval`` and by
mpmath at 120 bits; the error of each result in ulps of the exact value (the ulp of the binade of the exact
value, 2^-1074 below the normal range).  Special arguments (+-0, +-inf, NaN, subnormals, the overflow and
underflow limits) are checked against C's Annex F by tests/test_smath.py, not here.  The exactly rounded
functions (sqrt, fma, floor, ceil, trunc, round, nearbyint, fmod, fmin, fmax, fabs, copysign) are compared
bit for bit with numpy / glibc over random bit patterns; sqrt and fma also in their software versions.

    python benchmarks/smath_accuracy.py [--n 200000] [--seed 1] [--only tanh,tanhv]

Prints one row per function: the largest error in ulps, its argument, and the number of arguments.
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import time

import mpmath
import numpy as np
from mpmath import mpf

from sarins_fmu.core.smath import evaluate

mpmath.mp.prec = 120


def _ulp_errors(got: np.ndarray, exact: list) -> np.ndarray:
    """|got - exact| in ulps of exact (0 where both are the same infinity or exact is 0 and got is 0)."""
    out = np.empty(len(got))
    for i, (g, t) in enumerate(zip(got, exact)):
        if mpmath.isinf(t) or t == 0:
            out[i] = 0.0 if (g == t) else np.inf
            continue
        man, exp = t.man_exp  # |t| = |man| 2^exp: its binade exactly
        e = max(exp + abs(int(man)).bit_length() - 1, -1022)
        out[i] = float(mpmath.ldexp(abs(mpf(float(g)) - t), 52 - e))
    return out


def _pow_sets(rng, q: int) -> list:
    """pow's arguments: results across the whole normal range, bases near 1 with large exponents, negative
    bases with integer exponents, the RLS forgetting factor's form lambda^(dt/m)."""
    x = _log_uniform(rng, 1e-300, 1e300, 2 * q, signed=False)
    y = rng.uniform(-700.0, 700.0, 2 * q) / np.log(x)
    near = 1.0 + rng.uniform(-1e-6, 1e-6, q)
    big = rng.uniform(-700.0, 700.0, q) / np.log(near)
    neg = -_log_uniform(rng, 1e-3, 1e3, q, signed=False)
    ints = np.round(rng.uniform(-60.0, 60.0, q))
    return [("x 1e-300 .. 1e300, results 1e-304 .. 1e304", (x, y)),
            ("x near 1, |y| up to 1e9", (near, big)),
            ("x < 0, integer y", (neg, ints)),
            ("0.8 ** (dt / m), dt/m in 0 .. 2", (np.full(q, 0.8), rng.uniform(0.0, 2.0, q)))]


def _log_uniform(rng, lo: float, hi: float, n: int, signed: bool = True) -> np.ndarray:
    x = np.exp(rng.uniform(np.log(lo), np.log(hi), n))
    return x * rng.choice([-1.0, 1.0], n) if signed else x


def argument_sets(rng, n: int) -> dict[str, list[tuple[str, tuple[np.ndarray, ...]]]]:
    """{function: [(description, arguments)]}: n arguments over each function's range in all."""
    q = max(n // 4, 1)
    pio2 = np.pi / 2
    k = rng.integers(-10 ** 6, 10 ** 6, q).astype(float)
    trig = [("|x| < 10", (rng.uniform(-10.0, 10.0, q),)),
            ("near k pi/2 (|k| < 1e6)", (k * pio2 + rng.normal(0.0, 1e-6, q),)),
            ("1e-8 .. 1e22, both signs", (_log_uniform(rng, 1e-8, 1e22, q),)),
            ("1e22 .. 1.8e308 (exact reduction)", (_log_uniform(rng, 1e22, 1.7e308, q),))]
    return {
        "sin": trig, "cos": trig,
        "tan": [("|x| < 2", (rng.uniform(-2.0, 2.0, q),)), ("1e-8 .. 1e22", (_log_uniform(rng, 1e-8, 1e22, q),)),
                ("near k pi/2", (k * pio2 + rng.normal(0.0, 1e-3, q),))],
        "exp": [("whole range -745.2 .. 709.8", (rng.uniform(-745.2, 709.78, 2 * q),)),
                ("|x| < 1", (rng.uniform(-1.0, 1.0, q),)),
                ("subnormal results", (rng.uniform(-745.2, -708.4, q),))],
        "exp10": [("whole range -324 .. 308.2", (rng.uniform(-324.0, 308.25, 2 * q),)),
                  ("|x| < 1", (rng.uniform(-1.0, 1.0, 2 * q),))],
        "log": [("4.9e-324 .. 1.8e308", (_log_uniform(rng, 5e-324, 1.7e308, 2 * q, signed=False),)),
                ("0.9 .. 1.1", (rng.uniform(0.9, 1.1, 2 * q),))],
        "log10": [("4.9e-324 .. 1.8e308", (_log_uniform(rng, 5e-324, 1.7e308, 2 * q, signed=False),)),
                  ("0.9 .. 1.1", (rng.uniform(0.9, 1.1, 2 * q),))],
        "atan": [("1e-300 .. 1e300, both signs", (_log_uniform(rng, 1e-300, 1e300, 2 * q),)),
                 ("|x| < 2", (rng.uniform(-2.0, 2.0, 2 * q),))],
        "asin": [("-1 .. 1", (rng.uniform(-1.0, 1.0, 2 * q),)),
                 ("1e-10 .. 1, both signs", (_log_uniform(rng, 1e-10, 1.0, 2 * q),))],
        "acos": [("-1 .. 1", (rng.uniform(-1.0, 1.0, 2 * q),)),
                 ("1e-10 .. 1, both signs", (_log_uniform(rng, 1e-10, 1.0, 2 * q),))],
        "atan2": [("normal(0, 1) pairs", (rng.normal(size=2 * q), rng.normal(size=2 * q))),
                  ("1e-300 .. 1e300 pairs", (_log_uniform(rng, 1e-300, 1e300, 2 * q),
                                             _log_uniform(rng, 1e-300, 1e300, 2 * q)))],
        "pow": _pow_sets(rng, q),
        "tanh": [("|x| < 1 (both branches)", (rng.uniform(-1.0, 1.0, 2 * q),)),
                 ("near the branch point 5/8", (rng.uniform(0.6, 0.65, q) * rng.choice([-1.0, 1.0], q),)),
                 ("1e-300 .. 30, both signs", (_log_uniform(rng, 1e-300, 30.0, 2 * q),))],
        "tanhv": [("|x| < 1", (rng.uniform(-1.0, 1.0, 2 * q),)),
                  ("gate range |x| < 8", (rng.uniform(-8.0, 8.0, q),)),
                  ("1e-300 .. 30, both signs", (_log_uniform(rng, 1e-300, 30.0, q),))],
        "hypot": [("normal(0, 1) pairs", (rng.normal(size=2 * q), rng.normal(size=2 * q))),
                  ("1e-300 .. 1e300 pairs", (_log_uniform(rng, 1e-300, 1e300, 2 * q),
                                             _log_uniform(rng, 1e-300, 1e300, 2 * q)))],
    }


EXACT = {"sin": mpmath.sin, "cos": mpmath.cos, "tan": mpmath.tan, "exp": mpmath.exp,
         "exp10": lambda x: mpf(10) ** x, "log": mpmath.log, "log10": mpmath.log10, "atan": mpmath.atan,
         "asin": mpmath.asin, "acos": mpmath.acos, "atan2": mpmath.atan2,
         "hypot": lambda x, y: mpmath.sqrt(x * x + y * y), "tanh": mpmath.tanh, "pow": mpmath.power,
         "tanhv": mpmath.tanh}


def accuracy(n: int, seed: int, only=None) -> list[tuple[str, float, str, int]]:
    """(function, largest error in ulps, its argument, arguments tested) per function (those of ``only``, if
    given)."""
    rng = np.random.default_rng(seed)
    rows = []
    for name, sets in argument_sets(rng, n).items():
        if only and name not in only:
            continue
        worst, where, count = 0.0, "", 0
        for _, args in sets:
            got = evaluate(name, *args)
            exact = [EXACT[name](*(mpf(float(a[i])) for a in args)) for i in range(len(got))]
            err = _ulp_errors(got, exact)
            i = int(np.argmax(err))
            if err[i] > worst:
                worst, where = float(err[i]), ", ".join(repr(float(a[i])) for a in args)
            count += len(got)
        rows.append((name, worst, where, count))
    return rows


def _random_doubles(rng, n: int) -> np.ndarray:
    return rng.integers(0, 2 ** 64, n, dtype=np.uint64).view(np.float64)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    nan = np.isnan(a) & np.isnan(b)
    return bool(np.all((a.view(np.uint64) == b.view(np.uint64)) | nan))


def exactness(n: int, seed: int) -> list[tuple[str, bool, int]]:
    """(function, bit-identical to the reference, arguments) for the correctly rounded functions."""
    rng = np.random.default_rng(seed)
    x, y, z = _random_doubles(rng, n), _random_doubles(rng, n), _random_doubles(rng, n)
    # fma with cancellation: c close to -a b
    a2, b2 = rng.normal(size=n) * 2.0 ** rng.integers(-60, 60, n), rng.normal(size=n)
    c2 = -a2 * b2 * (1 + rng.normal(size=n) * 2.0 ** -rng.integers(0, 60, n).astype(float))
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    libm.fma.restype, libm.fma.argtypes = ctypes.c_double, [ctypes.c_double] * 3
    m = min(n, 200_000)  # glibc's fma through ctypes: slow, a subset
    rows = []
    with np.errstate(all="ignore"):
        for name, ref in (("sqrt", np.sqrt), ("soft_sqrt", np.sqrt), ("floor", np.floor), ("ceil", np.ceil),
                          ("trunc", np.trunc), ("nearbyint", np.rint), ("fabs", np.abs)):
            rows.append((name, _same(evaluate(name, x), ref(x)), n))
        for name, ref in (("fmod", np.fmod), ("fmin", np.fmin), ("fmax", np.fmax), ("copysign", np.copysign)):
            rows.append((name, _same(evaluate(name, x, y), ref(x, y)), n))
        half = np.abs(x) < 2.0 ** 52
        t = np.trunc(np.abs(x))
        ref_round = np.where(half, np.copysign(t + (np.abs(x) - t >= 0.5), x), x)
        rows.append(("round", _same(evaluate("round", x), ref_round), n))
        for label, (p, q, r) in (("random bits", (x, y, z)), ("cancellation", (a2, b2, c2))):
            hw, sw = evaluate("fma", p, q, r), evaluate("soft_fma", p, q, r)
            ref = np.array([libm.fma(p[i], q[i], r[i]) for i in range(m)])
            rows.append((f"fma ({label})", _same(hw[:m], ref) and _same(sw, hw), n))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=200_000, help="arguments per function")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--only", default=None, help="comma-separated functions (default: all; no exactness table)")
    args = parser.parse_args()
    t0 = time.perf_counter()
    only = args.only.split(",") if args.only else None
    print(f"{'function':10s} {'max ulp':>8s}  {'arguments':>10s}  worst at")
    for name, worst, where, count in accuracy(args.n, args.seed, only):
        print(f"{name:10s} {worst:8.3f}  {count:10d}  {where}", flush=True)
    if only:
        return
    print(f"\n{'function':24s} {'exact':>6s}  {'arguments':>10s}")
    for name, same, count in exactness(args.n, args.seed):
        print(f"{name:24s} {str(same):>6s}  {count:10d}")
    print(f"\n({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
