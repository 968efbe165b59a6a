r"""Quadratic temperature model of a gyro drift and its forgetting-factor RLS.

Seed 002 models the azimuth gyro drift as a quadratic in temperature (eq. 7),

.. math:: \varepsilon(T) = a T^2 + b T + c = h(T)^\mathsf{T} x, \qquad
          h(T) = [T^2, T, 1]^\mathsf{T}, \quad x = [a, b, c]^\mathsf{T},

fits it by least squares to a calibration (eq. 19), and updates it online at
vehicle stops with a forgetting-factor recursive least squares (eqs 8-18,
reconstructed here because the equations are missing from the seed's text).

Weighted objective (eqs 9-14)
    After k measurements :math:`z_i = h_i^\mathsf{T} x + v_i` at times
    :math:`t_i`, minimise

    .. math:: J_k(x) = \sum_{i=1}^{k} w_{k,i} (z_i - h_i^\mathsf{T} x)^2,
              \qquad w_{k,i} = \lambda^{(t_k - t_i)/m},

    i.e. the newest measurement has weight 1 and every older one is
    multiplied by :math:`\lambda_k = \lambda^{(t_{k+1}-t_k)/m}` when the next
    arrives (eq. 15). The factors telescope, so a measurement's weight is
    :math:`\lambda^{\mathrm{age}/m}` whatever the gaps were. With
    :math:`\lambda = 1` this is ordinary least squares; with
    ``time_scale=None`` every update forgets by :math:`\lambda` regardless of
    the gap (the weight is :math:`\lambda^{\text{number of later updates}}`).

Recursion (eqs 16-18), with :math:`P_k = (\sum_i w_{k,i} h_i h_i^\mathsf{T})^{-1}`

    .. math::

        K_{k+1} &= P_k h_{k+1} (\lambda_k + h_{k+1}^\mathsf{T} P_k h_{k+1})^{-1} \\
        x_{k+1} &= x_k + K_{k+1} (z_{k+1} - h_{k+1}^\mathsf{T} x_k) \\
        P_{k+1} &= (I - K_{k+1} h_{k+1}^\mathsf{T}) P_k / \lambda_k

Initialisation
    From a calibration batch (parameters and :math:`P` of its weighted least
    squares), or from given parameters and :math:`P_0`. A given
    :math:`P_0` acts as a prior: the recursion then minimises
    :math:`J_k + \lambda^{(t_k - t_0)/m} (x - x_0)^\mathsf{T} P_0^{-1} (x - x_0)`,
    which :func:`forgetting_least_squares` reproduces in batch form.
    :math:`P` is normalised to unit measurement weight; the parameter
    covariance is :math:`\sigma_z^2 P` for drift-measurement noise
    :math:`\sigma_z`.

Implementation
    The recursion, the forgetting factor, the covariance checks and the
    binary model file run in the C core (``sarins_fmu/core/rls.h``), the
    same code the DriftModelUpdater FMU runs, so the library and the FMU
    agree bit for bit; the batch fits stay here (numpy).

Units
    Temperature in °C (the seed's model is in °C). The drift may be in any
    unit (rad/s inside the library, °/h at the edges); the coefficients carry
    that unit per °C² , per °C and plain. **Times are in seconds (SI)**; the
    forgetting time scale m is one month = 30 days = 2 592 000 s
    (:data:`MONTH`), and seed 002 uses λ = 0.8.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..core import online as core_online
from ..drift_model import drift_model_value
from ..files import BudgetError, check_file_size
from . import netfile
from .modelfile import ModelFileError, get_array, load_model_file, save_model_file

__all__ = [
    "MONTH",
    "SEED002_FORGETTING",
    "RLSSettings",
    "QuadraticFit",
    "ForgettingRLS",
    "quadratic_regressors",
    "drift_model_value",
    "time_scaled_factor",
    "rls_update",
    "weighted_least_squares",
    "forgetting_least_squares",
    "fit_quadratic_temperature_model",
]

MONTH = 30.0 * 86400.0  # s, forgetting time scale m of seed 002 (one month = 30 days)
SEED002_FORGETTING = 0.8  # forgetting factor lambda of seed 002, per month

FORMAT_TAG = "sarins_fmu.identify.rls"
FORMAT_VERSION = 1


@dataclass(frozen=True)
class RLSSettings:
    """Forgetting of :class:`ForgettingRLS`.

    Attributes
    ----------
    forgetting_factor : float
        λ in (0, 1]; 1 gives ordinary (growing-memory) RLS.
    time_scale : float or None
        m, s: a gap Δt forgets by λ^(Δt/m). ``None`` forgets by λ at every
        update whatever the gap.
    """

    forgetting_factor: float = SEED002_FORGETTING
    time_scale: float | None = MONTH

    def __post_init__(self) -> None:
        lam = self.forgetting_factor
        if not (np.isfinite(lam) and 0.0 < lam <= 1.0):
            raise ValueError(f"forgetting_factor must be in (0, 1], got {lam!r}")
        m = self.time_scale
        if m is not None and not (np.isfinite(m) and m > 0.0):
            raise ValueError(f"time_scale must be positive (s) or None, got {m!r}")


@dataclass(frozen=True)
class QuadraticFit:
    """Least-squares fit of ε(T) = a T² + b T + c (seed 002 eq. 19).

    Attributes
    ----------
    coefficients : ndarray, shape (3,)
        [a, b, c]: drift unit per °C², per °C, and drift unit.
    residuals : ndarray, shape (n,)
        Measured minus fitted drift.
    residual_rms : float
        Root mean square of the residuals, drift unit.
    residual_max : float
        Largest absolute residual, drift unit.
    """

    coefficients: np.ndarray
    residuals: np.ndarray
    residual_rms: float
    residual_max: float

    def predict(self, temperature: np.ndarray) -> np.ndarray:
        """Model drift at ``temperature`` (°C), any shape."""
        return _evaluate(self.coefficients, temperature)


def _as_1d(values: object, name: str) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a scalar or 1-D array, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds NaN or infinity")
    return arr


def _evaluate(x: np.ndarray, temperature: object) -> np.ndarray:
    return drift_model_value(x, np.asarray(temperature, dtype=float))


def quadratic_regressors(temperature: object) -> np.ndarray:
    """Rows h(T) = [T², T, 1] of the quadratic temperature model.

    Parameters
    ----------
    temperature : array_like, shape (n,) or scalar
        °C.

    Returns
    -------
    ndarray, shape (n, 3)
    """
    t = _as_1d(temperature, "temperature")
    return np.column_stack([t * t, t, np.ones_like(t)])


def time_scaled_factor(forgetting_factor: float, dt: float, time_scale: float | None = MONTH) -> float:
    """Forgetting applied over a gap: λ^(Δt/m) (seed 002 eq. 15).

    Parameters
    ----------
    forgetting_factor : float
        λ per time scale.
    dt : float
        Gap between the previous and this update, s; >= 0.
    time_scale : float or None
        m, s; ``None`` gives λ whatever the gap.

    Returns
    -------
    float
        Factor by which older weights are multiplied.
    """
    if not np.isfinite(dt) or dt < 0.0:
        raise ValueError(f"time gap must be finite and >= 0 s, got {dt!r}")
    return core_online.rls_factor(forgetting_factor, dt, time_scale)


def rls_update(
    x: np.ndarray, P: np.ndarray, h: np.ndarray, z: float, lam: float
) -> tuple[np.ndarray, np.ndarray]:
    """One forgetting-factor RLS step (pure function; the C core's ``sarins_rls_gain_step``).

    Parameters
    ----------
    x : ndarray, shape (3,)
        Parameters before the step.
    P : ndarray, shape (3, 3)
        Inverse weighted information before the step.
    h : ndarray, shape (3,)
        Regressor of the new measurement.
    z : float
        New measurement.
    lam : float
        Forgetting applied to the old information in this step.

    Returns
    -------
    x, P : ndarray
        After the step: K = P h / (lam + h' P h), x + K (z - h' x), (P - K (P h)') / lam symmetrized.
    """
    return core_online.rls_gain_step(x, P, h, z, lam)


def weighted_least_squares(
    regressors: np.ndarray,
    measurements: np.ndarray,
    weights: np.ndarray,
    prior: tuple[np.ndarray, np.ndarray, float] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Minimise :math:`\sum_i w_i (z_i - h_i^\mathsf{T} x)^2` (+ prior term).

    Parameters
    ----------
    regressors : ndarray, shape (n, p)
        Rows :math:`h_i`.
    measurements : ndarray, shape (n,)
        :math:`z_i`.
    weights : ndarray, shape (n,)
        :math:`w_i \ge 0`.
    prior : (x0, P0, w0), optional
        Adds :math:`w_0 (x - x_0)^\mathsf{T} P_0^{-1} (x - x_0)`.

    Returns
    -------
    x : ndarray, shape (p,)
        Minimiser.
    P : ndarray, shape (p, p)
        Inverse of the weighted information
        :math:`(\sum_i w_i h_i h_i^\mathsf{T} + w_0 P_0^{-1})^{-1}`.

    Raises
    ------
    ValueError
        If the data (and prior) do not determine all parameters.
    """
    h = np.asarray(regressors, dtype=float)
    z = np.asarray(measurements, dtype=float)
    w = np.asarray(weights, dtype=float)
    if h.ndim != 2 or z.shape != (h.shape[0],) or w.shape != z.shape:
        raise ValueError("regressors (n, p), measurements (n,) and weights (n,) do not match")
    if np.any(w < 0.0) or not np.all(np.isfinite(w)):
        raise ValueError("weights must be finite and >= 0")
    p = h.shape[1]
    # sqrt(w) scales rows: || sqrt(W) (z - H x) ||^2
    sw = np.sqrt(w)
    rows, rhs = [h * sw[:, None]], [z * sw]
    if prior is not None:
        x0, p0, w0 = prior
        x0 = np.asarray(x0, dtype=float)
        # P0 = L L'  =>  (x - x0)' P0^-1 (x - x0) = || L^-1 (x - x0) ||^2
        chol = np.linalg.cholesky(np.asarray(p0, dtype=float))
        l_inv = solve_triangular(chol, np.eye(p), lower=True)
        rows.append(np.sqrt(w0) * l_inv)
        rhs.append(np.sqrt(w0) * (l_inv @ x0))
    a = np.vstack(rows)
    b = np.concatenate(rhs)
    q, r = np.linalg.qr(a)
    if a.shape[0] < p or np.min(np.abs(np.diag(r))) <= 1e-12 * np.max(np.abs(np.diag(r))):
        raise ValueError("the data do not determine all parameters (need >= 3 distinct temperatures)")
    x = solve_triangular(r, q.T @ b)
    r_inv = solve_triangular(r, np.eye(p))
    # P = (A'A)^-1 = R^-1 R^-T
    cov = r_inv @ r_inv.T
    return x, 0.5 * (cov + cov.T)


def _ages(time: np.ndarray, t_now: float, settings: RLSSettings) -> np.ndarray:
    """Age of each measurement in units of m, or in updates if time_scale is None."""
    if settings.time_scale is None:
        return np.arange(time.size - 1, -1, -1, dtype=float)
    if np.any(time > t_now):
        raise ValueError("a measurement is later than t_now")
    return (t_now - time) / settings.time_scale


def forgetting_least_squares(
    temperature: object,
    drift: object,
    time: object,
    t_now: float | None = None,
    settings: RLSSettings = RLSSettings(),
    prior: tuple[np.ndarray, np.ndarray, float] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Batch twin of :class:`ForgettingRLS`: weights λ^(age/m).

    Parameters
    ----------
    temperature : array_like, shape (n,)
        °C.
    drift : array_like, shape (n,)
        Measured drift, any unit.
    time : array_like, shape (n,)
        Measurement times, s, non-decreasing.
    t_now : float, optional
        Time at which ages are taken, s; default the last measurement time.
    settings : RLSSettings
        λ and m. With ``time_scale=None`` the age is the number of later
        measurements (the prior's age is n).
    prior : (x0, P0, t0), optional
        Initial parameters, inverse information and time of a recursion
        started from them (forgotten like a measurement taken at t0).

    Returns
    -------
    x : ndarray, shape (3,)
        [a, b, c].
    P : ndarray, shape (3, 3)
        Inverse weighted information.
    """
    h = quadratic_regressors(temperature)
    z = _as_1d(drift, "drift")
    t = np.broadcast_to(_as_1d(time, "time"), z.shape).astype(float)
    if z.shape[0] != h.shape[0]:
        raise ValueError(f"{h.shape[0]} temperatures but {z.shape[0]} drifts")
    if np.any(np.diff(t) < 0.0):
        raise ValueError("times must be non-decreasing")
    t_now = float(t[-1]) if t_now is None else float(t_now)
    lam = settings.forgetting_factor
    weights = lam ** _ages(t, t_now, settings)
    prior_term = None
    if prior is not None:
        x0, p0, t0 = prior
        if settings.time_scale is None:
            age0 = float(z.size)
        else:
            if t0 > t[0]:
                raise ValueError("the prior is later than the first measurement")
            age0 = (t_now - t0) / settings.time_scale
        prior_term = (x0, p0, lam**age0)
    return weighted_least_squares(h, z, weights, prior_term)


def fit_quadratic_temperature_model(temperature: object, drift: object) -> QuadraticFit:
    """Least-squares fit of ε(T) = a T² + b T + c (seed 002 eqs 7 and 19).

    Parameters
    ----------
    temperature : array_like, shape (n,)
        Calibration temperatures, °C; at least 3 distinct.
    drift : array_like, shape (n,)
        Drift measured at each temperature, any unit.

    Returns
    -------
    QuadraticFit
        Coefficients and residual RMS / max.
    """
    h = quadratic_regressors(temperature)
    z = _as_1d(drift, "drift")
    if z.shape[0] != h.shape[0]:
        raise ValueError(f"{h.shape[0]} temperatures but {z.shape[0]} drifts")
    x, _ = weighted_least_squares(h, z, np.ones_like(z))
    resid = z - h @ x
    return QuadraticFit(
        coefficients=x,
        residuals=resid,
        residual_rms=float(np.sqrt(np.mean(resid**2))),
        residual_max=float(np.max(np.abs(resid))),
    )


def _check_covariance(P: object) -> np.ndarray:
    p = np.asarray(P, dtype=float)
    if p.shape != (3, 3):
        raise ValueError(f"covariance must have shape (3, 3), got {p.shape}")
    core_online.check_covariance(p)  # finite, symmetric (1e-9), positive definite: the FMU's check
    return 0.5 * (p + p.T)


class ForgettingRLS:
    """Online update of the quadratic drift model ε(T) = a T² + b T + c.

    Parameters
    ----------
    parameters : array_like, shape (3,)
        Initial [a, b, c] (drift unit per °C², per °C, drift unit).
    covariance : array_like, shape (3, 3)
        Initial inverse information P0 (symmetric positive definite); acts
        as a prior weighted like a measurement taken at ``time``.
    time : float, default 0
        Time of the initial calibration, s.
    settings : RLSSettings
        λ (default 0.8) and m (default one month, s).

    Attributes
    ----------
    time : float
        Time of the last update (or of the initialisation), s.
    n_updates : int
        Updates since initialisation.
    """

    def __init__(
        self,
        parameters: object,
        covariance: object,
        time: float = 0.0,
        settings: RLSSettings = RLSSettings(),
    ) -> None:
        x = _as_1d(parameters, "parameters")
        if x.shape != (3,):
            raise ValueError(f"parameters must have shape (3,), got {x.shape}")
        if not np.isfinite(time):
            raise ValueError(f"time must be finite, got {time!r}")
        self.settings = settings
        p = _check_covariance(covariance)
        self._state = core_online.RlsState(x, p, float(time), settings.forgetting_factor, settings.time_scale)

    @property
    def time(self) -> float:
        """Time of the last update (or of the initialisation), s."""
        return self._state.time

    @property
    def n_updates(self) -> int:
        """Updates since initialisation."""
        return self._state.n_updates

    @n_updates.setter
    def n_updates(self, value: int) -> None:
        self._state.n_updates = int(value)

    @classmethod
    def from_calibration(
        cls,
        temperature: object,
        drift: object,
        time: object = 0.0,
        settings: RLSSettings = RLSSettings(),
    ) -> "ForgettingRLS":
        """Start from the (forgetting-weighted) least squares of calibration points.

        Parameters
        ----------
        temperature : array_like, shape (n,)
            °C; at least 3 distinct.
        drift : array_like, shape (n,)
            Drift, any unit.
        time : float or array_like, shape (n,)
            Time of each point (or one time for all), s. The state time is
            the last of them.
        settings : RLSSettings
            λ and m.
        """
        z = _as_1d(drift, "drift")
        t = np.broadcast_to(_as_1d(time, "time"), z.shape)
        x, P = forgetting_least_squares(temperature, z, t, settings=settings)
        return cls(x, P, float(t[-1]), settings)

    @property
    def parameters(self) -> np.ndarray:
        """Current [a, b, c], shape (3,) (a copy)."""
        return self._state.x.copy()

    @property
    def covariance(self) -> np.ndarray:
        """Current inverse weighted information P, shape (3, 3) (a copy)."""
        return self._state.p.copy()

    def __repr__(self) -> str:
        a, b, c = self._state.x
        return (
            f"ForgettingRLS(a={a:.6g}, b={b:.6g}, c={c:.6g}, "
            f"time={self.time:.6g} s, updates={self.n_updates})"
        )

    def update(self, temperature: float, drift: float, time: float) -> np.ndarray:
        """Add one drift measurement (e.g. from a stop's Kalman filter).

        Parameters
        ----------
        temperature : float
            Gyro temperature during the estimate, °C.
        drift : float
            Estimated drift, same unit as the model.
        time : float
            Time of the estimate, s; not earlier than the previous update.

        Returns
        -------
        ndarray, shape (3,)
            Updated [a, b, c].
        """
        self._state.update(temperature, drift, time)  # the C core's sarins_rls_update (checks, eqs 15-18)
        return self.parameters

    def predict(self, temperature: object) -> np.ndarray:
        """Model drift at ``temperature`` (°C), same shape as the input."""
        t = np.asarray(temperature, dtype=float)
        return _evaluate(self._state.x, t)

    # ------------------------------------------------------------ plain data
    def to_dict(self) -> dict:
        """State as plain JSON-ready data."""
        return {
            "parameters": self.parameters.tolist(),
            "covariance": self.covariance.tolist(),
            "time": self.time,
            "n_updates": self.n_updates,
            "settings": asdict(self.settings),
        }

    @classmethod
    def from_dict(cls, state: dict) -> "ForgettingRLS":
        """Rebuild from :meth:`to_dict` output.

        Raises
        ------
        KeyError, TypeError, ValueError
            On missing or invalid entries.
        """
        settings = state["settings"]
        if not isinstance(settings, dict):
            raise ValueError("'settings' is not an object")
        rls = cls(state["parameters"], state["covariance"], float(state["time"]), RLSSettings(**settings))
        n = state.get("n_updates", 0)
        if not isinstance(n, int) or isinstance(n, bool) or n < 0:
            raise ValueError(f"'n_updates' must be an integer >= 0, got {n!r}")
        rls.n_updates = n
        return rls

    def save(self, path: str | Path) -> Path:
        """Write the state as a JSON model file (or npz for ``.npz``)."""
        state = self.to_dict()
        meta = {k: state[k] for k in ("time", "n_updates", "settings")}
        arrays = {"parameters": self.parameters, "covariance": self.covariance}
        return save_model_file(path, FORMAT_TAG, FORMAT_VERSION, meta, arrays)

    def binary_arrays(self) -> dict:
        """The arrays of the binary model file (kind ``rls``, ``sarins_fmu/core/rls.h``): parameters,
        covariance, time, n_updates, forgetting_factor, time_scale (0: per update)."""
        m = self.settings.time_scale
        return {"parameters": self.parameters, "covariance": self.covariance, "time": np.float64(self.time),
                "n_updates": np.float64(self.n_updates),
                "forgetting_factor": np.float64(self.settings.forgetting_factor),
                "time_scale": np.float64(0.0 if m is None else m)}

    def binary(self) -> bytes:
        """The state as a binary model file's bytes (what the DriftModelUpdater FMU's ``model_file`` reads)."""
        return netfile.to_bytes("rls", self.binary_arrays())

    def export_binary(self, path: str | Path) -> Path:
        """Write :meth:`binary` to ``path`` (suffix ``.bin`` by convention); returns it."""
        return netfile.write(path, "rls", self.binary_arrays())

    @classmethod
    def load(cls, path: str | Path) -> "ForgettingRLS":
        """Read a state written by :meth:`save` or :meth:`export_binary` (told apart by the binary file's
        magic); a bad file raises ``ModelFileError``.  A binary file is read by the C core's reader, the
        FMU's (``sarins_rls_from_model``, at most 4096 bytes)."""
        if netfile.is_netfile(path):
            return cls._load_binary(Path(path))

        def build(meta: dict, arrays: dict) -> "ForgettingRLS":
            state = dict(meta)
            state["parameters"] = get_array(arrays, "parameters", (3,))
            state["covariance"] = get_array(arrays, "covariance", (3, 3))
            return cls.from_dict(state)

        return load_model_file(path, FORMAT_TAG, {FORMAT_VERSION}, build)

    @classmethod
    def from_binary(cls, data: bytes, source="<bytes>") -> "ForgettingRLS":
        """The state in a binary model file's bytes (``sarins_rls_from_model``); ModelFileError naming
        ``source`` and the reason."""
        try:
            state = core_online.RlsState.from_model_bytes(data)
        except ValueError as exc:
            raise ModelFileError(source, str(exc)) from None
        rls = cls.__new__(cls)
        rls.settings = RLSSettings(state.forgetting_factor, state.time_scale)
        rls._state = state
        return rls

    @classmethod
    def _load_binary(cls, path: Path) -> "ForgettingRLS":
        try:
            check_file_size(path, core_online.RLS_FILE_MAX, "an RLS model file (SARINS_RLS_FILE_MAX)")
            data = path.read_bytes()
        except BudgetError as exc:
            raise ModelFileError(path, exc.reason) from None
        except OSError as exc:
            raise ModelFileError(path, f"cannot be read: {exc.strerror or exc}") from None
        return cls.from_binary(data, path)


def solve_triangular(a, b, **options):
    """scipy.linalg.solve_triangular, imported on first use (scipy.linalg takes 0.3 s to import: the command
    line starts without it)."""
    from scipy.linalg import solve_triangular as scipy_solve_triangular

    return scipy_solve_triangular(a, b, **options)
