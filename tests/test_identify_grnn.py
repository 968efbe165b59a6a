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


# ------------------------------------------------------------ truncated evaluation, exact to a bound
U = EPS / 2  # unit roundoff


def _truncation_bound(net, kept, tolerance):
    """|truncated - dense| per output (grnn module docstring): the dropped weights each below tol / n, so
    less than (n - k) tol / n times the targets' range, plus both evaluations' rounding: the dense sums'
    gamma(n + 2) relative error on sum |y_j| P_j / sum P_j (<= max |y|), twice, and the cut's own rounding
    (a weight at the cut, off by a few ulp, weighs tol / n)."""
    y = net.y_train_
    n = y.shape[0]
    spread = y.max(axis=0) - y.min(axis=0)
    gamma = (n + 2) * U / (1 - (n + 2) * U)
    dropped = (n - np.asarray(kept))[:, None] * (tolerance / n) * (1 + 1e-12)
    return dropped * spread + 2 * gamma * np.abs(y).max(axis=0) + 4 * U * np.abs(y).max(axis=0)


@pytest.fixture(scope="module")
def campaign_data():
    """Seed 003's training and held-out recordings, short (in process, 0.1 s steps): real campaign inputs."""
    from sarins_fmu.experiments import mems_calibration as mc

    short = mc.with_profile(mc.PROFILES["quick"], step=0.1, warmup=20.0, train=dict(ramp_c_per_min=65.0, hold_min=0.5))
    train = mc.dataset(mc.record_in_process("dynamic", short, seed=2), short)
    test = mc.dataset(mc.record_in_process("heldout", short, seed=3), short)
    return train, test


@pytest.mark.parametrize("tolerance", [1e-9, 1e-3])
def test_truncated_within_its_bound_on_campaign_data(campaign_data, tolerance):
    """On the campaign's own inputs (held-out run, in time order and shuffled: the blocks' radii then grow)
    the truncated GRNN is within the derived bound of the dense C kernel, and the cut does drop patterns."""
    train, test = campaign_data
    net = GRNN(0.07).fit(train.X[::2], train.Y[::2] - train.X[::2, :6])
    q = np.concatenate([test.X[:4000], np.random.default_rng(1).permutation(test.X)[:500]])
    y, kept = net.predict_truncated(q, tolerance=tolerance, return_kept=True)
    dense = net.predict_dense(q)
    assert np.all(np.abs(y - dense) <= _truncation_bound(net, kept, tolerance))
    assert np.median(kept) < 0.5 * len(net.y_train_)  # the point of it: most patterns are not evaluated
    if tolerance > 1e-6:
        assert np.abs(y - dense).max() > 0  # a loose cut measurably moves the estimate, within its bound


def test_compensator_batch_is_the_truncated_grnn(campaign_data):
    """The campaigns' evaluation (GRNNCompensator.predict_batch, truncated) against the FMU's dense one
    (predict): within the bound scaled by the target scale (y = x + z s + m, rounding of the last step)."""
    from sarins_fmu.identify import compensators

    train, test = campaign_data
    comp = compensators.make("grnn", max_patterns=2000).fit(train.X, train.Y)
    y, kept = comp.predict_batch(test.X[-4000:], return_kept=True)
    dense = comp.predict(test.X[-4000:])
    bound = _truncation_bound(comp.net, kept, 1e-9) * comp.target_scale + 4 * U * np.abs(dense)
    assert np.all(np.abs(y - dense) <= bound)
    assert kept.max() <= 2000 and kept.min() >= 1


def test_truncated_on_adversarial_patterns():
    """All patterns equal: every one is kept, the result is the dense one bit for bit.  One query far from
    every pattern: the radius is relative to its nearest distance, so the nearest pattern is still found and
    the estimate is its target (as dense).  Queries in a random order and a single row work too."""
    rng = np.random.default_rng(5)
    x = np.ones((300, 3))
    y = rng.normal(size=(300, 2))
    net = GRNN(0.07).fit(x, y)
    q = np.vstack([np.ones((5, 3)), np.full((1, 3), 1.3), np.full((1, 3), -40.0)])
    out, kept = net.predict_truncated(q, return_kept=True)
    assert_array_equal(kept, 300)
    assert_array_equal(out, net.predict_dense(q))

    x = rng.normal(size=(500, 4))
    y = rng.normal(size=(500, 2))
    net = GRNN(0.07).fit(x, y)
    far = np.full((1, 4), 1e4)
    nearest = np.argmin(((x - far) ** 2).sum(axis=1))
    out, kept = net.predict_truncated(np.vstack([x[:3] + 0.01, far]), return_kept=True)
    assert kept[-1] >= 1
    assert_allclose(out[-1], y[nearest], rtol=0, atol=1e-15)
    assert_allclose(out, net.predict_dense(np.vstack([x[:3] + 0.01, far])),
                    atol=float(_truncation_bound(net, kept, 1e-9).max()))
    q = rng.normal(size=(700, 4)) * 3
    out, kept = net.predict_truncated(q, return_kept=True)
    assert np.all(np.abs(out - net.predict_dense(q)) <= _truncation_bound(net, kept, 1e-9))
    assert net.predict_truncated(q[:1]).shape == (1, 2)
    with pytest.raises(ValueError, match="tolerance"):
        net.predict_truncated(q, tolerance=0.0)


def test_truncated_does_not_depend_on_threads_or_chunks(campaign_data):
    from sarins_fmu.core import nets
    from sarins_fmu.identify import grnn

    train, test = campaign_data
    net = GRNN(0.07).fit(train.X[::3], train.Y[::3])
    z = nets.standardize(test.X[:5000], net.scaling_.mean, net.scaling_.scale)

    def run(**kw):
        return grnn.predict_truncated(z, net._z_train, 0.07, lambda rows, blocks: nets.grnn_predict_blocks(
            test.X[rows], net.scaling_.mean, net.scaling_.scale, net._z_train, net.y_train_, 0.07, blocks), **kw)[0]

    one = run(threads=1)
    assert_array_equal(run(threads=2, chunk_rows=1000, block=64), one)
    assert_array_equal(run(threads=1, chunk_rows=512, block=512), one)


@pytest.mark.slow
def test_truncated_kernels_run_clean_under_sanitizers(tmp_path):
    """The gathered block kernels (sarins_grnn_eval_blocks, sarins_comp_run_grnn_blocks) on the core built with
    ASan + UBSan: the scratch the binding sizes holds every block's gathered candidates; same bits as in the
    normal build's run of the same script."""
    import sanitized_core

    script = """
import numpy as np
from sarins_fmu.identify import compensators
from sarins_fmu.identify.grnn import GRNN
rng = np.random.default_rng(5)
x = rng.normal(size=(400, 7)); y = np.column_stack([np.sin(x[:, 0]), x[:, 1] * x[:, 2], x[:, 3] ** 2,
                                                    x[:, 4], x[:, 5] - x[:, 6], np.cos(x[:, 6])])
q = np.vstack([rng.normal(size=(900, 7)) * 2, np.full((1, 7), 50.0)])
net = GRNN(0.5).fit(x, y)
out, kept = net.predict_truncated(q, return_kept=True)
assert np.all(kept >= 1) and np.allclose(out, net.predict_dense(q), atol=1e-6)
comp = compensators.make("grnn", max_patterns=300).fit(x, y * 1e-3)
batch = comp.predict_batch(q)
assert np.allclose(batch, comp.predict(q), atol=1e-9)
print("sanitized run ok")
"""
    sanitized_core.run(tmp_path, script)
