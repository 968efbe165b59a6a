"""The RLS model file (kind ``rls`` of the binary model file, sarins_fmu/core/rls.h over netfile.h): the
library writes what the core reads, bit for bit; every corruption the checksum sees is refused; every
field behind the checksum is checked; the reader holds under AddressSanitizer and UBSan on every one-byte
change, truncation and extension of valid files (the harness tests/fuzz/fuzz_rls_model.c without
libFuzzer, the checksum skipped so that the changes reach the arrays), and (slow) under libFuzzer for a
minute."""

from __future__ import annotations

import shutil
import struct
import subprocess
from pathlib import Path

import libfuzzer
import numpy as np
import pytest

from fmus.cbuild import build_line

from sarins_fmu.identify import netfile
from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.online import prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "sarins_fmu" / "core"
HARNESS = ROOT / "tests" / "fuzz" / "fuzz_rls_model.c"
CORE_FILES = [CORE / f for f in ("rls.c", "netfile.c", "matrix.c", "report.c", "smath.c")]
NO_CHECKSUM = "-DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION"


def _models() -> list[ForgettingRLS]:
    a = ForgettingRLS([1e-11, -2e-10, 1e-8], prior_covariance(), 0.0, RLSSettings(0.8))
    b = ForgettingRLS([1e-11, -2e-10, 1e-8], prior_covariance(3.0, -10.0, 60.0), 5.0, RLSSettings(0.5, None))
    for k in range(4):
        a.update(10.0 * k, 1e-8 * k, 86400.0 * (k + 1))
    return [a, b]


def _valid_files() -> list[bytes]:
    return [m.binary() for m in _models()]


def test_the_core_reads_what_the_library_writes_bit_for_bit(tmp_path):
    for rls in _models():
        path = rls.export_binary(tmp_path / "m.bin")
        for back in (ForgettingRLS.load(path), ForgettingRLS.from_binary(path.read_bytes())):
            assert back.parameters.tobytes() == rls.parameters.tobytes()
            assert back.covariance.tobytes() == rls.covariance.tobytes()
            assert (back.time, back.n_updates, back.settings) == (rls.time, rls.n_updates, rls.settings)
        kind, arrays = netfile.read(path)  # the container's own Python reader agrees
        assert kind == "rls" and arrays["parameters"].tolist() == rls.parameters.tolist()
        assert len(path.read_bytes()) <= 4096


def test_every_one_byte_change_and_every_truncation_is_refused():
    """FNV-1a sees any change of one byte (its steps are bijections); a truncated or extended file has
    another size than its header says."""
    data = _valid_files()[0]
    for i in range(len(data)):
        for flip in (0x01, 0x80):
            bad = bytearray(data)
            bad[i] ^= flip
            with pytest.raises(ModelFileError):
                ForgettingRLS.from_binary(bytes(bad))
    for n in range(len(data)):
        with pytest.raises(ModelFileError):
            ForgettingRLS.from_binary(data[:n])
    with pytest.raises(ModelFileError, match="declared size"):
        ForgettingRLS.from_binary(data + b"\0" * 8)


def _resealed(data: bytes) -> bytes:
    """The file with its checksum recomputed (the size field left as it is)."""
    return data[:-8] + struct.pack("<Q", netfile.checksum(data[:-8]))


def test_fields_behind_the_checksum_are_each_checked():
    """With the checksum recomputed, a change in any header or array-header byte is still refused (another
    version, kind, size, count, name, rank or shape, or a non-zero reserved or padding byte); a value that
    is not finite, a covariance that is not positive definite, a fractional update count are refused."""
    for data in _valid_files():
        structural = set(range(0, 32))
        at = 32
        for _ in range(struct.unpack_from("<I", data, 24)[0]):
            structural |= set(range(at, at + 56))
            _, _, d0, d1 = struct.unpack_from("<IIQQ", data, at + 32)
            at += 56 + 8 * d0 * d1
        for i in sorted(structural):
            bad = bytearray(data)
            bad[i] ^= 0x01
            with pytest.raises(ModelFileError):
                ForgettingRLS.from_binary(_resealed(bytes(bad)))
    rls = _models()[0]
    for change, why in (({"time": np.nan}, "NaN or infinity"), ({"covariance": -rls.covariance}, "positive definite"),
                        ({"n_updates": 1.5}, "whole number"), ({"forgetting_factor": 1.5}, "forgetting_factor"),
                        ({"time_scale": -1.0}, "time_scale"), ({"extra": 1.0}, "unexpected array 'extra'")):
        arrays = {**rls.binary_arrays(), **change}
        with pytest.raises(ModelFileError, match=why):
            ForgettingRLS.from_binary(netfile.to_bytes("rls", arrays))
    with pytest.raises(ModelFileError, match="model kind 3"):
        ForgettingRLS.from_binary(netfile.to_bytes("rbf", rls.binary_arrays()))


def _cc():
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    return cc


def test_harness_under_sanitizers_on_mutated_files(tmp_path):
    """The libFuzzer harness built as a plain program (-DSARINS_FUZZ_MAIN, the checksum skipped) with
    AddressSanitizer and UBSan, run on the valid files and on every one-byte change (two bit patterns),
    truncation and one-byte extension of them: no sanitizer report, no abort (the harness aborts on an
    accepted model that fails the state check, before or after an update)."""
    exe = tmp_path / "fuzz_main"
    build_line([_cc(), "-std=c11", "-g", "-O1", "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
                    "-DSARINS_FUZZ_MAIN", NO_CHECKSUM, f"-I{CORE}", str(HARNESS), *map(str, CORE_FILES),
                    "-o", str(exe)])
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
    """clang's libFuzzer with ASan + UBSan on the harness, seeded with the valid files, for
    SARINS_FUZZ_SECONDS (default 60; .ci/run gives 60)."""
    clang = libfuzzer.clang_or_skip()
    exe = tmp_path / "fuzz"
    build_line([clang, "-std=c11", "-g", "-O1", "-fsanitize=fuzzer,address,undefined",
                    "-fno-sanitize-recover=all", NO_CHECKSUM, f"-I{CORE}", str(HARNESS), *map(str, CORE_FILES),
                    "-o", str(exe)])
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    for k, data in enumerate(_valid_files()):
        (corpus / f"seed{k}").write_bytes(data)
    print("rls model file", libfuzzer.run(exe, corpus, libfuzzer.budget(60), "-max_len=8192"))
