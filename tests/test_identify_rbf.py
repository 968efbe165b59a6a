"""Tests of sarins_fmu.identify.rbf (Gaussian RBF network grown like newrb)."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy.spatial.distance import cdist

from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.rbf import RBFNetwork, gaussian_width, radial_basis

EPS = np.finfo(float).eps  # unit roundoff u = EPS / 2; the bounds below use EPS, a factor 2 to spare


def _gauss_by_hand(xa, xb, spread):
    """Basis matrix from the definition, one element at a time."""
    out = np.empty((len(xa), len(xb)))
    for i, a in enumerate(xa):
        for j, b in enumerate(xb):
            dist2 = float(np.sum((np.atleast_1d(a) - np.atleast_1d(b)) ** 2))
            out[i, j] = np.exp(-np.log(2.0) * dist2 / spread**2)
    return out


@pytest.fixture
def sine_data():
    rng = np.random.default_rng(7)
    x = np.sort(rng.uniform(0.0, 6.0, 40))
    y = np.sin(x) + 0.05 * rng.standard_normal(40)
    return x, y


def test_spread_semantics_half_response_at_spread():
    assert_allclose(radial_basis(2.5, 2.5), 0.5, rtol=1e-15)
    assert_allclose(gaussian_width(2.0), 2.0 / np.sqrt(np.log(2.0)), rtol=1e-15)
    # Phi(u) = exp(-u^2 / delta^2) with that width, as in seed 000 eq (2)
    delta = gaussian_width(1.3)
    assert_allclose(radial_basis(0.7, 1.3), np.exp(-(0.7**2) / delta**2), rtol=1e-14)


@pytest.mark.parametrize("standardize", [False, True])
def test_network_neuron_answers_half_at_spread(standardize):
    x = np.array([0.0, 1.0, 2.0, 4.0, 7.0])
    y = np.array([0.0, 1.0, 3.0, 2.0, -1.0])
    spread = 1.5
    net = RBFNetwork(spread=spread, max_neurons=1, standardize=standardize).fit(x, y)
    assert net.n_neurons == 1
    c = net.centers_[0, 0]
    # spread is in standardised units when standardising: one std = x.std()
    step = spread * (x.std() if standardize else 1.0)
    response = (net.predict(np.array([c + step, c - step])) - net.bias_) / net.weights_[0]
    assert_allclose(response, [0.5, 0.5], rtol=1e-12)
    assert_allclose((net.predict([c]) - net.bias_) / net.weights_[0], [1.0], rtol=1e-12)


@pytest.mark.parametrize("selection", ["ols", "residual"])
def test_exact_interpolation_with_goal_zero(selection):
    rng = np.random.default_rng(3)
    x = rng.uniform(-3.0, 3.0, (9, 2))
    y = rng.standard_normal(9)
    spread = 1.0
    net = RBFNetwork(spread=spread, goal=0.0, standardize=False, selection=selection).fit(x, y)
    # bias + n-1 Gaussians already interpolate n points; OLS may stop there
    assert net.n_neurons >= len(y) - 1
    assert_allclose(net.predict(x), y, rtol=0, atol=1e-10 * np.abs(y).max())
    assert net.training_curve_[-1] < 1e-20
    # prediction elsewhere equals the same centres' least-squares network by hand
    phi = _gauss_by_hand(x, net.centers_, spread)
    sol = np.linalg.pinv(np.hstack([phi, np.ones((len(y), 1))])) @ y
    x_new = rng.uniform(-3.0, 3.0, (5, 2))
    expected = _gauss_by_hand(x_new, net.centers_, spread) @ sol[:-1] + sol[-1]
    assert_allclose(net.predict(x_new), expected, rtol=1e-7, atol=1e-9)


def test_residual_rule_uses_all_samples_when_goal_zero():
    x = np.array([0.0, 1.0, 2.5, 4.0, 6.0])
    y = np.array([1.0, -2.0, 0.5, 3.0, 0.0])
    net = RBFNetwork(spread=1.0, goal=0.0, standardize=False, selection="residual").fit(x, y)
    assert net.n_neurons == 5
    assert net.stop_reason_ == "max_neurons"
    # the first centre is the sample farthest from the mean
    assert net.centers_[0, 0] == 1.0
    assert_allclose(net.predict(x), y, atol=1e-10)


def test_goal_stops_growth_and_curve_recorded(sine_data):
    x, y = sine_data
    goal = 0.01
    net = RBFNetwork(spread=0.5, goal=goal).fit(x, y)
    curve = net.training_curve_
    assert net.stop_reason_ == "goal"
    assert 0 < net.n_neurons < len(y)
    assert curve.shape == (net.n_neurons + 1,)
    assert curve[-1] <= goal < curve[-2]
    assert np.all(np.diff(curve) <= 1e-15)
    assert_allclose(curve[0], np.var(y), rtol=1e-12)  # bias only
    assert_allclose(net.training_mse_, curve[-1], rtol=1e-8)
    assert_allclose(np.mean((net.predict(x) - y) ** 2), curve[-1], rtol=1e-8)


def test_max_neurons_caps_growth(sine_data):
    x, y = sine_data
    net = RBFNetwork(spread=0.5, goal=0.0, max_neurons=4).fit(x, y)
    assert net.n_neurons == 4
    assert net.stop_reason_ == "max_neurons"
    assert len(net.training_curve_) == 5


def test_ols_first_neuron_is_best_single_neuron(sine_data):
    """OLS picks, at each step, the candidate with the largest error reduction."""
    x, y = sine_data
    spread = 0.5
    net = RBFNetwork(spread=spread, max_neurons=2).fit(x, y)
    z = (x - x.mean()) / x.std()
    mse = []
    for c in z:
        a = np.column_stack([_gauss_by_hand(z, [c], spread)[:, 0], np.ones_like(z)])
        sol = np.linalg.lstsq(a, y, rcond=None)[0]
        mse.append(np.mean((a @ sol - y) ** 2))
    assert_allclose(net.training_curve_[1], min(mse), rtol=1e-9)
    assert net.centers_[0, 0] == x[int(np.argmin(mse))]


def test_one_dimensional_inputs_same_as_column(sine_data):
    x, y = sine_data
    a = RBFNetwork(spread=0.7, goal=1e-3).fit(x, y)
    b = RBFNetwork(spread=0.7, goal=1e-3).fit(x[:, None], y)
    assert_array_equal(a.predict(x), b.predict(x[:, None]))


def test_candidate_subset_and_chunking_do_not_change_small_fits(sine_data):
    x, y = sine_data
    a = RBFNetwork(spread=0.5, goal=1e-3).fit(x, y)
    b = RBFNetwork(spread=0.5, goal=1e-3, chunk_elements=7).fit(x, y)
    # the fit is the same network: same centres, weights and bias, bit for bit (the design matrix is
    # elementwise and the output layer one lstsq of the same matrix)
    assert_array_equal(a.centers_, b.centers_)
    assert_array_equal(a.weights_, b.weights_)
    assert a.bias_ == b.bias_
    # predict() sums phi @ w in row blocks of another size, so BLAS may sum in another order (and with
    # or without FMA): each output is a (k+1)-term dot product, whose rounding error is at most
    # gamma_(k+1) * sum_j |phi_j w_j| (+ |bias|), gamma_n = n eps / (1 - n eps) (Higham, Accuracy and
    # Stability, 3.1), for either order; the two outputs differ by at most twice that.  The weights here
    # reach 3e4 with cancellation down to |y| ~ 1, so the bound (~1e-10) is far above 1e-12.
    z, zc = a.scaling_.apply(x.reshape(-1, 1)), a.scaling_.apply(a.centers_)
    phi = radial_basis(cdist(z, zc), a.settings.spread)
    n = a.n_neurons + 1
    gamma = n * EPS / (1 - n * EPS)
    bound = 2 * gamma * (np.abs(phi) @ np.abs(a.weights_) + abs(a.bias_))
    assert np.all(np.abs(a.predict(x) - b.predict(x)) <= bound)
    c = RBFNetwork(spread=0.5, goal=0.0, max_candidates=10).fit(x, y)
    assert c.n_neurons <= 10


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_save_load_round_trip(tmp_path, sine_data, suffix):
    x, y = sine_data
    net = RBFNetwork(spread=0.5, goal=1e-3).fit(x, y, input_names=["t"], target_name="y")
    net.metadata = {"site": "lab", "lat_deg": 28.222}
    path = net.save(tmp_path / f"model{suffix}")
    back = RBFNetwork.load(path)
    x_new = np.linspace(-1.0, 7.0, 33)
    assert_array_equal(back.predict(x_new), net.predict(x_new))
    assert_array_equal(back.training_curve_, net.training_curve_)
    assert back.input_names == ("t",)
    assert back.target_name == "y"
    assert back.settings == net.settings
    assert back.metadata == net.metadata


def _saved_json(tmp_path, sine_data):
    x, y = sine_data
    path = RBFNetwork(spread=0.5, goal=1e-2).fit(x, y).save(tmp_path / "m.json")
    return path, json.loads(path.read_text())


@pytest.mark.parametrize(
    "corrupt",
    [
        lambda doc: "{not json",
        lambda doc: json.dumps({**doc, "format": "sarins_fmu.identify.grnn"}),
        lambda doc: json.dumps({**doc, "version": 99}),
        lambda doc: json.dumps({k: v for k, v in doc.items() if k != "arrays"}),
        lambda doc: json.dumps({**doc, "arrays": {k: v for k, v in doc["arrays"].items() if k != "bias"}}),
        lambda doc: json.dumps(
            {**doc, "arrays": {**doc["arrays"], "weights": {"shape": [1], "data": [0.5]}}}
        ),
        lambda doc: json.dumps(
            {**doc, "arrays": {**doc["arrays"], "centers": {"shape": [2, 2], "data": [1, 2, 3]}}}
        ),
        lambda doc: json.dumps(
            {**doc, "arrays": {**doc["arrays"], "weights": {**doc["arrays"]["weights"],
                               "data": [float("nan")] + doc["arrays"]["weights"]["data"][1:]}}}
        ),
        lambda doc: json.dumps({**doc, "meta": {**doc["meta"], "settings": {"spread": -1}}}),
        lambda doc: "[1, 2, 3]",
    ],
    ids=["bad-json", "format-tag", "version", "no-arrays", "no-bias", "weights-shape",
         "data-shape", "nan", "bad-settings", "not-object"],
)
def test_corrupt_model_file_rejected(tmp_path, sine_data, corrupt):
    path, doc = _saved_json(tmp_path, sine_data)
    path.write_text(corrupt(doc))
    with pytest.raises(ModelFileError, match="m.json") as info:
        RBFNetwork.load(path)
    assert isinstance(info.value, ValueError)


def test_missing_and_corrupt_npz_rejected(tmp_path):
    with pytest.raises(ModelFileError, match="absent.json"):
        RBFNetwork.load(tmp_path / "absent.json")
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(ModelFileError, match="bad.npz"):
        RBFNetwork.load(bad)


@pytest.mark.parametrize(
    "x, y, message",
    [
        ([[0.0], [np.nan], [1.0]], [1.0, 2.0, 3.0], "NaN"),
        ([0.0, 1.0, 2.0], [1.0, 2.0], "samples"),
        ([1.0], [2.0], "at least 2"),
        (np.zeros((3, 1, 1)), [1.0, 2.0, 3.0], "shape"),
        ([0.0, 1.0, 2.0], np.zeros((3, 1, 1)), "dimension"),
        ([0.0, 1.0, 2.0], [1.0, np.inf, 3.0], "NaN"),
    ],
)
def test_bad_training_data_rejected(x, y, message):
    with pytest.raises(ValueError, match=message):
        RBFNetwork().fit(x, y)


def test_bad_prediction_inputs_rejected(sine_data):
    x, y = sine_data
    with pytest.raises(RuntimeError, match="not fitted"):
        RBFNetwork().predict(x)
    net = RBFNetwork(spread=0.5, goal=1e-2).fit(x, y)
    with pytest.raises(ValueError, match="columns"):
        net.predict(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="NaN"):
        net.predict([1.0, np.nan])


@pytest.mark.parametrize(
    "kwargs", [{"spread": 0.0}, {"spread": np.nan}, {"goal": -1.0}, {"max_neurons": -2},
               {"selection": "random"}]
)
def test_bad_settings_rejected(kwargs):
    with pytest.raises(ValueError):
        RBFNetwork(**kwargs)


def test_multi_output_shares_centres(tmp_path, sine_data):
    x, y = sine_data
    single = RBFNetwork(spread=0.5, goal=1e-3).fit(x, y)
    # two identical outputs: same centres, same curve, same predictions per column
    double = RBFNetwork(spread=0.5, goal=1e-3).fit(x, np.column_stack([y, y]))
    assert_array_equal(double.centers_, single.centers_)
    # the curve is mean(r**2) of residuals r made by k+1 orthogonal projections r - q (q'r), each
    # computed to within gamma_n ||t|| per element (n samples), whichever BLAS kernel (one or two
    # columns) does it: relative error of mean(r**2) <= 2 (k+1) gamma_n ||t|| / ||r||
    n, k = len(x), len(single.training_curve_)
    gamma_n = n * EPS / (1 - n * EPS)
    r_norm = np.sqrt(n * single.training_curve_)
    rel = 2 * k * gamma_n * np.linalg.norm(y) / r_norm
    assert np.all(np.abs(double.training_curve_ - single.training_curve_) <= rel * single.training_curve_)
    pred = double.predict(x)
    assert pred.shape == (len(x), 2)
    # each column is one least-squares fit of the same [Phi 1] = A (n x p) by a backward-stable solver
    # (LAPACK gelsd: the computed w solves a problem perturbed by ||dA|| <= gamma_np ||A||_F); the fitted
    # values then move by at most gamma_np (kappa(A) ||r|| + ||A||_F ||w|| + ||y||) to first order
    # (Higham, Accuracy and Stability, 20.1), and the two columns by twice that.  kappa(A) ~ 1e7 here.
    z, zc = single.scaling_.apply(x.reshape(-1, 1)), single.scaling_.apply(single.centers_)
    a = np.hstack([radial_basis(cdist(z, zc), single.settings.spread), np.ones((n, 1))])
    gamma_np = n * a.shape[1] * EPS / (1 - n * a.shape[1] * EPS)
    w = np.append(single.weights_, single.bias_)
    bound = 2 * gamma_np * (np.linalg.cond(a) * np.linalg.norm(y - a @ w) + np.linalg.norm(a) * np.linalg.norm(w)
                            + np.linalg.norm(y))
    for col in range(2):
        assert np.linalg.norm(pred[:, col] - single.predict(x)) <= bound
    back = RBFNetwork.load(double.save(tmp_path / "two.json"))
    assert_array_equal(back.predict(x), pred)


def test_multi_output_exact_interpolation():
    rng = np.random.default_rng(11)
    x = rng.uniform(-2.0, 2.0, (7, 3))
    y = rng.standard_normal((7, 4))
    for selection in ("ols", "residual"):
        net = RBFNetwork(spread=1.0, standardize=False, selection=selection).fit(x, y)
        assert_allclose(net.predict(x), y, atol=1e-10)
