"""Binding of the core's text-log block parser (log_parse.h): sample lines -> doubles, or None.

:func:`parse_block` returns the (K, n_cols) numbers of a block of whole CSV sample lines when every line
keeps the log's line grammar and every field is a plain decimal of at most 19 significant digits that the
core converts exactly (correctly rounded, bit-identical to Python's ``float``; see log_parse.h); otherwise
None, and the caller parses the block its own way (numpy), which also words any error.
"""

from __future__ import annotations

import ctypes

import numpy as np

from ._lib import c_double_p, function

_parse = function("sarins_log_parse_block", ctypes.c_int64, ctypes.c_char_p, ctypes.c_int64, ctypes.c_int32,
                  ctypes.c_int32, ctypes.c_int32, c_double_p, ctypes.c_int64)


def parse_block(data: bytes, n_cols: int, crlf: bool, max_line: int) -> np.ndarray | None:
    """(K, n_cols) float64 of the block's lines, or None when the core does not take the block."""
    cap = len(data) // (2 * n_cols) + 1  # a line holds n_cols fields and n_cols - 1 commas, plus its end
    out = np.empty((cap, n_cols))
    rows = _parse(data, len(data), n_cols, int(crlf), max_line, out.ctypes.data_as(c_double_p), cap)
    if rows < 0:
        return None
    return out[:rows]
