r"""Gaussian radial-basis-function network grown one neuron at a time.

The network of seed 000, eqs (1)-(2), with one output:

.. math::

    f(x) = w_0 + \sum_{i=1}^{m} w_i \, \Phi(\lVert z(x) - z(c_i) \rVert),
    \qquad \Phi(u) = \exp(-u^2 / \delta^2),

where :math:`z(x) = (x - \mu) / s` standardises each input column with the
training mean :math:`\mu` and standard deviation :math:`s` (``standardize=True``,
the default; with ``standardize=False``, :math:`z(x) = x`).

Width from SPREAD, as MATLAB's ``newrb``
    ``newrb`` sets the hidden bias ``b = sqrt(-log(0.5)) / spread`` and the
    response ``a = exp(-(b * dist)**2)``, so a neuron answers 0.5 at distance
    ``spread`` from its centre. Hence :math:`\delta = \mathrm{spread}/\sqrt{\ln 2}`.
    **The distance is measured in standardised units** when ``standardize`` is
    on (SPREAD = 2 means two standard deviations of each input); with
    ``standardize=False`` it is measured in the inputs' own units, exactly as
    in MATLAB.

Growing the network
    The centres are training inputs, added one at a time until the mean
    squared training error reaches ``goal`` or ``max_neurons`` neurons exist
    (default: as many as samples). Two rules pick the next centre:

    ``selection="ols"`` (default)
        Orthogonal least squares (Chen, Cowan & Grant 1991), the rule that
        MATLAB's ``newrb`` implements in code: every candidate column is
        orthogonalised (Gram-Schmidt) against the columns already chosen
        (the bias column first) and the one that removes the most squared
        error, :math:`(r^\mathsf{T}\phi)^2 / \lVert\phi_\perp\rVert^2`, wins.
        Candidates whose orthogonal part is below 1e-10 of their energy
        (numerically dependent) are skipped.
    ``selection="residual"``
        The rule ``newrb``'s documentation describes: the training sample with
        the largest absolute residual (Euclidean norm over the outputs)
        becomes the next centre.

    After each addition the output weights and the bias are the linear
    least-squares solution; the mean squared error after each addition is
    kept in ``training_curve_`` (entry 0: bias only, no neuron).

    Several outputs (``y`` of shape (n, m), as ``newrb`` with a matrix of
    targets) share the centres; the error is then the mean over all n·m
    target elements and OLS sums the error reductions over the outputs.

    With more than ``max_candidates`` training samples, only an evenly spaced
    subset of them (in the order given) are candidates; every sample still
    counts in the error. One OLS step evaluates n x max_candidates basis
    values (in blocks of at most ``chunk_elements``; cached when they fit):
    n = 1e5 with 2000 candidates takes a few seconds per neuron.

Model files are plain JSON (or ``.npz``), see :mod:`.modelfile`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal, Sequence

import numpy as np

from .modelfile import get_array, load_model_file, save_model_file
from .preprocessing import Scaling, check_inputs, check_targets, fit_scaling

RANGE_MARGIN = 0.1  # inputs accepted up to this fraction of the training range beyond either end

__all__ = ["RBFSettings", "RBFNetwork", "gaussian_width", "radial_basis"]

FORMAT_TAG = "sarins_fmu.identify.rbf"
FORMAT_VERSION = 1

LN2 = float(np.log(2.0))  # ln 2: the Gaussian answers 0.5 at distance SPREAD
_DEPENDENT_TOL = 1e-10  # orthogonal energy / energy below which a candidate is dependent
_NO_GAIN_TOL = 1e-14  # error reduction / target energy below which a neuron is useless


def gaussian_width(spread: float) -> float:
    r"""Width :math:`\delta` of :math:`\exp(-u^2/\delta^2)` for a given SPREAD.

    Parameters
    ----------
    spread : float
        Distance at which the basis function equals 0.5.

    Returns
    -------
    float
        :math:`\delta = \mathrm{spread}/\sqrt{\ln 2}`, same unit as ``spread``.
    """
    return spread / np.sqrt(LN2)


def radial_basis(distance: np.ndarray, spread: float) -> np.ndarray:
    r"""Gaussian basis :math:`\exp(-\ln 2 \, (u/\mathrm{spread})^2)`.

    Parameters
    ----------
    distance : ndarray
        Distances u from the centre (any shape), same unit as ``spread``.
    spread : float
        Distance at which the response is 0.5.

    Returns
    -------
    ndarray
        Responses in (0, 1], same shape as ``distance``.
    """
    return np.exp(-LN2 * (np.asarray(distance, dtype=float) / spread) ** 2)


def _basis_from_sq(sq_dist: np.ndarray, spread: float) -> np.ndarray:
    # a = exp(-(b dist)^2), b = sqrt(ln 2) / spread
    return np.exp(sq_dist * (-LN2 / spread**2))


@dataclass(frozen=True)
class RBFSettings:
    """Training settings of :class:`RBFNetwork`.

    Attributes
    ----------
    spread : float
        Distance at which a neuron answers 0.5 (standardised units when
        ``standardize`` is on). Positive.
    goal : float
        Mean squared training error at which growing stops, in the target's
        unit squared. Zero or positive.
    max_neurons : int or None
        Most neurons to add; ``None`` means as many as training samples.
    standardize : bool
        Standardise each input column with its training mean and std.
    selection : {"ols", "residual"}
        How the next centre is chosen (see module docstring).
    max_candidates : int
        Most training samples considered as centres (evenly spaced subset).
    chunk_elements : int
        Largest number of basis values held in memory at once.
    """

    spread: float = 1.0
    goal: float = 0.0
    max_neurons: int | None = None
    standardize: bool = True
    selection: Literal["ols", "residual"] = "ols"
    max_candidates: int = 2000
    chunk_elements: int = 2**22

    def __post_init__(self) -> None:
        if not (np.isfinite(self.spread) and self.spread > 0.0):
            raise ValueError(f"spread must be positive and finite, got {self.spread!r}")
        if not (np.isfinite(self.goal) and self.goal >= 0.0):
            raise ValueError(f"goal must be zero or positive, got {self.goal!r}")
        k = self.max_neurons
        if k is not None and (isinstance(k, bool) or int(k) != k or k < 0):
            raise ValueError(f"max_neurons must be None or an integer >= 0, got {self.max_neurons!r}")
        if self.selection not in ("ols", "residual"):
            raise ValueError(f"selection must be 'ols' or 'residual', got {self.selection!r}")
        if int(self.max_candidates) < 1:
            raise ValueError(f"max_candidates must be >= 1, got {self.max_candidates!r}")
        if int(self.chunk_elements) < 1:
            raise ValueError(f"chunk_elements must be >= 1, got {self.chunk_elements!r}")


class RBFNetwork:
    """Gaussian RBF network with one output, grown like MATLAB's ``newrb``.

    Parameters
    ----------
    spread : float, default 1.0
        Distance at which a neuron answers 0.5 (standardised units when
        ``standardize`` is on).
    goal : float, default 0.0
        Mean squared training error (target unit squared) that stops growth.
    max_neurons : int, optional
        Most neurons; default as many as training samples.
    standardize : bool, default True
        Standardise inputs inside the model (scaling stored in the model file).
    selection : {"ols", "residual"}, default "ols"
        Centre selection rule.
    max_candidates : int, default 2000
        Most training samples tried as centres.
    chunk_elements : int, default 2**22
        Memory bound (number of basis values) for training and prediction.

    Attributes
    ----------
    centers_ : ndarray, shape (k, d)
        Centres, in the inputs' units (they are training samples).
    weights_ : ndarray, shape (k,), or (k, m) for m outputs
        Output weights, target unit.
    bias_ : float, or ndarray of shape (m,) for m outputs
        Output bias, target unit.
    scaling_ : Scaling
        Input standardisation (identity when ``standardize`` is off).
    training_curve_ : ndarray, shape (k + 1,)
        Mean squared training error with 0, 1, ..., k neurons.
    training_mse_ : float
        Mean squared training error of the final weights.
    stop_reason_ : str
        ``"goal"``, ``"max_neurons"`` or ``"no_candidate"``.
    input_names : tuple of str or None
        Names of the input columns, if given to :meth:`fit`.
    target_name : str or None
        Name of the target, if given to :meth:`fit`.
    metadata : dict
        Free JSON-ready data saved with the model (e.g. how it was trained).
    """

    def __init__(
        self,
        spread: float = 1.0,
        goal: float = 0.0,
        max_neurons: int | None = None,
        *,
        standardize: bool = True,
        selection: Literal["ols", "residual"] = "ols",
        max_candidates: int = 2000,
        chunk_elements: int = 2**22,
    ) -> None:
        self.settings = RBFSettings(
            spread=float(spread),
            goal=float(goal),
            max_neurons=None if max_neurons is None else max_neurons,
            standardize=bool(standardize),
            selection=selection,
            max_candidates=int(max_candidates),
            chunk_elements=int(chunk_elements),
        )
        self.centers_: np.ndarray | None = None
        self.weights_: np.ndarray | None = None
        self.bias_: float | np.ndarray | None = None
        self._single_output = True
        self.scaling_: Scaling | None = None
        self.training_curve_: np.ndarray | None = None
        self.training_mse_: float | None = None
        self.stop_reason_: str | None = None
        self.input_names: tuple[str, ...] | None = None
        self.target_name: str | None = None
        self.metadata: dict = {}
        self.input_range_: np.ndarray | None = None  # (2, d): least and largest training input
        self.input_range_exact_ = True  # False: a bound from the scaling statistics (older model files)

    # ------------------------------------------------------------------ info
    @property
    def n_neurons(self) -> int:
        """Number of hidden neurons (0 before fitting)."""
        return 0 if self.centers_ is None else int(self.centers_.shape[0])

    @property
    def n_features(self) -> int | None:
        """Number of inputs d (``None`` before fitting)."""
        return None if self.scaling_ is None else int(self.scaling_.mean.size)

    def __repr__(self) -> str:
        s = self.settings
        state = f", neurons={self.n_neurons}" if self.centers_ is not None else ", unfitted"
        return f"RBFNetwork(spread={s.spread}, goal={s.goal}, max_neurons={s.max_neurons}{state})"

    # ------------------------------------------------------------- training
    def fit(
        self,
        X: np.ndarray,
        y: np.ndarray,
        *,
        input_names: Sequence[str] | None = None,
        target_name: str | None = None,
    ) -> "RBFNetwork":
        """Grow the network on training data.

        Parameters
        ----------
        X : array_like, shape (n, d) or (n,)
            Training inputs (a 1-D array is one input column). n >= 2.
        y : array_like, shape (n,) or (n, m)
            Training targets (m outputs sharing the centres).
        input_names : sequence of str, optional
            Names of the d input columns (stored in the model file).
        target_name : str, optional
            Name of the target (stored in the model file).

        Returns
        -------
        RBFNetwork
            ``self``, fitted.

        Raises
        ------
        ValueError
            On NaN/inf, mismatched shapes, fewer than 2 samples or wrongly
            many input names.
        """
        x = check_inputs(X, "X")
        n, d = x.shape
        if n < 2:
            raise ValueError(f"RBF training needs at least 2 samples, got {n}")
        t = check_targets(y, n, "y", ndim=(1, 2))
        single = t.ndim == 1
        t = t[:, None] if single else t
        if input_names is not None:
            input_names = tuple(str(v) for v in input_names)
            if len(input_names) != d:
                raise ValueError(f"{len(input_names)} input names for {d} input columns")
        s = self.settings
        scaling = fit_scaling(x, s.standardize)
        z = scaling.apply(x)
        n_cand = min(n, s.max_candidates)
        cand = np.unique(np.round(np.linspace(0, n - 1, n_cand)).astype(int))
        max_k = len(cand) if s.max_neurons is None else min(int(s.max_neurons), len(cand))
        if s.selection == "ols":
            chosen, curve, reason = _grow_ols(z, t, cand, max_k, s)
        else:
            chosen, curve, reason = _grow_residual(z, t, cand, max_k, s)
        weights, bias = _solve_output_layer(_design(z, z[chosen], s), t)

        self.scaling_ = scaling
        self.centers_ = x[chosen].copy()
        self._single_output = single
        self.weights_ = weights[:, 0].copy() if single else weights
        self.bias_ = float(bias[0]) if single else bias
        self.training_curve_ = np.asarray(curve, dtype=float)
        self.stop_reason_ = reason
        self.input_names = input_names
        self.target_name = None if target_name is None else str(target_name)
        self.input_range_ = np.vstack([x.min(axis=0), x.max(axis=0)])
        self.input_range_exact_ = True
        fitted = self.predict_reference(x)  # numpy: the trained file does not depend on the C build
        self.training_mse_ = float(np.mean((t - (fitted[:, None] if single else fitted)) ** 2))
        return self

    # ----------------------------------------------------------- prediction
    def outside_training_range(self, X: np.ndarray, margin: float = RANGE_MARGIN) -> np.ndarray:
        """Rows of ``X`` with an input outside the training range widened by ``margin``.

        The accepted interval of input j is ``[lo_j - margin * w_j, hi_j + margin * w_j]``,
        ``[lo_j, hi_j]`` the least and largest training value and ``w_j = hi_j - lo_j``:
        beyond it every basis function has decayed and the output is the bias plus the
        tails of the nearest neurons, not a drift the data support.  Models saved
        before the range was stored bound it by Samuelson's inequality (every sample
        lies within ``mean +- std sqrt(n - 1)``) from the stored scaling and the
        ``n_samples`` metadata; without either, nothing is flagged.

        Returns
        -------
        ndarray of bool, shape (n,)
        """
        self._check_fitted()
        x = check_inputs(X, "X", n_features=self.n_features)
        if self.input_range_ is None:
            return np.zeros(x.shape[0], dtype=bool)
        lo, hi = self.input_range_
        width = hi - lo
        return np.any((x < lo - margin * width) | (x > hi + margin * width), axis=1)

    def _check_fitted(self) -> None:
        if self.centers_ is None or self.scaling_ is None:
            raise RuntimeError("RBFNetwork is not fitted: call fit() or load() first")

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Network output for each input row, computed by the C core (``sarins_rbf_eval``, the kernel the
        RBFIdentifier and IMUCompensator FMUs run: the same numbers bit for bit).

        Parameters
        ----------
        X : array_like, shape (n, d) or (n,)
            Inputs, same units and column order as in training.

        Returns
        -------
        ndarray, shape (n,), or (n, m) if trained with m outputs
            Outputs, target unit.
        """
        from sarins_fmu.core import nets

        self._check_fitted()
        x = check_inputs(X, "X", n_features=self.n_features)
        zc = nets.standardize(self.centers_, self.scaling_.mean, self.scaling_.scale)
        bias = np.atleast_1d(self.bias_)
        w = np.asarray(self.weights_, dtype=float).reshape(zc.shape[0], bias.size)
        out = nets.rbf_predict(x, self.scaling_.mean, self.scaling_.scale, zc, w, bias, self.settings.spread)
        return out[:, 0] if self._single_output else out

    def predict_reference(self, X: np.ndarray) -> np.ndarray:
        """:meth:`predict` in numpy (cdist and a matrix product, chunked): the reference the C kernel is
        tested against (they differ by rounding only: the summation orders differ) and the evaluation of
        the training error, so that a trained model file does not depend on the C build."""
        self._check_fitted()
        x = check_inputs(X, "X", n_features=self.n_features)
        z = self.scaling_.apply(x)
        zc = self.scaling_.apply(self.centers_)
        out = np.empty((x.shape[0],) + np.shape(self.bias_))
        rows = max(1, self.settings.chunk_elements // max(1, zc.shape[0]))
        for start in range(0, x.shape[0], rows):
            stop = start + rows
            if zc.shape[0]:
                phi = _basis_from_sq(cdist(z[start:stop], zc, "sqeuclidean"), self.settings.spread)
                out[start:stop] = phi @ self.weights_ + self.bias_
            else:
                out[start:stop] = self.bias_
        return out

    # -------------------------------------------------------------- file IO
    def to_payload(self) -> tuple[dict, dict[str, np.ndarray]]:
        """Plain-data form: ``(meta, arrays)`` as written to a model file."""
        self._check_fitted()
        meta = {
            "settings": asdict(self.settings),
            "n_features": self.n_features,
            "single_output": self._single_output,
            "training_mse": float(self.training_mse_),
            "stop_reason": self.stop_reason_,
            "input_names": None if self.input_names is None else list(self.input_names),
            "target_name": self.target_name,
            "metadata": self.metadata,
        }
        arrays = {
            "centers": self.centers_,
            "weights": self.weights_,
            "bias": np.atleast_1d(self.bias_),
            "scaling_mean": self.scaling_.mean,
            "scaling_scale": self.scaling_.scale,
            "training_curve": self.training_curve_,
        }
        if self.input_range_ is not None and self.input_range_exact_:
            arrays["input_min"], arrays["input_max"] = self.input_range_
        return meta, arrays

    @classmethod
    def from_payload(cls, meta: dict, arrays: dict[str, np.ndarray]) -> "RBFNetwork":
        """Rebuild a fitted network from :meth:`to_payload` output.

        Raises
        ------
        KeyError, TypeError, ValueError
            On a missing entry, a wrong type or an inconsistent shape.
        """
        settings = meta["settings"]
        if not isinstance(settings, dict):
            raise ValueError("'settings' is not an object")
        net = cls(**settings)
        d = meta["n_features"]
        if not isinstance(d, int) or isinstance(d, bool) or d < 1:
            raise ValueError(f"'n_features' must be a positive integer, got {d!r}")
        centers = get_array(arrays, "centers", (None, d))
        k = centers.shape[0]
        single = meta["single_output"]
        if not isinstance(single, bool):
            raise ValueError(f"'single_output' must be a boolean, got {single!r}")
        bias = get_array(arrays, "bias", (1,) if single else (None,))
        weights = get_array(arrays, "weights", (k,) if single else (k, bias.size))
        mean = get_array(arrays, "scaling_mean", (d,))
        scale = get_array(arrays, "scaling_scale", (d,))
        curve = get_array(arrays, "training_curve", (None,))
        names = meta.get("input_names")
        if names is not None:
            if not isinstance(names, list) or len(names) != d or not all(isinstance(v, str) for v in names):
                raise ValueError(f"'input_names' must be a list of {d} strings")
            names = tuple(names)
        target = meta.get("target_name")
        if target is not None and not isinstance(target, str):
            raise ValueError("'target_name' must be a string")
        net.scaling_ = Scaling(mean, scale)
        net.centers_ = centers
        net._single_output = single
        net.weights_ = weights
        net.bias_ = float(bias[0]) if single else bias
        net.training_curve_ = curve
        net.training_mse_ = float(meta.get("training_mse", np.nan))
        net.stop_reason_ = meta.get("stop_reason")
        metadata = meta.get("metadata", {})
        if not isinstance(metadata, dict):
            raise ValueError("'metadata' must be an object")
        net.input_names = names
        net.target_name = target
        net.metadata = metadata
        if "input_min" in arrays or "input_max" in arrays:
            lo, hi = get_array(arrays, "input_min", (d,)), get_array(arrays, "input_max", (d,))
            if np.any(lo > hi):
                raise ValueError("'input_min' exceeds 'input_max'")
            net.input_range_ = np.vstack([lo, hi])
        else:  # written before the range was stored
            net.input_range_ = _samuelson_range(net.scaling_, metadata.get("n_samples"), net.settings.standardize)
            net.input_range_exact_ = False
        return net

    def save(self, path: str | Path) -> Path:
        """Write the fitted network to ``path`` (JSON, or npz for ``.npz``).

        Returns
        -------
        Path
            The written file.
        """
        meta, arrays = self.to_payload()
        return save_model_file(path, FORMAT_TAG, FORMAT_VERSION, meta, arrays)

    @classmethod
    def load(cls, path: str | Path) -> "RBFNetwork":
        """Read a network written by :meth:`save`.

        Raises
        ------
        ModelFileError
            (a ``ValueError``) naming the file, if it is missing, corrupt,
            of another model kind or inconsistent.
        """
        return load_model_file(path, FORMAT_TAG, {FORMAT_VERSION}, cls.from_payload)


# ---------------------------------------------------------------- internals
def _samuelson_range(scaling: Scaling, n_samples, standardized: bool) -> np.ndarray | None:
    """(2, d) bound of the training inputs from their mean and (population) std:
    every one of n samples lies within mean +- std sqrt(n - 1) (Samuelson 1968)."""
    if not standardized or isinstance(n_samples, bool) or not isinstance(n_samples, int) or n_samples < 2:
        return None
    half = scaling.scale * np.sqrt(n_samples - 1.0)
    return np.vstack([scaling.mean - half, scaling.mean + half])


def _design(z: np.ndarray, zc: np.ndarray, s: RBFSettings) -> np.ndarray:
    """Basis matrix, shape (n, k): response of each centre to each sample."""
    if zc.shape[0] == 0:
        return np.empty((z.shape[0], 0))
    return _basis_from_sq(cdist(z, zc, "sqeuclidean"), s.spread)


def _solve_output_layer(phi: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares output weights (k, m) and bias (m,) for basis phi (n, k), targets t (n, m)."""
    # [Phi 1] [W; w0'] = T  in the least-squares sense
    a = np.hstack([phi, np.ones((phi.shape[0], 1))])
    sol, *_ = np.linalg.lstsq(a, t, rcond=None)
    return sol[:-1].copy(), sol[-1].copy()


def _candidate_blocks(z: np.ndarray, cand: np.ndarray, s: RBFSettings):
    """Yield (slice into cand, basis block of shape (n, m)) within the memory bound."""
    cols = max(1, s.chunk_elements // z.shape[0])
    for start in range(0, len(cand), cols):
        sl = slice(start, min(start + cols, len(cand)))
        yield sl, _basis_from_sq(cdist(z, z[cand[sl]], "sqeuclidean"), s.spread)


def _grow_ols(
    z: np.ndarray, t: np.ndarray, cand: np.ndarray, max_k: int, s: RBFSettings
) -> tuple[np.ndarray, list[float], str]:
    """Forward selection by orthogonal least squares; returns chosen sample indices."""
    n = z.shape[0]
    n_cand = len(cand)
    # orthonormal basis of the chosen columns; column 0 is the (normalised) bias
    q_basis = np.empty((n, max_k + 1))
    q_basis[:, 0] = 1.0 / np.sqrt(n)
    resid = t - np.outer(q_basis[:, 0], q_basis[:, 0] @ t)  # (n, m)
    curve = [float(np.mean(resid**2))]
    target_energy = float(np.sum(t * t)) or 1.0

    energy = np.empty(n_cand)  # ||phi_c||^2
    proj2 = np.empty(n_cand)  # ||Q' phi_c||^2, grows as columns are chosen
    r_phi = np.empty((n_cand, t.shape[1]))  # phi_c' r for the current residuals r
    cache = [] if n * n_cand <= s.chunk_elements else None
    for sl, block in _candidate_blocks(z, cand, s):
        energy[sl] = np.einsum("ij,ij->j", block, block)
        proj2[sl] = (q_basis[:, 0] @ block) ** 2
        r_phi[sl] = block.T @ resid
        if cache is not None:
            cache.append((sl, block))
    blocks = (lambda: iter(cache)) if cache is not None else (lambda: _candidate_blocks(z, cand, s))

    available = np.ones(n_cand, dtype=bool)
    chosen: list[int] = []
    reason = "max_neurons"
    while True:
        if curve[-1] <= s.goal:
            reason = "goal"
            break
        if len(chosen) >= max_k:
            reason = "max_neurons"
            break
        # energy of each candidate orthogonal to the chosen columns
        perp = energy - proj2
        usable = available & (perp > _DEPENDENT_TOL * energy)
        if not usable.any():
            reason = "no_candidate"
            break
        gain = np.full(n_cand, -np.inf)
        # error reduction (summed over outputs) if candidate c were added
        gain[usable] = np.sum(r_phi[usable] ** 2, axis=1) / perp[usable]
        j = int(np.argmax(gain))
        if gain[j] <= _NO_GAIN_TOL * target_energy:
            reason = "no_candidate"
            break
        k = len(chosen) + 1
        phi = _basis_from_sq(cdist(z, z[cand[j : j + 1]], "sqeuclidean"), s.spread)[:, 0]
        q_prev = q_basis[:, :k]
        q = phi - q_prev @ (q_prev.T @ phi)
        q -= q_prev @ (q_prev.T @ q)  # second Gram-Schmidt pass for orthogonality
        q /= np.linalg.norm(q)
        q_basis[:, k] = q
        # r <- r - q (q' r)
        resid = resid - np.outer(q, q @ resid)
        curve.append(float(np.mean(resid**2)))
        chosen.append(int(cand[j]))
        available[j] = False
        for sl, block in blocks():
            proj2[sl] += (q @ block) ** 2
            r_phi[sl] = block.T @ resid
    return np.asarray(chosen, dtype=int), curve, reason


def _grow_residual(
    z: np.ndarray, t: np.ndarray, cand: np.ndarray, max_k: int, s: RBFSettings
) -> tuple[np.ndarray, list[float], str]:
    """Add the candidate sample with the largest residual, refit, repeat."""
    resid = t - t.mean(axis=0)
    curve = [float(np.mean(resid**2))]
    available = np.ones(len(cand), dtype=bool)
    chosen: list[int] = []
    reason = "max_neurons"
    while True:
        if curve[-1] <= s.goal:
            reason = "goal"
            break
        if len(chosen) >= max_k:
            reason = "max_neurons"
            break
        if not available.any():
            reason = "no_candidate"
            break
        score = np.where(available, np.sum(resid[cand] ** 2, axis=1), -np.inf)
        j = int(np.argmax(score))
        chosen.append(int(cand[j]))
        available[j] = False
        phi = _design(z, z[chosen], s)
        w, b = _solve_output_layer(phi, t)
        resid = t - (phi @ w + b)
        curve.append(float(np.mean(resid**2)))
    return np.asarray(chosen, dtype=int), curve, reason


def cdist(a, b, metric):
    """scipy.spatial.distance.cdist, imported on first use (scipy.spatial takes 0.5 s to import: the
    command line starts without it)."""
    from scipy.spatial.distance import cdist as scipy_cdist

    return scipy_cdist(a, b, metric)
