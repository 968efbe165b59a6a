r"""Specht's general regression neural network (GRNN), seed 003 eqs (3)-(6).

For training pairs :math:`(x_i, y_i)`, i = 1..n, and a query x:

.. math::

    P_i = \exp\!\left(-\frac{D_i^2}{2\sigma^2}\right), \quad
    D_i^2 = \lVert z(x) - z(x_i) \rVert^2 \quad \text{(pattern layer, eq. 3)}

    S_D = \sum_i P_i, \qquad S_j = \sum_i y_{ij} P_i
    \quad \text{(summation layer, eqs 4-5)}

    \hat y_j = S_j / S_D \quad \text{(output layer, eq. 6)}

which is the Nadaraya-Watson kernel regression estimate (Specht 1991,
IEEE Trans. Neural Networks 2(6)). :math:`z` standardises each input column
with the training mean and standard deviation (``standardize=True``, the
default), so :math:`\sigma` is in standardised units; the seed's
σ = 0.07 is the default.

MATLAB's ``newgrnn(P, T, spread)`` uses ``exp(-ln 2 (D / spread)^2)``
instead; :meth:`GRNN.from_matlab_spread` converts
(σ = spread / sqrt(2 ln 2)).

Numerics
    Each query's exponents are shifted by their maximum before ``exp``
    (the log-sum-exp trick), which leaves the ratio unchanged and makes the
    largest weight exactly 1, so :math:`S_D \ge 1`: no 0/0 and no underflow
    to NaN. **Far from every training sample** the output therefore tends to
    the target of the nearest sample (ties averaged) instead of failing; it
    is an extrapolation, flagged by ``return_distance=True`` (distance to the
    nearest training sample in standardised units, compare with σ).

Truncation, exact to a bound (:meth:`GRNN.predict_truncated`, the campaigns' evaluation)
    With the weights normalised by the largest, :math:`w_j = P_j / \max P \in (0, 1]` (the nearest
    pattern's is exactly 1), every pattern whose weight is below :math:`c = \tau / n` (n patterns, relative
    tolerance :math:`\tau`, default :data:`GRNN_TOLERANCE` = 1e-9) is left out: those with
    :math:`D_j^2 > D_{min}^2 + R^2`, :math:`R^2 = 2\sigma^2 \ln(n / \tau)`.  Of the dense sums, the kept
    part :math:`S_K \ge 1` remains and the dropped part :math:`S_R = \sum_{dropped} w_j < (n - k) c \le \tau`
    goes (k kept).  The dense estimate is :math:`\hat y = (S_K \hat y_K + S_R \bar y_R) / (S_K + S_R)`,
    :math:`\bar y_R` the weighted mean of the dropped targets, so

    .. math::

        \hat y_o - \hat y_{K,o} = \frac{S_R}{S_K + S_R} (\bar y_{R,o} - \hat y_{K,o}), \qquad
        |\hat y_o - \hat y_{K,o}| < (n - k)\, c\, (\max_j y_{jo} - \min_j y_{jo}) \le \tau\, \mathrm{range}_o

    (both means lie within the targets' range, and :math:`S_R / (S_K + S_R) \le S_R`).  The prediction
    moves by less than τ times the range of each output's training targets; both are evaluated in float64
    (the kept terms are the dense kernel's, in the same order, so the rounding of the two differs only by the
    missing terms).

    The candidates come from a k-d tree (``scipy.spatial.cKDTree``) in one vectorised call per chunk:
    the queries, taken in blocks of :data:`SEARCH_BLOCK` consecutive rows (a time series: neighbours), each
    block with its centre c and radius ρ (largest distance of a row to c) and the centre's nearest-pattern
    distance :math:`D_c`.  A row q of the block has :math:`D_{min}(q) \le \rho + D_c`, so every pattern it
    keeps lies within :math:`\rho + \sqrt{(\rho + D_c)^2 + R^2}` of c, and so does its nearest pattern
    (within :math:`2\rho + D_c`): one ball query per block finds a superset, sorted by pattern index, and the
    C kernel (``sarins_grnn_eval_gathered``) applies the exact cut per row.  The radius is relative to the
    nearest distance, so a query far from every pattern still finds its nearest one; a fixed number of
    nearest neighbours would not be exact (the rate-table data hold many near-duplicate patterns).

Memory
    Queries are processed in chunks so that at most ``chunk_elements``
    query-sample pairs are held at once (default 2**22, one 32 MB array,
    computed in place), so 1e5 training samples by 1e5 queries run in
    bounded memory. The cost is one ``exp`` per query-sample pair
    (about 1.5 ns each on one core: 1e10 pairs take minutes).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from itertools import chain
from pathlib import Path

import numpy as np

from .modelfile import get_array, load_model_file, save_model_file
from .preprocessing import Scaling, check_inputs, check_targets, fit_scaling

__all__ = ["GRNNSettings", "GRNN", "grnn_predict", "Blocks", "neighbour_blocks", "predict_truncated",
           "GRNN_TOLERANCE"]

FORMAT_TAG = "sarins_fmu.identify.grnn"
FORMAT_VERSION = 1

SEED003_SIGMA = 0.07  # smoothing factor of seed 003's GRNN, standardised units
GRNN_TOLERANCE = 1e-9  # truncation: the prediction moves by less than this times each output's target range
SEARCH_BLOCK = 256  # consecutive query rows sharing one k-d tree ball query (benchmarks/bench_grnn.py --blocks)
CHUNK_ROWS = 2**17  # query rows searched and evaluated at once (memory bound: a few (rows, d) arrays)
RADIUS_MARGIN = 1e-9  # relative widening of the ball radius against the tree's own distance rounding


@dataclass(frozen=True)
class GRNNSettings:
    """Settings of :class:`GRNN`.

    Attributes
    ----------
    sigma : float
        Smoothing factor σ (standardised units when ``standardize`` is on).
    standardize : bool
        Standardise each input column with its training mean and std.
    chunk_elements : int
        Most query-sample pairs evaluated at once (memory bound).
    """

    sigma: float = SEED003_SIGMA
    standardize: bool = True
    chunk_elements: int = 2**22

    def __post_init__(self) -> None:
        if not (np.isfinite(self.sigma) and self.sigma > 0.0):
            raise ValueError(f"sigma must be positive and finite, got {self.sigma!r}")
        if int(self.chunk_elements) < 1:
            raise ValueError(f"chunk_elements must be >= 1, got {self.chunk_elements!r}")


def grnn_predict(
    z_query: np.ndarray,
    z_train: np.ndarray,
    y_train: np.ndarray,
    sigma: float,
    chunk_elements: int = 2**22,
) -> tuple[np.ndarray, np.ndarray]:
    """Nadaraya-Watson / GRNN estimate, chunked and max-shifted.

    Parameters
    ----------
    z_query : ndarray, shape (q, d)
        Query inputs (already standardised, if standardising).
    z_train : ndarray, shape (n, d)
        Training inputs, same units.
    y_train : ndarray, shape (n, m)
        Training targets.
    sigma : float
        Smoothing factor, same unit as the inputs.
    chunk_elements : int
        Most query-sample pairs held at once.

    Returns
    -------
    y : ndarray, shape (q, m)
        Estimates.
    nearest : ndarray, shape (q,)
        Distance of each query to its nearest training sample.
    """
    q = z_query.shape[0]
    out = np.empty((q, y_train.shape[1]))
    nearest = np.empty(q)
    rows = max(1, int(chunk_elements) // z_train.shape[0])
    inv_two_var = 1.0 / (2.0 * sigma**2)
    # distances are translation invariant: centre on the training mean so the
    # expansion |a|^2 + |b|^2 - 2 a.b loses no precision to a large offset
    offset = z_train.mean(axis=0)
    zt = z_train - offset
    zt_sq = np.einsum("ij,ij->i", zt, zt)
    for start in range(0, q, rows):
        sl = slice(start, min(start + rows, q))
        zq = z_query[sl] - offset
        # D^2 = |zq|^2 + |zt|^2 - 2 zq.zt, built in place in one (rows, n) array
        d2 = zq @ zt.T
        d2 *= -2.0
        d2 += zt_sq
        d2 += np.einsum("ij,ij->i", zq, zq)[:, None]
        np.maximum(d2, 0.0, out=d2)
        d2_min = d2.min(axis=1)
        # P_i / max_i P_i = exp(-(D_i^2 - min D^2) / (2 sigma^2)): the largest weight is 1
        w = np.subtract(d2_min[:, None], d2, out=d2)
        w *= inv_two_var
        np.exp(w, out=w)
        # y_j = S_j / S_D, with S_D >= 1
        out[sl] = (w @ y_train) / w.sum(axis=1)[:, None]
        nearest[sl] = np.sqrt(d2_min)
    return out, nearest


@dataclass(frozen=True)
class Blocks:
    """Candidate patterns of blocks of consecutive query rows (CSR layout, int64).

    Rows ``row_ptr[b] .. row_ptr[b+1]-1`` share the candidates ``cand[cand_ptr[b] .. cand_ptr[b+1]-1]``
    (ascending pattern indices); ``log_cut`` is ln c, c the smallest kept weight relative to the largest.
    """

    row_ptr: np.ndarray
    cand_ptr: np.ndarray
    cand: np.ndarray
    log_cut: float


def log_cut(n_patterns: int, tolerance: float) -> float:
    """ln c, c = tolerance / n: the weight (relative to the largest) below which a pattern is dropped."""
    if not (np.isfinite(tolerance) and 0.0 < tolerance < 1.0):
        raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
    return float(np.log(tolerance / int(n_patterns)))


def neighbour_blocks(tree, z_query: np.ndarray, sigma: float, tolerance: float = GRNN_TOLERANCE,
                     block: int = SEARCH_BLOCK) -> Blocks:
    """Candidates of the truncated GRNN for the standardised queries ``z_query`` (q >= 1, d): per block of
    ``block`` consecutive rows, every pattern of ``tree`` (a ``cKDTree`` of the standardised patterns) within
    rho + sqrt((rho + D_c)^2 + R^2) of the block's centre (module docstring), by one ball query."""
    q, d = z_query.shape
    starts = np.arange(0, q, int(block))
    counts = np.diff(np.append(starts, q))
    centres = np.add.reduceat(z_query, starts, axis=0) / counts[:, None]
    rows_off = z_query - np.repeat(centres, counts, axis=0)
    rho = np.sqrt(np.maximum.reduceat(np.einsum("ij,ij->i", rows_off, rows_off), starts))
    cut = log_cut(tree.n, tolerance)
    r2 = -2.0 * sigma**2 * cut  # R^2 = 2 sigma^2 ln(n / tol)
    d_c, _ = tree.query(centres, k=1)
    radius = (rho + np.sqrt((rho + d_c) ** 2 + r2)) * (1.0 + RADIUS_MARGIN)
    lists = tree.query_ball_point(centres, radius, return_sorted=True)
    sizes = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
    cand = np.fromiter(chain.from_iterable(lists), dtype=np.int64, count=int(sizes.sum()))
    return Blocks(np.append(starts, q).astype(np.int64), np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
                  cand, cut)


def predict_truncated(z_query: np.ndarray, z_train: np.ndarray, sigma: float, evaluate, *,
                      tolerance: float = GRNN_TOLERANCE, block: int = SEARCH_BLOCK, chunk_rows: int = CHUNK_ROWS,
                      threads: int | None = None):
    """Run ``evaluate(rows, blocks) -> (y, kept)`` over chunks of the queries with their candidates
    (:func:`neighbour_blocks`); ``rows`` is the slice of query rows.  Chunks run on ``threads`` threads
    (default ``SARINS_THREADS`` or every core; the tree search and the C kernel release the GIL); the result
    does not depend on the number.  Returns (y, kept) stacked in row order."""
    from concurrent.futures import ThreadPoolExecutor

    from scipy.spatial import cKDTree

    from sarins_fmu.core.imu import thread_count

    tree = cKDTree(z_train)
    if not len(z_query):
        empty = np.zeros(1, dtype=np.int64)
        return evaluate(slice(0, 0), Blocks(empty, empty, np.empty(0, dtype=np.int64),
                                            log_cut(tree.n, tolerance)))
    step = max(int(block), int(chunk_rows) // int(block) * int(block))
    chunks = [slice(s, min(s + step, len(z_query))) for s in range(0, len(z_query), step)]

    def one(rows):
        return evaluate(rows, neighbour_blocks(tree, z_query[rows], sigma, tolerance, block))

    workers = min(len(chunks), thread_count() if threads is None else int(threads))
    if workers <= 1:
        parts = [one(rows) for rows in chunks]
    else:
        with ThreadPoolExecutor(workers) as pool:
            parts = list(pool.map(one, chunks))
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


class GRNN:
    """General regression neural network with optional multi-output targets.

    Parameters
    ----------
    sigma : float, default 0.07
        Smoothing factor (standardised units when ``standardize`` is on).
    standardize : bool, default True
        Standardise inputs inside the model (stored in the model file).
    chunk_elements : int, default 2**22
        Memory bound for prediction.

    Attributes
    ----------
    x_train_ : ndarray, shape (n, d)
        Training inputs, in their own units.
    y_train_ : ndarray, shape (n, m)
        Training targets.
    scaling_ : Scaling
        Input standardisation.
    input_names, output_names : tuple of str or None
        Column names, if given to :meth:`fit`.
    """

    def __init__(
        self, sigma: float = SEED003_SIGMA, *, standardize: bool = True, chunk_elements: int = 2**22
    ) -> None:
        self.settings = GRNNSettings(float(sigma), bool(standardize), int(chunk_elements))
        self.x_train_: np.ndarray | None = None
        self.y_train_: np.ndarray | None = None
        self.scaling_: Scaling | None = None
        self._z_train: np.ndarray | None = None
        self._single_output = False
        self.input_names: tuple[str, ...] | None = None
        self.output_names: tuple[str, ...] | None = None

    @classmethod
    def from_matlab_spread(cls, spread: float, **kwargs) -> "GRNN":
        """GRNN equal to MATLAB ``newgrnn(P, T, spread)`` (0.5 response at ``spread``)."""
        return cls(sigma=spread / np.sqrt(2.0 * np.log(2.0)), **kwargs)

    @property
    def n_features(self) -> int | None:
        """Number of inputs d (``None`` before fitting)."""
        return None if self.scaling_ is None else int(self.scaling_.mean.size)

    def __repr__(self) -> str:
        n = "unfitted" if self.x_train_ is None else f"samples={self.x_train_.shape[0]}"
        return f"GRNN(sigma={self.settings.sigma}, {n})"

    def fit(
        self,
        X: np.ndarray,
        Y: np.ndarray,
        *,
        input_names: list[str] | tuple[str, ...] | None = None,
        output_names: list[str] | tuple[str, ...] | None = None,
    ) -> "GRNN":
        """Store the training samples (a GRNN has no other training).

        Parameters
        ----------
        X : array_like, shape (n, d) or (n,)
            Training inputs.
        Y : array_like, shape (n, m) or (n,)
            Training targets; a 1-D ``Y`` makes :meth:`predict` return 1-D.
        input_names, output_names : sequence of str, optional
            Column names stored in the model file.

        Returns
        -------
        GRNN
            ``self``.
        """
        x = check_inputs(X, "X")
        y = check_targets(Y, x.shape[0], "Y", ndim=(1, 2))
        self._single_output = y.ndim == 1
        y2 = y[:, None] if y.ndim == 1 else y
        if input_names is not None and len(input_names) != x.shape[1]:
            raise ValueError(f"{len(input_names)} input names for {x.shape[1]} input columns")
        if output_names is not None and len(output_names) != y2.shape[1]:
            raise ValueError(f"{len(output_names)} output names for {y2.shape[1]} outputs")
        self.scaling_ = fit_scaling(x, self.settings.standardize)
        self.x_train_ = x.copy()
        self.y_train_ = y2.copy()
        self._z_train = self.scaling_.apply(x)
        self.input_names = None if input_names is None else tuple(map(str, input_names))
        self.output_names = None if output_names is None else tuple(map(str, output_names))
        return self

    def predict(self, X: np.ndarray, *, return_distance: bool = False):
        """GRNN estimate for each query row.

        Parameters
        ----------
        X : array_like, shape (q, d) or (q,)
            Queries, same units and column order as the training inputs.
        return_distance : bool, default False
            Also return each query's distance to the nearest training sample
            (standardised units): large compared with σ means extrapolation.

        Returns
        -------
        y : ndarray, shape (q, m), or (q,) if trained with 1-D targets
            Estimates, target units.
        nearest : ndarray, shape (q,)
            Only with ``return_distance=True``.
        """
        if self.x_train_ is None or self.scaling_ is None:
            raise RuntimeError("GRNN is not fitted: call fit() or load() first")
        x = check_inputs(X, "X", n_features=self.n_features)
        y, nearest = grnn_predict(
            self.scaling_.apply(x), self._z_train, self.y_train_, self.settings.sigma,
            self.settings.chunk_elements,
        )
        if self._single_output:
            y = y[:, 0]
        return (y, nearest) if return_distance else y

    def predict_dense(self, X: np.ndarray) -> np.ndarray:
        """The dense GRNN of the C core (``sarins_grnn_eval``: every pattern, direct differences, sums in
        pattern order), the IMUCompensator FMU's evaluation bit for bit; shape as :meth:`predict`.
        :func:`grnn_predict` (numpy) equals it to rounding (bound in tests/test_nets.py)."""
        from sarins_fmu.core import nets

        if self.x_train_ is None or self.scaling_ is None:
            raise RuntimeError("GRNN is not fitted: call fit() or load() first")
        x = check_inputs(X, "X", n_features=self.n_features)
        y = nets.grnn_predict_dense(x, self.scaling_.mean, self.scaling_.scale, self._z_train, self.y_train_,
                                    self.settings.sigma)
        return y[:, 0] if self._single_output else y

    def predict_truncated(self, X: np.ndarray, *, tolerance: float = GRNN_TOLERANCE, return_kept: bool = False):
        """The GRNN truncated to ``tolerance`` (module docstring: each output within tolerance times its
        training targets' range of :meth:`predict_dense`), by the C core (``sarins_grnn_eval_blocks``) over the
        candidates of a k-d tree; shape as :meth:`predict`.  ``return_kept``: also each row's kept patterns."""
        from sarins_fmu.core import nets

        if self.x_train_ is None or self.scaling_ is None:
            raise RuntimeError("GRNN is not fitted: call fit() or load() first")
        x = check_inputs(X, "X", n_features=self.n_features)
        mean, scale = self.scaling_.mean, self.scaling_.scale

        def evaluate(rows, blocks):
            return nets.grnn_predict_blocks(x[rows], mean, scale, self._z_train, self.y_train_, self.settings.sigma,
                                            blocks)

        y, kept = predict_truncated(nets.standardize(x, mean, scale), self._z_train, self.settings.sigma, evaluate,
                                    tolerance=tolerance)
        y = y[:, 0] if self._single_output else y
        return (y, kept) if return_kept else y

    # -------------------------------------------------------------- file IO
    def to_payload(self) -> tuple[dict, dict[str, np.ndarray]]:
        """Plain-data form ``(meta, arrays)`` as written to a model file."""
        if self.x_train_ is None:
            raise RuntimeError("GRNN is not fitted: nothing to save")
        meta = {
            "settings": asdict(self.settings),
            "n_features": self.n_features,
            "n_outputs": int(self.y_train_.shape[1]),
            "single_output": self._single_output,
            "input_names": None if self.input_names is None else list(self.input_names),
            "output_names": None if self.output_names is None else list(self.output_names),
        }
        arrays = {
            "x_train": self.x_train_,
            "y_train": self.y_train_,
            "scaling_mean": self.scaling_.mean,
            "scaling_scale": self.scaling_.scale,
        }
        return meta, arrays

    @classmethod
    def from_payload(cls, meta: dict, arrays: dict[str, np.ndarray]) -> "GRNN":
        """Rebuild a fitted GRNN from :meth:`to_payload` output."""
        settings = meta["settings"]
        if not isinstance(settings, dict):
            raise ValueError("'settings' is not an object")
        net = cls(**settings)
        d, m = meta["n_features"], meta["n_outputs"]
        for key, val in (("n_features", d), ("n_outputs", m)):
            if not isinstance(val, int) or isinstance(val, bool) or val < 1:
                raise ValueError(f"'{key}' must be a positive integer, got {val!r}")
        x = get_array(arrays, "x_train", (None, d))
        if x.shape[0] < 1:
            raise ValueError("no training samples")
        y = get_array(arrays, "y_train", (x.shape[0], m))
        mean = get_array(arrays, "scaling_mean", (d,))
        scale = get_array(arrays, "scaling_scale", (d,))
        single = meta["single_output"]
        if not isinstance(single, bool) or (single and m != 1):
            raise ValueError("'single_output' must be a boolean, true only with one output")
        for key, size in (("input_names", d), ("output_names", m)):
            names = meta.get(key)
            if names is not None and (
                not isinstance(names, list) or len(names) != size
                or not all(isinstance(v, str) for v in names)
            ):
                raise ValueError(f"'{key}' must be a list of {size} strings")
        net.scaling_ = Scaling(mean, scale)
        net.x_train_, net.y_train_ = x, y
        net._z_train = net.scaling_.apply(x)
        net._single_output = single
        net.input_names = None if meta.get("input_names") is None else tuple(meta["input_names"])
        net.output_names = None if meta.get("output_names") is None else tuple(meta["output_names"])
        return net

    def save(self, path: str | Path) -> Path:
        """Write the GRNN (all training samples) to JSON, or npz for ``.npz``.

        npz is advised for large sample sets.
        """
        meta, arrays = self.to_payload()
        return save_model_file(path, FORMAT_TAG, FORMAT_VERSION, meta, arrays)

    @classmethod
    def load(cls, path: str | Path) -> "GRNN":
        """Read a GRNN written by :meth:`save`.

        Raises
        ------
        ModelFileError
            (a ``ValueError``) naming the file, if missing, corrupt or mismatched.
        """
        return load_model_file(path, FORMAT_TAG, {FORMAT_VERSION}, cls.from_payload)
