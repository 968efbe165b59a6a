"""The master's inner loop in C: the prepared plan of :class:`~orchestration.master.Master` run for
a block of steps in one call (``orchestration/steploop.c``, built by ``pip install`` as
``orchestration/_steploop*.so``).

The plan is the Python loop's own: the same FMI calls (through the same function pointers, with
the same value buffers), unit maps and casts, in the same order, so both loops give the same
numbers bit for bit; only the per-call cost of Python and ctypes goes.  Rows are recorded into the
:class:`~orchestration.recorder.Recorder`'s storage.  The loop returns to Python after each block
(the master keeps blocks short, so a signal is acted on within milliseconds), at the first failing
call, at an FMI 3.0 terminate request and at a failing record, which the master reports as before.

When the library is missing (a source checkout without a build) :func:`load` returns ``None`` and the
master runs its Python loop.
"""
from __future__ import annotations

import ctypes
import importlib.machinery
from ctypes import POINTER, Structure, c_bool, c_double, c_float, c_int8, c_int16, c_int32, c_int64, \
    c_uint8, c_uint16, c_uint32, c_uint64, c_void_p
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["load", "CompiledLoop", "OpSpec", "ABI"]

ABI = 1  # SL_ABI in steploop.c
NAME = "_steploop"
OP_VALUES2, OP_VALUES3, OP_STEP2, OP_STEP3, OP_MAP, OP_CAST = range(6)
DONE, CALL_FAILED, TERMINATED, RECORD_FAILED, FULL, BAD_OP = range(6)
_TYPE_CODES = {c_double: 0, c_float: 1, c_int8: 2, c_uint8: 3, c_int16: 4, c_uint16: 5, c_int32: 6,
               c_uint32: 7, c_int64: 8, c_uint64: 9, c_bool: 10}


class _Op(Structure):
    _fields_ = [("kind", c_int32), ("type", c_int32), ("type_to", c_int32), ("pad", c_int32),
                ("fn", c_void_p), ("instance", c_void_p), ("vrs", c_void_p), ("nvr", c_uint64),
                ("values", c_void_p), ("n_values", c_uint64), ("factor", c_void_p), ("offset", c_void_p),
                ("target", c_void_p), ("event", c_void_p), ("terminate", c_void_p), ("early", c_void_p),
                ("last_time", c_void_p)]


class _Record(Structure):
    _fields_ = [("fmi3", c_int32), ("pad", c_int32), ("fn", c_void_p), ("instance", c_void_p),
                ("vrs", c_void_p), ("nvr", c_uint64), ("n_values", c_uint64), ("base", c_void_p),
                ("row_bytes", c_uint64)]


class _State(Structure):
    _fields_ = [("begin", c_double), ("h", c_double), ("end", c_double), ("j0", c_int64), ("count", c_int64),
                ("seg_count", c_int64), ("done", c_int64), ("total", c_int64), ("every", c_int64),
                ("next_record", c_int64), ("rows", c_int64), ("capacity", c_int64), ("times", c_void_p),
                ("outcome", c_int32), ("status", c_int32), ("where", c_int64), ("t_fail", c_double),
                ("t_end", c_double), ("seconds", c_void_p)]


@dataclass
class OpSpec:
    """One operation of the plan in C terms; ``owner`` is the index of the Python loop's operation it
    belongs to (for error reports).

    kind ``values``: an FMI getter or setter ``function`` on ``instance`` (a c_void_p), ``vrs`` (a ctypes
    array), ``values`` (a ctypes array or a c_void_p holding an address), ``n_values``, ``fmi3``.
    kind ``step``: ``fmi2DoStep`` / ``fmi3DoStep`` (``flags``: the DoStep3Flags of an FMI 3.0 FMU).
    kind ``map``: ``values`` (a numpy view of a float buffer) = values * factors + offsets.
    kind ``cast``: numpy arrays ``source`` -> ``target``.
    """

    kind: str
    owner: int
    function: object = None
    instance: object = None
    vrs: object = None
    values: object = None
    n_values: int = 0
    fmi3: bool = False
    flags: object = None
    factors: object = None
    offsets: object = None
    source: object = None
    target: object = None


def _library_path() -> Path | None:
    here = Path(__file__).resolve().parent
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        if (here / (NAME + suffix)).is_file():
            return here / (NAME + suffix)
    return None


_LIB: list = []


def load():
    """The compiled loop library, or ``None`` when it is not built (the master then loops in Python)."""
    if not _LIB:
        path = _library_path()
        lib = None
        if path is not None:
            try:
                lib = ctypes.CDLL(str(path))
                lib.sl_abi.restype = ctypes.c_int
                if lib.sl_abi() != ABI:
                    lib = None
                else:
                    lib.sl_run.restype = ctypes.c_int
                    lib.sl_run.argtypes = [POINTER(_Op), c_uint64, POINTER(_Record), c_uint64, POINTER(_State)]
            except OSError:
                lib = None
        _LIB.append(lib)
    return _LIB[0]


def _address(obj) -> int:
    """The address of a ctypes array, c_void_p or numpy array."""
    if isinstance(obj, np.ndarray):
        return obj.ctypes.data
    if isinstance(obj, c_void_p):
        return obj.value or 0
    return ctypes.addressof(obj)


def _function_address(function) -> int:
    return ctypes.cast(function, c_void_p).value


def _numpy_code(array: np.ndarray) -> int | None:
    for ctype, code in _TYPE_CODES.items():
        if np.dtype(ctype) == array.dtype:
            return code
    return None


class CompiledLoop:
    """The plan as C operations and the recorder's blocks as C records.

    Raises ``ValueError`` for a plan the C loop cannot run (the master then uses its Python loop).
    """

    def __init__(self, lib, specs: list[OpSpec], recorder, profile: bool = False):
        self.lib = lib
        # profile: wall seconds per operation, recording last (sums over the run)
        self.seconds = np.zeros(len(specs) + 1) if profile else None
        self.specs = list(specs)
        self.owners = [s.owner for s in specs]
        self.ops = (_Op * max(1, len(specs)))()
        self.n_ops = len(specs)
        for op, spec in zip(self.ops, specs):
            self._fill(op, spec)
        blocks = recorder.blocks
        self.records = (_Record * max(1, len(blocks)))()
        self.n_records = len(blocks)
        for record, (get, args, address, row_bytes, _data, _i, _kind, _pointer) in zip(self.records, blocks):
            record.fmi3 = 1 if len(args) == 5 else 0
            record.fn = _function_address(get)
            record.instance = args[0].value
            record.vrs = ctypes.addressof(args[1])
            record.nvr = args[2].value
            record.n_values = args[4].value if len(args) == 5 else args[2].value
            record.base = address
            record.row_bytes = row_bytes
        self.recorder = recorder
        self.state = _State()

    @staticmethod
    def _fill(op: _Op, spec: OpSpec) -> None:
        if spec.kind == "values":
            op.kind = OP_VALUES3 if spec.fmi3 else OP_VALUES2
            op.fn = _function_address(spec.function)
            op.instance = spec.instance.value
            op.vrs = ctypes.addressof(spec.vrs)
            op.nvr = len(spec.vrs)
            op.values = _address(spec.values)
            op.n_values = spec.n_values
        elif spec.kind == "step":
            op.kind = OP_STEP3 if spec.fmi3 else OP_STEP2
            op.fn = _function_address(spec.function)
            op.instance = spec.instance.value
            if spec.fmi3:
                flags = spec.flags
                op.event, op.terminate, op.early = (ctypes.addressof(f) for f in
                                                    (flags.event, flags.terminate, flags.early))
                op.last_time = ctypes.addressof(flags.last_time)
        elif spec.kind == "map":
            code = _numpy_code(spec.values)
            if code not in (0, 1) or spec.factors.dtype != np.float64 or spec.offsets.dtype != np.float64:
                raise ValueError("unit maps only on float buffers")
            op.kind, op.type = OP_MAP, code
            op.values = _address(spec.values)
            op.n_values = spec.values.size
            op.factor, op.offset = _address(spec.factors), _address(spec.offsets)
        elif spec.kind == "cast":
            source, target = _numpy_code(spec.source), _numpy_code(spec.target)
            if source is None or target is None:
                raise ValueError("cast between types the C loop does not know")
            op.kind, op.type, op.type_to = OP_CAST, source, target
            op.values, op.target = _address(spec.source), _address(spec.target)
            op.n_values = spec.source.size
        else:
            raise ValueError(f"unknown operation {spec.kind}")

    def run(self, begin: float, h: float, end: float, j0: int, count: int, seg_count: int, done: int,
            total: int, every: int, next_record: int) -> _State:
        """Steps ``j0 .. j0 + count - 1`` of the segment; the returned state holds the counters and the
        outcome (:data:`DONE` ... ); the recorder's row count is updated."""
        s = self.state
        recorder = self.recorder
        s.begin, s.h, s.end, s.j0, s.count, s.seg_count = begin, h, end, j0, count, seg_count
        s.done, s.total, s.every, s.next_record = done, total, every, next_record
        s.rows, s.capacity = recorder.count, len(recorder.time)
        s.times = recorder.time.ctypes.data
        s.seconds = None if self.seconds is None else self.seconds.ctypes.data
        self.lib.sl_run(self.ops, self.n_ops, self.records, self.n_records, ctypes.byref(s))
        recorder.count = s.rows
        return s

