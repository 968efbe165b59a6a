"""Check an FMU's shared library before it is loaded.

``dlopen`` maps the segments an ELF file's program headers name; a segment
that lies past the end of a truncated file is mapped all the same, and the
first access to it kills the process with SIGBUS: no exception, no message.
:func:`check_shared_library` reads the ELF header and program headers (the
standard library only) and refuses a file whose headers or loadable segments
do not lie within it.  Other formats (PE DLLs, Mach-O) are left to the
loader, which reports their faults as errors.
"""

from __future__ import annotations

import struct
from pathlib import Path

__all__ = ["BinaryError", "check_shared_library"]

ELF_MAGIC = b"\x7fELF"
PT_LOAD = 1
_HEADER_64 = "HHIQQQIHHHHHH"  # e_type .. e_shstrndx after e_ident (16 bytes)
_HEADER_32 = "HHIIIIIHHHHHH"
_PHDR_64 = "IIQQQQQQ"  # p_type, p_flags, p_offset, p_vaddr, p_paddr, p_filesz, p_memsz, p_align
_PHDR_32 = "IIIIIIII"  # p_type, p_offset, p_vaddr, p_paddr, p_filesz, p_memsz, p_flags, p_align
MAX_PROGRAM_HEADERS = 4096


class BinaryError(ValueError):
    """The shared library is not one the loader can map safely (truncated, malformed)."""


def _header(data: bytes, size: int):
    if len(data) < 16 or data[4] not in (1, 2) or data[5] not in (1, 2):
        raise BinaryError(f"not a valid ELF file (its {size}-byte identification is malformed)")
    wide, order = data[4] == 2, "<" if data[5] == 1 else ">"
    fmt = order + (_HEADER_64 if wide else _HEADER_32)
    if len(data) < 16 + struct.calcsize(fmt):
        raise BinaryError(f"truncated: {size} bytes, shorter than the ELF header")
    fields = struct.unpack_from(fmt, data, 16)
    phoff, shoff = fields[4], fields[5]
    phentsize, phnum, shentsize, shnum = fields[8], fields[9], fields[10], fields[11]
    return wide, order, phoff, phentsize, phnum, shoff, shentsize, shnum


def check_shared_library(path: Path | str) -> None:
    """Raise :class:`BinaryError` when the ELF file at ``path`` would map bytes past its end.

    Checked: the ELF header, the program header table and every loadable
    (``PT_LOAD``) segment's file bytes, and the section header table, lie
    within the file.  A file that does not start with the ELF magic is not
    checked (another platform's format).
    """
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(64)
        if not head.startswith(ELF_MAGIC):
            return
        wide, order, phoff, phentsize, phnum, shoff, shentsize, shnum = _header(head, size)
        phdr = order + (_PHDR_64 if wide else _PHDR_32)
        if phnum == 0 or phnum > MAX_PROGRAM_HEADERS or phentsize < struct.calcsize(phdr):
            raise BinaryError(f"malformed ELF program header table ({phnum} entries of {phentsize} bytes)")
        if phoff + phnum * phentsize > size:
            raise BinaryError(f"truncated: {size} bytes, but its program headers end at byte "
                              f"{phoff + phnum * phentsize}")
        if shoff and shoff + shnum * shentsize > size:
            raise BinaryError(f"truncated: {size} bytes, but its section headers end at byte "
                              f"{shoff + shnum * shentsize}")
        fh.seek(phoff)
        table = fh.read(phnum * phentsize)
    for k in range(phnum):
        entry = struct.unpack_from(phdr, table, k * phentsize)
        kind = entry[0]
        offset, filesz = (entry[2], entry[5]) if wide else (entry[1], entry[4])
        if kind == PT_LOAD and offset + filesz > size:
            raise BinaryError(f"truncated: {size} bytes, but its loadable segment {k} needs bytes up to "
                              f"{offset + filesz}")
