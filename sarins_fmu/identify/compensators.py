"""IMU compensators of seed 003: one interface over five models.

Every compensator maps the measured IMU outputs and temperature,

    x = (Wx, Wy, Wz, Ax, Ay, Az, T)   (rad/s, m/s^2, degC),

to estimates of the true outputs y = (wx, wy, wz, ax, ay, az) (rad/s,
m/s^2), seed 003 Fig. 3.  Kinds (:data:`KINDS`):

``traditional``
    Eqs (1)-(2) per triad: y = K^-1 (W - b) (:mod:`.calibration`).
``rbf``
    The project's RBF network (:mod:`.rbf`), seed 003's settings: spread 60,
    at most 30 neurons, goal 1e-5.
``grnn``
    Specht's GRNN (:mod:`.grnn`), smoothing factor 0.07, inputs standardised.
``lstm``, ``gru``
    One recurrent layer of 60 units and a linear output (:mod:`.recurrent`).
``lstm3``, ``gru3``
    Three stacked recurrent layers of 60 units and a linear output: the
    other reading of seed 003's "3-layer recurrent hidden layer".

The networks learn the *correction* y - x[:6] (standardised per output with
its training mean and std) rather than y itself: the same input-output map
(y = x[:6] + net(x)), but the network's whole range goes to the error, which
is 1e-3 of the signal (a skip connection; predicting the 100 deg/s signal
itself would bury the 0.01 deg/s errors in the fit's own error).  The
inputs are standardised inside each network.

``fit(X, Y)`` trains, ``predict(X)`` compensates a time-ordered series (the
recurrent models carry their state along it), ``stream()`` gives a
stateful one-sample-at-a-time compensator (the FMU), ``save``/``load``
write plain data (JSON or npz, :mod:`.modelfile`), never pickle.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from . import recurrent
from .calibration import TriadCalibration, compensate_triad
from .grnn import GRNN
from .modelfile import get_array, load_model_file, save_model_file
from .preprocessing import check_inputs, check_targets
from .rbf import RBFNetwork

FORMAT_TAG = "sarins_fmu.identify.compensator"
FORMAT_VERSION = 1
N_IN, N_OUT = 7, 6
KINDS = ("traditional", "rbf", "grnn", "lstm", "gru", "lstm3", "gru3")
RECURRENT_KINDS = {"lstm": ("lstm", 1), "gru": ("gru", 1), "lstm3": ("lstm", 3), "gru3": ("gru", 3)}


def _check_xy(X, Y=None):
    x = check_inputs(X, "X", n_features=N_IN)
    if Y is None:
        return x
    y = check_targets(Y, x.shape[0], "Y", ndim=(2,))
    if y.shape[1] != N_OUT:
        raise ValueError(f"Y must have {N_OUT} columns (wx, wy, wz, ax, ay, az), got {y.shape[1]}")
    return x, y


class Compensator:
    """Base class: ``kind``, ``fit``, ``predict``, ``stream``, ``save``/``load``, ``fit_seconds``."""

    kind = ""

    def __init__(self):
        self.fit_seconds: float | None = None

    def fit(self, X, Y) -> "Compensator":
        x, y = _check_xy(X, Y)
        t0 = time.perf_counter()
        self._fit(x, y)
        self.fit_seconds = time.perf_counter() - t0
        return self

    def predict(self, X) -> np.ndarray:
        """Compensated outputs (n, 6) of a time-ordered series of inputs (n, 7)."""
        return self._predict(_check_xy(X))

    def stream(self) -> "Stream":
        """A stateful compensator fed one sample at a time."""
        return Stream(self)

    @property
    def n_parameters(self) -> int:
        """Number of stored numbers that define the fitted model."""
        return int(sum(np.asarray(a).size for a in self._payload()[1].values()))

    def save(self, path: str | Path) -> Path:
        meta, arrays = self._payload()
        header = {"kind": self.kind, "model": meta, "fit_seconds": self.fit_seconds}
        return save_model_file(path, FORMAT_TAG, FORMAT_VERSION, header, arrays)

    # subclasses: _fit, _predict, _payload, _from_payload


class Stream:
    """Sample-by-sample compensation (stateless models call predict on one row)."""

    def __init__(self, model: Compensator):
        self.model = model
        self.reset()

    def reset(self) -> None:
        self._state = None

    def step(self, x) -> np.ndarray:
        """Compensated (6,) outputs of one (7,) input sample."""
        return self.model.predict(np.asarray(x, float).reshape(1, N_IN))[0]


class TraditionalCompensator(Compensator):
    """Seed 003 eqs (1)-(2): bias, scale factor and misalignment per triad."""

    kind = "traditional"

    def __init__(self, gyro: TriadCalibration | None = None, accel: TriadCalibration | None = None):
        super().__init__()
        self.gyro, self.accel = gyro, accel

    def _fit(self, x, y):
        from .calibration import fit_triad

        self.gyro = fit_triad(y[:, :3], x[:, :3])
        self.accel = fit_triad(y[:, 3:], x[:, 3:6])

    def _predict(self, x):
        if self.gyro is None:
            raise RuntimeError("traditional compensator is not fitted")
        return np.column_stack([compensate_triad(self.gyro, x[:, :3]), compensate_triad(self.accel, x[:, 3:6])])

    def _payload(self):
        if self.gyro is None:
            raise RuntimeError("traditional compensator is not fitted: nothing to save")
        arrays = {}
        for name, cal in (("gyro", self.gyro), ("accel", self.accel)):
            arrays[f"{name}_bias"] = cal.bias
            arrays[f"{name}_matrix"] = cal.matrix
        return {}, arrays

    @classmethod
    def _from_payload(cls, meta, arrays):
        return cls(*(TriadCalibration.from_matrix(get_array(arrays, f"{n}_bias", (3,)),
                                                  get_array(arrays, f"{n}_matrix", (3, 3))) for n in ("gyro", "accel")))


class _Residual(Compensator):
    """Networks that learn the standardised correction y - x[:6]."""

    def __init__(self):
        super().__init__()
        self.target_mean: np.ndarray | None = None
        self.target_scale: np.ndarray | None = None

    def _targets(self, x, y):
        d = y - x[:, :N_OUT]
        self.target_mean = d.mean(axis=0)
        scale = d.std(axis=0)
        self.target_scale = np.where(scale > 0, scale, 1.0)
        return (d - self.target_mean) / self.target_scale

    def _output(self, x, z_out):
        return x[:, :N_OUT] + z_out * self.target_scale + self.target_mean

    def _scaling_arrays(self):
        return {"target_mean": self.target_mean, "target_scale": self.target_scale}

    def _load_scaling(self, arrays):
        self.target_mean = get_array(arrays, "target_mean", (N_OUT,))
        self.target_scale = get_array(arrays, "target_scale", (N_OUT,))
        if np.any(self.target_scale <= 0):
            raise ValueError("target_scale must be positive")


def _subsample(n: int, most: int | None) -> np.ndarray:
    """Evenly spaced indices of at most ``most`` of n samples (all if None)."""
    if most is None or n <= most:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, int(most))).astype(int))


def _prefixed(prefix, arrays):
    return {f"{prefix}{k}": v for k, v in arrays.items()}


def _unprefixed(prefix, arrays):
    return {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}


class _NetworkResidual(_Residual):
    """A residual compensator around one network (``net``: fit/predict/to_payload),
    trained on at most ``_limit()`` evenly spaced samples."""

    net_class = None

    def _limit(self) -> int | None:
        raise NotImplementedError

    def _fit(self, x, y):
        z = self._targets(x, y)
        idx = _subsample(len(x), self._limit())
        self.net.fit(x[idx], z[idx])

    def _predict(self, x):
        return self._output(x, self.net.predict(x))

    def _payload(self):
        meta, arrays = self.net.to_payload()
        return {"net": meta}, _prefixed("net.", arrays) | self._scaling_arrays()

    @classmethod
    def _from_payload(cls, meta, arrays):
        out = cls()
        out.net = cls.net_class.from_payload(meta["net"], _unprefixed("net.", arrays))
        out._load_scaling(arrays)
        return out


class RBFCompensator(_NetworkResidual):
    """RBF network (seed 003: spread 60, 30 neurons, goal 1e-5 on the standardised correction).

    ``max_samples``: evenly spaced training samples used (all when None).
    """

    kind = "rbf"
    net_class = RBFNetwork

    def __init__(self, spread: float = 60.0, max_neurons: int = 30, goal: float = 1e-5, *,
                 max_samples: int | None = 50000, max_candidates: int = 2000):
        super().__init__()
        self.net = RBFNetwork(spread, goal, max_neurons, max_candidates=max_candidates)
        self.max_samples = max_samples

    def _limit(self):
        return self.max_samples


class GRNNCompensator(_NetworkResidual):
    """GRNN (seed 003: smoothing factor 0.07, standardised inputs).

    ``max_patterns``: evenly spaced training samples kept as the pattern
    layer (all when None); prediction costs one exp per query-pattern pair.
    """

    kind = "grnn"
    net_class = GRNN

    def __init__(self, sigma: float = 0.07, *, max_patterns: int | None = 20000):
        super().__init__()
        self.net = GRNN(sigma)
        self.max_patterns = max_patterns

    def _limit(self):
        return self.max_patterns


class RecurrentCompensator(_Residual):
    """LSTM or GRU, ``layers`` (1 or 3) stacked layers of ``hidden`` units (seed 003: 60, MSE, NAdam, 4000 steps).

    ``threads``: torch intra-op threads while training (default 1: the
    network is small, and on a shared machine more threads mostly contend).
    ``memory=False``: the control without memory (every sample from a zero
    state, :func:`.recurrent.train`), not seed 003's method.
    """

    def __init__(self, cell: str = "gru", *, hidden: int = 60, layers: int = 1, steps: int = 4000,
                 seq_len: int = 100, streams: int = 32, lr: float = 2e-3, seed: int = 0, threads: int = 1,
                 memory: bool = True):
        super().__init__()
        self.cell = recurrent._check_cell(cell)
        if (self.cell, int(layers)) not in RECURRENT_KINDS.values():
            raise ValueError(f"layers must be 1 or 3 (seed 003's two readings of its '3-layer recurrent hidden "
                             f"layer'), got {layers}")
        self.options = dict(hidden=int(hidden), layers=int(layers), steps=int(steps), seq_len=int(seq_len),
                            streams=int(streams), lr=float(lr), seed=int(seed), threads=int(threads),
                            memory=bool(memory))
        self.weights: recurrent.RecurrentWeights | None = None
        self.losses: np.ndarray | None = None
        self.input_mean: np.ndarray | None = None
        self.input_scale: np.ndarray | None = None

    @property
    def kind(self):
        return next(k for k, v in RECURRENT_KINDS.items() if v == (self.cell, self.options["layers"]))

    def _fit(self, x, y):
        recurrent.require_torch()
        z_out = self._targets(x, y)
        self.input_mean = x.mean(axis=0)
        scale = x.std(axis=0)
        self.input_scale = np.where(scale > 0, scale, 1.0)
        self.weights, self.losses = recurrent.train(self.cell, self._z(x), z_out, **self.options)

    def _z(self, x):
        return (x - self.input_mean) / self.input_scale

    def _predict(self, x):
        if self.weights is None:
            raise RuntimeError(f"{self.cell} compensator is not fitted")
        return self._output(x, recurrent.run(self.weights, self._z(x), self.options["memory"]))

    @property
    def n_parameters(self) -> int:
        """Trainable parameters (recurrent layer + linear output), as the paper counts them."""
        w = self.weights
        if w is None:
            return recurrent.n_parameters(self.cell, N_IN, self.options["hidden"], N_OUT, self.options["layers"])
        return recurrent.n_parameters(self.cell, w.n_in, w.hidden, w.n_out, w.layers)

    def stream(self) -> "RecurrentStream":
        return RecurrentStream(self)

    def _payload(self):
        if self.weights is None:
            raise RuntimeError(f"{self.cell} compensator is not fitted: nothing to save")
        arrays = _prefixed("net.", self.weights.arrays()) | self._scaling_arrays()
        arrays |= {"input_mean": self.input_mean, "input_scale": self.input_scale}
        return {"cell": self.cell, "options": self.options}, arrays

    @classmethod
    def _from_payload(cls, meta, arrays):
        out = cls(meta["cell"], **({"layers": 1, "memory": True} | meta["options"]))  # older files lack both
        out.weights = recurrent.RecurrentWeights(meta["cell"], _unprefixed("net.", arrays))
        if out.weights.n_in != N_IN or out.weights.n_out != N_OUT:
            raise ValueError(f"recurrent weights map {out.weights.n_in} -> {out.weights.n_out}, "
                             f"expected {N_IN} -> {N_OUT}")
        if out.weights.layers != out.options["layers"]:
            raise ValueError(f"the file holds {out.weights.layers} recurrent layers, its options say "
                             f"{out.options['layers']}")
        out.input_mean = get_array(arrays, "input_mean", (N_IN,))
        out.input_scale = get_array(arrays, "input_scale", (N_IN,))
        out._load_scaling(arrays)
        return out


class RecurrentStream(Stream):
    """Sample-by-sample recurrent compensation: the hidden state is carried (numpy cells)."""

    def reset(self) -> None:
        self._state = self.model.weights.zero_state(1)

    def step(self, x) -> np.ndarray:
        x = _check_xy(np.asarray(x, float).reshape(1, N_IN))
        if not self.model.options["memory"]:
            self.reset()
        z_out, self._state = self.model.weights.step(self.model._z(x), self._state)
        return self.model._output(x, z_out)[0]


_CLASSES = {"traditional": TraditionalCompensator, "rbf": RBFCompensator, "grnn": GRNNCompensator} | {
    kind: RecurrentCompensator for kind in RECURRENT_KINDS}


def make(kind: str, **options) -> Compensator:
    """A new, unfitted compensator of one of :data:`KINDS` (seed 003's settings by default)."""
    if kind not in _CLASSES:
        raise ValueError(f"unknown compensator {kind!r}; choose one of {', '.join(KINDS)}")
    if kind in RECURRENT_KINDS:
        cell, layers = RECURRENT_KINDS[kind]
        if options.get("layers", layers) != layers:
            raise ValueError(f"{kind} has {layers} recurrent layer(s); choose the kind, not 'layers'")
        return RecurrentCompensator(cell, **(options | {"layers": layers}))
    return _CLASSES[kind](**options)


def _build(meta, arrays):
    kind = meta["kind"]
    if kind not in _CLASSES:
        raise ValueError(f"unknown compensator kind {kind!r}")
    model = meta["model"]
    if not isinstance(model, dict):
        raise ValueError("'model' is not an object")
    out = _CLASSES[kind]._from_payload(model, arrays)
    seconds = meta.get("fit_seconds")
    out.fit_seconds = float(seconds) if isinstance(seconds, (int, float)) else None
    return out


def load(path: str | Path) -> Compensator:
    """Read any compensator written by :meth:`Compensator.save`.

    Raises ModelFileError (a ValueError) naming the file when it is missing,
    corrupt or of another kind.
    """
    return load_model_file(path, FORMAT_TAG, {FORMAT_VERSION}, _build)
