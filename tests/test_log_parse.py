"""The core's text-log block parser: bit-identical to Python's float(), and the blocks it must leave to numpy."""

import numpy as np
import pytest

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
                                  "1e-5", "000123.4500"])
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
    (b"1,1234567890123456\n", False),  # more digits than the exact path holds
    (b"1,1e23\n", False), (b"1,1e-23\n", False),
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
