r"""Traditional IMU calibration model of seed 003 (eqs 1-2), fit and compensation.

Each sensor triad (three gyros, or three accelerometers) is modelled as

.. math::

    y = b + (I + S + M) u + v, \qquad
    S = \mathrm{diag}(s_x, s_y, s_z), \quad
    M = \begin{bmatrix} 0 & m_{xy} & m_{xz} \\ m_{yx} & 0 & m_{yz} \\
                        m_{zx} & m_{zy} & 0 \end{bmatrix},

where u is the true input in the body (IMU) frame (angular rate, rad/s, or
specific force, m/s^2), y the measured output in the same unit, b the bias,
S the scale-factor errors (dimensionless), M the misalignment / cross-axis
coupling (dimensionless, rad for small angles) and v noise. Row i of
:math:`K = I + S + M` says how much of each true axis the sensor i sees.

Fit
    Linear least squares of :math:`y_i = b_i + \sum_j K_{ij} u_j` over all
    samples, 12 unknowns per triad: :func:`fit_triad`. Data from a multi
    position tumble (true specific force = gravity reaction projected into
    each orientation, :func:`tumble_truth`) determine the accelerometer
    triad; rate-table tests (:func:`rate_test_truth`) at large rates about
    each axis determine the gyro scale factors and misalignment.

Gyro bias from a static tumble
    A resting gyro triad measures the Earth rate
    :math:`\omega_{ie}^b = C_n^b \, [0, \Omega\cos L, \Omega\sin L]^\mathsf{T}`
    (ENU). Pass a true-rate array that includes it (``tumble_truth`` does,
    given the Earth-rate vector in the navigation frame). Taking the true
    rate as zero leaves the Earth rate (up to 7.3e-5 rad/s, 15 °/h) in the
    fit residual and, unless the orientations are balanced so that the
    projections average to zero (as over the 24 of
    :func:`cube_orientations`), in the bias.

Compensation
    :math:`\hat u = K^{-1} (y - b)` (:func:`compensate_triad`).

All functions take and return numpy arrays of shape (n, 3), one row per
sample, in the body frame.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

__all__ = [
    "TriadCalibration",
    "triad_model",
    "fit_triad",
    "compensate_triad",
    "cube_orientations",
    "tumble_truth",
    "rate_test_truth",
]

_RANK_TOL = 1e-10  # smallest/largest singular value of the scaled regressors


def _as_triad(values: object, name: str) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} is not a numeric array: {exc}") from None
    if arr.ndim == 1 and arr.shape == (3,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds NaN or infinity")
    return arr


@dataclass(frozen=True)
class TriadCalibration:
    """Bias, scale-factor and misalignment of one sensor triad.

    Attributes
    ----------
    bias : ndarray, shape (3,)
        b, in the measured unit (rad/s or m/s^2).
    scale_factor : ndarray, shape (3,)
        Scale-factor errors s (dimensionless; 1e-4 = 100 ppm).
    misalignment : ndarray, shape (3, 3)
        M, zero diagonal; ``misalignment[i, j]`` is the part of true axis j
        seen by sensor i (dimensionless).
    """

    bias: np.ndarray
    scale_factor: np.ndarray
    misalignment: np.ndarray

    def __post_init__(self) -> None:
        bias = np.asarray(self.bias, dtype=float)
        scale = np.asarray(self.scale_factor, dtype=float)
        mis = np.asarray(self.misalignment, dtype=float)
        if bias.shape != (3,) or scale.shape != (3,) or mis.shape != (3, 3):
            raise ValueError("bias (3,), scale_factor (3,) and misalignment (3, 3) expected")
        if not all(np.all(np.isfinite(a)) for a in (bias, scale, mis)):
            raise ValueError("calibration holds NaN or infinity")
        if np.any(np.diag(mis) != 0.0):
            raise ValueError("misalignment must have a zero diagonal (scale factors hold it)")
        for name, arr in (("bias", bias), ("scale_factor", scale), ("misalignment", mis)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def matrix(self) -> np.ndarray:
        """K = I + S + M, shape (3, 3)."""
        return np.eye(3) + np.diag(self.scale_factor) + self.misalignment

    @classmethod
    def from_matrix(cls, bias: np.ndarray, matrix: np.ndarray) -> "TriadCalibration":
        """Split K = I + S + M into scale factors and misalignment."""
        k = np.asarray(matrix, dtype=float)
        mis = k - np.diag(np.diag(k))
        return cls(np.asarray(bias, dtype=float), np.diag(k) - 1.0, mis)

    def to_dict(self) -> dict:
        """Plain JSON-ready data."""
        return {
            "bias": self.bias.tolist(),
            "scale_factor": self.scale_factor.tolist(),
            "misalignment": self.misalignment.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict) -> "TriadCalibration":
        """Rebuild from :meth:`to_dict` output (``KeyError``/``ValueError`` if bad)."""
        return cls(data["bias"], data["scale_factor"], data["misalignment"])


def triad_model(cal: TriadCalibration, true: object) -> np.ndarray:
    """Noise-free sensor output y = b + (I + S + M) u.

    Parameters
    ----------
    cal : TriadCalibration
        Error parameters.
    true : array_like, shape (n, 3)
        True input u, body frame.

    Returns
    -------
    ndarray, shape (n, 3)
        Measured output, same unit.
    """
    u = _as_triad(true, "true")
    return cal.bias + u @ cal.matrix.T


def fit_triad(true: object, measured: object) -> TriadCalibration:
    """Least-squares bias, scale factors and misalignment of one triad.

    Parameters
    ----------
    true : array_like, shape (n, 3)
        True inputs u (rad/s including the Earth rate for gyros; m/s^2 for
        accelerometers), body frame.
    measured : array_like, shape (n, 3)
        Sensor outputs y, same unit (averaged per position or rate point).

    Returns
    -------
    TriadCalibration

    Raises
    ------
    ValueError
        On shape mismatch, NaN, or data that do not excite all three axes
        plus an offset (fewer than 4 independent samples).
    """
    u = _as_triad(true, "true")
    y = _as_triad(measured, "measured")
    if u.shape != y.shape:
        raise ValueError(f"true {u.shape} and measured {y.shape} differ in shape")
    # y_i = b_i + sum_j K_ij u_j  ->  [1 u] [b; K'] = y
    a = np.hstack([np.ones((u.shape[0], 1)), u])
    # scale the columns for conditioning (rates of 1e-5 and 3 rad/s mix)
    col = np.sqrt(np.mean(a * a, axis=0))
    col[col == 0.0] = 1.0
    a_s = a / col
    sv = np.linalg.svd(a_s, compute_uv=False)
    if a.shape[0] < 4 or sv[-1] <= _RANK_TOL * sv[0]:
        raise ValueError("the true inputs do not excite all three axes independently of the bias")
    sol, *_ = np.linalg.lstsq(a_s, y, rcond=None)
    sol /= col[:, None]
    return TriadCalibration.from_matrix(sol[0], sol[1:].T)


def compensate_triad(cal: TriadCalibration, measured: object) -> np.ndarray:
    """Invert the model: u = K^-1 (y - b) (LU with partial pivoting in the C core, ``sarins_triad_compensate``).

    Parameters
    ----------
    cal : TriadCalibration
        Fitted parameters.
    measured : array_like, shape (n, 3)
        Raw sensor outputs.

    Returns
    -------
    ndarray, shape (n, 3)
        Compensated inputs, same unit.
    """
    from sarins_fmu.core import nets

    y = _as_triad(measured, "measured")
    # K u = y - b per sample, by the C core (the IMUCompensator FMU's function)
    return nets.triad_compensate(cal.matrix, cal.bias, y)


def cube_orientations() -> np.ndarray:
    """The 24 orientations of a 24-position tumble (all right-handed axis swaps).

    Each is a signed permutation matrix with determinant +1: every body axis
    points along ±east, ±north or ±up, four headings per axis direction.

    Returns
    -------
    ndarray, shape (24, 3, 3)
        ``mat_nb``: projects body-frame vectors into the navigation frame
        (ENU), so a navigation vector v_n appears as ``mat_nb.T @ v_n``.
    """
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            m = np.zeros((3, 3))
            m[list(perm), range(3)] = signs
            if np.linalg.det(m) > 0.0:
                out.append(m)
    return np.array(out)


def tumble_truth(
    mat_nb: np.ndarray, gravity: float, earth_rate_n: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """True specific force and angular rate of a resting IMU in each orientation.

    Parameters
    ----------
    mat_nb : ndarray, shape (n, 3, 3)
        Body-to-navigation (ENU) direction cosine matrices.
    gravity : float
        Local gravity magnitude, m/s^2 (the resting IMU senses +g up).
    earth_rate_n : ndarray, shape (3,)
        Earth rate in the navigation frame, rad/s:
        [0, Ω cos L, Ω sin L] in ENU.

    Returns
    -------
    specific_force : ndarray, shape (n, 3)
        f_b = C_n^b [0, 0, g], m/s^2.
    rate : ndarray, shape (n, 3)
        ω_b = C_n^b ω_ie^n, rad/s.
    """
    c = np.asarray(mat_nb, dtype=float)
    if c.ndim != 3 or c.shape[1:] != (3, 3):
        raise ValueError(f"mat_nb must have shape (n, 3, 3), got {c.shape}")
    w = np.asarray(earth_rate_n, dtype=float)
    if w.shape != (3,):
        raise ValueError(f"earth_rate_n must have shape (3,), got {w.shape}")
    f_n = np.array([0.0, 0.0, float(gravity)])
    # v_b = C_nb' v_n for every orientation
    return np.einsum("kji,j->ki", c, f_n), np.einsum("kji,j->ki", c, w)


def rate_test_truth(rates: object, axis: int, earth_rate_up: float = 0.0) -> np.ndarray:
    """True mean body rates of a single-axis rate test over whole revolutions.

    The IMU axis ``axis`` points up along the table axis; over whole
    revolutions the horizontal Earth-rate components average out and the
    vertical one, Ω sin L, adds to the table rate on that axis.

    Parameters
    ----------
    rates : array_like, shape (k,)
        Table rates, rad/s (positive: right-handed about up).
    axis : {0, 1, 2}
        Body axis pointing up.
    earth_rate_up : float, default 0
        Ω sin L, rad/s.

    Returns
    -------
    ndarray, shape (k, 3)
        True body rates, rad/s.
    """
    r = np.atleast_1d(np.asarray(rates, dtype=float))
    if r.ndim != 1 or not np.all(np.isfinite(r)):
        raise ValueError("rates must be a finite 1-D array")
    if axis not in (0, 1, 2):
        raise ValueError(f"axis must be 0, 1 or 2, got {axis!r}")
    out = np.zeros((r.size, 3))
    out[:, axis] = r + earth_rate_up
    return out
