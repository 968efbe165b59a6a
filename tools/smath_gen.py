"""Generate ``sarins_fmu/core/smath_tables.h``: the constants of the core's portable math (smath.c).

Every number in that header comes from here, computed with mpmath at 200 bits and rounded once to
binary64: split constants (pi/2, ln 2 / 64, ln 10, ...), the tables (2^(j/64), log(1/c_j), atan(j/64)),
the bits of 2/pi for the large-argument reduction of sin/cos, and the polynomial coefficients, each a
Chebyshev fit (:func:`mpmath.chebyfit`, near-minimax) of the function's remainder after its leading
terms on the interval the C code evaluates it on.  The fit errors are printed; the accuracy of the
functions as a whole is measured by ``benchmarks/smath_accuracy.py``.

    python3 tools/smath_gen.py            # rewrite the header
    python3 tools/smath_gen.py --check    # exit 1 if the header differs from what this script writes
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mpmath
from mpmath import mp, mpf

mp.prec = 200
OUT = Path(__file__).resolve().parent.parent / "sarins_fmu" / "core" / "smath_tables.h"

EXP_N = 64  # exp: table of 2^(j/64)
LOG_N = 128  # log: cells of the mantissa [1, 2) by its top 7 bits
LOG_INV_BITS = 9  # log: significant bits of each cell's reciprocal c_j (so that m c_j is exact, see smath.c)
ATAN_N = 64  # atan: table of atan(j/64), j = 0 .. 64
ATAN_DIRECT = mpf(1) / 16  # atan: below this ratio the polynomial alone
TANH_POLY_MAX = mpf(1) / 16  # tanh: below this |x| the polynomial, above 1 - 2 / (exp(2|x|) + 1)


def d(x) -> float:
    """x rounded to the nearest binary64."""
    return float(mpf(x))


def c_double(x: float) -> str:
    return float.hex(float(x))


def split(x, bits: int) -> tuple[float, float]:
    """(hi, lo): hi = x rounded to ``bits`` significant bits, lo = the rest rounded to binary64."""
    x = mpf(x)
    if x == 0:
        return 0.0, 0.0
    e = int(mpmath.floor(mpmath.log(abs(x), 2)))
    q = mpf(2) ** (e - bits + 1)
    hi = mpmath.nint(x / q) * q
    return float(hi), d(x - hi)


def split_fixed(x, quantum) -> tuple[float, float]:
    """(hi, lo): hi = x rounded to a multiple of ``quantum`` (a power of two), lo = the rest."""
    x = mpf(x)
    hi = mpmath.nint(x / quantum) * quantum
    return float(hi), d(x - hi)


def dd(x) -> tuple[float, float]:
    """x as a double-double (hi = nearest binary64, lo = the rest)."""
    hi = d(x)
    return hi, d(mpf(x) - mpf(hi))


def fit(f, a, b, degree: int, name: str) -> list[float]:
    """Coefficients c_0 .. c_degree of the Chebyshev fit of f on [a, b] (f(t) ~ sum c_i t^i), printed with
    the fit's largest absolute error.  f is evaluated at 800 bits (its cancellations near 0)."""

    def precise(t):
        with mpmath.workprec(800):
            return f(t)

    coeffs, err = mpmath.chebyfit(precise, [mpf(a), mpf(b)], degree + 1, error=True)
    print(f"  {name}: degree {degree} on [{float(a):.6g}, {float(b):.6g}], fit error {float(err):.3g}",
          file=sys.stderr)
    return [d(c) for c in reversed(coeffs)]


def sin_tail(z):
    """(sin r - r + r^3/6) / r^5 with z = r^2."""
    r = mpmath.sqrt(z)
    return (mpmath.sin(r) - r + r ** 3 / 6) / r ** 5


def cos_tail(z):
    """(cos r - 1 + r^2/2) / r^4 with z = r^2."""
    r = mpmath.sqrt(z)
    return (mpmath.cos(r) - 1 + r ** 2 / 2) / r ** 4


def exp_tail(r):
    """(exp r - 1 - r - r^2/2) / r^3."""
    if r == 0:
        return mpf(1) / 6
    return (mpmath.exp(r) - 1 - r - r ** 2 / 2) / r ** 3


def log_tail(r):
    """(log(1 + r) - r + r^2/2) / r^3."""
    if r == 0:
        return mpf(1) / 3
    return (mpmath.log1p(r) - r + r ** 2 / 2) / r ** 3


def atan_tail(z):
    """(atan u - u) / u^3 with z = u^2."""
    u = mpmath.sqrt(z)
    return (mpmath.atan(u) - u) / u ** 3


def asin_tail(z):
    """(asin x - x) / x^3 with z = x^2."""
    x = mpmath.sqrt(z)
    return (mpmath.asin(x) - x) / x ** 3


def tanh_tail(z):
    """(tanh x - x) / x^3 with z = x^2."""
    x = mpmath.sqrt(z)
    return (mpmath.tanh(x) - x) / x ** 3


def log_cells():
    """Per cell j of [1, 2) (m in [1 + j/128, 1 + (j + 1)/128)): c_j with LOG_INV_BITS bits ~ 1 / centre
    (1 in the first cell, 1/2 in the last, so that log x near 1 and near 2^k cancels exactly), and
    -log(c_j) split as a multiple of 2^-42 plus the rest; the largest |m c_j - 1| over the cells."""
    cells, rmax = [], mpf(0)
    for j in range(LOG_N):
        lo, hi = 1 + mpf(j) / LOG_N, 1 + mpf(j + 1) / LOG_N
        if j == 0:
            c = mpf(1)
        elif j == LOG_N - 1:
            c = mpf(1) / 2
        else:
            c = mpmath.nint(2 / (lo + hi) * 2 ** LOG_INV_BITS) / 2 ** LOG_INV_BITS
        rmax = max(rmax, abs(lo * c - 1), abs(hi * c - 1))
        cells.append((float(c), *split_fixed(-mpmath.log(c), mpf(2) ** -42)))
    return cells, rmax


def two_over_pi_words(n: int) -> list[int]:
    """The first 32 n bits of the fraction of 2/pi as n 32-bit words, most significant first."""
    with mpmath.workprec(32 * n + 64):
        x = 2 / mpmath.pi
        return [int(mpmath.floor(x * mpf(2) ** (32 * (i + 1)))) % (1 << 32) for i in range(n)]


def header() -> str:
    lines = ["/* Constants of smath.c: generated by tools/smath_gen.py (mpmath, 200 bits).  Do not edit. */",
             "#ifndef SARINS_SMATH_TABLES_H", "#define SARINS_SMATH_TABLES_H", "", "#include <stdint.h>", ""]

    def const(name, value, comment=""):
        lines.append(f"#define {name} {c_double(value)}{'  /* ' + comment + ' */' if comment else ''}")

    def array(name, values, comment):
        lines.append(f"/* {comment} */")
        lines.append(f"static const double {name}[{len(values)}] = {{")
        for i in range(0, len(values), 4):
            lines.append("    " + ", ".join(c_double(v) for v in values[i:i + 4]) + ",")
        lines.append("};")

    pi = mpmath.pi
    # sin / cos: pi/2 in three 27-bit parts (k p_i exact for |k| < 2^26) and a 53-bit tail
    p1, rest = split(pi / 2, 27)
    p2, rest = split(pi / 2 - mpf(p1), 27)
    p3, _ = split(pi / 2 - mpf(p1) - mpf(p2), 27)
    p4 = d(pi / 2 - mpf(p1) - mpf(p2) - mpf(p3))
    for name, v in (("SM_PIO2_1", p1), ("SM_PIO2_2", p2), ("SM_PIO2_3", p3), ("SM_PIO2_4", p4)):
        const(name, v, "pi/2 = sum of the four parts")
    const("SM_INV_PIO2", d(2 / pi), "2/pi")
    h, lo = dd(pi / 2)
    const("SM_PIO2_HI", h, "pi/2 as a double-double")
    const("SM_PIO2_LO", lo)
    h, lo = dd(pi)
    const("SM_PI_HI", h, "pi as a double-double")
    const("SM_PI_LO", lo)
    h, lo = dd(mpf(1) / 6)
    const("SM_SIXTH_HI", h, "1/6 as a double-double")
    const("SM_SIXTH_LO", lo)
    z_max = (pi / 4) ** 2 * (1 + mpf(2) ** -20)
    array("SM_SIN_TAIL", fit(sin_tail, mpf(2) ** -80, z_max, 5, "sin"),
          "sin r = r - r^3/6 + r^5 P(r^2), |r| <= pi/4: P's coefficients c_0 .. c_5")
    array("SM_COS_TAIL", fit(cos_tail, mpf(2) ** -80, z_max, 5, "cos"),
          "cos r = 1 - r^2/2 + r^4 P(r^2), |r| <= pi/4: P's coefficients c_0 .. c_5")
    words = two_over_pi_words(40)
    lines.append("/* the fraction of 2/pi, 32 bits a word, most significant first */")
    lines.append(f"static const uint32_t SM_TWO_OVER_PI[{len(words)}] = {{")
    for i in range(0, len(words), 6):
        lines.append("    " + ", ".join(f"0x{w:08x}u" for w in words[i:i + 6]) + ",")
    lines.append("};")

    # exp: x = (64 m + j) ln2/64 + r
    ln2 = mpmath.log(2)
    l1, _ = split(ln2 / EXP_N, 36)  # n l1 exact for |n| < 2^17
    const("SM_EXP_N", float(EXP_N), "table size of exp")
    const("SM_EXP_INV_L", d(EXP_N / ln2), "64 / ln 2")
    const("SM_EXP_L1", l1, "ln2/64 = L1 + L2, L1 with 36 bits")
    const("SM_EXP_L2", d(ln2 / EXP_N - mpf(l1)))
    tab = []
    for j in range(EXP_N):
        tab.extend(dd(mpf(2) ** (mpf(j) / EXP_N)))
    array("SM_EXP_TAB", tab, "2^(j/64) as double-doubles (hi, lo), j = 0 .. 63")
    r_max = ln2 / EXP_N / 2 * (1 + mpf(2) ** -10)
    array("SM_EXP_TAIL", fit(exp_tail, -r_max, r_max, 3, "exp"),
          "exp r = 1 + r + r^2/2 + r^3 P(r), |r| <= ln2/128: P's coefficients c_0 .. c_3")
    h, lo = dd(mpmath.log(10))
    const("SM_LN10_HI", h, "ln 10 as a double-double")
    const("SM_LN10_LO", lo)

    # log: x = 2^k m, m in [1, 2); log x = k ln2 - log c_j + log(1 + r), r = m c_j - 1
    cells, rmax = log_cells()
    l2h, l2l = split(ln2, 42)
    const("SM_LN2_HI", l2h, "ln 2 = HI + LO, HI with 42 bits (k HI exact for |k| < 2^11)")
    const("SM_LN2_LO", l2l)
    array("SM_LOG_TAB", [v for cell in cells for v in cell],
          "per cell j of [1, 2): c_j (9 bits), -log c_j = hi (a multiple of 2^-42) + lo")
    array("SM_LOG_TAIL", fit(log_tail, -rmax * (1 + mpf(2) ** -10), rmax * (1 + mpf(2) ** -10), 5, "log"),
          f"log(1 + r) = r - r^2/2 + r^3 P(r), |r| <= {float(rmax):.6g}: P's coefficients c_0 .. c_5")
    h, lo = dd(1 / mpmath.log(10))
    const("SM_INV_LN10_HI", h, "1 / ln 10 as a double-double")
    const("SM_INV_LN10_LO", lo)

    # atan: q = c_j + ..., c_j = j/64; atan q = atan c_j + atan u, |u| <= 1/128
    tab = []
    for j in range(ATAN_N + 1):
        tab.extend(dd(mpmath.atan(mpf(j) / ATAN_N)))
    array("SM_ATAN_TAB", tab, "atan(j/64) as double-doubles (hi, lo), j = 0 .. 64")
    u_max = (mpf(1) / (2 * ATAN_N)) ** 2 * (1 + mpf(2) ** -10)
    array("SM_ATAN_TAIL", fit(atan_tail, mpf(2) ** -80, u_max, 3, "atan, reduced"),
          "atan u = u + u^3 P(u^2), |u| <= 1/128: P's coefficients c_0 .. c_3")
    q_max = (ATAN_DIRECT + mpf(1) / (2 * ATAN_N)) ** 2
    array("SM_ATAN_DIRECT", fit(atan_tail, mpf(2) ** -80, q_max, 7, "atan, direct"),
          "atan q = q + q^3 P(q^2), 0 <= q < 1/16 + 1/128: P's coefficients c_0 .. c_7")

    # asin: x + x^3 P(x^2) on [0, 1/2]
    array("SM_ASIN_TAIL", fit(asin_tail, mpf(2) ** -80, mpf(1) / 4 * (1 + mpf(2) ** -20), 13, "asin"),
          "asin x = x + x^3 P(x^2), |x| <= 1/2: P's coefficients c_0 .. c_13")

    # tanh: x + x^3 P(x^2) on [0, 5/8]
    const("SM_TANH_POLY_MAX", d(TANH_POLY_MAX), "tanh: the polynomial below this |x|")
    array("SM_TANH_TAIL", fit(tanh_tail, mpf(2) ** -80, TANH_POLY_MAX ** 2 * (1 + mpf(2) ** -20), 5, "tanh"),
          "tanh x = x + x^3 P(x^2), |x| <= 1/16: P's coefficients c_0 .. c_5")
    lines += ["", "#endif", ""]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the header instead of writing it")
    args = parser.parse_args()
    text = header()
    if args.check:
        same = OUT.is_file() and OUT.read_text() == text
        print(f"{OUT}: {'up to date' if same else 'differs from tools/smath_gen.py'}")
        return 0 if same else 1
    OUT.write_text(text)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
