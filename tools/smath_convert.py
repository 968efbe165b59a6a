"""Convert C files of the core or the native FMUs from <math.h> calls to the core's smath.

    python3 tools/smath_convert.py FILE.c|FILE.h ...    # rewrite in place, print what changed
    python3 tools/smath_convert.py --check FILE ...     # exit 1 if a file still calls <math.h>

In code (not comments or strings): ``sin(`` -> ``sm_sin(`` for every function smath provides,
``pow(10.0, x)`` -> ``sm_exp10(x)``; ``#include <math.h>`` -> ``#include "smath.h"``, and in a .c
file ``#include "smath.h"`` moved to be its first include (it fixes the file's floating-point contract).
A call smath does not provide (another pow, sinh, ...) is reported and left for a person to rewrite.
The same scan is what ``tests/test_portable_math.py`` runs over the sources.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

# <math.h> function -> smath function
PROVIDED = {name: f"sm_{name}" for name in (
    "sqrt", "fma", "fabs", "copysign", "fmin", "fmax", "floor", "ceil", "trunc", "round", "nearbyint", "fmod",
    "sin", "cos", "sincos", "tan", "exp", "exp10", "log", "log10", "atan", "atan2", "asin", "acos", "hypot",
    "tanh", "pow")}
# every other <math.h> (C11 + common extensions) function: not allowed, no automatic rewrite
OTHERS = ("acosh", "asinh", "atanh", "cbrt", "cosh", "erf", "erfc", "exp2", "expm1", "fdim", "frexp", "ilogb",
          "ldexp", "lgamma", "llrint", "llround", "log1p", "log2", "logb", "lrint", "lround", "modf", "nan",
          "nextafter", "nexttoward", "remainder", "remquo", "rint", "scalbln", "scalbn", "sinh",
          "tgamma", "exp10", "pow10")
ALL = sorted(set(PROVIDED) | set(OTHERS))
CALL = re.compile(r"(?<![\w.>])(" + "|".join(ALL) + r")([fl]?)\s*\(")
POW10 = re.compile(r"(?<![\w.>])pow\s*\(\s*10(?:\.0*)?\s*,\s*")
INCLUDE_MATH = re.compile(r'^[ \t]*#[ \t]*include[ \t]*<math\.h>[^\n]*\n', re.M)
INCLUDE_SMATH = re.compile(r'^[ \t]*#[ \t]*include[ \t]*"smath\.h"[^\n]*\n', re.M)
FIRST_INCLUDE = re.compile(r'^[ \t]*#[ \t]*include\b', re.M)


def code_spans(text: str) -> list[tuple[int, int]]:
    """(start, end) of the parts of C source text outside comments, string and character literals."""
    spans, i, start, n = [], 0, 0, len(text)
    while i < n:
        two = text[i:i + 2]
        if two in ("/*", "//") or text[i] in "\"'":
            spans.append((start, i))
            if two == "/*":
                j = text.find("*/", i + 2)
                i = n if j < 0 else j + 2
            elif two == "//":
                j = text.find("\n", i)
                i = n if j < 0 else j
            else:
                quote, i = text[i], i + 1
                while i < n and text[i] != quote:
                    i += 2 if text[i] == "\\" else 1
                i += 1
            start = i
        else:
            i += 1
    spans.append((start, n))
    return spans


def math_calls(text: str) -> list[tuple[int, str]]:
    """(line, name) of every <math.h> function called in the code of ``text``."""
    found = []
    for a, b in code_spans(text):
        for m in CALL.finditer(text, a, b):
            if m.end() <= b:
                found.append((text.count("\n", 0, m.start()) + 1, m.group(1) + m.group(2)))
    return found


def convert(text: str, is_c_file: bool) -> tuple[str, list[str]]:
    """The converted text and the calls left (names smath does not provide)."""
    out, last = [], 0
    for a, b in code_spans(text):
        out.append(text[last:a])
        code = POW10.sub("sm_exp10(", text[a:b])
        code = CALL.sub(lambda m: PROVIDED[m.group(1)] + "(" if m.group(2) == "" and m.group(1) in PROVIDED
                        else m.group(0), code)
        out.append(code)
        last = b
    text = "".join(out) + text[last:]
    had_math = bool(INCLUDE_MATH.search(text))
    text = INCLUDE_MATH.sub("", text)
    uses = "sm_" in text or had_math
    if is_c_file or (had_math and not INCLUDE_SMATH.search(text)):
        text = INCLUDE_SMATH.sub("", text)
        if is_c_file or uses:
            first = FIRST_INCLUDE.search(text)
            line = '#include "smath.h"\n'
            if first is None:
                text = line + text
            else:
                blank = "\n" if is_c_file else ""
                text = text[:first.start()] + line + blank + text[first.start():]
    left = [name for _, name in math_calls(text)]
    return text, left


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+", type=Path)
    parser.add_argument("--check", action="store_true", help="report <math.h> calls, change nothing")
    args = parser.parse_args()
    status = 0
    for path in args.files:
        text = path.read_text()
        if args.check:
            for line, name in math_calls(text):
                print(f"{path}:{line}: {name}() from <math.h>: use smath.h")
                status = 1
            continue
        new, left = convert(text, path.suffix == ".c")
        if new != text:
            path.write_text(new)
            print(f"converted {path}")
        for name in left:
            print(f"{path}: {name}() has no smath equivalent: rewrite it by hand", file=sys.stderr)
            status = 1
    return status


if __name__ == "__main__":
    raise SystemExit(main())
