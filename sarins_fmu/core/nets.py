"""ctypes binding of the network inference kernels (``nets.h``) and the trained models built from a
binary model file (``netmodel.h``, ``netfile.h``): the computations the RBFIdentifier and IMUCompensator
FMUs run, called in process so that both give the same numbers bit for bit.

Units are those of the model (see ``netmodel.h``): the axial identifier takes the latitude error in rad
and temperatures in degC and returns the drift in deg/h; the compensators map (rad/s, m/s^2, degC) rows
to (rad/s, m/s^2) rows.
"""

from __future__ import annotations

import ctypes
import weakref

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P, _SZ = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_size_t

MAX_INPUTS = 64  # SARINS_NET_MAX_INPUTS
MAX_STREAMS = 8  # SARINS_RNN_MAX_STREAMS
COMP_N_IN, COMP_N_OUT = 7, 6
STATUS = {1: "an input is not finite", 2: "the result is not finite", 3: "a calibration matrix K is singular",
          4: "not a GRNN compensator"}

_checksum = function("sarins_netfile_checksum", ctypes.c_uint64, ctypes.c_char_p, _SZ)
_standardize = function("sarins_standardize", None, _I64, _I64, _P, _P, _P, _P)
_rbf = function("sarins_rbf_predict", None, _I64, _I64, _I64, _P, _P, _P, _P, _P, _F64, _I64, _P, _P)
_grnn = function("sarins_grnn_predict", None, _I64, _I64, _I64, _P, _P, _P, _P, _F64, _I64, _P, _P, _P)
_grnn_blocks = function("sarins_grnn_predict_blocks", None, _I64, _I64, _I64, _P, _P, _P, _P, _F64, _I64, _P, _P,
                        _P, _F64, _P, _P, _P, _P)
_triad = function("sarins_triad_compensate", ctypes.c_int, _P, _P, _I64, _P, _P)
_axial_open = function("sarins_axial_open", _P, ctypes.c_char_p, _SZ, ctypes.c_char_p, _SZ)
_axial_close = function("sarins_axial_close", None, _P)
_axial_drift = function("sarins_axial_drift", ctypes.c_int, _P, _F64, _F64, _F64, ctypes.POINTER(_F64))
_comp_open = function("sarins_comp_open", _P, ctypes.c_char_p, _SZ, ctypes.c_char_p, _SZ)
_comp_close = function("sarins_comp_close", None, _P)
_comp_state = function("sarins_comp_state_size", _I64, _P)
_comp_scratch = function("sarins_comp_scratch_size", _I64, _P)
_comp_per_candidate = function("sarins_comp_grnn_per_candidate", _I64, _P)
_comp_run = function("sarins_comp_run", ctypes.c_int, _P, _P, _I64, _P, _P, _P)
_comp_streams_work = function("sarins_comp_streams_work", _I64, _P, _I64)
_comp_run_streams = function("sarins_comp_run_streams", ctypes.c_int, _P, _I64, _P, _I64, _P, _P, _P)
_comp_grnn_blocks = function("sarins_comp_run_grnn_blocks", ctypes.c_int, _P, _I64, _P, _P, _P, _F64, _P, _P, _P, _P)


def netfile_checksum(data: bytes) -> int:
    """FNV-1a 64 of ``data`` (the model files' checksum)."""
    return int(_checksum(data, len(data)))


def standardize(x, mean, scale) -> np.ndarray:
    """(x - mean) / scale per column of x (n, d), as the kernels standardise."""
    x = _arrays.read(x, np.shape(x), "x")
    if x.ndim != 2:
        raise ValueError(f"x must have shape (n, d), got {x.shape}")
    d = x.shape[1]
    mean, scale = _arrays.read(mean, (d,), "mean"), _arrays.read(scale, (d,), "scale")
    out = np.empty_like(x)
    _standardize(x.shape[0], d, x.ctypes.data, mean.ctypes.data, scale.ctypes.data, out.ctypes.data)
    return out


def _rows(x, d: int, name: str = "x") -> np.ndarray:
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != d:
        raise ValueError(f"{name} must have shape (n, {d}), got {x.shape}")
    if d > MAX_INPUTS:
        raise ValueError(f"{d} inputs: the C kernels take at most {MAX_INPUTS}")
    return x


def rbf_predict(x, mean, scale, zc, weights, bias, spread: float) -> np.ndarray:
    """Outputs (n, m) of the Gaussian RBF network (``sarins_rbf_eval``): x (n, d) in the inputs' units, the
    standardisation mean/scale (d,), standardised centres zc (k, d), weights (k, m), bias (m,), spread > 0."""
    zc = np.ascontiguousarray(zc, dtype=np.float64)
    k, d = zc.shape
    x = _rows(x, d)
    w = np.ascontiguousarray(weights, dtype=np.float64)
    m = w.shape[1]
    w = _arrays.read(w, (k, m), "weights")
    bias = _arrays.read(bias, (m,), "bias")
    mean, scale = _arrays.read(mean, (d,), "mean"), _arrays.read(scale, (d,), "scale")
    out = np.empty((x.shape[0], m))
    _rbf(d, k, m, mean.ctypes.data, scale.ctypes.data, zc.ctypes.data, w.ctypes.data, bias.ctypes.data,
         float(spread), x.shape[0], x.ctypes.data, out.ctypes.data)
    return out


def grnn_predict_dense(x, mean, scale, z_train, y_train, sigma: float) -> np.ndarray:
    """Outputs (n, m) of the dense GRNN (``sarins_grnn_eval``, every pattern): x (n, d), the
    standardisation mean/scale (d,), standardised patterns z_train (p, d), targets y_train (p, m)."""
    zt = np.ascontiguousarray(z_train, dtype=np.float64)
    p, d = zt.shape
    x = _rows(x, d)
    yt = np.ascontiguousarray(y_train, dtype=np.float64)
    m = yt.shape[1]
    yt = _arrays.read(yt, (p, m), "y_train")
    mean, scale = _arrays.read(mean, (d,), "mean"), _arrays.read(scale, (d,), "scale")
    out = np.empty((x.shape[0], m))
    scratch = np.empty(p)
    _grnn(d, p, m, mean.ctypes.data, scale.ctypes.data, zt.ctypes.data, yt.ctypes.data, float(sigma), x.shape[0],
          x.ctypes.data, out.ctypes.data, scratch.ctypes.data)
    return out


def _checked_blocks(blocks, n_rows: int, n_patterns: int, per_candidate: int):
    """The int64 arrays (row_ptr, cand_ptr, cand) of ``blocks`` (a :class:`~sarins_fmu.identify.grnn.Blocks`),
    checked against the rows and patterns they index (the C kernels trust them), and the kernels' scratch:
    ``per_candidate`` doubles (2 + d + m, ``sarins_grnn_block_scratch``) per candidate of the largest block."""
    row_ptr, cand_ptr, cand = (np.ascontiguousarray(a, dtype=np.int64)
                               for a in (blocks.row_ptr, blocks.cand_ptr, blocks.cand))
    nb = len(row_ptr) - 1
    if (nb < 0 or len(cand_ptr) != nb + 1 or row_ptr[0] != 0 or row_ptr[-1] != n_rows or cand_ptr[0] != 0
            or cand_ptr[-1] != len(cand) or np.any(np.diff(row_ptr) < 0) or np.any(np.diff(cand_ptr) < 0)
            or (len(cand) and (cand.min() < 0 or cand.max() >= n_patterns))):
        raise ValueError("GRNN blocks do not index these rows and patterns")
    scratch = np.empty(max(1, int(np.diff(cand_ptr).max(initial=0)) * per_candidate))
    return row_ptr, cand_ptr, cand, scratch


def grnn_predict_blocks(x, mean, scale, z_train, y_train, sigma: float, blocks) -> tuple[np.ndarray, np.ndarray]:
    """Outputs (n, m) of the truncated GRNN (``sarins_grnn_eval_blocks``) and each row's kept patterns (n,):
    arguments as :func:`grnn_predict_dense`, ``blocks`` the candidates of
    :func:`sarins_fmu.identify.grnn.neighbour_blocks` (with their ``log_cut``)."""
    zt = np.ascontiguousarray(z_train, dtype=np.float64)
    p, d = zt.shape
    x = _rows(x, d)
    yt = np.ascontiguousarray(y_train, dtype=np.float64)
    m = yt.shape[1]
    yt = _arrays.read(yt, (p, m), "y_train")
    mean, scale = _arrays.read(mean, (d,), "mean"), _arrays.read(scale, (d,), "scale")
    row_ptr, cand_ptr, cand, scratch = _checked_blocks(blocks, x.shape[0], p, 2 + d + m)
    out = np.empty((x.shape[0], m))
    kept = np.empty(x.shape[0], dtype=np.int64)
    _grnn_blocks(d, p, m, mean.ctypes.data, scale.ctypes.data, zt.ctypes.data, yt.ctypes.data, float(sigma),
                 len(row_ptr) - 1, row_ptr.ctypes.data, cand_ptr.ctypes.data, cand.ctypes.data, float(blocks.log_cut),
                 x.ctypes.data, out.ctypes.data, scratch.ctypes.data, kept.ctypes.data)
    return out, kept


def triad_compensate(matrix, bias, measured) -> np.ndarray:
    """u = K^-1 (y - b) per row of ``measured`` (n, 3) (``sarins_triad_compensate``); LinAlgError when K is
    singular."""
    k = _arrays.read(matrix, (3, 3), "matrix")
    b = _arrays.read(bias, (3,), "bias")
    y = _rows(measured, 3, "measured")
    out = np.empty_like(y)
    if _triad(k.ctypes.data, b.ctypes.data, y.shape[0], y.ctypes.data, out.ctypes.data):
        raise np.linalg.LinAlgError("Singular matrix")
    return out


class _Handle:
    """A model built by the core from a model file's bytes, freed with the object."""

    def __init__(self, data: bytes, opener, closer, source):
        msg = ctypes.create_string_buffer(512)
        ptr = opener(data, len(data), msg, len(msg))
        if not ptr:
            from sarins_fmu.identify.modelfile import ModelFileError

            raise ModelFileError(source, msg.value.decode(errors="replace"))
        self.ptr = ptr
        self._finalizer = weakref.finalize(self, closer, ptr)


class AxialModel(_Handle):
    """The seed 000 axial drift identifier built from its binary model file (``sarins_axial_*``)."""

    def __init__(self, data: bytes, source="<model>"):
        super().__init__(data, _axial_open, _axial_close, source)

    def drift_dph(self, lat_error: float, temp_c: float, temp_change_c: float) -> float:
        """Axial drift (deg/h) from the latitude error (rad) and temperatures (degC); ValueError when an
        input the model uses or the result is not finite."""
        out = _F64()
        status = _axial_drift(self.ptr, float(lat_error), float(temp_c), float(temp_change_c), ctypes.byref(out))
        if status:
            raise ValueError(f"axial drift identifier: {STATUS[status]}")
        return out.value


class CompensatorModel(_Handle):
    """A seed 003 compensator built from its binary model file (``sarins_comp_*``)."""

    def __init__(self, data: bytes, source="<model>"):
        super().__init__(data, _comp_open, _comp_close, source)
        self.state_size = int(_comp_state(self.ptr))
        self.scratch_size = int(_comp_scratch(self.ptr))

    def zero_state(self) -> np.ndarray:
        """A zero recurrent state (empty for the stateless kinds)."""
        return np.zeros(self.state_size)

    def run(self, x, state: np.ndarray | None = None) -> np.ndarray:
        """Compensated rows (n, 6) of the time-ordered rows x (n, 7); ``state`` (from :meth:`zero_state`) is
        advanced in place (default: a zero state, the series compensated from its start)."""
        x = _rows(x, COMP_N_IN)
        state = self.zero_state() if state is None else _arrays.written(state, (self.state_size,), "state")
        out = np.empty((x.shape[0], COMP_N_OUT))
        scratch = np.empty(self.scratch_size)  # per call: threads may share the model (ctypes drops the GIL)
        status = _comp_run(self.ptr, state.ctypes.data, x.shape[0], x.ctypes.data, out.ctypes.data,
                           scratch.ctypes.data)
        if status:
            raise ValueError(f"compensator: {STATUS[status]}")
        return out

    def run_streams(self, xs, states) -> list[np.ndarray]:
        """:meth:`run` of up to :data:`MAX_STREAMS` independent series side by side (a recurrent compensator):
        ``xs`` a list of (n, 7) row arrays of one length n, ``states`` one state each (advanced in place);
        returns each series' rows (n, 6), bit for bit those of :meth:`run` (``sarins_comp_run_streams``: the
        series share each block of the weights while it is in cache)."""
        if not 1 <= len(xs) == len(states) <= MAX_STREAMS:
            raise ValueError(f"1 to {MAX_STREAMS} series with one state each expected, got {len(xs)} and "
                             f"{len(states)}")
        rows = [_rows(x, COMP_N_IN) for x in xs]
        if len({r.shape[0] for r in rows}) != 1:
            raise ValueError(f"the series must have one length, got {[r.shape[0] for r in rows]}")
        if self.state_size == 0:
            raise ValueError("run_streams needs a recurrent compensator")
        states = [_arrays.written(st, (self.state_size,), "state") for st in states]
        n, k = rows[0].shape[0], len(rows)
        x = np.stack(rows)
        packed = np.stack(states)
        out = np.empty((k, n, COMP_N_OUT))
        work = np.empty(int(_comp_streams_work(self.ptr, k)))
        status = _comp_run_streams(self.ptr, k, packed.ctypes.data, n, x.ctypes.data, out.ctypes.data,
                                   work.ctypes.data)
        for state, new in zip(states, packed):
            state[:] = new
        if status:
            raise ValueError(f"compensator: {STATUS[status]}")
        return list(out)

    def run_grnn_blocks(self, x, blocks) -> tuple[np.ndarray, np.ndarray]:
        """Compensated rows (n, 6) of x (n, 7) by the truncated GRNN (``sarins_comp_run_grnn_blocks``) over the
        candidates ``blocks`` (:func:`sarins_fmu.identify.grnn.neighbour_blocks` of the model's patterns),
        and each row's kept patterns (n,)."""
        x = _rows(x, COMP_N_IN)
        row_ptr, cand_ptr, cand, scratch = _checked_blocks(blocks, x.shape[0], self.scratch_size,
                                                           int(_comp_per_candidate(self.ptr)))
        out = np.empty((x.shape[0], COMP_N_OUT))
        kept = np.empty(x.shape[0], dtype=np.int64)
        status = _comp_grnn_blocks(self.ptr, len(row_ptr) - 1, row_ptr.ctypes.data, cand_ptr.ctypes.data,
                                   cand.ctypes.data, float(blocks.log_cut), x.ctypes.data, out.ctypes.data,
                                   scratch.ctypes.data, kept.ctypes.data)
        if status:
            raise ValueError(f"compensator: {STATUS[status]}")
        return out, kept
