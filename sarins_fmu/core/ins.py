"""ctypes binding of the strapdown INS state (``ins.h``) and of the StrapdownINS FMU's step (``ins_fmu_step.h``).

The C structs live in numpy byte buffers owned by the Python objects
(:class:`InsState`, :class:`FmuState`); their fields a caller may read or
write (the attitude quaternion, velocity, position, the alignment
estimates, the FMU's outputs) are numpy views into them, at the offsets
the library reports, so no layout is written twice.  The structs hold no
pointer: a copy of the buffer is a copy of the state.
"""

from __future__ import annotations

import ctypes

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P, _INT, _SIZE = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t

# settings array of sarins_ins_init (the enum of ins.h, in order)
CONFIG_FIELDS = ("lat", "lon", "height", "align_time", "coarse_time", "step")
FILTER_FIELDS = ("arw", "vrw", "drift_rw", "bias_rw", "velocity_meas_std", "tilt0_std", "heading0_std",
                 "velocity0_std", "drift0_std", "bias0_std")
CONFIG_SIZE = len(CONFIG_FIELDS) + len(FILTER_FIELDS)
PHASES = ("coarse", "fine", "navigate")

# inputs and Real outputs of the FMU step (the enums of ins_fmu_step.h, in order)
FMU_INPUTS = ("dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z", "increment_end_time", "temp_gyro_z",
              "axial_drift_correction", "axial_drift_correction_b", "axial_drift_correction_a",
              "axial_drift_apply_from")
FMU_OUTPUTS = ("lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "lat_error", "lon_error",
               "north_error", "east_error", "position_error", "nav_time", "gyro_drift_est_x", "gyro_drift_est_y",
               "accel_bias_est_x", "accel_bias_est_y", "temp_align_start", "temp_align_end", "temp_change_align",
               "temp_azimuth_gyro", "solution_time")

_MSG = 512  # bytes of a reason

_config_check = function("sarins_ins_config_check", _INT, _P, ctypes.c_char_p, _SIZE)
_init = function("sarins_ins_init", _INT, _P, _P, _P, ctypes.c_char_p, _SIZE)
_reset = function("sarins_ins_reset", None, _P)
_phase = function("sarins_ins_phase", _INT, _P)
_steps = function("sarins_ins_steps", _INT, _P, _I64, _P, _P, _P, _P, _P)
_position_error = function("sarins_ins_position_error", None, _P, _I64, _P, _P)
_layout = function("sarins_ins_layout", _I64, _P)
_mat_to_quat = function("sarins_mat_to_quat", None, _P, _P)
_fmu_setup = function("sarins_ins_fmu_setup", None, _P, _P, _P, _F64)
_fmu_start = function("sarins_ins_fmu_start", _INT, _P, _P, ctypes.c_char_p, _SIZE)
_fmu_do_step = function("sarins_ins_fmu_do_step", _INT, _P, _P, _F64, _F64, ctypes.c_char_p, _SIZE)
_comp_init = function("sarins_ins_comp_init", None, _P, _P, _F64)
_comp_value_at = function("sarins_ins_comp_value_at", _INT, _P, _P, _F64, _F64, _F64, _P, ctypes.c_char_p, _SIZE)
_fmu_layout = function("sarins_ins_fmu_layout", _I64, _P)


def _struct_layout(fn, count: int) -> tuple[int, np.ndarray]:
    offsets = np.zeros(count, dtype=np.int64)
    return int(fn(offsets.ctypes.data)), offsets


_INS_SIZE, _INS_OFFSETS = _struct_layout(_layout, 12)
_FMU_SIZE, _FMU_OFFSETS = _struct_layout(_fmu_layout, 5)


def _buffer(size: int) -> np.ndarray:
    """Zeroed float64 storage (8-byte aligned) of at least ``size`` bytes."""
    return np.zeros((size + 7) // 8)


def _view(buffer: np.ndarray, offset: int, count: int, dtype=np.float64) -> np.ndarray:
    """Writable view of ``count`` values of ``dtype`` at byte ``offset`` of ``buffer``."""
    return buffer.view(np.uint8)[offset:offset + 8 * count].view(dtype)


def config_array(config) -> np.ndarray:
    """The settings array of ``sarins_ins_init`` from an :class:`sarins_fmu.ins.InsConfig`."""
    values = []
    for owner, fields, prefix in ((config, CONFIG_FIELDS, ""), (getattr(config, "filter", None), FILTER_FIELDS,
                                                                  "filter.")):
        for name in fields:
            if not hasattr(owner, name):
                raise ValueError(f"INS settings need an InsConfig (sarins_fmu.ins) with {prefix}{name}; got "
                                 f"{type(config).__name__}")
            try:
                values.append(float(getattr(owner, name)))
            except (TypeError, ValueError, OverflowError):
                raise ValueError(f"INS setting {prefix}{name} must be a number, got "
                                 f"{getattr(owner, name)!r}") from None
    return np.array(values)


def config_problem(config: np.ndarray) -> str | None:
    """The reason ``sarins_ins_config_check`` refuses a settings array, or None."""
    config = _arrays.read(config, (CONFIG_SIZE,), "INS settings")
    msg = ctypes.create_string_buffer(_MSG)
    return None if _config_check(config.ctypes.data, msg, _MSG) == 0 else msg.value.decode()


def mat_to_quat(mat) -> np.ndarray:
    """Unit quaternion [w x y z] of a DCM (``sarins_mat_to_quat``)."""
    mat = _arrays.read(mat, (3, 3), "mat")
    q = np.empty(4)
    _mat_to_quat(mat.ctypes.data, q.ctypes.data)
    return q


class InsState:
    """A ``sarins_ins`` struct (ins.h).  Raises ValueError with the core's reason for bad settings.

    Attributes (views into the struct, writable): q (4,) q_nb [w x y z]; v (3,) ENU m/s; pos (3,) lat,
    lon rad, height m; gyro_comp (3,) rad/s; accel_comp (3,) m/s^2; x (9,); p (9, 9); q_diag (9,).
    """

    def __init__(self, config: np.ndarray, mat_nb0=None):
        config = _arrays.read(config, (CONFIG_SIZE,), "INS settings")
        mat = None if mat_nb0 is None else _arrays.read(mat_nb0, (3, 3), "initial attitude")
        self.buffer = _buffer(_INS_SIZE)
        msg = ctypes.create_string_buffer(_MSG)
        if _init(self.buffer.ctypes.data, config.ctypes.data, None if mat is None else mat.ctypes.data, msg,
                 _MSG) != 0:
            raise ValueError(msg.value.decode())
        o = _INS_OFFSETS
        self.q, self.v, self.pos = _view(self.buffer, o[0], 4), _view(self.buffer, o[1], 3), _view(self.buffer, o[2], 3)
        self.gyro_comp, self.accel_comp = _view(self.buffer, o[3], 3), _view(self.buffer, o[4], 3)
        self.x, self.p = _view(self.buffer, o[5], 9), _view(self.buffer, o[6], 81).reshape(9, 9)
        self.q_diag = _view(self.buffer, o[7], 9)
        self._steps = _view(self.buffer, o[8], 1, np.int64)
        self.n_coarse = int(_view(self.buffer, o[9], 1, np.int64)[0])  # steps of the coarse alignment
        self.n_align = int(_view(self.buffer, o[10], 1, np.int64)[0])  # steps of the whole alignment

    @property
    def steps(self) -> int:
        """Major-loop steps integrated."""
        return int(self._steps[0])

    @property
    def phase(self) -> str:
        """'coarse', 'fine' or 'navigate'."""
        return PHASES[_phase(self.buffer.ctypes.data)]

    def reset(self) -> None:
        """Back to the state after initialisation."""
        _reset(self.buffer.ctypes.data)

    def steps_run(self, dtheta, dv, axial_corr) -> tuple[np.ndarray, np.ndarray]:
        """``sarins_ins_steps`` over K steps: returns the (K, 9) rows and the (K, 9) P diagonal after each
        fine-alignment step (NaN in the rows of other steps).  ValueError for a non-finite input."""
        dtheta = _arrays.read(dtheta, (np.shape(dtheta)[0], 3), "dtheta")
        k = dtheta.shape[0]
        dv = _arrays.read(dv, (k, 3), "dv")
        axial_corr = _arrays.read(axial_corr, (k,), "axial_corr")
        out = np.empty((k, 9))
        p_diag = np.full((k, 9), np.nan)
        if _steps(self.buffer.ctypes.data, k, dtheta.ctypes.data, dv.ctypes.data, axial_corr.ctypes.data,
                  out.ctypes.data, p_diag.ctypes.data) != 0:
            raise ValueError("increments or axial correction contain NaN or infinity")
        return out, p_diag

    def position_error(self, rows) -> np.ndarray:
        """(K, 4) dlat, dlon (rad), north, east (m) of (K, 9) rows wrt the start."""
        rows = _arrays.read(rows, (np.shape(rows)[0], 9), "rows")
        err = np.empty((rows.shape[0], 4))
        _position_error(self.buffer.ctypes.data, rows.shape[0], rows.ctypes.data, err.ctypes.data)
        return err


class FmuState:
    """A ``sarins_ins_fmu`` struct (ins_fmu_step.h): the StrapdownINS FMU's whole state.

    ``out`` (24,) is a view of its Real outputs in the order :data:`FMU_OUTPUTS`; :attr:`phase` its
    Integer output.  The methods raise ValueError with the core's reason when it refuses a call (the
    state is then unchanged).
    """

    def __init__(self):
        self.buffer = _buffer(_FMU_SIZE)
        self.out = _view(self.buffer, int(_FMU_OFFSETS[0]), len(FMU_OUTPUTS))
        self._phase = _view(self.buffer, int(_FMU_OFFSETS[1]), 1, np.int64)
        self._msg = ctypes.create_string_buffer(_MSG)

    @property
    def phase(self) -> int:
        """0 coarse alignment, 1 fine alignment, 2 navigation."""
        return int(self._phase[0])

    def setup(self, config: np.ndarray, attitude0, start_time: float) -> None:
        """``sarins_ins_fmu_setup``: the settings, yaw0/pitch0/roll0 (rad) and start time (s); start outputs."""
        config = _arrays.read(config, (CONFIG_SIZE,), "INS settings")
        attitude0 = _arrays.read(attitude0, (3,), "attitude0")
        _fmu_setup(self.buffer.ctypes.data, config.ctypes.data, attitude0.ctypes.data, float(start_time))

    def _check(self, status: int) -> None:
        if status != 0:
            raise ValueError(self._msg.value.decode())

    def start(self, inputs: np.ndarray) -> None:
        """``sarins_ins_fmu_start`` with the inputs (:data:`FMU_INPUTS` order)."""
        inputs = _arrays.read(inputs, (len(FMU_INPUTS),), "inputs")
        self._check(_fmu_start(self.buffer.ctypes.data, inputs.ctypes.data, self._msg, _MSG))

    def do_step(self, inputs: np.ndarray, t: float, h: float) -> None:
        """``sarins_ins_fmu_do_step``: doStep(t, h) with the inputs (:data:`FMU_INPUTS` order)."""
        inputs = _arrays.read(inputs, (len(FMU_INPUTS),), "inputs")
        self._check(_fmu_do_step(self.buffer.ctypes.data, inputs.ctypes.data, float(t), float(h), self._msg, _MSG))


class CompensationQueue:
    """A ``sarins_ins_comp`` (the FMU's azimuth drift compensation queue, ins_fmu_step.h), on its own.

    value: (c, b, a) rad/s per degC^n; apply_from and nav_start: nav time, s.
    """

    def __init__(self, value, apply_from: float):
        self.buffer = _buffer(_FMU_SIZE)  # larger than the queue: the FMU struct holds one
        self._count = _view(self.buffer, int(_FMU_OFFSETS[4]) - int(_FMU_OFFSETS[3]), 1, np.int64)
        self._msg = ctypes.create_string_buffer(_MSG)
        value = _arrays.read(value, (3,), "value")
        _comp_init(self.buffer.ctypes.data, value.ctypes.data, float(apply_from))

    @property
    def queued(self) -> int:
        """Pairs waiting to apply."""
        return int(self._count[0])

    def value_at(self, nav_start: float, value, apply_from: float, step: float) -> tuple:
        """The value in force for the interval starting at ``nav_start`` given the input pair."""
        value = _arrays.read(value, (3,), "value")
        current = np.empty(3)
        if _comp_value_at(self.buffer.ctypes.data, value.ctypes.data, float(apply_from), float(nav_start),
                          1e-6 * float(step), current.ctypes.data, self._msg, _MSG) != 0:
            raise ValueError(self._msg.value.decode())
        return tuple(float(x) for x in current)

