"""The binary model file (sarins_fmu/core/modelfile.h) and its RLS kind: the library writes what the core
reads, bit for bit; every corruption a checksum can see is refused; the reader holds under AddressSanitizer
and UBSan on every one-byte change, truncation and extension of valid files (the harness
tests/fuzz/fuzz_rls_model.c without libFuzzer), and (slow) under libFuzzer for a minute."""

from __future__ import annotations

import shutil
import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu.core import online as core
from sarins_fmu.identify.modelfile import ModelFileError, binary_model_bytes, load_model_file, save_model_file
from sarins_fmu.identify.online import prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "sarins_fmu" / "core"
HARNESS = ROOT / "tests" / "fuzz" / "fuzz_rls_model.c"
CORE_FILES = [CORE / f for f in ("modelfile.c", "rls.c", "matrix.c", "report.c")]


def _valid_files() -> list[bytes]:
    a = ForgettingRLS([1e-11, -2e-10, 1e-8], prior_covariance(), 0.0, RLSSettings(0.8))
    b = ForgettingRLS([1e-11, -2e-10, 1e-8], prior_covariance(3.0, -10.0, 60.0), 5.0, RLSSettings(0.5, None))
    for k in range(4):
        a.update(10.0 * k, 1e-8 * k, 86400.0 * (k + 1))
    out = []
    for rls in (a, b):
        settings = rls.settings
        meta = {"time": rls.time, "n_updates": rls.n_updates,
                "settings": {"forgetting_factor": settings.forgetting_factor, "time_scale": settings.time_scale}}
        out.append(binary_model_bytes("sarins_fmu.identify.rls", 1, meta,
                                      {"parameters": rls.parameters, "covariance": rls.covariance}))
    return out


def test_the_core_reads_what_the_library_writes_bit_for_bit(tmp_path):
    rls = ForgettingRLS([1.5e-11, -2e-10, 1e-8], prior_covariance(), 7.0, RLSSettings(0.8))
    rls.update(33.3, 2e-8, 86400.0)
    back = ForgettingRLS.load(rls.save(tmp_path / "m.smf"))
    assert back.parameters.tobytes() == rls.parameters.tobytes()
    assert back.covariance.tobytes() == rls.covariance.tobytes()
    assert (back.time, back.n_updates, back.settings) == (rls.time, rls.n_updates, rls.settings)
    data = (tmp_path / "m.smf").read_bytes()
    assert data[:8] == b"SARINSMF" and struct.unpack_from("<Q", data, 72)[0] == len(data)
    assert struct.unpack_from("<I", data, len(data) - 4)[0] == zlib.crc32(data[:-4]) == core.crc32(data[:-4])
    assert len(data) <= core.RLS_FILE_MAX


def test_generic_binary_files_round_trip_meta_and_arrays(tmp_path):
    meta = {"n": 3, "scale": 2.5, "none": None, "nested": {"deep": {"x": -1}, "y": 1e-300}}
    arrays = {"w": np.arange(12.0).reshape(3, 4), "v": np.array([np.pi]), "big": np.linspace(0, 1, 1000)}
    path = save_model_file(tmp_path / "g.smf", "a.kind", 7, meta, arrays)
    header, got = load_model_file(path, "a.kind", {7}, lambda m, a: ({"meta": m}, a))
    assert header["meta"] == meta
    assert sorted(got) == sorted(arrays) and all(np.array_equal(got[k], arrays[k]) for k in arrays)
    with pytest.raises(ModelFileError, match="format tag is 'a.kind', expected 'b.kind'"):
        load_model_file(path, "b.kind", {7}, lambda m, a: None)
    for bad in ({"s": "text"}, {"l": [1, 2]}, {"b": True}):
        with pytest.raises(ValueError, match="numbers and None only"):
            save_model_file(tmp_path / "x.smf", "a.kind", 1, bad, arrays)
    with pytest.raises(ValueError, match="does not fit"):
        save_model_file(tmp_path / "x.smf", "a.kind", 1, {}, {"9bad": np.zeros(2)})


def test_every_one_byte_change_and_every_truncation_is_refused():
    """The checksum sees any change of one byte; a truncated or extended file has another size than its
    header says."""
    data = _valid_files()[0]
    for i in range(len(data)):
        for flip in (0x01, 0x80):
            bad = bytearray(data)
            bad[i] ^= flip
            with pytest.raises(ValueError):
                core.RlsState.from_model_bytes(bytes(bad))
    for n in range(len(data)):
        with pytest.raises(ValueError):
            core.RlsState.from_model_bytes(data[:n])
    with pytest.raises(ValueError, match="header says"):
        core.RlsState.from_model_bytes(data + b"\0" * 8)


def _fixed_up(data: bytes) -> bytes:
    """The harness's second reading: total size and checksum rewritten to match."""
    b = bytearray(data)
    struct.pack_into("<Q", b, 72, len(b))
    struct.pack_into("<I", b, len(b) - 4, zlib.crc32(bytes(b[:-4])))
    return bytes(b)


def test_fields_behind_the_checksum_are_each_checked():
    """With the size field and the checksum fixed up, a change in any other header or entry-header byte is
    still refused (another kind, version, count, name, dtype or shape, or a non-NUL padding byte); a value
    that is not finite is refused."""
    for data in _valid_files():
        structural = set(range(0, 72))  # the header but its size field (which the fix-up rewrites)
        at = 80
        for _ in range(struct.unpack_from("<I", data, 12)[0]):
            structural |= set(range(at, at + 48))  # name, dtype, rank, dims
            dtype, ndim, d0, d1 = struct.unpack_from("<4I", data, at + 32)
            count = 0 if dtype == 0 else (d0 if ndim >= 1 else 1) * (d1 if ndim == 2 else 1)
            at += 48 + 8 * count
        for i in sorted(structural):
            bad = bytearray(data)
            bad[i] ^= 0x01
            with pytest.raises(ValueError):
                core.RlsState.from_model_bytes(_fixed_up(bytes(bad)))
    nan = bytearray(data)
    struct.pack_into("<d", nan, 80 + 48, float("nan"))  # the first value of the first entry
    with pytest.raises(ValueError, match="NaN or infinity"):
        core.RlsState.from_model_bytes(_fixed_up(bytes(nan)))


def _cc():
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    return cc


def test_harness_under_sanitizers_on_mutated_files(tmp_path):
    """The libFuzzer harness built as a plain program (-DSARINS_FUZZ_MAIN) with AddressSanitizer and UBSan,
    run on the valid files and on every one-byte change (two bit patterns), truncation and one-byte
    extension of them: no sanitizer report, no abort (the harness aborts on an accepted view outside the
    input or an accepted model that fails the state check)."""
    exe = tmp_path / "fuzz_main"
    subprocess.run([_cc(), "-std=c11", "-g", "-O1", "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
                    "-DSARINS_FUZZ_MAIN", f"-I{CORE}", str(HARNESS), *map(str, CORE_FILES), "-lm", "-o", str(exe)],
                   check=True)
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    n = 0
    for data in _valid_files():
        variants = [data, data + b"\x01"] + [data[:k] for k in range(len(data))]
        for i in range(len(data)):
            for flip in (0x01, 0xFF):
                bad = bytearray(data)
                bad[i] ^= flip
                variants.append(bytes(bad))
        for v in variants:
            (corpus / f"{n:05d}").write_bytes(v)
            n += 1
    files = sorted(str(p) for p in corpus.iterdir())
    for k in range(0, len(files), 1000):
        proc = subprocess.run([str(exe), *files[k:k + 1000]], capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0 and "runtime error" not in proc.stderr, proc.stderr[-3000:]
    assert n > 2900  # two files of about 500 bytes, each 3 variants per byte


@pytest.mark.slow
def test_libfuzzer_finds_nothing_in_a_minute(tmp_path):
    """clang's libFuzzer with ASan + UBSan on the harness, seeded with the valid files, 60 s."""
    clang = shutil.which("clang")
    if clang is None:
        pytest.skip("clang (with libFuzzer) not installed (Debian: apt-get install clang)")
    exe = tmp_path / "fuzz"
    subprocess.run([clang, "-std=c11", "-g", "-O1", "-fsanitize=fuzzer,address,undefined",
                    "-fno-sanitize-recover=all", f"-I{CORE}", str(HARNESS), *map(str, CORE_FILES), "-lm", "-o",
                    str(exe)], check=True)
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    for k, data in enumerate(_valid_files()):
        (corpus / f"seed{k}").write_bytes(data)
    proc = subprocess.run([str(exe), "-max_len=8192", "-max_total_time=60", "-print_final_stats=1", str(corpus)],
                          capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "stat::number_of_executed_units" in proc.stderr
