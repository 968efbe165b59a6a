"""Recording of FMU variables into a numpy structured array.

The result has ``time`` (s) as its first field and one field per recorded
variable, named ``component.variable`` (float64 for Real, int32 for Integer
and Enumeration, bool for Boolean).  It is a :class:`ResultArray`, a plain
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

from .coupling import VALUE_TYPES
from .errors import UnknownVariableError
from .rawcalls import C_TYPES, count, getter, handle, value_buffer, vr_array

__all__ = ["ResultArray", "Recorder", "select_variables", "write_csv", "NUMPY_TYPES"]

NUMPY_TYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.bool_}


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
        if (i, var.name) not in seen and VALUE_TYPES.get(var.type, "String") != "String":
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
                   and VALUE_TYPES.get(var.type, "String") != "String"]
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
    """Preallocated storage filled by one ``fmi2Get*`` call per component and type.

    Parameters
    ----------
    slaves : sequence
        FMPy ``FMU2Slave`` per component (instantiated).
    names : sequence of str
        Component names.
    selection : list of (int, ModelVariable)
        From :func:`select_variables`.
    rows : int
        Number of rows to preallocate.
    """

    def __init__(self, slaves: Sequence, names: Sequence[str],
                 selection: list[tuple[int, object]], rows: int):
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
        for (i, kind), members in groups.items():
            n = len(members)
            storage = value_buffer(kind, rows * n)  # fmi2Get* writes rows in place
            data = np.ctypeslib.as_array(storage).reshape(rows, n)
            self.storage.append(storage)
            self.blocks.append((getter(slaves[i], kind), handle(slaves[i]),
                                vr_array(v.valueReference for v in members), count(n),
                                ctypes.addressof(storage),
                                n * ctypes.sizeof(C_TYPES[kind]), data, i, kind, ctypes.c_void_p()))
        # per block: (function, its arguments (the last one the row's address), that c_void_p,
        # the storage address, bytes per row, block index)
        self._calls = [(get, (component, vrs, n, pointer), pointer, address, row_bytes, b)
                       for b, (get, component, vrs, n, address, row_bytes, _, _, _, pointer)
                       in enumerate(self.blocks)]
        self._times = memoryview(self.time)  # item assignment without numpy's overhead
        position = {(block[7], v.name): (b, k) for b, block in enumerate(self.blocks)
                    for k, v in enumerate(groups[(block[7], block[8])])}
        for i, var in selection:
            b, k = position[(i, var.name)]
            self.columns.append((f"{names[i]}.{var.name}", VALUE_TYPES[var.type], b, k))

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
        return self.blocks[block][7], self.blocks[block][8]

    def result(self, meta: dict) -> ResultArray:
        """Assemble the structured array of the rows recorded so far."""
        dtype = [("time", np.float64)] + [(field, NUMPY_TYPES[kind])
                                          for field, kind, _, _ in self.columns]
        n = self.count
        out = np.empty(n, dtype=dtype)
        out["time"] = self.time[:n]
        for field, _, b, k in self.columns:
            out[field] = self.blocks[b][6][:n, k]
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
