"""The core's text-log block parser: bit-identical to Python's float(), and the blocks it must leave to numpy."""

import ctypes
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fmus.cbuild import build_line

from sarins_fmu.core.log_parse import parse_block
from sarins_fmu.imu_log_text import Block, TextError, check_lines


def _random_fields(rng, n):
    out = []
    for _ in range(n):
        kind = rng.integers(6)
        mant = str(int(rng.integers(0, 10 ** int(rng.integers(1, 19)))))
        sign = ["", "-", "+"][int(rng.integers(3))]
        if kind == 0:
            out.append(sign + mant)
        elif kind == 1:
            cut = int(rng.integers(0, len(mant) + 1))
            out.append(sign + mant[:cut] + "." + mant[cut:])
        elif kind == 2:
            out.append(f"{sign}{mant}e{int(rng.integers(-30, 30))}")
        elif kind == 3:
            out.append(f"{sign}{mant[:1]}.{mant[1:]}E{['', '+', '-'][int(rng.integers(3))]}{int(rng.integers(0, 25))}")
        elif kind == 4:
            out.append(repr(float(rng.standard_normal() * 10.0 ** int(rng.integers(-8, 8)))))
        else:
            out.append(f"{rng.standard_normal() * 10.0 ** int(rng.integers(-6, 6)):.{int(rng.integers(0, 16))}f}")
    return out


def test_random_fields_bit_identical_to_float_or_left_to_numpy():
    rng = np.random.default_rng(5)
    taken = 0
    for field in _random_fields(rng, 60_000):
        got = parse_block(f" {field}\t,1\n".encode(), 2, False, 4096)
        want = float(field)
        if got is None:
            continue
        taken += 1
        assert got.shape == (1, 2)
        assert got[0, 0].tobytes() == np.float64(want).tobytes(), field
    assert taken > 30_000  # most plain decimals are taken by the core


@pytest.mark.parametrize("field", ["0", "-0", "+0.0", "0e999", "1e22", "999999999999999", "123456789012345",
                                  "1.5e-21", "5.", ".5", "-.5e+3", "0.000000000000001", "4.35", "0.1", "2.675",
                                  "1e-5", "000123.4500", "1234567890123456", "1e23", "1e-23"])
def test_edge_fields(field):
    got = parse_block(f"{field},2\n".encode(), 2, False, 4096)
    assert got is not None
    assert got[0, 0].tobytes() == np.float64(float(field)).tobytes()
    assert got[0, 1] == 2.0


@pytest.mark.parametrize("data, crlf", [
    (b"1,2\n3\n", False),            # a column missing
    (b"1,2\n3,4,5\n", False),        # one too many
    (b"1,2\r\n3,4\n", True),         # LF among CRLF
    (b"1,2\r\n3,4\n", False),        # CRLF among LF
    (b"1,2\n\n", False),             # blank line
    (b"1,2\n#x,1\n", False),         # '#' line
    (b"1,2\n1\r2,3\n", False),       # CR inside
    (b"1,,2\n", False),              # empty field
    (b"1,abc\n", False),             # not a number
    (b"1,nan\n", False), (b"1,inf\n", False),
    (b"1,1_0\n", False), (b"1,1e\n", False), (b"1,0x10\n", False), (b"1.5\xa0,2\n", False),
    (b"1,12345678901234567890\n", False),  # 20 significant digits: more than the exact paths hold
    (b"1,1.00000000000000000000\n", False),
    (b"1,1e309\n", False), (b"1,1.7976931348623159e308\n", False), (b"1,-1e350\n", False),  # overflow
])
def test_blocks_left_to_numpy(data, crlf):
    assert parse_block(data, 2, crlf, 4096) is None


def test_long_line_left_to_numpy():
    line = b"1," + b"0" * 50 + b"\n"
    assert parse_block(line, 2, False, 20) is None
    assert parse_block(line, 2, False, 4096) is not None


def test_block_matches_numpy_and_grammar_check():
    rng = np.random.default_rng(1)
    values = rng.standard_normal((500, 7)) * 1e-3
    text = "".join(",".join(f"{v:.6f}" for v in row) + "\r\n" for row in values).encode()
    got = parse_block(text[:-2], 7, True, 4096)  # the file's last line may lack its line end
    want = np.loadtxt(text.decode().splitlines(), delimiter=",")
    assert got.tobytes() == want.tobytes()
    check_lines("x.csv", Block(1, text), b"\r\n", 6, 4096)  # numpy's path agrees the block is valid
    with pytest.raises(TextError):
        check_lines("x.csv", Block(1, text + b"1\r\n"), b"\r\n", 6, 4096)
    assert parse_block(text + b"1\r\n", 7, True, 4096) is None


# ------------------------------------------------- 16 to 19 digits, any exponent: the 128-bit power-of-five path

ROOT = Path(__file__).resolve().parents[1]


def _random_doubles(rng, n):
    """n finite doubles: uniform bit patterns (every binade, subnormals, both signs) and values near 1."""
    bits = rng.integers(0, 2**64, size=n, dtype=np.uint64)
    wide = bits.view(np.float64)
    wide = wide[np.isfinite(wide)]
    near = rng.standard_normal(n // 4) * 10.0 ** rng.integers(-12, 12, n // 4)
    return np.concatenate([wide, near])


def _assert_identical_to_float(fields, n_cols=4):
    """The fields as lines of n_cols columns: the core takes the block, every value has float()'s bits."""
    fields = fields[: len(fields) // n_cols * n_cols]
    text = "\n".join(",".join(fields[i:i + n_cols]) for i in range(0, len(fields), n_cols)) + "\n"
    got = parse_block(text.encode(), n_cols, False, 4096)
    assert got is not None
    want = np.fromiter(map(float, fields), float, len(fields))
    bad = np.flatnonzero(got.reshape(-1).view(np.uint64) != want.view(np.uint64))
    assert not bad.size, [fields[i] for i in bad[:10]]


def _check_random_doubles(fmt, n):
    values = _random_doubles(np.random.default_rng({"%.17g": 17, "%.6g": 6, "repr": 1}[fmt] + n), n)
    fields = list(map(repr, values.tolist())) if fmt == "repr" else [fmt % v for v in values.tolist()]
    _assert_identical_to_float(fields)


@pytest.mark.parametrize("fmt", ["%.17g", "%.6g", "repr"])
def test_random_doubles_bit_identical_to_float(fmt):
    """About 0.2 million doubles a format, each printed and read back."""
    _check_random_doubles(fmt, 160_000)


@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["%.17g", "%.6g", "repr"])
def test_millions_of_random_doubles_bit_identical_to_float(fmt):
    """About 1.1 million doubles a format (3.4 million in all)."""
    _check_random_doubles(fmt, 900_000)


def test_random_decimals_of_16_to_19_digits_any_exponent():
    """Decimal mantissas the double cannot hold, with exponents over the whole range and beyond (to +-0)."""
    rng = np.random.default_rng(19)
    n = 300_000
    mant = rng.integers(10**15, 10**19, n, dtype=np.uint64).tolist()
    exps = rng.integers(-360, 290, n).tolist()  # 10^19 10^289 < 1.8e308
    fields = [f"{m}e{e}" for m, e in zip(mant, exps)]
    _assert_identical_to_float(fields)


@pytest.mark.parametrize("field", [
    "5e-324", "4.9406564584124654e-324", "2.4703282292062327e-324", "2.4703282292062328e-324", "2.5e-324",
    "7.4109846876186982e-324", "2.2250738585072011e-308", "2.2250738585072014e-308", "2.2250738585072012e-308",
    "0.1e-308", "1.7976931348623157e308", "1.7976931348623158e308", "8.98846567431158e307", "1e308",
    "9007199254740993", "9007199254740995", "-9007199254740993e0", "18014398509481989",
    "1e-342", "1e-343", "1e-350", "-1e-350", "9999999999999999999e-342", "9999999999999999999e-361",
    "9999999999999999999", "00000000000000000000000000001234567890123456789",
    "0.000000000000000000000000000000000001234567890123456789e-300", "-0.0e-999", "1e+00022", "1e-99999",
    "7.2057594037927933e16", "1.1754943508222875e-38", "0.10000000000000001", "0.29999999999999999",
    "1125899906842624.125", "4503599627370496.5", "4503599627370497.5", "61469481332793735e-1",  # exact ties
    "6681146288349088400e-2", "-4.9406564584124654e-324", "-2.4703282292062327e-324",
])
def test_edge_values_exact(field):
    """Subnormals, the extremes, halfway cases (ties to even, also with a negative decimal exponent), exponents
    beyond +-350, leading zeros."""
    got = parse_block(f"{field},2\n".encode(), 2, False, 4096)
    assert got is not None
    assert got[0, 0].tobytes() == np.float64(float(field)).tobytes()


@pytest.mark.parametrize("field", ["12345678901234567890e-25", "0.00000100000000000000000123", "1.7976931348623159e308",
                                   "1e400"])
def test_long_or_overflowing_fields_read_exactly_by_the_reader(tmp_path, field):
    """20 or more digits, overflow: the core leaves the block, and the reader's own path gives float()'s value
    (or its error for inf)."""
    from sarins_fmu.imu_log import LogError, read_log, write_log

    k = 5
    path = write_log(tmp_path / "x.csv", np.arange(k) * 0.01, np.full((k, 3), 1e-6), np.tile([0, 0, 0.098], (k, 1)),
                     lat_deg=45.0)
    lines = path.read_text().splitlines()
    head = lines.index(next(line for line in lines if line.startswith("time_s")))
    row = lines[head + 2].split(",")
    row[1] = field  # dtheta_x of the second sample
    lines[head + 2] = ",".join(row)
    path.write_text("\n".join(lines) + "\n")
    assert parse_block(("\n".join(lines[head + 1:]) + "\n").encode(), 7, False, 4096) is None
    if np.isfinite(float(field)):
        log = read_log(path)
        assert log.dtheta[1, 0].tobytes() == np.float64(float(field)).tobytes()
    else:
        with pytest.raises(LogError):
            read_log(path)


def test_own_log_read_bit_identical(tmp_path):
    """write_log's %.17g CSV now goes through the core: read_log returns exactly what was written."""
    from sarins_fmu.imu_log import read_log, write_log

    rng = np.random.default_rng(3)
    k = 20_000
    dtheta = 7.29e-7 * np.array([0, 0.7, 0.7]) + 1e-7 * rng.standard_normal((k, 3))
    dv = np.array([0, 0, 0.09806]) + 1e-5 * rng.standard_normal((k, 3))
    path = write_log(tmp_path / "own.csv", np.arange(k) * 0.01, dtheta, dv, lat_deg=45.0)
    body = path.read_bytes().split(b"dv_z_mps\n", 1)[1]
    assert parse_block(body, 7, False, 4096) is not None  # the core takes every block of this log
    log = read_log(path)
    assert log.dtheta.tobytes() == dtheta.tobytes() and log.dv.tobytes() == dv.tobytes()


def test_the_power_of_five_table_is_the_generators():
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "log_parse_gen.py"), "--check"], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_portable_multiply_gives_the_same_bits(tmp_path):
    """Without unsigned __int128 and __builtin_clzll (MSVC, other compilers) the same doubles come out."""
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("no C compiler")
    lib = tmp_path / "lp_portable.so"
    core = ROOT / "sarins_fmu" / "core"
    build_line([cc, "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-DSARINS_LOG_PARSE_PORTABLE",
                    "-fPIC", "-shared", f"-I{core}", str(core / "log_parse.c"), "-o", str(lib)])
    fn = ctypes.CDLL(str(lib)).sarins_log_parse_block
    fn.restype = ctypes.c_int64
    fn.argtypes = [ctypes.c_char_p, ctypes.c_int64, ctypes.c_int32, ctypes.c_int32, ctypes.c_int32,
                   ctypes.POINTER(ctypes.c_double), ctypes.c_int64]
    rng = np.random.default_rng(7)
    values = _random_doubles(rng, 100_000)
    text = ("\n".join(f"{v:.17g}" for v in values.tolist()) + "\n").encode()
    out = np.empty(len(values))
    rows = fn(text, len(text), 1, 0, 4096, out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(values))
    assert rows == len(values)
    assert out.tobytes() == parse_block(text, 1, False, 4096)[:, 0].tobytes()
