"""Budgets and targets for the files the toolkit reads and writes.

One small check per kind, shared by every reader and writer:

* :func:`check_file_size` -- a plain file (a CSV log, a JSON model) is
  refused before it is read if it is larger than its reader's budget;
* :func:`check_zip_budget` -- a zip (an ``.npz`` log, model or campaign
  result) is refused before any member is decompressed if it has more
  members, or its members declare more bytes, than the budget allows (the
  zip module never inflates a member beyond its declared size, so the
  declared sizes bound the memory a read can take);
* :func:`check_output_path` -- a file the user names for writing must be a
  regular file or a new path in an existing folder (a FIFO, a device or a
  folder there is refused at once, before any work);
* :func:`naming_path` -- an ``OSError`` raised while writing a file carries
  the file's name (a full disk then says which file it could not write).

The budgets are named constants in the readers' modules (``MAX_LOG_BYTES``
in :mod:`sarins_fmu.imu_log`, ...); the messages quote them.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import zipfile
from pathlib import Path

__all__ = ["BudgetError", "OutputPathError", "check_file_size", "check_zip_budget", "check_output_path",
           "naming_path", "DISK_FULL_ERRNOS", "format_bytes"]

DISK_FULL_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)  # a write that failed for want of room


class BudgetError(ValueError):
    """A file larger than its reader's budget; ``str()`` is ``'<path>: <reason>'``, the reason gives the limit."""

    def __init__(self, path, reason: str):
        self.path = str(path)
        self.reason = reason
        super().__init__(f"{path}: {reason}")


class OutputPathError(ValueError):
    """A path named for writing that is not a regular file or a new path."""


def format_bytes(n: int) -> str:
    """``n`` bytes in the largest binary unit that keeps it whole-ish (``'2 GiB'``)."""
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.4g} {unit}"
    return f"{n} bytes"


def check_file_size(path, limit: int, what: str) -> None:
    """Refuse a file larger than ``limit`` bytes before reading it.

    Parameters
    ----------
    path : str or Path
        The file (its size is taken with ``stat``; nothing is opened).
    limit : int
        Budget, bytes.
    what : str
        What the file is, for the message (``'an IMU log'``).

    Raises
    ------
    BudgetError
        If the file is larger than ``limit``.
    """
    size = os.stat(path).st_size
    if size > limit:
        raise BudgetError(path, f"{format_bytes(size)} is more than the limit of {format_bytes(limit)} "
                          f"({limit} bytes) for {what}; refused")


def check_zip_budget(path, limit: int, what: str, max_members: int = 1000) -> None:
    """Refuse a zip whose members declare more than ``limit`` bytes in total.

    Only the central directory is read (no member is decompressed).

    Parameters
    ----------
    path : str or Path
        The zip (e.g. an ``.npz``).
    limit : int
        Budget for the sum of the members' uncompressed sizes, bytes.
    what : str
        What the file is, for the message.
    max_members : int
        Most members accepted.

    Raises
    ------
    BudgetError
        Over a limit.
    zipfile.BadZipFile, OSError
        Not a zip, or unreadable (the caller says which file).
    """
    with zipfile.ZipFile(path) as archive:
        members = archive.infolist()
    if len(members) > max_members:
        raise BudgetError(path, f"{len(members)} members, more than the limit of {max_members} for {what}; "
                          "refused")
    declared = sum(m.file_size for m in members)
    if declared > limit:
        raise BudgetError(path, f"its members expand to {format_bytes(declared)}, more than the limit of "
                          f"{format_bytes(limit)} ({limit} bytes) for {what}; refused")
    for member in members:
        if member.filename.endswith(".npy"):
            _check_npy_header(path, member)


def _check_npy_header(path, member: zipfile.ZipInfo) -> None:
    """Refuse an ``.npy`` member whose header claims more data than the member holds: numpy would
    allocate what the header says (7e9 float64 = 56 GB) before it finds the data missing.  Only the
    header is decompressed."""
    import numpy as np

    with zipfile.ZipFile(path) as archive, archive.open(member) as fh:
        try:
            version = np.lib.format.read_magic(fh)
            reader = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
            if version not in reader:
                raise ValueError(f"unknown .npy format version {version}")
            shape, _, dtype = reader[version](fh, max_header_size=10000)
            header = fh.tell()
        except (ValueError, EOFError, SyntaxError) as exc:
            raise BudgetError(path, f"member {member.filename}: not a readable .npy header ({exc})") from None
    count = 1
    for n in shape:
        count *= int(n)
    claimed = count * dtype.itemsize
    if dtype.hasobject or claimed > member.file_size - header:
        raise BudgetError(path, f"member {member.filename}: its header claims shape {tuple(shape)} of {dtype} "
                          f"({format_bytes(claimed)}) but the member holds {format_bytes(member.file_size - header)}; "
                          "refused")


def check_output_path(path, option: str) -> Path:
    """A path to write: a regular file (replaced) or a new path in an existing folder.

    Parameters
    ----------
    path : str or Path
        The path the user named.
    option : str
        The option that named it (``'--output'``), for the message.

    Returns
    -------
    Path

    Raises
    ------
    OutputPathError
        A FIFO, socket, device, folder or symbolic link at ``path`` (writing
        there would block, or write somewhere else than the named file), or a
        parent that is not an existing folder.
    """
    path = Path(path)
    if path.is_symlink():  # the write would land wherever the link points, perhaps outside the folder
        raise OutputPathError(f"{option} {path}: is a symbolic link (to {os.readlink(path)}); give a regular file "
                              "or a new path")
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        parent = path.parent
        if not parent.is_dir():
            raise OutputPathError(f"{option} {path}: the folder {parent} does not exist") from None
        return path
    except OSError as exc:
        raise OutputPathError(f"{option} {path}: cannot be written ({exc.strerror})") from None
    if not stat.S_ISREG(mode):
        kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode)
                else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "a socket"
                if stat.S_ISSOCK(mode) else "not a regular file")
        raise OutputPathError(f"{option} {path}: is {kind}; give a regular file or a new path")
    return path


def refuse_links(paths, what: str) -> None:
    """OutputPathError when one of ``paths`` (files about to be written) is a symbolic link: writing
    it would write wherever the link points, perhaps outside the output folder.  Checked before
    anything is written."""
    for path in map(Path, paths):
        if path.is_symlink():
            raise OutputPathError(f"{what} {path}: is a symbolic link (to {os.readlink(path)}); the file would be "
                                  "written where it points. Remove the link or choose another folder")


@contextlib.contextmanager
def naming_path(path, replacing=()):
    """Within the block, an ``OSError`` without a file name gets ``path`` as its name.

    A write that fails for want of room (``ENOSPC``) is raised by ``write``
    or ``close``, which know no file name; re-raised with it, the message
    says which file could not be written.  ``replacing``: other names (a
    temporary file written in its place) that are replaced by ``path`` too.
    """
    try:
        yield
    except OSError as exc:
        others = {str(p) for p in replacing}
        if exc.errno is None or (exc.filename is not None and str(exc.filename) not in others):
            raise
        raise type(exc)(exc.errno, exc.strerror or os.strerror(exc.errno), str(path)) from None
