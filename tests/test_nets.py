"""The C core's network kernels and binary model files (sarins_fmu/core/nets.c, netmodel.c, netfile.c).

* Every model kind evaluated by the core equals an independent scalar Python evaluation in the same
  operation order bit for bit (its exp and tanh are the core's own, sm_exp and sm_tanh_lanes of smath.h,
  through sarins_fmu.core.smath; sm_tanh_lanes gives the same bits for a value in any lane, so the
  reference calls it one value at a time).
* The numpy references (RBFNetwork.predict_reference, grnn.grnn_predict, np.linalg.solve) differ from the
  core by rounding only, within bounds derived here from the summation lengths.
* The binary model file: Python writer/reader and the C reader agree, and every malformed file is refused
  with a reason, before anything is allocated for a declared size over the budget.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu.core import nets
from sarins_fmu.core.smath import evaluate
from sarins_fmu.identify import compensators, netfile, recurrent
from sarins_fmu.identify.axial import DEFAULT_MODELS, DriftIdentifier
from sarins_fmu.identify.calibration import TriadCalibration, compensate_triad
from sarins_fmu.identify.grnn import GRNN, grnn_predict
from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.rbf import RBFNetwork

U = np.finfo(float).eps / 2  # unit roundoff


def _exp(x: float) -> float:
    """The core's exp (sm_exp), the function the kernels call."""
    return float(evaluate("exp", x)[0])


def _tanh(x: float) -> float:
    """The recurrent gates' tanh (sm_tanh_lanes of one value: the bits it gives in any lane)."""
    return float(evaluate("tanhv", x)[0])


def gamma(n: int) -> float:
    """Higham's gamma_n = n u / (1 - n u): the relative error bound of n floating-point operations."""
    return n * U / (1 - n * U)


def _toy(n=400, seed=3):
    """Rows x (n, 7) = (rate rad/s, specific force m/s2, temperature degC) and truths y (n, 6)."""
    rng = np.random.default_rng(seed)
    y = np.column_stack([rng.normal(0, 0.5, (n, 3)), rng.normal(0, 3.0, (n, 3))])
    temp = np.linspace(-10, 40, n)
    x = np.column_stack([y * (1 + 1e-3) + 1e-3 * np.sin(temp)[:, None], temp])
    return x, y


def _recurrent(kind: str, hidden=5, seed=0, memory=True) -> compensators.RecurrentCompensator:
    """A recurrent compensator with random weights (no training: inference is what is tested)."""
    cell, layers = compensators.RECURRENT_KINDS[kind]
    rng = np.random.default_rng(seed)
    g = 4 if cell == "lstm" else 3
    arrays = {}
    for k in range(layers):
        suffix = "" if k == 0 else f"_l{k}"
        arrays[f"w_ih{suffix}"] = rng.normal(0, 0.5, (g * hidden, 7 if k == 0 else hidden))
        arrays[f"w_hh{suffix}"] = rng.normal(0, 0.5, (g * hidden, hidden))
        arrays[f"b_ih{suffix}"] = rng.normal(0, 0.1, g * hidden)
        arrays[f"b_hh{suffix}"] = rng.normal(0, 0.1, g * hidden)
    arrays |= {"w_out": rng.normal(0, 0.5, (6, hidden)), "b_out": rng.normal(0, 0.1, 6)}
    comp = compensators.make(kind, hidden=hidden, memory=memory)
    comp.weights = recurrent.RecurrentWeights(cell, arrays)
    x, _ = _toy()
    comp.input_mean, comp.input_scale = x.mean(axis=0), x.std(axis=0)
    comp.target_mean, comp.target_scale = rng.normal(0, 1e-3, 6), rng.uniform(1e-3, 2e-3, 6)
    return comp


def fitted(kind: str):
    x, y = _toy()
    if kind in compensators.RECURRENT_KINDS:
        return _recurrent(kind)
    opts = {"grnn": dict(max_patterns=150), "rbf": dict(max_neurons=12)}.get(kind, {})
    return compensators.make(kind, **opts).fit(x, y)


# ------------------------------------------------------------------ scalar references (same order as C)
def _sq(a, b):
    s = 0.0
    for p, q in zip(a, b):
        t = p - q
        s += t * t
    return s


def rbf_scalar(x, mean, scale, centers, w, bias, spread):
    ln2 = math.log(2.0)
    factor = -ln2 / (spread * spread)
    zc = [[(c - m) / s for c, m, s in zip(row, mean, scale)] for row in centers]
    out = []
    for row in x:
        z = [(v - m) / s for v, m, s in zip(row, mean, scale)]
        acc = [0.0] * len(bias)
        for j, c in enumerate(zc):
            phi = _exp(_sq(z, c) * factor)
            for o in range(len(bias)):
                acc[o] += phi * w[j][o]
        out.append([a + b for a, b in zip(acc, bias)])
    return np.array(out)


def grnn_scalar(x, mean, scale, xt, yt, sigma):
    inv = 1.0 / (2.0 * (sigma * sigma))
    zt = [[(c - m) / s for c, m, s in zip(row, mean, scale)] for row in xt]
    out = []
    for row in x:
        z = [(v - m) / s for v, m, s in zip(row, mean, scale)]
        d2 = [_sq(z, t) for t in zt]
        dmin = min(d2)
        sd, acc = 0.0, [0.0] * len(yt[0])
        for j, dj in enumerate(d2):
            p = _exp((dmin - dj) * inv)
            sd += p
            for o in range(len(acc)):
                acc[o] += yt[j][o] * p
        out.append([a / sd for a in acc])
    return np.array(out)


def _sigmoid(v):
    return 0.5 * (1.0 + _tanh(0.5 * v))


def _affine(w, v, b):
    out = []
    for i, row in enumerate(w):
        s = 0.0
        for j, vj in enumerate(v):
            s += vj * row[j]
        out.append(s + b[i])
    return out


def rnn_scalar(comp, x):
    """The recurrent compensator, one sample at a time, from a zero state."""
    w = comp.weights
    layers = [{k: v.tolist() for k, v in layer.items()} for layer in w._layer]
    n = w.hidden
    h = [[0.0] * n for _ in layers]
    c = [[0.0] * n for _ in layers]
    out = []
    for row in x:
        if not comp.options["memory"]:
            h = [[0.0] * n for _ in layers]
            c = [[0.0] * n for _ in layers]
        v = [(a - m) / s for a, m, s in zip(row, comp.input_mean, comp.input_scale)]
        for k, layer in enumerate(layers):
            gi = _affine(layer["w_ih"], v, layer["b_ih"])
            gh = _affine(layer["w_hh"], h[k], layer["b_hh"])
            for q in range(n):
                if w.cell == "lstm":
                    i_, f_ = _sigmoid(gi[q] + gh[q]), _sigmoid(gi[n + q] + gh[n + q])
                    g_, o_ = _tanh(gi[2 * n + q] + gh[2 * n + q]), _sigmoid(gi[3 * n + q] + gh[3 * n + q])
                    c[k][q] = f_ * c[k][q] + i_ * g_
                    h[k][q] = o_ * _tanh(c[k][q])
                else:
                    r_ = _sigmoid(gi[q] + gh[q])
                    z_ = _sigmoid(gi[n + q] + gh[n + q])
                    cand = _tanh(gi[2 * n + q] + r_ * gh[2 * n + q])
                    h[k][q] = (1.0 - z_) * cand + z_ * h[k][q]
            v = h[k]
        zo = _affine(w.w_out.tolist(), v, w.b_out.tolist())
        out.append([row[o] + zo[o] * comp.target_scale[o] + comp.target_mean[o] for o in range(6)])
    return np.array(out)


def _residual(comp, x, z):
    return np.array([[r[o] + zz[o] * comp.target_scale[o] + comp.target_mean[o] for o in range(6)]
                     for r, zz in zip(x.tolist(), z.tolist())])


def compensator_scalar(comp, x):
    if comp.kind == "traditional":
        k_g, k_a = comp.gyro.matrix, comp.accel.matrix
        return np.column_stack([triad_scalar(k_g, comp.gyro.bias, x[:, :3]), triad_scalar(k_a, comp.accel.bias,
                                                                                            x[:, 3:6])])
    if comp.kind == "rbf":
        net = comp.net
        z = rbf_scalar(x.tolist(), net.scaling_.mean.tolist(), net.scaling_.scale.tolist(), net.centers_.tolist(),
                       net.weights_.tolist(), np.atleast_1d(net.bias_).tolist(), net.settings.spread)
        return _residual(comp, x, z)
    if comp.kind == "grnn":
        net = comp.net
        z = grnn_scalar(x.tolist(), net.scaling_.mean.tolist(), net.scaling_.scale.tolist(), net.x_train_.tolist(),
                        net.y_train_.tolist(), net.settings.sigma)
        return _residual(comp, x, z)
    return rnn_scalar(comp, x.tolist())


def triad_scalar(k, b, y):
    """u = K^-1 (y - b) by Doolittle LU with partial pivoting, as sarins_triad_compensate."""
    a = [list(map(float, r)) for r in k]
    perm = [0, 1, 2]
    for col in range(3):
        p = max(range(col, 3), key=lambda r: (abs(a[r][col]), -r))
        a[col], a[p] = a[p], a[col]
        perm[col], perm[p] = perm[p], perm[col]
        for r in range(col + 1, 3):
            f = a[r][col] / a[col][col]
            a[r][col] = f
            for j in range(col + 1, 3):
                a[r][j] -= f * a[col][j]
    out = []
    for row in y.tolist():
        r = [row[j] - b[j] for j in range(3)]
        v = [0.0] * 3
        for j in range(3):
            v[j] = r[perm[j]]
            for q in range(j):
                v[j] -= a[j][q] * v[q]
        for j in (2, 1, 0):
            for q in range(j + 1, 3):
                v[j] -= a[j][q] * v[q]
            v[j] = v[j] / a[j][j]
        out.append(v)
    return np.array(out)


# ------------------------------------------------------------------ bit identity
@pytest.mark.parametrize("kind", compensators.KINDS)
def test_each_compensator_kind_equals_the_scalar_reference_bit_for_bit(kind):
    comp = fitted(kind)
    x, _ = _toy(60, seed=11)
    x[:, :6] *= 1.0 + 0.05 * np.random.default_rng(5).standard_normal((60, 6))  # off the training rows
    expected = compensator_scalar(comp, x)
    np.testing.assert_array_equal(comp.predict(x), expected)
    stream = comp.stream()
    np.testing.assert_array_equal(np.array([stream.step(r) for r in x]), expected)


def test_memoryless_recurrent_model_restarts_every_sample():
    comp = _recurrent("gru", memory=False)
    x, _ = _toy(20, seed=2)
    np.testing.assert_array_equal(comp.predict(x), rnn_scalar(comp, x.tolist()))
    np.testing.assert_array_equal(comp.predict(x[::-1])[::-1], comp.predict(x))  # no state: order is irrelevant


@pytest.mark.parametrize("kind", ["hot", "cold"])
def test_shipped_identifiers_equal_the_scalar_reference_bit_for_bit(kind):
    ident = DriftIdentifier(DEFAULT_MODELS[kind])
    net = ident.network
    rng = np.random.default_rng(7)
    for lat_error, temp, change in zip(rng.normal(0, 3e-5, 40), rng.uniform(-5, 45, 40), rng.uniform(0, 20, 40)):
        row = ident.inputs(lat_error, temp, change)
        ref = rbf_scalar(row.tolist(), net.scaling_.mean.tolist(), net.scaling_.scale.tolist(), net.centers_.tolist(),
                         net.weights_.reshape(-1, 1).tolist(), [net.bias_], net.settings.spread)[0, 0]
        assert ident.drift_dph(lat_error, temp, change) == ref
        assert net.predict(row)[0] == ref


# ------------------------------------------------------------------ numpy references, derived bounds
def test_rbf_numpy_reference_within_the_rounding_bound():
    """|C - numpy| <= 2 B: each computes the exact value to within B = gamma(k+1) (sum |w phi| + |b|)
    + sum |w| phi (|s f| gamma(d+3) + 2u) (the k-term output sum, then each basis value's exponent
    s f from a d-term distance and the exp's own error, relative to u)."""
    x, y = _toy(300)
    net = RBFNetwork(spread=1.5, max_neurons=25).fit(x, y[:, 0])
    q = x[::7] * 1.01
    z, zc = net.scaling_.apply(q), net.scaling_.apply(net.centers_)
    f = -math.log(2.0) / net.settings.spread ** 2
    s = ((z[:, None, :] - zc[None]) ** 2).sum(axis=2)
    phi = np.exp(s * f)
    k, d = zc.shape
    aw = np.abs(net.weights_)
    bound = gamma(k + 1) * (phi @ aw + abs(net.bias_)) + (phi * (np.abs(s * f) * gamma(d + 3) + 2 * U)) @ aw
    diff = np.abs(net.predict(q) - net.predict_reference(q))
    assert np.all(diff <= 2 * bound)
    assert np.any(diff > 0) or np.all(bound > 0)


def test_grnn_numpy_reference_within_the_rounding_bound():
    """The numpy GRNN forms D^2 = |a|^2 + |b|^2 - 2 a.b about the training mean (error up to
    gamma(3d+6) (|a| + |b|)^2), the C one sum (a_i - b_i)^2 (gamma(d+2) D^2).  A weight's exponent
    (D_j^2 - D_min^2) / (2 sigma^2) is then off by e_j = (E_j + E_min) / (2 sigma^2) + 2u in relative
    terms of P_j, and the ratio y = sum y_j P_j / sum P_j by at most sum P_j |y_j - y| e_j / sum P_j
    (first order, doubled for the second), plus both sums' rounding gamma(n+2) (sum P |y_j| / sum P + |y|)
    in each implementation."""
    x, y = _toy(200)
    net = GRNN(sigma=0.3).fit(x, y)
    q = x[::5] * 1.002
    mean, scale = net.scaling_.mean, net.scaling_.scale
    zq, zt = net.scaling_.apply(q), net._z_train
    off = zt.mean(axis=0)
    na, nb = np.linalg.norm(zq - off, axis=1), np.linalg.norm(zt - off, axis=1)
    d2 = ((zq[:, None, :] - zt[None]) ** 2).sum(axis=2)
    n, dim = zt.shape
    e = gamma(3 * dim + 6) * (na[:, None] + nb[None]) ** 2 + gamma(dim + 2) * d2
    jmin = d2.argmin(axis=1)
    inv = 1.0 / (2.0 * net.settings.sigma ** 2)
    eps = (e + e[np.arange(len(q)), jmin][:, None]) * inv + 2 * U
    p = np.exp((d2.min(axis=1)[:, None] - d2) * inv)
    ys = (p @ y) / p.sum(axis=1)[:, None]
    spread = np.abs(y[None, :, :] - ys[:, None, :])
    first = np.einsum("qj,qjo->qo", p * eps, spread) / p.sum(axis=1)[:, None]
    sums = gamma(n + 2) * ((p @ np.abs(y)) / p.sum(axis=1)[:, None] + np.abs(ys))
    bound = 2 * first + 2 * sums
    ref, _ = grnn_predict(zq, zt, y, net.settings.sigma)
    diff = np.abs(net.predict_dense(q) - ref)
    assert np.all(diff <= bound)
    np.testing.assert_array_equal(net.predict_dense(q), grnn_scalar(q.tolist(), mean.tolist(), scale.tolist(),
                                                                    net.x_train_.tolist(), y.tolist(), 0.3))


def test_triad_inverse_within_the_backward_error_bound_of_lu():
    """u = K^-1 (y - b): LU with partial pivoting is backward stable, |K du| <= 3 gamma(3)|L||U||u| per
    row (Higham, Thm 9.4 for n = 3, solve included), so |u_C - u_lapack| <= 2 |K^-1| 3 gamma(3) |L||U||u|;
    with |L||U| <= 2 |K| here (pivots within [1/2, 2])."""
    rng = np.random.default_rng(4)
    k = np.eye(3) + rng.normal(0, 1e-2, (3, 3))
    cal = TriadCalibration.from_matrix(rng.normal(0, 1e-3, 3), k)
    y = rng.normal(0, 2.0, (100, 3))
    ours = compensate_triad(cal, y)
    lapack = np.linalg.solve(cal.matrix, (y - cal.bias).T).T
    kinv = np.abs(np.linalg.inv(cal.matrix))
    bound = 2 * (kinv @ (2 * np.abs(cal.matrix) @ np.abs(lapack).T)).T * 3 * gamma(3) + 4 * U * np.abs(lapack)
    assert np.all(np.abs(ours - lapack) <= bound)
    np.testing.assert_array_equal(ours, triad_scalar(cal.matrix, cal.bias, y))
    with pytest.raises(np.linalg.LinAlgError):
        nets.triad_compensate(np.zeros((3, 3)), np.zeros(3), y)


# ------------------------------------------------------------------ the binary model file
@pytest.mark.parametrize("kind", compensators.KINDS)
def test_binary_file_round_trips_in_python_and_c(kind, tmp_path):
    comp = fitted(kind)
    path = comp.export_binary(tmp_path / "m.bin")
    assert netfile.is_netfile(path)
    got_kind, arrays = netfile.read(path)
    assert got_kind == kind
    for name, value in comp.binary_arrays().items():
        np.testing.assert_array_equal(arrays[name], np.asarray(value, float))
    model = nets.CompensatorModel(path.read_bytes(), path)
    x, _ = _toy(10, seed=1)
    np.testing.assert_array_equal(model.run(x), comp.predict(x))


def test_identifier_binary_file_has_the_documented_layout():
    data = DriftIdentifier(DEFAULT_MODELS["cold"]).binary()
    assert data[:8] == b"SARNET\x00\x01"
    version, kind, total, n_arrays, reserved = struct.unpack_from("<IIQII", data, 8)
    assert (version, kind, total, reserved) == (1, netfile.KINDS["axial_rbf"], len(data), 0)
    assert struct.unpack_from("<Q", data, len(data) - 8)[0] == netfile.checksum(data[:-8])
    assert nets.netfile_checksum(data[:-8]) == netfile.checksum(data[:-8])
    assert netfile.from_bytes(data)[1]["inputs"].tolist() == [0.0, 2.0, 3.0]


def _with_header(data: bytes, **fields) -> bytes:
    """data with header fields replaced and the checksum recomputed (a well-formed but lying file)."""
    version, kind, total, n_arrays, reserved = struct.unpack_from("<IIQII", data, 8)
    values = dict(version=version, kind=kind, total=total, n_arrays=n_arrays, reserved=reserved) | fields
    body = bytearray(data[:-8])
    struct.pack_into("<IIQII", body, 8, *values.values())
    return bytes(body) + struct.pack("<Q", netfile.checksum(bytes(body)))


def _bad_files(good: bytes) -> dict:
    flipped = bytearray(good)
    flipped[100] ^= 1
    huge_dim = bytearray(good[:-8])
    struct.pack_into("<Q", huge_dim, 32 + 40, 1 << 40)
    huge_dim = bytes(huge_dim) + struct.pack("<Q", netfile.checksum(bytes(huge_dim)))
    return {"truncated": (good[:len(good) // 2], "declared size"),
            "empty": (b"", "wrong magic"),
            "wrong magic": (b"NOTSARIN" + good[8:], "wrong magic"),
            "flipped byte": (bytes(flipped), "checksum"),
            "huge declared size": (_with_header(good, total=1 << 62), "over the budget"),
            "huge dimension": (huge_dim, "over the budget"),
            "wrong version": (_with_header(good, version=7), "format version 7"),
            "too many arrays": (_with_header(good, n_arrays=10_000), "arrays"),
            "padded": (good + b"\0" * 8, "declared size")}


BAD_CASES = ("truncated", "empty", "wrong magic", "flipped byte", "huge declared size", "huge dimension",
             "wrong version", "too many arrays", "padded")


@pytest.mark.parametrize("case", BAD_CASES)
def test_bad_model_files_are_refused_with_the_reason(case, tmp_path):
    good = DriftIdentifier(DEFAULT_MODELS["hot"]).binary()
    data, reason = _bad_files(good)[case]
    for opener in (nets.AxialModel, nets.CompensatorModel):
        with pytest.raises(ModelFileError, match=reason):
            opener(data, "bad.bin")
    with pytest.raises(ModelFileError, match=reason):
        netfile.from_bytes(data, "bad.bin")


def test_a_model_of_the_other_kind_is_refused():
    ident = DriftIdentifier(DEFAULT_MODELS["hot"]).binary()
    comp = fitted("traditional").binary()
    with pytest.raises(ModelFileError, match="not a compensator"):
        nets.CompensatorModel(ident)
    with pytest.raises(ModelFileError, match="not an axial drift identifier"):
        nets.AxialModel(comp)
    lying = _with_header(comp, kind=netfile.KINDS["gru"])  # a traditional model's arrays called a GRU
    with pytest.raises(ModelFileError, match="lacks the array 'target_mean'"):
        nets.CompensatorModel(lying)


def test_writer_refuses_bad_names_shapes_and_budgets():
    with pytest.raises(ValueError, match="array name"):
        netfile.to_bytes("rbf", {"Bad Name": np.zeros(2)})
    with pytest.raises(ValueError, match="2 dimensions"):
        netfile.to_bytes("rbf", {"w": np.zeros((2, 2, 2))})
    with pytest.raises(ValueError, match="unknown model kind"):
        netfile.to_bytes("svm", {"w": np.zeros(2)})
    with pytest.raises(ValueError, match="budget"):
        netfile.to_bytes("grnn", {f"a{k}": np.zeros(netfile.MAX_ELEMENTS) for k in range(2)})


def test_non_finite_or_non_positive_model_values_are_refused():
    comp = fitted("grnn")
    arrays = comp.binary_arrays()
    for name, value, reason in (("net.sigma", 0.0, "positive"), ("target_mean", np.full(6, np.nan), "finite"),
                                ("net.scale", -np.ones(7), "positive")):
        with pytest.raises(ModelFileError, match=reason):
            nets.CompensatorModel(netfile.to_bytes("grnn", arrays | {name: value}))


def _netfile_fuzzer(tmp_path):
    """tests/fuzz/fuzz_netfile.c built with libFuzzer, ASan and UBSan, and a corpus of the model files of every
    kind: (executable, corpus), or a skip."""
    from pathlib import Path

    import libfuzzer

    clang = libfuzzer.clang_or_skip()
    root = Path(__file__).resolve().parents[1]
    core = root / "sarins_fmu" / "core"
    exe = tmp_path / "fuzz"
    libfuzzer.build(clang, "-std=c11", "-g", "-O1", "-fsanitize=fuzzer,address,undefined",
                    "-fno-sanitize-recover=undefined", "-DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION",
                    f"-I{core}", str(root / "tests" / "fuzz" / "fuzz_netfile.c"),
                    *(str(core / f) for f in ("netfile.c", "netmodel.c", "nets.c", "smath.c")), "-o", str(exe))
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    (corpus / "hot.bin").write_bytes(DriftIdentifier(DEFAULT_MODELS["hot"]).binary())
    for kind in compensators.KINDS:
        (corpus / f"{kind}.bin").write_bytes(fitted(kind).binary())
    return exe, corpus


def test_the_fuzz_harness_builds_and_runs_clean_on_the_model_files(tmp_path):
    """tests/fuzz/fuzz_netfile.c under clang's libFuzzer with ASan and UBSan: 5,000 runs from the model files
    of every kind (the timed run is the slow test below)."""
    import subprocess

    import libfuzzer

    exe, corpus = _netfile_fuzzer(tmp_path)
    run = subprocess.run([str(exe), "-runs=5000", "-max_len=65536", "-seed=1", libfuzzer.rss_limit(), str(corpus)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]


@pytest.mark.slow
def test_libfuzzer_finds_nothing_in_the_network_files(tmp_path):
    """The same harness for SARINS_FUZZ_SECONDS (default 5; .ci/run gives 60)."""
    import libfuzzer

    exe, corpus = _netfile_fuzzer(tmp_path)
    print("network files", libfuzzer.run(exe, corpus, libfuzzer.budget(5), "-max_len=65536"))


def test_drift_identifier_reads_its_binary_file(tmp_path):
    src = DriftIdentifier(DEFAULT_MODELS["cold"])
    back = DriftIdentifier(src.export_binary(tmp_path / "cold.bin"))
    assert back.input_names == src.input_names and back.local_lat_deg == src.local_lat_deg
    assert back.binary() == src.binary()
    assert back.drift(2e-5, 30.0, 10.0) == src.drift(2e-5, 30.0, 10.0)
    fitted("rbf").export_binary(tmp_path / "comp.bin")
    with pytest.raises(ModelFileError, match="not an axial drift identifier"):
        DriftIdentifier(tmp_path / "comp.bin")


def test_threads_share_a_model_safely():
    """ctypes releases the GIL during the call: each call brings its own GRNN scratch, so threads that
    share one model get the serial results."""
    from concurrent.futures import ThreadPoolExecutor

    comp = fitted("grnn")
    parts = [_toy(300, seed=s)[0] for s in range(6)]
    serial = [comp.predict(p) for p in parts]
    with ThreadPoolExecutor(3) as pool:
        threaded = list(pool.map(comp.predict, parts))
    for a, b in zip(serial, threaded):
        np.testing.assert_array_equal(a, b)


# ------------------------------------------------------------------ several series side by side
@pytest.mark.parametrize("kind", [*compensators.RECURRENT_KINDS, "gru-memoryless"])
def test_series_side_by_side_are_each_series_alone_bit_for_bit(kind):
    """sarins_comp_run_streams: three series of other inputs and lengths in lockstep (hidden 11: the 32-row
    blocks, the four-row blocks and the single rows of the weight sums; a series that ends leaves the others,
    chunks of other lengths), each series' rows those of its own run bit for bit, states advanced the same."""
    memoryless = kind.endswith("-memoryless")
    comp = _recurrent(kind.removesuffix("-memoryless"), hidden=11, memory=not memoryless)
    native = comp.native()
    series = [_toy(n, seed)[0] for n, seed in ((300, 1), (300, 2), (170, 4))]
    alone = [native.run(x) for x in series]
    states = [native.zero_state() for _ in series]
    together = native.run_streams([x[:170] for x in series], states)
    for a, b in zip(alone, together):
        np.testing.assert_array_equal(a[:170].view(np.uint64), b.view(np.uint64))
    chunked = {k: [] for k in range(3)}
    sources = [[x[:100], x[100:130], x[130:]] for x in series[:2]] + [[series[2][:50], series[2][50:]]]
    for step in comp.predict_batch_streams(sources):
        for k, rows in step:
            chunked[k].append(rows)
    for k, a in enumerate(alone):
        np.testing.assert_array_equal(np.concatenate(chunked[k]).view(np.uint64), a.view(np.uint64))
    whole = native.zero_state()
    native.run(series[0][:170], whole)
    np.testing.assert_array_equal(states[0], whole)


def test_side_by_side_refuses_what_it_cannot_run():
    native = _recurrent("gru", hidden=11).native()
    x = _toy(20)[0]
    with pytest.raises(ValueError, match="one length"):
        native.run_streams([x, x[:10]], [native.zero_state(), native.zero_state()])
    with pytest.raises(ValueError, match="1 to 8 series"):
        native.run_streams([x] * 9, [native.zero_state()] * 9)
    with pytest.raises(ValueError, match="recurrent"):
        fitted("rbf").native().run_streams([x], [np.zeros(0)])
    bad = x.copy()
    bad[7, 2] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        native.run_streams([x, bad], [native.zero_state(), native.zero_state()])


@pytest.mark.slow
def test_series_side_by_side_run_clean_under_sanitizers(tmp_path):
    """sarins_comp_run_streams on the core built with ASan + UBSan (tests/sanitized_core.py): one to eight
    series of the LSTM-3 and the GRU-3 (hidden 11), the work the binding sizes; each series that of its own run."""
    import sanitized_core

    script = f"""
import sys
sys.path.insert(0, {str(Path(__file__).resolve().parent)!r})
import numpy as np
from test_nets import _recurrent, _toy
for kind in ("lstm3", "gru3"):
    native = _recurrent(kind, hidden=11).native()
    for k in (1, 3, 8):
        series = [_toy(60, seed)[0] for seed in range(k)]
        together = native.run_streams(series, [native.zero_state() for _ in series])
        assert all(np.array_equal(native.run(x), y) for x, y in zip(series, together))
print("sanitized run ok")
"""
    sanitized_core.run(tmp_path, script)
