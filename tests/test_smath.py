"""The core's portable math (sarins_fmu/core/smath.h) through the Python binding.

Accuracy against mpmath (120 bits) on random arguments over each function's range: the largest error stays
below the bound stated per function (``BOUND``, ulps of the exact value; the measured figures over 200 000
arguments a function are in docs/native-layer.md, from benchmarks/smath_accuracy.py).  The correctly
rounded functions bit for bit against numpy and glibc on random bit patterns (every class of double: zeros,
subnormals, normals, infinities, NaNs), the software sqrt and fma against the hardware ones, sm_sincos4
against sm_sincos, and the special values of C's Annex F.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu.core.smath import evaluate

mpmath = pytest.importorskip("mpmath")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from smath_accuracy import EXACT, _ulp_errors, argument_sets  # noqa: E402

# largest error in ulps allowed per function: the measured maximum (docs/native-layer.md) plus a margin
BOUND = {"sin": 0.6, "cos": 0.6, "tan": 0.65, "exp": 0.52, "exp10": 0.52, "log": 0.51, "log10": 0.51,
         "atan": 0.51, "asin": 0.65, "acos": 0.7, "atan2": 0.51, "hypot": 0.51, "tanh": 0.55, "pow": 0.55,
         "tanhv": 3.0}  # sm_tanh_lanes, the recurrent gates' tanh: "below 3 ulp" (smath.h); measured 2.2


def _bits(x: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float64).view(np.uint64)


def _same(a, b) -> bool:
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return bool(np.all((_bits(a) == _bits(b)) | (np.isnan(a) & np.isnan(b))))


def _accuracy(name: str, n: int, seed: int) -> tuple[float, str]:
    worst, where = 0.0, ""
    for _, args in argument_sets(np.random.default_rng(seed), n)[name]:
        got = evaluate(name, *args)
        exact = [EXACT[name](*(mpmath.mpf(float(a[i])) for a in args)) for i in range(len(got))]
        err = _ulp_errors(got, exact)
        i = int(np.argmax(err))
        if err[i] > worst:
            worst, where = float(err[i]), ", ".join(repr(float(a[i])) for a in args)
    return worst, where


@pytest.mark.parametrize("name", list(BOUND))
def test_accuracy_against_mpmath(name):
    worst, where = _accuracy(name, 400, seed=11)
    assert worst < BOUND[name], f"{name}: {worst:.3f} ulp at {where}"


@pytest.mark.slow
@pytest.mark.parametrize("name", list(BOUND))
def test_accuracy_against_mpmath_on_many_arguments(name):
    worst, where = _accuracy(name, 10_000, seed=12)
    assert worst < BOUND[name], f"{name}: {worst:.3f} ulp at {where}"


def _random_doubles(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 2 ** 64, n, dtype=np.uint64).view(np.float64)


SPECIALS = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, -5e-324, 2.2250738585072014e-308,
                     1.7976931348623157e308, -1.7976931348623157e308, 1.0, -1.0, 0.5, -0.5, 1.5, 2.5, -2.5,
                     0.49999999999999994, 4503599627370495.5, 4503599627370496.0, 9007199254740993.0])


def test_correctly_rounded_functions_are_bit_identical_to_numpy():
    x = np.concatenate([_random_doubles(100_000, 1), SPECIALS])
    y = np.concatenate([_random_doubles(100_000, 2), SPECIALS[::-1]])
    with np.errstate(all="ignore"):
        for name, ref in (("sqrt", np.sqrt), ("soft_sqrt", np.sqrt), ("floor", np.floor), ("ceil", np.ceil),
                          ("trunc", np.trunc), ("nearbyint", np.rint), ("fabs", np.abs)):
            assert _same(evaluate(name, x), ref(x)), name
        for name, ref in (("fmod", np.fmod), ("fmin", np.fmin), ("fmax", np.fmax), ("copysign", np.copysign)):
            assert _same(evaluate(name, x, y), ref(x, y)), name
        t = np.trunc(np.abs(x))
        away = np.where(np.abs(x) < 2.0 ** 52, np.copysign(t + (np.abs(x) - t >= 0.5), x), x)
        assert _same(evaluate("round", x), away)


def test_fma_is_correctly_rounded_in_hardware_and_software():
    rng = np.random.default_rng(3)
    n = 20_000
    a, b = rng.normal(size=n) * 2.0 ** rng.integers(-60, 60, n), rng.normal(size=n)
    c = -a * b * (1 + rng.normal(size=n) * 2.0 ** -rng.integers(0, 60, n).astype(float))  # cancellation
    x, y, z = _random_doubles(n, 4), _random_doubles(n, 5), _random_doubles(n, 6)
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    libm.fma.restype, libm.fma.argtypes = ctypes.c_double, [ctypes.c_double] * 3
    for p, q, r in ((a, b, c), (x, y, z)):
        hw, sw = evaluate("fma", p, q, r), evaluate("soft_fma", p, q, r)
        assert _same(hw, sw)
        assert _same(hw, [libm.fma(p[i], q[i], r[i]) for i in range(n)])


def test_sincos_and_sincos4_give_the_bits_of_sin_and_cos():
    rng = np.random.default_rng(7)
    x = np.concatenate([rng.uniform(-1e3, 1e3, 20_000), rng.uniform(-1, 1, 4_000),
                        np.exp(rng.uniform(-80, 700, 4_000)) * rng.choice([-1, 1], 4_000), SPECIALS,
                        [math.pi / 4, -math.pi / 4, math.nextafter(math.pi / 4, 1), 2.0 ** 26, 2.0 ** 26 - 1,
                         math.pi / 2, math.pi, 1e-8, 6381956970095103 * 2.0 ** 797]])
    both = evaluate("sincos", x)
    assert _same(both[0], evaluate("sin", x)) and _same(both[1], evaluate("cos", x))
    assert _same(evaluate("sincos4", x), both)


def test_tanh_lanes_give_the_same_bits_in_every_lane_and_alone():
    """sm_tanh_lanes: a value's bits do not depend on where it falls (a SIMD lane of a group of four, or the
    scalar rest), nor on the array it is in; and it agrees with sm_tanh within the two functions' bounds."""
    rng = np.random.default_rng(8)
    x = np.concatenate([rng.uniform(-8, 8, 4_001), rng.normal(0, 0.3, 2_000), SPECIALS, -SPECIALS,
                        np.exp(rng.uniform(-700, 4, 2_000)) * rng.choice([-1, 1], 2_000),
                        [0.17328679513998632, 0.1732867951399863, 22.0, -22.0, 21.999999999999996, 2.0 ** -28,
                         -(2.0 ** -28), math.nextafter(2.0 ** -28, 0)]])
    whole = evaluate("tanhv", x)
    alone = np.array([evaluate("tanhv", x[i:i + 1])[0] for i in range(len(x))])
    shifted = evaluate("tanhv", np.concatenate([[0.5, 0.25], x]))[2:]
    assert _same(whole, alone) and _same(whole, shifted)
    finite = np.isfinite(x)
    ref = evaluate("tanh", x)
    assert np.all(np.abs(whole[finite] - ref[finite]) <= (BOUND["tanhv"] + BOUND["tanh"]) * np.spacing(np.abs(ref[finite])))
    assert np.all(np.abs(whole[~np.isnan(x)]) <= 1.0)


def _exp_lane_arguments(seed: int) -> np.ndarray:
    """sm_exp_lanes' test arguments: the GRNN weights' range, every class of double, and the edges of sm_exp's
    ordinary case (|x| = 2^-60, 708) and of its result (overflow, subnormal, zero)."""
    rng = np.random.default_rng(seed)
    edges = [2.0 ** -60, 708.0, 709.782712893384, 709.7827128933841, 745.1332191019411, 745.1332191019412, 745.0,
             746.0, 20.7, 20.723265836946411, 708.3964185322641, 1e-300, 0.0]
    edges = np.array(edges + [math.nextafter(v, d) for v in edges for d in (0.0, math.inf)])
    return np.concatenate([rng.uniform(-25.0, 0.0, 40_001), rng.uniform(-760.0, 760.0, 20_000),
                           np.exp(rng.uniform(-60.0, 6.6, 20_000)) * rng.choice([-1, 1], 20_000),
                           rng.uniform(-1e-17, 1e-17, 2_000), _random_doubles(20_000, 13), SPECIALS, -SPECIALS,
                           edges, -edges])


def test_exp_lanes_give_the_bits_of_exp():
    """sm_exp_lanes (the truncated GRNN's weights): sm_exp's bits on every argument, wherever it falls (a SIMD
    lane of a group of four, or the scalar rest; in place too)."""
    x = _exp_lane_arguments(10)
    ref = evaluate("exp", x)
    assert _same(evaluate("expv", x), ref)
    assert _same(evaluate("expv", np.concatenate([[-0.5, 1e-30, 710.0], x]))[3:], ref)
    for start in range(4):  # each value in each lane, next to ordinary and special values
        for fill in (-1.0, np.nan):
            y = np.full(4 * 64, fill)
            y[start::4] = x[:64]
            assert _same(evaluate("expv", y)[start::4], ref[:64])
    assert _same(np.array([evaluate("expv", x[i:i + 1])[0] for i in range(0, len(x), 97)]), ref[::97])


def test_special_values_follow_annex_f():
    inf, nan = math.inf, math.nan

    def one(name, *args):
        return float(evaluate(name, *[[a] for a in args])[0])

    def same(a, b):
        return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a) == math.copysign(1, b))

    cases = [("sin", (-0.0,), -0.0), ("sin", (inf,), nan), ("cos", (nan,), nan), ("cos", (0.0,), 1.0),
             ("tan", (-0.0,), -0.0), ("exp", (-inf,), 0.0), ("exp", (inf,), inf), ("exp", (-0.0,), 1.0),
             ("exp", (710.0,), inf), ("exp", (-746.0,), 0.0), ("exp", (-745.0,), 5e-324), ("exp10", (3.0,), 1000.0),
             ("exp10", (-2.0,), 0.01), ("log", (1.0,), 0.0), ("log", (0.0,), -inf), ("log", (-0.0,), -inf),
             ("log", (-1.0,), nan), ("log", (inf,), inf), ("log10", (1000.0,), 3.0), ("log10", (1e-5,), -5.0),
             ("atan", (-inf,), -math.pi / 2), ("atan", (-0.0,), -0.0), ("atan2", (0.0, -0.0), math.pi),
             ("atan2", (-0.0, -0.0), -math.pi), ("atan2", (-0.0, 0.0), -0.0), ("atan2", (inf, -inf), 3 * math.pi / 4),
             ("atan2", (-inf, inf), -math.pi / 4), ("atan2", (1.0, 0.0), math.pi / 2), ("atan2", (1.0, -inf), math.pi),
             ("asin", (1.0,), math.pi / 2), ("asin", (-0.0,), -0.0), ("asin", (1.5,), nan), ("acos", (1.0,), 0.0),
             ("acos", (-1.0,), math.pi), ("acos", (0.0,), math.pi / 2), ("hypot", (inf, nan), inf),
             ("hypot", (nan, 1.0), nan), ("hypot", (3.0, 4.0), 5.0), ("hypot", (-0.0, 0.0), 0.0),
             ("hypot", (1e308, 1e308), 1.4142135623730951e308), ("hypot", (3e-320, 4e-320), 5e-320),
             ("sqrt", (-0.0,), -0.0), ("sqrt", (-1.0,), nan), ("fmod", (5.5, inf), 5.5), ("fmod", (inf, 1.0), nan),
             ("fmod", (-0.0, 1.0), -0.0), ("fma", (2.0, 3.0, -6.0), 0.0), ("fma", (1e308, 10.0, -inf), -inf),
             ("tanh", (-0.0,), -0.0), ("tanh", (inf,), 1.0), ("tanh", (-inf,), -1.0), ("tanh", (nan,), nan),
             ("tanh", (30.0,), 1.0), ("tanh", (5e-324,), 5e-324),
             ("tanhv", (-0.0,), -0.0), ("tanhv", (0.0,), 0.0), ("tanhv", (inf,), 1.0), ("tanhv", (-inf,), -1.0),
             ("tanhv", (nan,), nan), ("tanhv", (30.0,), 1.0), ("tanhv", (-22.0,), -1.0), ("tanhv", (5e-324,), 5e-324),
             ("tanhv", (1e-20,), 1e-20),
             ("expv", (-0.0,), 1.0), ("expv", (-inf,), 0.0), ("expv", (inf,), inf), ("expv", (nan,), nan),
             ("expv", (710.0,), inf), ("expv", (-746.0,), 0.0), ("expv", (-745.0,), 5e-324), ("expv", (0.0,), 1.0),
             ("pow", (nan, 0.0), 1.0), ("pow", (1.0, nan), 1.0), ("pow", (nan, 1.0), nan), ("pow", (-0.0, -3.0), -inf),
             ("pow", (0.0, -2.0), inf), ("pow", (-0.0, 3.0), -0.0), ("pow", (-0.0, 2.0), 0.0), ("pow", (-1.0, inf), 1.0),
             ("pow", (0.5, -inf), inf), ("pow", (2.0, -inf), 0.0), ("pow", (0.5, inf), 0.0), ("pow", (2.0, inf), inf),
             ("pow", (-inf, -3.0), -0.0), ("pow", (-inf, -2.0), 0.0), ("pow", (-inf, 3.0), -inf), ("pow", (-inf, 2.5), inf),
             ("pow", (inf, -1.0), 0.0), ("pow", (-2.0, 0.5), nan), ("pow", (-2.0, 3.0), -8.0), ("pow", (2.0, 10.0), 1024.0),
             ("pow", (10.0, 400.0), inf), ("pow", (10.0, -400.0), 0.0), ("pow", (2.0, -1074.0), 5e-324),
             ("pow", (-2.0, 1e300), inf),
             # |y| near DBL_MAX: the product's error term overflows (libFuzzer found NaN reaching exp's core)
             ("pow", (0.5, 1.7e308), 0.0), ("pow", (0.5, -1.7e308), inf), ("pow", (1.0000001, 1.7e308), inf),
             ("pow", (0.9999999999999999, -1.7e308), inf), ("pow", (-0.5, 1.7e308), 0.0)]
    for name, args, expected in cases:
        got = one(name, *args)
        assert same(got, expected), (name, args, got, expected)


TANHV_DRIVER = r"""
#include "smath.h"
#include <stdio.h>
#include <stdlib.h>
int main(int argc, char **argv)
{
    FILE *f = fopen(argv[1], "rb");
    if (f == NULL) return 2;
    static double x[1 << 18], y[1 << 18];
    size_t n = fread(x, sizeof x[0], sizeof x / sizeof x[0], f);
    fclose(f);
    if (argc > 3)
        sm_exp_lanes((int64_t)n, x, y);
    else
        sm_tanh_lanes((int64_t)n, x, y);
    f = fopen(argv[2], "wb");
    if (f == NULL || fwrite(y, sizeof y[0], n, f) != n) return 3;
    return fclose(f) != 0;
}
"""


@pytest.mark.parametrize("line", [("gcc", "-O0"), ("gcc", "-O3", "-march=native"), ("clang", "-O2"),
                                  ("clang", "-O3", "-march=native")])
def test_tanh_lanes_give_the_libraries_bits_on_other_compile_lines(line, tmp_path):
    """sm_tanh_lanes and sm_exp_lanes compiled by another compiler / optimisation level / instruction set (-march=native: wider
    vectors, FMA available but not contracted) gives the bits of the library's build."""
    import shutil
    import subprocess

    if shutil.which(line[0]) is None:
        pytest.skip(f"{line[0]} not installed")
    core = Path(__file__).resolve().parent.parent / "sarins_fmu" / "core"
    (tmp_path / "driver.c").write_text(TANHV_DRIVER)
    exe = tmp_path / "driver"
    cmd = [*line, "-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{core}", str(tmp_path / "driver.c"),
           str(core / "smath.c"), "-o", str(exe)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    rng = np.random.default_rng(9)
    x = np.concatenate([rng.uniform(-10, 10, 30_001), np.exp(rng.uniform(-700, 4, 10_000)) * rng.choice([-1, 1], 10_000),
                        SPECIALS, -SPECIALS])
    x.tofile(tmp_path / "x.bin")
    subprocess.run([str(exe), str(tmp_path / "x.bin"), str(tmp_path / "y.bin")], check=True, timeout=60)
    assert _same(np.fromfile(tmp_path / "y.bin"), evaluate("tanhv", x))
    x = _exp_lane_arguments(14)
    x.tofile(tmp_path / "x.bin")
    subprocess.run([str(exe), str(tmp_path / "x.bin"), str(tmp_path / "y.bin"), "exp"], check=True, timeout=60)
    assert _same(np.fromfile(tmp_path / "y.bin"), evaluate("exp", x))
