"""Input checks and per-column standardisation shared by the networks."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Scaling", "fit_scaling", "check_inputs", "check_targets"]


@dataclass(frozen=True)
class Scaling:
    """Affine map of each input column: ``z = (x - mean) / scale``.

    Attributes
    ----------
    mean : ndarray, shape (d,)
        Column offsets, in the inputs' units.
    scale : ndarray, shape (d,)
        Column divisors, in the inputs' units; strictly positive.
    """

    mean: np.ndarray
    scale: np.ndarray

    def __post_init__(self) -> None:
        mean = np.asarray(self.mean, dtype=float)
        scale = np.asarray(self.scale, dtype=float)
        if mean.ndim != 1 or scale.shape != mean.shape:
            raise ValueError(
                f"scaling mean and scale must be 1-D of equal length, got {mean.shape} and {scale.shape}"
            )
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(scale))):
            raise ValueError("scaling holds NaN or infinity")
        if np.any(scale <= 0.0):
            raise ValueError("scaling divisors must be positive")
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "scale", scale)

    def apply(self, x: np.ndarray) -> np.ndarray:
        """Standardise ``x`` of shape (n, d); returns shape (n, d), dimensionless."""
        return (x - self.mean) / self.scale


def fit_scaling(x: np.ndarray, standardize: bool) -> Scaling:
    """Column means and standard deviations of ``x`` (or the identity map).

    Parameters
    ----------
    x : ndarray, shape (n, d)
        Training inputs.
    standardize : bool
        ``False`` gives the identity map (mean 0, scale 1).

    Returns
    -------
    Scaling
        A column with zero spread gets scale 1 (it is only centred), so a
        constant input never divides by zero.
    """
    d = x.shape[1]
    if not standardize:
        return Scaling(np.zeros(d), np.ones(d))
    mean = x.mean(axis=0)
    std = x.std(axis=0)
    # a constant column only shifts; dividing by its zero spread is meaningless
    scale = np.where(std > 0.0, std, 1.0)
    return Scaling(mean, scale)


def check_inputs(x: object, name: str = "X", n_features: int | None = None) -> np.ndarray:
    """Return inputs as a finite float array of shape (n, d).

    Parameters
    ----------
    x : array_like, shape (n, d) or (n,)
        A 1-D array is read as n samples of one input.
    name : str
        Used in error messages.
    n_features : int, optional
        Required number of columns d.

    Raises
    ------
    ValueError
        On a wrong number of dimensions or columns, no samples, NaN or inf.
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} is not a numeric array: {exc}") from None
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise ValueError(f"{name} must have shape (n, d) or (n,), got {arr.shape}")
    if arr.shape[0] == 0:
        raise ValueError(f"{name} holds no samples")
    if arr.shape[1] == 0:
        raise ValueError(f"{name} has no input columns")
    if n_features is not None and arr.shape[1] != n_features:
        raise ValueError(f"{name} has {arr.shape[1]} columns, the model expects {n_features}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds NaN or infinity")
    return arr


def check_targets(y: object, n: int, name: str = "y", ndim: tuple[int, ...] = (1,)) -> np.ndarray:
    """Return targets as a finite float array with n rows.

    Parameters
    ----------
    y : array_like, shape (n,) or (n, m)
        Targets.
    n : int
        Required number of samples.
    name : str
        Used in error messages.
    ndim : tuple of int
        Accepted numbers of dimensions.

    Raises
    ------
    ValueError
        On a wrong shape, NaN or inf.
    """
    try:
        arr = np.asarray(y, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} is not a numeric array: {exc}") from None
    if arr.ndim not in ndim:
        allowed = " or ".join(map(str, ndim))
        raise ValueError(f"{name} must have {allowed} dimension(s), got shape {arr.shape}")
    if arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} samples but the inputs have {n}")
    if arr.ndim == 2 and arr.shape[1] == 0:
        raise ValueError(f"{name} has no output columns")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds NaN or infinity")
    return arr
