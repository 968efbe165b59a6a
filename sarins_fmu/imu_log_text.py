"""Streamed text of a log file: plain or gzip, in blocks of whole lines, with the line grammar checked.

A text log (the project's CSV, a vendor CSV, an i2Nav text file) is read in blocks of about
:data:`BLOCK_BYTES` of whole lines, so that memory does not grow with the file: the caller parses
each block into numbers and keeps only what it needs.  A gzip file (recognised by its magic bytes,
whatever its name) is decompressed as it is read, and refused as soon as its text passes the
reader's budget (a small ``.gz`` that inflates to many GiB stops there, without holding it).

The line grammar of the sample lines is checked on each block with vectorised byte operations
(:func:`check_lines`): one kind of line end in the whole file (LF or CRLF), no carriage return
inside a line, no blank or whitespace-only line, no line longer than the limit, no ``#`` line among
the samples, and the same number of separators on every line.  Each error names the file and the
line, counted from 1.
"""

from __future__ import annotations

import gzip
import zlib
from dataclasses import dataclass

import numpy as np

from .files import format_bytes

BLOCK_BYTES = 4 * 2**20  # bytes of text per block (about 60 000 lines of a 7-column CSV)
GZIP_MAGIC = b"\x1f\x8b"
_WHITESPACE = np.zeros(256, bool)
_WHITESPACE[[9, 10, 13, 32]] = True


class TextError(ValueError):
    """A text log that breaks the line grammar; the message names the file and the line."""


def is_gzip(path) -> bool:
    """True if the file starts with the gzip magic bytes."""
    with open(path, "rb") as fh:
        return fh.read(2) == GZIP_MAGIC


@dataclass
class Block:
    """Whole lines of a text file: ``data`` (bytes, each line ending in its line end, except possibly
    the file's last line) and the number of its first line (from 1)."""

    first_line: int
    data: bytes


class TextReader:
    """Blocks of whole lines of a plain or gzip text file, the decompressed size held to ``limit``.

    ``eol`` is the file's line end (b"\\n" or b"\\r\\n"), taken from its first line.
    """

    def __init__(self, path, limit: int, what: str):
        self.path, self.limit, self.what = path, limit, what
        self.gzip = is_gzip(path)
        self._fh = gzip.open(path, "rb") if self.gzip else open(path, "rb")
        self._rest = b""
        self._line = 1
        self._read = 0
        self._eof = False
        self.eol = None

    def close(self) -> None:
        self._fh.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _chunk(self, size: int) -> bytes:
        try:
            data = self._fh.read(size)
        except (OSError, EOFError, zlib.error) as exc:  # a truncated or damaged gzip stream
            raise TextError(f"{self.path}: not a readable gzip file ({' '.join(str(exc).split())[:160]})") from None
        self._read += len(data)
        if self._read > self.limit:
            kind = "its text (decompressed)" if self.gzip else "it"
            raise TextError(f"{self.path}: {kind} is more than the limit of {format_bytes(self.limit)} "
                            f"({self.limit} bytes) for {self.what}; refused")
        return data

    def lines(self, count_limit: int, limit_for):
        """The next lines one by one (without their line end) for a file's head: at most ``count_limit``
        lines, each at most ``limit_for(first byte)`` bytes long; yields (number, bytes)."""
        for _ in range(count_limit):
            while b"\n" not in self._rest and not self._eof:
                more = self._chunk(65536)
                if not more:
                    self._eof = True
                self._rest += more
                limit = limit_for(self._rest[:1])
                if b"\n" not in self._rest and len(self._rest) > limit + 2:
                    raise TextError(f"{self.path}: line {self._line}: longer than {limit} characters")
            if not self._rest:
                return
            cut = self._rest.find(b"\n")
            raw, self._rest = (self._rest, b"") if cut < 0 else (self._rest[:cut + 1], self._rest[cut + 1:])
            number = self._line
            self._line += 1
            yield number, self._strip_eol(raw, number, limit_for(raw[:1]))

    def _strip_eol(self, raw: bytes, number: int, max_line: int) -> bytes:
        ending = b"\r\n" if raw.endswith(b"\r\n") else b"\n" if raw.endswith(b"\n") else b""
        if ending:
            if self.eol is None:
                self.eol = ending
            elif ending != self.eol:
                raise TextError(f"{self.path}: line {number}: line ends in {_eol_name(ending)}, the lines before "
                                f"in {_eol_name(self.eol)}; use one kind of line end")
        body = raw[: len(raw) - len(ending)]
        if b"\r" in body:
            raise TextError(f"{self.path}: line {number}: a carriage return inside the line")
        if len(body) > max_line:
            raise TextError(f"{self.path}: line {number}: longer than {max_line} characters")
        return body

    def blocks(self):
        """The rest of the file as :class:`Block` s of whole lines."""
        while True:
            more = b"" if self._eof else self._chunk(BLOCK_BYTES)
            if not more:
                self._eof = True
            data = self._rest + more
            if self._eof:
                block, self._rest = data, b""
            else:
                cut = data.rfind(b"\n")
                if cut < 0:  # no whole line in a block: a line far beyond any limit
                    raise TextError(f"{self.path}: line {self._line}: longer than {BLOCK_BYTES} bytes")
                block, self._rest = data[:cut + 1], data[cut + 1:]
            if block:
                yield Block(self._line, block)
                self._line += block.count(b"\n") + (0 if block.endswith(b"\n") else 1)
            if self._eof:
                return


def _eol_name(ending: bytes) -> str:
    return "CRLF" if ending == b"\r\n" else "LF"


def check_lines(path, block: Block, eol: bytes | None, separators: int | None, max_line: int,
                separator: int = ord(",")) -> tuple[np.ndarray, np.ndarray]:
    """Check the line grammar of a block of sample lines (see the module docstring).

    separators : the number of ``separator`` bytes every line must hold (None: not checked).
    Returns (starts, ends) of the lines in the block: byte offsets, the end excluding the line end.
    """
    buf = np.frombuffer(block.data, np.uint8)
    newline = np.flatnonzero(buf == 10)
    ends = newline if block.data.endswith(b"\n") else np.append(newline, buf.size)
    starts = np.concatenate(([0], ends[:-1] + 1))
    has_eol = ends < buf.size
    crlf = np.zeros(ends.size, bool)
    ok = has_eol & (ends > starts)
    crlf[ok] = buf[ends[ok] - 1] == 13
    body_end = ends - crlf
    # one kind of line end
    if eol is not None:
        wrong = has_eol & (crlf != (eol == b"\r\n"))
        if wrong.any():
            i = int(np.argmax(wrong))
            got = b"\r\n" if crlf[i] else b"\n"
            raise TextError(f"{path}: line {block.first_line + i}: line ends in {_eol_name(got)}, the lines before "
                            f"in {_eol_name(eol)}; use one kind of line end")
    # no carriage return inside a line
    cr = np.flatnonzero(buf == 13)
    if cr.size:
        line_of = np.searchsorted(ends, cr)
        inside = cr < body_end[line_of]
        if inside.any():
            raise TextError(f"{path}: line {block.first_line + int(line_of[np.argmax(inside)])}: a carriage return "
                            "inside the line")
    lengths = body_end - starts
    long = lengths > max_line
    if long.any():
        raise TextError(f"{path}: line {block.first_line + int(np.argmax(long))}: longer than {max_line} characters")
    # blank or whitespace-only lines: no byte other than whitespace from a line's start to the next's
    # (each segment holds at least its line end, which is whitespace)
    blank = ~np.logical_or.reduceat(~_WHITESPACE[buf], starts)
    if blank.any():
        raise TextError(f"{path}: line {block.first_line + int(np.argmax(blank))}: blank line (the log has none: "
                        "metadata, header, samples)")
    comment = buf[starts] == ord("#")
    if comment.any():
        raise TextError(f"{path}: line {block.first_line + int(np.argmax(comment))}: a '#' line among the samples "
                        "(metadata comes before the column header)")
    if separators is not None:
        count = np.add.reduceat(buf == separator, starts, dtype=np.int64)
        bad = count != separators
        if bad.any():
            i = int(np.argmax(bad))
            raise TextError(f"{path}: line {block.first_line + i}: the number of columns changed from "
                            f"{separators + 1} to {int(count[i]) + 1}")
    return starts, body_end
