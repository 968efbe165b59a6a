"""Seed 003's large arrays kept on disk between the campaign's phases and read back a chunk at a time.

The recordings stay in the campaign's stored results (``<out>/recordings/<id>.npz``) and are loaded one at a
time when a phase needs them (:class:`StoredRecordings`); the data sets the evaluation reads are written to
``<out>/datasets/<name>.{X,Y,time}.npy`` and read back ``rows`` at a time (:class:`StoredSet`), so the
campaign holds at most one recording, the training set while the models are fitted, and chunk-long
temporaries.  Reading never changes a number: the arrays are float64 as computed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarins_fmu.experiments.mems_calibration import Dataset

COLUMNS = ("X", "Y", "time")


class StoredRecordings(Mapping):
    """{recording id: stored result file} read as {id: recording dict}: each access loads (and checks) the
    file, and nothing is cached, so a caller holds only the recordings it keeps references to."""

    def __init__(self, paths: dict):
        self.paths = {k: Path(v) for k, v in paths.items()}

    def __getitem__(self, key: str) -> dict:
        from sarins.campaign import load_result

        return load_result(self.paths[key])

    def __iter__(self):
        return iter(self.paths)

    def __len__(self) -> int:
        return len(self.paths)


@dataclass(frozen=True)
class StoredSet:
    """Rows ``start .. stop - 1`` of a data set stored by :func:`save_set` (inputs X (n, 7), targets Y (n, 6),
    times (n,) s, as :class:`~sarins_fmu.experiments.mems_calibration.Dataset`)."""

    folder: Path
    name: str
    start: int
    stop: int

    def path(self, column: str) -> Path:
        return Path(self.folder) / f"{self.name}.{column}.npy"

    def __len__(self) -> int:
        return self.stop - self.start

    def _read(self, column: str, a: int, b: int) -> np.ndarray:
        """Rows a .. b - 1 (relative to ``start``) of one column, copied out of a mapping that is closed at
        once (a mapping kept open would keep every page read in the resident set)."""
        mapped = np.load(self.path(column), mmap_mode="r")
        try:
            return np.array(mapped[self.start + a:self.start + b])
        finally:
            del mapped

    def rows(self, a: int, b: int) -> Dataset:
        """Rows a .. b - 1 (relative to ``start``) in memory."""
        a, b = max(0, int(a)), min(len(self), int(b))
        return Dataset(*(self._read(c, a, max(a, b)) for c in COLUMNS))

    def chunks(self, rows: int):
        """(X, Y) of consecutive chunks of ``rows`` rows (the last shorter), in order."""
        for a in range(0, len(self), int(rows)):
            part = self.rows(a, a + int(rows))
            yield part.X, part.Y

    @property
    def time(self) -> np.ndarray:
        """Every row's time, s (n,)."""
        return self._read("time", 0, len(self))

    def head(self, n: int) -> "StoredSet":
        """The first ``n`` rows."""
        return StoredSet(self.folder, self.name, self.start, self.start + max(0, min(int(n), len(self))))

    def tail(self, n: int) -> "StoredSet":
        """The last ``n`` rows (contiguous, still in time order)."""
        return StoredSet(self.folder, self.name, self.stop - max(0, min(int(n), len(self))), self.stop)

    def load(self) -> Dataset:
        """All rows in memory."""
        return self.rows(0, len(self))


def save_set(folder: Path, name: str, data: Dataset) -> StoredSet:
    """Write ``data`` as ``<folder>/<name>.{X,Y,time}.npy`` (each atomically); the stored set."""
    from sarins.campaign import atomic_output

    folder = Path(folder)
    for column in COLUMNS:
        with atomic_output(folder / f"{name}.{column}.npy", keep_suffix=True) as tmp:
            np.save(tmp, np.ascontiguousarray(getattr(data, column)))
    return StoredSet(folder, name, 0, len(data))
