"""Tests of sarins_fmu.identify.grnn (Specht's GRNN / Nadaraya-Watson)."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from sarins_fmu.identify.grnn import GRNN
from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.rbf import RBFNetwork


EPS = np.finfo(float).eps  # the bounds use EPS = 2u, a factor 2 to spare


def test_matches_nadaraya_watson_by_hand():
    # three samples on a line, sigma = 1, no standardisation
    x = [0.0, 1.0, 3.0]
    y = [[1.0, 10.0], [2.0, 20.0], [4.0, -40.0]]
    net = GRNN(sigma=1.0, standardize=False).fit(x, y)
    # query 1.5: D^2 = 2.25, 0.25, 2.25; P = exp(-D^2 / 2)
    p1, p2, p3 = math.exp(-1.125), math.exp(-0.125), math.exp(-1.125)
    expected = [
        (1.0 * p1 + 2.0 * p2 + 4.0 * p3) / (p1 + p2 + p3),
        (10.0 * p1 + 20.0 * p2 - 40.0 * p3) / (p1 + p2 + p3),
    ]
    assert_allclose(net.predict([1.5]), [expected], rtol=1e-14)
    # query 0: D^2 = 0, 1, 9
    q1, q2, q3 = 1.0, math.exp(-0.5), math.exp(-4.5)
    assert_allclose(net.predict([0.0])[0, 0], (q1 + 2 * q2 + 4 * q3) / (q1 + q2 + q3), rtol=1e-14)


def test_standardised_inputs_by_hand():
    x = np.array([[0.0, 100.0], [2.0, 300.0]])
    y = np.array([5.0, 7.0])
    net = GRNN(sigma=0.5).fit(x, y)
    # each column has mean/std: (1, 200) / (1, 100); sample z = (-1,-1), (1,1)
    zq = np.array([(0.5 - 1.0) / 1.0, (180.0 - 200.0) / 100.0])
    d1 = (zq[0] + 1) ** 2 + (zq[1] + 1) ** 2
    d2 = (zq[0] - 1) ** 2 + (zq[1] - 1) ** 2
    w1, w2 = math.exp(-d1 / 0.5), math.exp(-d2 / 0.5)
    out = net.predict([[0.5, 180.0]])
    assert out.shape == (1,)
    assert_allclose(out[0], (5 * w1 + 7 * w2) / (w1 + w2), rtol=1e-13)


def test_limits_of_sigma():
    x = np.array([0.0, 1.0, 2.0, 5.0])
    y = np.array([1.0, 3.0, -2.0, 8.0])
    assert_allclose(GRNN(1e-3, standardize=False).fit(x, y).predict([0.9, 4.0]), [3.0, 8.0])
    assert_allclose(GRNN(1e6, standardize=False).fit(x, y).predict([0.9]), [y.mean()], rtol=1e-9)


def test_far_queries_give_nearest_target_not_nan():
    x = np.array([0.0, 1.0, 3.0])
    y = np.array([1.0, 2.0, 4.0])
    net = GRNN().fit(x, y)
    out, dist = net.predict([1e6, -1e6, 2.0], return_distance=True)
    assert np.all(np.isfinite(out))
    assert_allclose(out[:2], [4.0, 1.0])
    assert dist[0] > 1e5 and dist[2] > 0


def test_matlab_spread_half_response():
    net = GRNN.from_matlab_spread(2.0, standardize=False).fit([0.0, 2.0], [0.0, 1.0])
    # at x = 0 the weights are 1 and 0.5
    assert_allclose(net.predict([0.0]), [0.5 / 1.5], rtol=1e-14)


def test_chunking_does_not_change_result():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(300, 3))
    y = rng.normal(size=(300, 2))
    q = rng.normal(size=(257, 3)) * 2
    net = GRNN(0.3, chunk_elements=10**7).fit(x, y)
    whole = net.predict(q)
    small = GRNN(0.3, chunk_elements=301).fit(x, y).predict(q)
    tiny = GRNN(0.3, chunk_elements=1).fit(x, y).predict(q)
    assert_array_equal(tiny.shape, whole.shape)
    # Query blocks of another size reach BLAS as other shapes, which may sum in another order.  What
    # the arithmetic guarantees (Higham 3.1, gamma_n = n eps / (1 - n eps)): the squared distances,
    # |zq|^2 + |zt|^2 - 2 zq.zt around the training mean, each within
    # gamma_d (|zq|^2 + 2 sum|zq_k zt_k|) + |zt|^2 eps; the exponents (d2 - min d2) / (2 sigma^2) then within
    # E = 2 max(error) / (2 sigma^2), so each weight within a factor exp(+-E); the weighted mean of y moves
    # by at most (exp(2E) - 1) (max|y| + |out|), and its two sums add 2 gamma_n (max|y| + |out|).
    # Twice that for the two results compared.
    zt = net.scaling_.apply(x) - net.scaling_.apply(x).mean(axis=0)
    zq = net.scaling_.apply(q) - net.scaling_.apply(x).mean(axis=0)
    n, d = zt.shape
    gamma = lambda k: k * EPS / (1 - k * EPS)  # noqa: E731
    d2_err = (gamma(d) * ((zq**2).sum(axis=1)[:, None] + 2 * np.abs(zq) @ np.abs(zt).T)
              + 2 * EPS * (zt**2).sum(axis=1)[None, :])
    e = 2 * d2_err.max(axis=1) / (2 * 0.3**2)
    spread = np.abs(y).max() + np.abs(whole).max(axis=1)
    bound = 2 * (np.expm1(2 * e) + 2 * gamma(n)) * spread
    for other in (small, tiny):
        assert np.all(np.abs(other - whole) <= bound[:, None])


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_save_load_round_trip(tmp_path, suffix):
    rng = np.random.default_rng(2)
    x = rng.normal(size=(50, 7))
    y = rng.normal(size=(50, 6))
    net = GRNN().fit(x, y, input_names=list("abcdefg"), output_names=list("uvwxyz"))
    back = GRNN.load(net.save(tmp_path / f"g{suffix}"))
    q = rng.normal(size=(20, 7))
    assert_array_equal(back.predict(q), net.predict(q))
    assert back.input_names == tuple("abcdefg")
    assert back.output_names == tuple("uvwxyz")


def test_single_output_round_trip_keeps_1d(tmp_path):
    net = GRNN().fit([0.0, 1.0, 2.0], [3.0, 4.0, 5.0])
    back = GRNN.load(net.save(tmp_path / "g.json"))
    assert back.predict([0.5]).shape == (1,)


def test_other_model_kind_rejected(tmp_path):
    path = RBFNetwork(spread=1.0).fit([0.0, 1.0, 2.0], [1.0, 0.0, 1.0]).save(tmp_path / "r.json")
    with pytest.raises(ModelFileError, match="r.json.*format tag"):
        GRNN.load(path)
    path.write_text('{"format": "sarins_fmu.identify.grnn", "version": 1, "meta": {}, "arrays": {}}')
    with pytest.raises(ModelFileError, match="r.json"):
        GRNN.load(path)


def test_bad_inputs_rejected():
    with pytest.raises(ValueError, match="sigma"):
        GRNN(sigma=0.0)
    with pytest.raises(ValueError, match="samples"):
        GRNN().fit(np.zeros((3, 2)), np.zeros(4))
    with pytest.raises(ValueError, match="NaN"):
        GRNN().fit([[0.0], [1.0]], [np.nan, 1.0])
    net = GRNN().fit(np.zeros((3, 2)) + [[0, 0], [1, 1], [2, 3]], np.arange(3.0))
    with pytest.raises(ValueError, match="columns"):
        net.predict(np.zeros((2, 3)))
    with pytest.raises(RuntimeError, match="not fitted"):
        GRNN().predict([1.0])


def test_large_input_offset_keeps_precision():
    x = np.array([0.0, 0.1, 0.3, 0.35])
    y = np.array([1.0, 2.0, 4.0, 3.0])
    q = np.array([0.05, 0.2, 0.33])
    near = GRNN(0.07, standardize=False).fit(x, y).predict(q)
    far = GRNN(0.07, standardize=False).fit(x + 1e6, y).predict(q + 1e6)
    assert_allclose(far, near, rtol=1e-8)
