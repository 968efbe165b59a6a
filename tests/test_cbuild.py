"""fmus.cbuild: one object per file, side by side, cached by content: a cached build is the build, and a
change to a file or to a header it includes is compiled again."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import pytest

from fmus import cbuild


@pytest.fixture
def cc():
    found = shutil.which("gcc") or shutil.which("cc")
    if found is None:
        pytest.skip("no C compiler (gcc/cc)")
    return found


def _sources(folder, value: int):
    folder.mkdir(exist_ok=True)
    (folder / "inc").mkdir(exist_ok=True)
    (folder / "inc" / "k.h").write_text(f"#define K {value}\n")
    (folder / "a.c").write_text('#include "k.h"\nint a(void) { return K; }\n')
    (folder / "b.c").write_text("int a(void);\nint b(void) { return a() + 1; }\n")


def _value(lib) -> int:
    return ctypes.CDLL(str(lib)).b()


def test_a_cached_build_is_the_build_and_a_changed_header_is_compiled_again(cc, tmp_path):
    src, cache = tmp_path / "src", tmp_path / "cache"
    _sources(src, 41)
    flags = ["-std=c11", "-O2", "-fPIC", "-Iinc"]
    first = cbuild.build(cc, ["a.c", "b.c"], tmp_path / "one.so", flags, ["-shared"], cwd=src, cache=cache)
    assert _value(first) == 42
    assert len(list(cache.glob("*.o"))) == 2
    whole = tmp_path / "whole.so"
    subprocess.run([cc, *flags, "-shared", "a.c", "b.c", "-o", str(whole)], cwd=src, check=True)
    again = cbuild.build(cc, ["a.c", "b.c"], tmp_path / "two.so", flags, ["-shared"], cwd=src, cache=cache)
    assert _value(again) == _value(whole) == 42
    assert len(list(cache.glob("*.o"))) == 2  # both from the cache
    moved = tmp_path / "elsewhere"
    shutil.copytree(src, moved)
    there = cbuild.build(cc, ["a.c", "b.c"], tmp_path / "moved.so", [*flags[:-1], f"-I{moved / 'inc'}"], ["-shared"],
                         cwd=moved, cache=cache)
    assert _value(there) == 42 and len(list(cache.glob("*.o"))) == 2  # the same bytes in another folder
    _sources(src, 99)  # only the header changes
    changed = cbuild.build(cc, ["a.c", "b.c"], tmp_path / "three.so", flags, ["-shared"], cwd=src, cache=cache)
    assert _value(changed) == 100
    assert len(list(cache.glob("*.o"))) == 3  # a.c again, b.c from the cache
    other = cbuild.build(cc, ["a.c", "b.c"], tmp_path / "four.so", [*flags, "-O1"], ["-shared"], cwd=src,
                         cache=cache)
    assert _value(other) == 100 and len(list(cache.glob("*.o"))) == 5  # other flags, other objects


def test_build_line_splits_one_command_and_errors_name_the_file(cc, tmp_path):
    src = tmp_path / "src"
    _sources(src, 1)
    lib = cbuild.build_line([cc, "-std=c11", "-fPIC", "-shared", f"-I{src / 'inc'}", str(src / "a.c"),
                             str(src / "b.c"), "-lm", "-o", str(tmp_path / "x.so")], cache=tmp_path / "c")
    assert _value(lib) == 2
    (src / "b.c").write_text("int b(void) { return undeclared; }\n")
    with pytest.raises(RuntimeError, match="compiling .*b.c failed"):
        cbuild.build_line([cc, "-std=c11", "-fPIC", "-shared", str(src / "b.c"), "-o", str(tmp_path / "y.so")])
    with pytest.raises(ValueError, match="sources and -o"):
        cbuild.build_line([cc, "-std=c11", str(src / "b.c")])
