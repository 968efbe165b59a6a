"""The fmuResourceLocation parser (fmus/c/sarins_uri.h) under libFuzzer with AddressSanitizer and UBSan:
the harness tests/fuzz/fuzz_uri.c, built as it is and with -D_WIN32 (the drive-letter branch), seeded with
tests/fuzz/corpus_uri, run for SARINS_FUZZ_SECONDS per build (default 3; .ci/run gives 60).  A finding is
any sanitizer report or a broken invariant of the harness (the output NUL-terminated within its buffer, OK
only with an absolute path, "" on every error)."""

from __future__ import annotations

import shutil
from pathlib import Path

import libfuzzer
import pytest

from fmus.cbuild import build_line

ROOT = Path(__file__).resolve().parents[1]
HARNESS = ROOT / "tests" / "fuzz" / "fuzz_uri.c"
CORPUS = ROOT / "tests" / "fuzz" / "corpus_uri"


@pytest.mark.parametrize("defines", [[], ["-D_WIN32"]], ids=["posix", "win32"])
def test_libfuzzer_finds_nothing_in_the_uri_parser(tmp_path, defines):
    clang = libfuzzer.clang_or_skip()
    exe = tmp_path / "fuzz_uri"
    build_line([clang, "-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-Werror",
                    "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all", *defines,
                    f"-I{ROOT / 'fmus' / 'c'}", str(HARNESS), "-o", str(exe)])
    corpus = tmp_path / "corpus"  # libFuzzer adds to its corpus folder: a copy, never the repository's
    shutil.copytree(CORPUS, corpus)
    assert len(list(corpus.iterdir())) >= 5
    print(defines, libfuzzer.run(exe, corpus, libfuzzer.budget(3), "-max_len=4096"))
