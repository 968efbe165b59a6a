"""Compile C files into one shared library or program: one object per file, the files compiled side by side,
the objects kept in a content-addressed cache when one is named.

A build that names every file in one compiler call compiles each file on its own anyway and then links; this
module does the same steps itself so that the same file compiled the same way is compiled once: the core's
files (``smath.c``, ``imu.c``, the glue) are the same in every FMU and every FMI version.  An object is reused
only when the compiler (its path, size and time stamp), the flags, the file and every header it includes by
quoted name (transitively, from its own folder and the ``-I`` folders) are the same bytes, so a cached object
is the object the compiler would write now.

The cache folder is ``cache`` when given, else ``$SARINS_CC_CACHE`` when set (the test session sets it in its
temporary folder), else none: every file is compiled.  Objects are written under a temporary name and renamed,
so processes may share one cache folder.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

CACHE_ENV = "SARINS_CC_CACHE"
_INCLUDE = re.compile(rb'^\s*#\s*include\s+"([^"]+)"', re.M)


def cache_dir(cache: Path | str | None = None) -> Path | None:
    """``cache``, else ``$SARINS_CC_CACHE``, else None (no cache)."""
    chosen = cache if cache is not None else os.environ.get(CACHE_ENV)
    return Path(chosen) if chosen else None


def _compiler_identity(cc: str) -> bytes:
    found = shutil.which(cc)
    if found is None:
        raise RuntimeError(f"C compiler {cc!r} not found on PATH")
    real = os.path.realpath(found)
    st = os.stat(real)
    return f"{real}\0{st.st_size}\0{st.st_mtime_ns}".encode()


def _include_dirs(flags: list[str]) -> list[Path]:
    dirs, take = [], False
    for flag in flags:
        if take:
            dirs.append(Path(flag))
            take = False
        elif flag == "-I":
            take = True
        elif flag.startswith("-I"):
            dirs.append(Path(flag[2:]))
    return dirs


def _without_include_dirs(flags: list[str]) -> list[str]:
    kept, skip = [], False
    for flag in flags:
        if skip:
            skip = False
        elif flag == "-I":
            skip = True
        elif not flag.startswith("-I"):
            kept.append(flag)
    return kept


def source_key(source: Path, flags: list[str], compiler_id: bytes, cwd: Path) -> str:
    """The cache key of ``source`` compiled with ``flags``: a hash of the compiler, the flags (but the ``-I``
    folders' names), the file and the headers it includes by quoted name, found as the compiler finds them
    (the including file's folder, then the ``-I`` folders in order), transitively (a header not found there
    is keyed by its name)."""
    dirs = [cwd / d for d in _include_dirs(flags)]
    # the -I folders' names are not part of the key (their headers' bytes are): the same files unpacked into
    # another temporary folder hit the cache
    digest = hashlib.sha256(compiler_id + b"\0" + "\0".join(_without_include_dirs(flags)).encode())
    seen: set[Path] = set()
    todo = [cwd / source]
    while todo:
        path = todo.pop()
        data = path.read_bytes()
        digest.update(b"\0file\0" + data)
        for name in _INCLUDE.findall(data):
            name = name.decode()
            found = next((d / name for d in (path.parent, *dirs) if (d / name).is_file()), None)
            if found is None:
                digest.update(b"\0missing\0" + name.encode())
            elif found.resolve() not in seen:
                seen.add(found.resolve())
                todo.append(found)
    return digest.hexdigest()


def _compile_one(cc: str, flags: list[str], source: Path, obj: Path, cwd: Path, cache: Path | None,
                 compiler_id: bytes) -> None:
    cached = cache / (source_key(source, flags, compiler_id, cwd) + ".o") if cache else None
    if cached is not None and cached.is_file():
        shutil.copyfile(cached, obj)
        return
    cmd = [cc, *flags, "-c", str(source), "-o", str(obj)]
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"compiling {source} failed:\n{' '.join(cmd)}\n{proc.stderr}")
    if cached is not None:
        cache.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=cache, suffix=".tmp")
        os.close(fd)
        shutil.copyfile(obj, tmp)
        os.replace(tmp, cached)


def build(cc: str, sources: list[Path | str], out: Path, flags: list[str] | tuple[str, ...] = (),
          link_flags: list[str] | tuple[str, ...] = (), cwd: Path | str | None = None,
          cache: Path | str | None = None, jobs: int | None = None) -> Path:
    """Compile ``sources`` (relative to ``cwd``) with ``cc`` and ``flags`` (``-I`` folders relative to
    ``cwd``), one object each and up to ``jobs`` at once (default: the cores), then link them with ``flags``
    and ``link_flags`` into ``out``; returns ``out``.  RuntimeError with the compiler's message."""
    cwd = Path(cwd or ".").resolve()
    flags, cache = list(flags), cache_dir(cache)
    compiler_id = _compiler_identity(cc)
    out = Path(out).resolve()
    with tempfile.TemporaryDirectory(prefix="sarins_cc_") as tmp:
        objects = [Path(tmp) / f"{i}_{Path(s).stem}.o" for i, s in enumerate(sources)]
        with ThreadPoolExecutor(max_workers=max(1, min(jobs or os.cpu_count() or 1, len(sources)))) as pool:
            for job in [pool.submit(_compile_one, cc, flags, Path(s), o, cwd, cache, compiler_id)
                        for s, o in zip(sources, objects)]:
                job.result()
        cmd = [cc, *flags, *map(str, objects), *link_flags, "-o", str(out)]
        proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"linking {out.name} failed:\n{' '.join(cmd)}\n{proc.stderr}")
    return out


@contextmanager
def shared_cache():
    """A cache for the builds inside the ``with`` block: ``$SARINS_CC_CACHE`` when set, else a temporary
    folder named in ``$SARINS_CC_CACHE`` until the block ends (then removed); yields the folder."""
    if os.environ.get(CACHE_ENV):
        yield Path(os.environ[CACHE_ENV])
        return
    with tempfile.TemporaryDirectory(prefix="sarins_cc_cache_") as tmp:
        os.environ[CACHE_ENV] = tmp
        try:
            yield Path(tmp)
        finally:
            os.environ.pop(CACHE_ENV, None)


_LINK_ONLY = ("-shared", "-static", "-rdynamic")
_WITH_ARGUMENT = ("-I", "-D", "-U", "-include", "-isystem")


def build_line(cmd: list[str], cwd: Path | str | None = None, cache: Path | str | None = None) -> Path:
    """:func:`build` for one compiler command line (``cc [flags] a.c b.c [-lm] -o out``): the ``.c``
    arguments are the sources, ``-l``/``-L`` and ``-shared``/``-static``/``-rdynamic`` go to the link only,
    every other argument is a flag of both; returns the output path."""
    cc, args, sources, flags, link, out = cmd[0], list(cmd[1:]), [], [], [], None
    while args:
        arg = args.pop(0)
        if arg == "-o":
            out = args.pop(0)
        elif arg in _WITH_ARGUMENT:
            flags += [arg, args.pop(0)]
        elif arg.endswith(".c") and not arg.startswith("-"):
            sources.append(arg)
        elif arg.startswith(("-l", "-L")) or arg in _LINK_ONLY:
            link.append(arg)
        else:
            flags.append(arg)
    if out is None or not sources:
        raise ValueError(f"a compile line with sources and -o expected: {' '.join(cmd)}")
    return build(cc, sources, Path(cwd or ".") / out, flags, link, cwd=cwd, cache=cache)
