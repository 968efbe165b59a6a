"""Recording of FMU variables into a numpy structured array.

The result has ``time`` (s) as its first field and one field per recorded
variable, named ``component.variable`` (float64 for Real, int32 for Integer
and Enumeration, bool for Boolean; an FMI 3.0 variable gets the numpy type
of its own type, ``Float32`` float32 ... ``UInt64`` uint64).  An FMI 3.0
array gets one field per element, ``component.variable[1]`` ..
``component.variable[n]`` (``[i,j]`` for more dimensions, row-major), all
read by the same ``fmi3Get*`` call.  It is a :class:`ResultArray`, a plain
structured ``ndarray`` that also carries a ``meta`` dictionary (coupling
scheme, stepping order, step, ...).
"""
from __future__ import annotations

import csv
import ctypes
import fnmatch
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .errors import UnknownVariableError
from .fmitypes import NUMPY_TYPES, RECORDABLE, VALUE_TYPES, c_type, element_names, size_of
from .rawcalls import getter, handle, is_fmi3_slave, value_args, value_buffer, vr_array

__all__ = ["ResultArray", "Recorder", "select_variables", "write_csv", "NUMPY_TYPES"]


def _recordable(var) -> bool:
    return VALUE_TYPES.get(var.type) in RECORDABLE


class ResultArray(np.ndarray):
    """Structured array of results with a ``meta`` dict (kept by views and slices)."""

    def __new__(cls, data: np.ndarray, meta: dict | None = None):
        array = np.asarray(data).view(cls)
        array.meta = dict(meta or {})
        return array

    def __array_finalize__(self, obj) -> None:
        self.meta = getattr(obj, "meta", {})


def select_variables(names: Sequence[str], variables: Sequence[dict],
                     patterns: Sequence[str] | None, files: Sequence[str]
                     ) -> list[tuple[int, object]]:
    """Resolve what to record.

    Parameters
    ----------
    names : sequence of str
        Component names.
    variables : sequence of dict
        ``{name: ModelVariable}`` per component.
    patterns : sequence of str or None
        ``component.variable`` names or shell patterns (``'imu.*'``);
        ``None`` records every output of every component.
    files : sequence of str
        FMU file per component, for error messages.

    Returns
    -------
    list of (int, ModelVariable)
        Component index and variable, in recording order, without repeats.

    Raises
    ------
    UnknownVariableError
        If a name or pattern matches nothing recordable.
    """
    chosen: list[tuple[int, object]] = []
    seen = set()

    def add(i: int, var) -> None:
        if (i, var.name) not in seen and _recordable(var):
            seen.add((i, var.name))
            chosen.append((i, var))

    if patterns is None:
        for i in range(len(names)):
            for var in variables[i].values():
                if var.causality == "output":
                    add(i, var)
        return chosen
    for pattern in patterns:
        matched = [(i, var) for i, name in enumerate(names) for var in variables[i].values()
                   if fnmatch.fnmatchcase(f"{name}.{var.name}", pattern)
                   and _recordable(var)]
        if not matched:
            component, _, variable = pattern.partition(".")
            file = files[names.index(component)] if component in names else None
            raise UnknownVariableError("nothing recordable (Real, Integer, Boolean) matches "
                                       f"'{pattern}'", file=file, component=component,
                                       variable=variable or None)
        for i, var in matched:
            add(i, var)
    return chosen


class Recorder:
    """Preallocated storage filled by one ``fmi2Get*`` / ``fmi3Get*`` call per component and type.

    Parameters
    ----------
    slaves : sequence
        FMPy ``FMU2Slave`` or ``FMU3Slave`` per component (instantiated).
    names : sequence of str
        Component names.
    selection : list of (int, ModelVariable)
        From :func:`select_variables`.
    rows : int
        Number of rows to preallocate.
    shapes : sequence of dict, optional
        Per component, ``{name: shape}`` of its FMI 3.0 array variables.
    """

    def __init__(self, slaves: Sequence, names: Sequence[str],
                 selection: list[tuple[int, object]], rows: int,
                 shapes: Sequence[dict] | None = None):
        self.names = list(names)
        self.selection = selection
        self.time = np.empty(rows)
        self.count = 0
        self.columns: list[tuple[str, str, int, int]] = []  # (field, kind, block, column)
        self.storage = []  # keeps the C arrays alive
        self.blocks = []  # (get, component handle, vr array, n, address, row bytes, data, i, kind, pointer)
        groups: dict[tuple[int, str], list] = {}
        for i, var in selection:
            groups.setdefault((i, VALUE_TYPES[var.type]), []).append(var)
        def shape(i: int, var) -> tuple:
            return () if shapes is None else shapes[i].get(var.name, ())

        position = {}
        for (i, kind), members in groups.items():
            fmi3 = is_fmi3_slave(slaves[i])
            n = 0
            for v in members:
                position[(i, v.name)] = (len(self.blocks), n)
                n += size_of(shape(i, v))
            storage = value_buffer(kind, rows * n, fmi3)  # fmi2Get*/fmi3Get* write rows in place
            data = np.ctypeslib.as_array(storage).reshape(rows, n)
            self.storage.append(storage)
            pointer = ctypes.c_void_p()
            self.blocks.append((getter(slaves[i], kind),
                                value_args(slaves[i], handle(slaves[i]),
                                           vr_array(v.valueReference for v in members), pointer, n),
                                ctypes.addressof(storage), n * ctypes.sizeof(c_type(kind, fmi3)),
                                data, i, kind, pointer))
        # per block: (function, its arguments (the values argument is that c_void_p), the
        # c_void_p, the storage address, bytes per row, block index)
        self._calls = [(get, args, pointer, address, row_bytes, b)
                       for b, (get, args, address, row_bytes, _, _, _, pointer)
                       in enumerate(self.blocks)]
        self._times = memoryview(self.time)  # item assignment without numpy's overhead
        for i, var in selection:
            b, k = position[(i, var.name)]
            for offset, field in enumerate(element_names(f"{names[i]}.{var.name}", shape(i, var))):
                self.columns.append((field, VALUE_TYPES[var.type], b, k + offset))

    def sample(self, time: float) -> int:
        """Store the current values as a row at ``time``; return a failing block or -1.

        Returns the index of the block whose ``fmi2Get*`` returned an error
        status (the row is then not kept), or -1 on success.
        """
        row = self.count
        self._times[row] = time
        for get, args, pointer, address, row_bytes, b in self._calls:
            pointer.value = address + row * row_bytes
            if get(*args) > 1:
                return b
        self.count = row + 1
        return -1

    def block_owner(self, block: int) -> tuple[int, str]:
        """Component index and kind of a block (for error reports)."""
        return self.blocks[block][5], self.blocks[block][6]

    def result(self, meta: dict) -> ResultArray:
        """Assemble the structured array of the rows recorded so far."""
        dtype = [("time", np.float64)] + [(field, NUMPY_TYPES[kind])
                                          for field, kind, _, _ in self.columns]
        n = self.count
        out = np.empty(n, dtype=dtype)
        out["time"] = self.time[:n]
        for field, _, b, k in self.columns:
            out[field] = self.blocks[b][4][:n, k]
        return ResultArray(out, meta)


def write_csv(result: np.ndarray, path: str | Path) -> Path:
    """Write a structured result array to CSV with a header row of field names.

    Parameters
    ----------
    result : numpy structured array
        E.g. the return value of :meth:`orchestration.Master.simulate`.
    path : str or Path
        File to write.

    Returns
    -------
    Path
        The written file.
    """
    path = Path(path)
    names = result.dtype.names
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(names)
        columns = [result[name].tolist() for name in names]
        for row in zip(*columns):
            writer.writerow(repr(v) if isinstance(v, float) else int(v) if isinstance(v, bool)
                            else v for v in row)
    return path
