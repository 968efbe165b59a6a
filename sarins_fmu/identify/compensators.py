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

``fit(X, Y)`` trains (Python, torch for the recurrent models), ``predict(X)``
compensates a time-ordered series (the recurrent models carry their state
along it, from a zero state), ``stream()`` gives a stateful
one-sample-at-a-time compensator, ``save``/``load`` write plain data (JSON or
npz, :mod:`.modelfile`), never pickle.  ``binary()`` / ``export_binary(path)``
give the model as the binary model file (:mod:`.netfile`) that the
IMUCompensator FMU reads; ``predict`` and ``stream`` evaluate exactly that
file with the C core (``sarins_comp_run``, float64), so the in-process and the
co-simulated compensation are the same numbers bit for bit.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from . import netfile, recurrent
from .calibration import TriadCalibration, compensate_triad
from .grnn import GRNN, GRNN_TOLERANCE
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
        self.fit_cpu_seconds: float | None = None  # CPU seconds of the fitting thread (torch: one thread)
        self._c_model = None

    def fit(self, X, Y) -> "Compensator":
        """Fit on inputs X (n, 7) and targets Y (n, 6): arrays, or (the recurrent and residual networks)
        row sources -- objects with ``shape`` whose row slices are arrays, e.g. a stored set read from disk a
        slice at a time -- checked and summed a block at a time, the same numbers as on the arrays."""
        x, y = _check_rows(X, Y) if _is_rows(X) or _is_rows(Y) else _check_xy(X, Y)
        t0, cpu0 = time.perf_counter(), time.thread_time()
        self._fit(x, y)
        self.fit_seconds = time.perf_counter() - t0
        self.fit_cpu_seconds = time.thread_time() - cpu0
        self._c_model = None
        return self

    def predict(self, X) -> np.ndarray:
        """Compensated outputs (n, 6) of a time-ordered series of inputs (n, 7), by the C core."""
        return self.native().run(_check_xy(X))

    def predict_batch(self, X) -> np.ndarray:
        """:meth:`predict` of a whole series as the campaigns evaluate it: the same computation, except for
        the GRNN (:meth:`GRNNCompensator.predict_batch`: truncated, exact to a stated bound)."""
        return self.predict(X)

    def predict_batch_chunks(self, chunks):
        """:meth:`predict_batch` of one series given as consecutive chunks of rows (an iterable of (m, 7)
        arrays), yielded chunk by chunk: the rows :meth:`predict_batch` gives for the whole series, bit for bit
        (the recurrent state carried from chunk to chunk), with nothing series-long held."""
        native = self.native()
        state = native.zero_state()
        for x in chunks:
            yield native.run(_check_xy(x), state)

    def binary_arrays(self) -> dict:
        """The arrays of the binary model file (layout in ``sarins_fmu/core/netmodel.h``)."""
        return self._binary_arrays()

    def binary(self) -> bytes:
        """The binary model file's bytes (:mod:`.netfile`, kind :attr:`kind`)."""
        return netfile.to_bytes(self.kind, self.binary_arrays())

    def export_binary(self, path: str | Path) -> Path:
        """Write the binary model file the IMUCompensator FMU reads; returns its path."""
        return netfile.write(path, self.kind, self.binary_arrays())

    def native(self):
        """The model built by the C core from :meth:`binary` (kept until the next fit)."""
        if self._c_model is None:
            from sarins_fmu.core.nets import CompensatorModel

            self._c_model = CompensatorModel(self.binary(), f"<{self.kind} compensator>")
        return self._c_model

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_c_model"] = None  # a C handle does not cross processes; rebuilt on first use
        return state

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

    # subclasses: _fit, _binary_arrays, _payload, _from_payload


class Stream:
    """Sample-by-sample compensation by the C core; the recurrent state (zero at the start) is carried
    from sample to sample, as in the IMUCompensator FMU."""

    def __init__(self, model: Compensator):
        self.model = model
        self._c_model = model.native()
        self.reset()

    def reset(self) -> None:
        self._state = self._c_model.zero_state()

    def step(self, x) -> np.ndarray:
        """Compensated (6,) outputs of one (7,) input sample."""
        x = _check_xy(np.asarray(x, float).reshape(1, N_IN))
        return self._c_model.run(x, self._state)[0]


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

    def predict_triads(self, X) -> np.ndarray:
        """:func:`.calibration.compensate_triad` on both triads (the same C function as :meth:`predict`)."""
        x = _check_xy(X)
        if self.gyro is None:
            raise RuntimeError("traditional compensator is not fitted")
        return np.column_stack([compensate_triad(self.gyro, x[:, :3]), compensate_triad(self.accel, x[:, 3:6])])

    def _binary_arrays(self):
        if self.gyro is None:
            raise RuntimeError("traditional compensator is not fitted")
        return {"gyro_bias": self.gyro.bias, "gyro_matrix": self.gyro.matrix, "accel_bias": self.accel.bias,
                "accel_matrix": self.accel.matrix}

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
        """The standardised correction ((y - x[:, :6]) - mean) / scale as a :class:`_Correction` (its rows
        computed when sliced); its mean and std summed a block at a time (:func:`column_stats`): the numbers of
        ``d.mean(axis=0)``, ``d.std(axis=0)`` and the in-place standardisation of the whole d, without it."""
        self.target_mean, scale = column_stats(lambda a, b: y[a:b] - x[a:b][:, :N_OUT], len(x))
        self.target_scale = np.where(scale > 0, scale, 1.0)
        return _Correction(x, y, self.target_mean, self.target_scale)

    def _output(self, x, z_out):
        return x[:, :N_OUT] + z_out * self.target_scale + self.target_mean

    def _scaling_arrays(self):
        return {"target_mean": self.target_mean, "target_scale": self.target_scale}

    def _binary_arrays(self):
        if self.target_mean is None:
            raise RuntimeError(f"{self.kind} compensator is not fitted")
        return self._scaling_arrays() | _prefixed("net.", self._net_binary_arrays())

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


STATS_ROWS = 1 << 16  # rows summed at once by :func:`column_stats`


def column_stats(rows, n: int, block: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(mean, std) over the rows of an (n, d) series (d >= 2) given as ``rows(a, b)`` (rows a .. b - 1, a
    C-ordered float64 array): the numbers of ``x.mean(axis=0)`` and ``x.std(axis=0)`` on the whole array,
    bit for bit (numpy sums a C-ordered array along axis 0 row after row: the running sum carried from block
    to block is the same sum; tests/test_compensators.py), with block-long temporaries only."""
    block = STATS_ROWS if block is None else block
    total = None
    for a in range(0, n, int(block)):
        part = rows(a, min(a + int(block), n))
        total = np.add.reduce(part if total is None else np.concatenate([total[None], part]), axis=0)
    mean = total / n  # np.mean: the sum divided by the count
    keep = total[None] / n  # np.var's mean (kept dimension): the same division
    squares = None
    for a in range(0, n, int(block)):
        dev = rows(a, min(a + int(block), n)) - keep
        np.multiply(dev, dev, out=dev)
        squares = np.add.reduce(dev if squares is None else np.concatenate([squares[None], dev]), axis=0)
    return mean, np.sqrt(squares / n)


class _Correction:
    """The standardised correction ((y - x[:, :6]) - mean) / scale of :meth:`_Residual._targets`, computed on
    the rows sliced out only (the same operations in the same order as on the whole series)."""

    def __init__(self, x, y, mean: np.ndarray, scale: np.ndarray):
        self.x, self.y, self.mean, self.scale = x, y, mean, scale

    @property
    def shape(self) -> tuple:
        return (self.x.shape[0], N_OUT)

    def __len__(self) -> int:
        return self.x.shape[0]

    def __getitem__(self, rows) -> np.ndarray:
        d = self.y[rows] - self.x[rows][:, :N_OUT]
        d -= self.mean
        d /= self.scale
        return d


def _is_rows(value) -> bool:
    """A row source (not an array or nested sequence): ``shape`` and row slices."""
    return hasattr(value, "shape") and hasattr(value, "__getitem__") and not isinstance(value, np.ndarray)


class _Rows:
    """A row source as float64 rows (fancy indices read in order)."""

    def __init__(self, source):
        self.source, self.shape = source, tuple(source.shape)

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, rows) -> np.ndarray:
        return np.ascontiguousarray(self.source[rows], dtype=float)


def _check_rows(X, Y):
    """:func:`_check_xy` of row sources, a block at a time (shapes, finite values); as row sources."""
    x = _Rows(X) if _is_rows(X) else _check_xy(X)
    y = _Rows(Y) if _is_rows(Y) else np.asarray(Y, dtype=float)
    n = x.shape[0]
    if len(x.shape) != 2 or x.shape[1] != N_IN or n == 0:
        raise ValueError(f"X must have shape (n, {N_IN}) with n > 0, got {x.shape}")
    if tuple(y.shape) != (n, N_OUT):
        raise ValueError(f"Y must have shape ({n}, {N_OUT}), got {tuple(y.shape)}")
    for a in range(0, n, STATS_ROWS):
        _check_xy(x[a:a + STATS_ROWS], y[a:a + STATS_ROWS])
    return x, y


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

    def _net_binary_arrays(self):
        net = self.net
        return {"mean": net.scaling_.mean, "scale": net.scaling_.scale, "centers": net.centers_,
                "weights": np.asarray(net.weights_, float).reshape(net.centers_.shape[0], np.size(net.bias_)),
                "bias": np.atleast_1d(net.bias_), "spread": np.float64(net.settings.spread)}


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

    def predict_batch(self, X, *, tolerance: float = GRNN_TOLERANCE, return_kept: bool = False):
        """:meth:`predict` with the GRNN truncated to ``tolerance`` (:mod:`.grnn`: each standardised correction
        within ``tolerance`` times its training range of the dense one, so each output within ``tolerance``
        times that range times the target scale), by the C core over k-d tree candidates; the IMUCompensator
        FMU and :meth:`predict` evaluate it dense.  ``return_kept``: also each row's kept patterns."""
        from .grnn import predict_truncated

        x = _check_xy(X)
        model, net = self.native(), self.net
        y, kept = predict_truncated(net.scaling_.apply(x), net._z_train, net.settings.sigma,
                                    lambda rows, blocks: model.run_grnn_blocks(x[rows], blocks), tolerance=tolerance)
        return (y, kept) if return_kept else y

    def predict_batch_chunks(self, chunks, *, tolerance: float = GRNN_TOLERANCE):
        """:meth:`predict_batch` chunk by chunk (see :meth:`Compensator.predict_batch_chunks`): every chunk but
        the last a whole number of the truncation's chunks (:data:`.grnn.CHUNK_ROWS` rows), so the rows are
        those of the whole series bit for bit."""
        from .grnn import CHUNK_ROWS

        last = None
        for x in chunks:
            if last is not None and last % CHUNK_ROWS:
                raise ValueError(f"GRNN chunks must be whole multiples of {CHUNK_ROWS} rows (but the last), "
                                 f"got one of {last}")
            out = self.predict_batch(x, tolerance=tolerance)
            last = len(out)
            yield out

    def _net_binary_arrays(self):
        net = self.net
        return {"mean": net.scaling_.mean, "scale": net.scaling_.scale, "x_train": net.x_train_,
                "y_train": net.y_train_, "sigma": np.float64(net.settings.sigma)}


class _Standardised:
    """The inputs standardised as :meth:`RecurrentCompensator._z` does, (x - mean) / scale, computed on the
    rows sliced out only: the recurrent fit converts its training windows a stream at a time
    (:func:`.recurrent.train`) without a float64 copy of the whole series."""

    def __init__(self, x: np.ndarray, mean: np.ndarray, scale: np.ndarray):
        self.x, self.mean, self.scale = x, mean, scale

    @property
    def shape(self) -> tuple:
        return self.x.shape

    def __getitem__(self, rows) -> np.ndarray:
        z = self.x[rows] - self.mean
        z /= self.scale
        return z


class RecurrentCompensator(_Residual):
    """LSTM or GRU, ``layers`` (1 or 3) stacked layers of ``hidden`` units (seed 003: 60, MSE, NAdam, 4000 steps).

    ``threads``: torch intra-op threads while training (default 1: the
    network is small, and on a shared machine more threads mostly contend).
    ``memory=False``: the control without memory (every sample from a zero
    state, :func:`.recurrent.train`), not seed 003's method.
    ``device``: where torch trains it (:func:`.recurrent.training_device`;
    the prediction always runs on the CPU, in the C core).
    """

    def __init__(self, cell: str = "gru", *, hidden: int = 60, layers: int = 1, steps: int = 4000,
                 seq_len: int = 100, streams: int = 32, lr: float = 2e-3, seed: int = 0, threads: int = 1,
                 memory: bool = True, device: str = "cpu"):
        super().__init__()
        self.cell = recurrent._check_cell(cell)
        if (self.cell, int(layers)) not in RECURRENT_KINDS.values():
            raise ValueError(f"layers must be 1 or 3 (seed 003's two readings of its '3-layer recurrent hidden "
                             f"layer'), got {layers}")
        self.options = dict(hidden=int(hidden), layers=int(layers), steps=int(steps), seq_len=int(seq_len),
                            streams=int(streams), lr=float(lr), seed=int(seed), threads=int(threads),
                            memory=bool(memory), device=str(device))
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
        self.input_mean, scale = column_stats(lambda a, b: x[a:b], len(x))  # x.mean(axis=0), x.std(axis=0)
        self.input_scale = np.where(scale > 0, scale, 1.0)
        self.weights, self.losses = recurrent.train(self.cell, _Standardised(x, self.input_mean, self.input_scale),
                                                    z_out, **self.options)

    def _z(self, x):
        z = x - self.input_mean
        z /= self.input_scale  # in place: the same numbers as (x - mean) / scale
        return z

    def predict_batch_streams(self, sources):
        """:meth:`predict_batch_chunks` of up to eight independent series side by side (the campaign's test
        sets): ``sources`` a list of iterables of (m, 7) chunks, one per series.  Yields, for each call of
        the C core, a list of (series index, output rows), each series' rows in its order and bit for bit
        those :meth:`predict_batch_chunks` gives it alone (``sarins_comp_run_streams``: the series advance
        in lockstep, sharing each block of the weights while it is in cache; a series that ends leaves the
        others to go on)."""
        native = self.native()
        chunks = [iter(source) for source in sources]
        states = [native.zero_state() for _ in chunks]
        pending: list = [np.empty((0, N_IN)) for _ in chunks]
        active = list(range(len(chunks)))
        while active:
            for k in list(active):
                while len(pending[k]) == 0:
                    chunk = next(chunks[k], None)
                    if chunk is None:
                        active.remove(k)
                        break
                    pending[k] = _check_xy(chunk)
            if not active:
                return
            m = min(len(pending[k]) for k in active)
            outs = native.run_streams([pending[k][:m] for k in active], [states[k] for k in active])
            yield list(zip(active, outs))
            for k in active:
                pending[k] = pending[k][m:]

    def predict_reference(self, X) -> np.ndarray:
        """:meth:`predict` by the numpy cells (:meth:`.recurrent.RecurrentWeights.step`, float64, BLAS sums):
        the reference the C core is tested against (equal to rounding, bound in tests/test_nets.py)."""
        x = _check_xy(X)
        w = self.weights
        if not self.options["memory"]:
            return self._output(x, w.step(self._z(x), w.zero_state(len(x)))[0])
        return self._output(x, w.run(self._z(x)))

    def predict_torch(self, X) -> np.ndarray:
        """:meth:`predict` by torch (float32, :func:`.recurrent.run`): faster on long series, equal to
        float32 rounding only."""
        x = _check_xy(X)
        return self._output(x, recurrent.run(self.weights, self._z(x), self.options["memory"]))

    def _binary_arrays(self):
        if self.weights is None:
            raise RuntimeError(f"{self.cell} compensator is not fitted")
        return (_prefixed("net.", self.weights.arrays()) | self._scaling_arrays()
                | {"input_mean": self.input_mean, "input_scale": self.input_scale,
                   "memory": np.float64(1.0 if self.options["memory"] else 0.0)})

    @property
    def n_parameters(self) -> int:
        """Trainable parameters (recurrent layer + linear output), as the paper counts them."""
        w = self.weights
        if w is None:
            return recurrent.n_parameters(self.cell, N_IN, self.options["hidden"], N_OUT, self.options["layers"])
        return recurrent.n_parameters(self.cell, w.n_in, w.hidden, w.n_out, w.layers)

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
