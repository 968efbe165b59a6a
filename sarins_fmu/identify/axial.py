"""Axial-drift identifier: a trained RBF model applied to a navigation state.

Seed 000 (sec. 2.1-2.3): after 4 h alignment and 12 h navigation the
network maps the latitude error (hot start) or the latitude error, the
azimuth gyro temperature and its change over the alignment (cold start) to
the axial gyro drift.  A model file names its inputs; this class builds
them from SI navigation quantities:

* ``lat_error_deg`` latitude error, deg (= ``lat_error`` rad in degrees);
* ``lat_deg`` latitude *reading*, deg (the paper's Table 2 feeds readings):
  site latitude (the model's ``local_lat_deg``) + error;
* ``temp_c`` azimuth gyro temperature at identification, degC;
* ``temp_change_c`` its change over the alignment, degC.

The target is in deg/h (``drift_dph``); :meth:`DriftIdentifier.drift` returns rad/s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..units import DPH_TO_RPS, RAD_TO_DEG
from . import netfile
from .modelfile import ModelFileError
from .rbf import RBFNetwork
from ..site import SITE_LAT_DEG

DATA = Path(__file__).resolve().parents[1] / "data"
DEFAULT_MODELS = {"hot": DATA / "axial_rbf_hot.json", "cold": DATA / "axial_rbf_cold.json"}
KNOWN_INPUTS = ("lat_error_deg", "lat_deg", "temp_c", "temp_change_c")
# delay from the identification (nav time) to the first navigation interval
# compensated with its result, s: a few steps, so that the INS receives the
# drift in time under any co-simulation scheme (Jacobi adds a step per link)
APPLY_LATENCY = 10.0


def default_model_path(kind: str) -> Path:
    """Shipped model file of kind 'hot' or 'cold'."""
    try:
        return DEFAULT_MODELS[kind]
    except KeyError:
        raise ValueError(f"model kind must be 'hot' or 'cold', got {kind!r}") from None


# what a model expects of the run it identifies when its metadata does not say (seed 000's protocol,
# which made the shipped models): alignment and navigation before identification (h), INS step (s)
DEFAULT_PROTOCOL = {"align_hours": 4.0, "identify_hours": 12.0, "step_s": 1.0}


def model_protocol(metadata: dict, path) -> dict:
    """The run a model was trained on: ``align_hours``, ``identify_hours``
    (h) and ``step_s`` (s) from its metadata, :data:`DEFAULT_PROTOCOL` for
    absent keys; :class:`ModelFileError` if one is not a positive number."""
    meta = metadata if isinstance(metadata, dict) else {}
    out = {}
    for key, default in DEFAULT_PROTOCOL.items():
        value = meta.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < 1e6:
            raise ModelFileError(path, f"{key!r} must be a positive number, got {value!r}")
        out[key] = float(value)
    return out


def site_latitude_deg(metadata: dict, path) -> float:
    """The model's site latitude (deg; default the paper's site when absent),
    checked: a number within +-90 deg, else :class:`ModelFileError`."""
    value = metadata.get("local_lat_deg", SITE_LAT_DEG) if isinstance(metadata, dict) else None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not abs(value) <= 90.0:
        raise ModelFileError(path, f"'local_lat_deg' must be a latitude in deg within +-90, got {value!r}")
    return float(value)


class DriftIdentifier:
    """An RBF drift model with named inputs (see module docstring).

    Parameters
    ----------
    path : model file written by ``RBFNetwork.save`` with ``input_names``
        among :data:`KNOWN_INPUTS` and a target in deg/h, or the binary model
        file of :meth:`export_binary` (its protocol is then :data:`DEFAULT_PROTOCOL`).

    Attributes: ``input_names``, ``local_lat_deg`` (the training site, deg)
    and ``protocol`` (:func:`model_protocol`).

    Raises
    ------
    ModelFileError
        If the file is unreadable, or its inputs are unnamed or unknown.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.network = _network_from_binary(self.path) if netfile.is_netfile(self.path) else RBFNetwork.load(self.path)
        names = self.network.input_names
        if not names:
            raise ModelFileError(self.path, "the model does not name its inputs")
        unknown = [n for n in names if n not in KNOWN_INPUTS]
        if unknown:
            raise ModelFileError(self.path, f"unsupported model input(s) {unknown}; known: {KNOWN_INPUTS}")
        if np.ndim(self.network.bias_) != 0:
            raise ModelFileError(self.path, "an identifier has one output (the drift in deg/h)")
        self.input_names = tuple(names)
        self.local_lat_deg = site_latitude_deg(self.network.metadata, self.path)
        self.protocol = model_protocol(self.network.metadata, self.path)
        from sarins_fmu.core.nets import AxialModel

        self._native = AxialModel(self.binary(), self.path)

    def binary_arrays(self) -> dict:
        """The arrays of the binary model file (:mod:`.netfile`, kind ``axial_rbf``) that the RBFIdentifier
        FMU and :meth:`drift_dph` evaluate (layout in ``sarins_fmu/core/netmodel.h``)."""
        net = self.network
        return {"mean": net.scaling_.mean, "scale": net.scaling_.scale, "centers": net.centers_,
                "weights": np.asarray(net.weights_, float).reshape(-1, 1), "bias": np.atleast_1d(net.bias_),
                "spread": np.float64(net.settings.spread),
                "inputs": np.array([KNOWN_INPUTS.index(n) for n in self.input_names], float),
                "local_lat_deg": np.float64(self.local_lat_deg)}

    def binary(self) -> bytes:
        """The binary model file's bytes (:meth:`binary_arrays`)."""
        return netfile.to_bytes("axial_rbf", self.binary_arrays())

    def export_binary(self, path: str | Path) -> Path:
        """Write the binary model file the RBFIdentifier FMU reads (``model_file``); returns its path."""
        return netfile.write(path, "axial_rbf", self.binary_arrays())

    def inputs(self, lat_error: float, temp_c: float = np.nan, temp_change_c: float = np.nan) -> np.ndarray:
        """Model input row (1, d) from the latitude error (rad) and temperatures (degC)."""
        values = {"lat_error_deg": lat_error * RAD_TO_DEG, "lat_deg": self.local_lat_deg + lat_error * RAD_TO_DEG,
                  "temp_c": temp_c, "temp_change_c": temp_change_c}
        row = np.array([[values[n] for n in self.input_names]], float)
        if not np.isfinite(row).all():
            raise ValueError(f"identifier inputs {self.input_names} are not all finite: {row[0].tolist()}")
        return row

    def drift_dph(self, lat_error: float, temp_c: float = np.nan, temp_change_c: float = np.nan) -> float:
        """Identified axial drift, deg/h, computed by the C core (``sarins_axial_drift``, the RBFIdentifier
        FMU's function)."""
        self.inputs(lat_error, temp_c, temp_change_c)  # the error message names the inputs
        return self._native.drift_dph(lat_error, temp_c, temp_change_c)

    def drift(self, lat_error: float, temp_c: float = np.nan, temp_change_c: float = np.nan) -> float:
        """Identified axial drift, rad/s."""
        return self.drift_dph(lat_error, temp_c, temp_change_c) * DPH_TO_RPS


def _network_from_binary(path: Path) -> RBFNetwork:
    """The RBF network of a binary identifier file (kind ``axial_rbf``), with its input names and site."""
    kind, arrays = netfile.read(path)
    if kind != "axial_rbf":
        raise ModelFileError(path, f"model kind {kind!r} is not an axial drift identifier")
    try:
        codes = arrays["inputs"]
        if codes.ndim != 1 or not all(c in range(len(KNOWN_INPUTS)) for c in codes.tolist()):
            raise ValueError(f"input codes {codes.tolist()} (0 .. {len(KNOWN_INPUTS) - 1})")
        weights = arrays["weights"]
        if weights.ndim != 2 or weights.shape[1] != 1:
            raise ValueError(f"weights of shape {weights.shape}, expected (k, 1)")
        meta = {"settings": {"spread": float(arrays["spread"])}, "n_features": len(codes), "single_output": True,
                "input_names": [KNOWN_INPUTS[int(c)] for c in codes], "target_name": "drift_dph",
                "metadata": {"local_lat_deg": float(arrays["local_lat_deg"])}}
        payload = {"centers": arrays["centers"], "weights": weights[:, 0], "bias": arrays["bias"],
                   "scaling_mean": arrays["mean"], "scaling_scale": arrays["scale"], "training_curve": np.zeros(0)}
        return RBFNetwork.from_payload(meta, payload)
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(path, f"not a consistent identifier: {exc}") from None


def export_identifier(model_file: str | Path, out: str | Path) -> Path:
    """Convert an identifier model file (JSON/npz, :meth:`RBFNetwork.save`) into the binary file the
    RBFIdentifier FMU reads; returns ``out``."""
    return DriftIdentifier(model_file).export_binary(out)


def fmu_model_file(model_file: str | Path, folder: str | Path) -> Path:
    """The binary model file the RBFIdentifier FMU reads for ``model_file``: the file itself when it is
    one already, else its conversion ``folder/<stem>-<digest>.bin`` (named by the source's content, so a
    campaign's runs share it; written once)."""
    import hashlib

    model_file = Path(model_file)
    if netfile.is_netfile(model_file):
        return model_file
    try:
        digest = hashlib.sha256(model_file.read_bytes()).hexdigest()[:16]
    except OSError as exc:
        raise ModelFileError(model_file, f"cannot read it: {exc.strerror or exc}") from None
    out = Path(folder) / f"{model_file.stem}-{digest}{netfile.SUFFIX}"
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        export_identifier(model_file, out)
    return out
