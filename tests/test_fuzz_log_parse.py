"""The text-log block parser (sarins_fmu/core/log_parse.c) under libFuzzer with AddressSanitizer and UBSan: the
harness tests/fuzz/fuzz_log_parse.c checks every value of a block the parser takes against its own slow exact
reference (big integers, ties to even), seeded with tests/fuzz/corpus_log_parse, run for 3 s by default and for
SARINS_FUZZ_SECONDS (default 60; .ci/run gives 60) in a slow test.  Also: the harness catches a parser that
rounds one tie the wrong way (a mutant built here)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import libfuzzer
import pytest

from fmus.cbuild import build_line

ROOT = Path(__file__).resolve().parents[1]
HARNESS = ROOT / "tests" / "fuzz" / "fuzz_log_parse.c"
CORPUS = ROOT / "tests" / "fuzz" / "corpus_log_parse"
CORE = ROOT / "sarins_fmu" / "core"


def _build(cc, parser: Path, out: Path, flags: list[str]) -> Path:
    build_line([cc, "-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-Werror", *flags, f"-I{CORE}", str(HARNESS),
                    str(parser), "-o", str(out)])
    return out


def test_libfuzzer_finds_nothing_in_the_log_parser(tmp_path):
    _fuzz(tmp_path, 3)


@pytest.mark.slow
def test_libfuzzer_long_run_finds_nothing_in_the_log_parser(tmp_path):
    _fuzz(tmp_path, int(os.environ.get("SARINS_FUZZ_SECONDS", "60")))


def _fuzz(tmp_path, seconds: int) -> None:
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    exe = _build(clang, CORE / "log_parse.c", tmp_path / "fuzz_log_parse",
                 ["-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all"])
    corpus = tmp_path / "corpus"  # libFuzzer adds to its corpus folder: a copy, never the repository's
    shutil.copytree(CORPUS, corpus)
    assert len(list(corpus.iterdir())) >= 5
    libfuzzer.run(exe, corpus, seconds, "-max_len=4096")


def test_the_reference_catches_a_wrong_tie(tmp_path):
    """The corpus run as files (no libFuzzer): clean with the parser, an abort with a parser that rounds ties up."""
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("no C compiler")
    files = [str(p) for p in sorted(CORPUS.iterdir())]
    good = _build(cc, CORE / "log_parse.c", tmp_path / "good", ["-DSARINS_FUZZ_MAIN"])
    assert subprocess.run([str(good), *files], capture_output=True).returncode == 0
    source = (CORE / "log_parse.c").read_text()
    rule = "if (half && (rest || (m & 1u))) m++;"
    assert rule in source
    (tmp_path / "log_parse.c").write_text(source.replace(rule, "if (half && (rest || 1)) m++;"))
    bad = _build(cc, tmp_path / "log_parse.c", tmp_path / "bad", ["-DSARINS_FUZZ_MAIN"])
    assert subprocess.run([str(bad), str(CORPUS / "edges")], capture_output=True).returncode != 0
