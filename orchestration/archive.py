"""Extraction of ``.ssp`` and ``.fmu`` archives (zip) with limits.

An archive is extracted only if it holds at most ``max_members`` entries
whose declared sizes add up to at most ``max_bytes``; the bytes actually
written are counted as well (a member may lie about its size), and
extraction stops with an error at the limit.  Members whose names are
absolute, contain ``..`` or a drive letter, or are symbolic links are
refused: nothing is ever written outside the target folder.  On any error
the partly extracted folder is removed.
"""
from __future__ import annotations

import shutil
import stat
import tempfile
import zipfile
from pathlib import Path, PurePosixPath

from .errors import SystemFileError

__all__ = ["extract_archive", "MAX_ARCHIVE_BYTES", "MAX_ARCHIVE_MEMBERS", "TEMP_PREFIX"]

MAX_ARCHIVE_BYTES = 1 << 29  # 512 MiB uncompressed in total
MAX_ARCHIVE_MEMBERS = 10_000
TEMP_PREFIX = "orchestration_"
_CHUNK = 1 << 20


def _member_path(info: zipfile.ZipInfo, file: str) -> PurePosixPath | None:
    name = info.filename.replace("\\", "/")
    path = PurePosixPath(name)
    if name.startswith("/") or ".." in path.parts or (path.parts and ":" in path.parts[0]):
        raise SystemFileError(f"archive member '{info.filename}' would be written outside "
                              "the extraction folder (absolute path or '..'); refused",
                              file=file)
    if stat.S_ISLNK(info.external_attr >> 16):
        raise SystemFileError(f"archive member '{info.filename}' is a symbolic link; refused",
                              file=file)
    parts = [p for p in path.parts if p not in ("", ".")]
    return PurePosixPath(*parts) if parts else None


def extract_archive(path: str | Path, *, kind: str, max_bytes: int = MAX_ARCHIVE_BYTES,
                    max_members: int = MAX_ARCHIVE_MEMBERS, component: str | None = None
                    ) -> Path:
    """Extract a zip archive into a new temporary folder and return the folder.

    Parameters
    ----------
    path : str or Path
        Archive file.
    kind : str
        ``'ssp'`` or ``'fmu'`` (folder prefix and messages).
    max_bytes, max_members : int
        Limits on the total uncompressed size (bytes) and the number of members.
    component : str, optional
        Component name, for error messages.

    Raises
    ------
    SystemFileError
        Not a zip archive, over a limit, a member escaping the folder, or an
        I/O error (the message names the archive).
    """
    file = str(path)
    try:
        archive = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError) as error:
        raise SystemFileError(f"cannot open archive: {error}", file=file,
                              component=component) from None
    with archive:
        members = archive.infolist()
        if len(members) > max_members:
            raise SystemFileError(f"archive has {len(members)} members, more than the limit "
                                  f"of {max_members}; refused", file=file, component=component)
        declared = sum(m.file_size for m in members)
        if declared > max_bytes:
            raise SystemFileError(f"archive would extract to {declared} bytes, more than the "
                                  f"limit of {max_bytes} bytes; refused", file=file,
                                  component=component)
        targets = [(m, _member_path(m, file)) for m in members]
        folder = Path(tempfile.mkdtemp(prefix=f"{TEMP_PREFIX}{kind}_"))
        try:
            _write_members(archive, targets, folder, max_bytes, file)
        except BaseException as error:
            shutil.rmtree(folder, ignore_errors=True)
            if isinstance(error, (zipfile.BadZipFile, OSError, EOFError,
                                  NotImplementedError, RuntimeError)):
                raise SystemFileError(f"cannot extract archive: {error}", file=file,
                                      component=component) from None
            raise
    return folder


def _write_members(archive: zipfile.ZipFile, targets, folder: Path, max_bytes: int,
                   file: str) -> None:
    written = 0
    for info, relative in targets:
        if relative is None:
            continue
        target = folder.joinpath(*relative.parts)
        if info.is_dir():
            target.mkdir(parents=True, exist_ok=True)
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        with archive.open(info) as source, open(target, "wb") as sink:
            while chunk := source.read(_CHUNK):
                written += len(chunk)
                if written > max_bytes:
                    raise SystemFileError(f"archive extracts to more than the limit of "
                                          f"{max_bytes} bytes; refused", file=file)
                sink.write(chunk)
