"""Seed 003 metrics on the held-out test set.

Residual r = compensated (or raw) output - truth, per channel (wx, wy, wz,
ax, ay, az; SI units).  Per model and channel: the signed mean, the std,
the mean |r| and the **systematic residual** sqrt(max(mean(r^2) - s^2, 0)),
s the white-noise std of one sample (:func:`noise_floor`): what is left
above the floor no compensator can go below (the sensor's white noise is
independent from sample to sample).  Reductions are against the raw output,
averaged over the six channels (the paper does not define its "combined"
figure).  The models fall into seed 003's groups (:data:`GROUPS`);
:func:`ordering` states whether every recurrent model beats every shallow
one and every shallow one the traditional model.
"""

from __future__ import annotations

import numpy as np

GROUPS = {"traditional": ("traditional",), "shallow": ("rbf", "grnn"),
          "recurrent": ("lstm", "gru", "lstm3", "gru3")}
METRICS = ("mean", "std", "mae", "sys")
METRIC_NAMES = {"mean": "|mean|", "std": "std", "mae": "mean |r|", "sys": "systematic rms above the noise floor"}


def noise_floor(model, step: float) -> np.ndarray:
    """White-noise std (6,) of one sample's mean rate (rad/s) and specific force (m/s^2): the angle and
    velocity random walks over a step of ``step`` s, rw / sqrt(step)."""
    return np.concatenate([model.gyro.random_walk, model.accel.random_walk]) / np.sqrt(float(step))


def residual_stats(residual: np.ndarray, floor: np.ndarray) -> dict:
    """Per-channel mean, std, mean |r| and systematic rms above ``floor`` of (n, 6) residuals, SI units."""
    r = np.asarray(residual, float)
    mean_square = np.mean(r ** 2, axis=0)
    return {"mean": r.mean(axis=0), "std": r.std(axis=0), "mae": np.abs(r).mean(axis=0),
            "sys": np.sqrt(np.maximum(mean_square - np.asarray(floor) ** 2, 0.0))}


def _add_rows(total: np.ndarray | None, rows: np.ndarray) -> np.ndarray:
    """``total + rows[0] + rows[1] + ...`` per column, in row order: numpy's sum over the first axis of a
    C-ordered (n, 6) array adds the rows one after another, so carrying ``total`` from chunk to chunk gives the
    whole array's sum bit for bit."""
    if total is None:
        return np.add.reduce(rows, axis=0)
    return np.add.reduce(np.concatenate([total[None], rows]), axis=0)


# rows a ResidualSums keeps in memory; the later ones go to a temporary file (a paper test set's residuals are
# 135 MB, and the campaign evaluates a recurrent model on three sets at once, two models at a time)
SPOOL_ROWS = 1 << 18


class ResidualSums:
    """:func:`residual_stats` of (n, 6) residuals fed a chunk of rows at a time, in row order, equal to the
    whole array's bit for bit (the same sums in the same order, tests/test_mems_calibration.py).

    The std is numpy's two-pass one (the mean first, then the squared deviations from it), so the rows are
    kept until :meth:`stats`: the first ``spool_rows`` (default :data:`SPOOL_ROWS`) in memory, the rest in an
    unnamed temporary file (``tempfile.TemporaryFile``, gone when this object is) read back a chunk at a time.
    """

    def __init__(self, spool_rows: int | None = None):
        self.n = 0
        self._width = None  # columns of the rows, set by the first non-empty chunk
        self._sum = self._abs = self._square = None
        self._chunks = []
        self._spool_rows = SPOOL_ROWS if spool_rows is None else int(spool_rows)
        self._spool = None  # the temporary file of the rows after the in-memory ones
        self._spooled = []  # lengths of the chunks in the file, in order

    def add(self, rows: np.ndarray) -> None:
        """Rows (m, 6) following those added so far (m may be 0)."""
        r = np.ascontiguousarray(rows, dtype=float)
        if r.ndim != 2 or (self._width is not None and r.shape[1] != self._width):
            raise ValueError(f"residual rows must be (m, {self._width or 'k'}), got {r.shape}")
        if not len(r):
            return
        self._width = r.shape[1]
        self._sum = _add_rows(self._sum, r)
        self._abs = _add_rows(self._abs, np.abs(r))
        self._square = _add_rows(self._square, r * r)
        if self._spool is None and self.n + len(r) <= self._spool_rows:
            self._chunks.append(r)
        else:
            if self._spool is None:
                import tempfile

                self._spool = tempfile.TemporaryFile()
            r.tofile(self._spool)
            self._spooled.append(len(r))
        self.n += len(r)

    def _kept(self):
        """The rows added, a chunk at a time, in order."""
        yield from self._chunks
        if self._spool is not None:
            self._spool.flush()
            self._spool.seek(0)
            for m in self._spooled:
                yield np.fromfile(self._spool, dtype=float, count=m * self._width).reshape(m, self._width)

    def stats(self, floor: np.ndarray) -> dict:
        """:func:`residual_stats` of every row added (at least one)."""
        if not self.n:
            raise ValueError("no residual rows were added")
        mean = self._sum / self.n
        deviation = None
        for r in self._kept():
            d = r - mean
            deviation = _add_rows(deviation, np.multiply(d, d, out=d))
        return {"mean": mean, "std": np.sqrt(deviation / self.n), "mae": self._abs / self.n,
                "sys": np.sqrt(np.maximum(self._square / self.n - np.asarray(floor) ** 2, 0.0))}


def reductions(stats: dict, raw: dict) -> dict:
    """Reduction vs the raw output, % per metric: the mean over the six channels of 1 - x / x_raw
    (x = |mean|, std, mean |r|, systematic rms)."""
    return {key: float(100.0 * np.mean(1.0 - np.abs(stats[key]) / np.abs(raw[key]))) for key in METRICS}


def _extreme(red: dict, names, pick):
    present = [(red[n], n) for n in names if n in red]
    return pick(present) if present else None


def ordering(red: dict) -> dict:
    """Per metric: does every recurrent model beat every shallow model, and every shallow model the
    traditional one (higher reduction = better)?

    Returns {metric: {"recurrent_over_shallow": bool or None, "shallow_over_traditional": bool or None,
    "worst_recurrent": [name, %], "best_shallow": [name, %], "worst_shallow": [name, %],
    "traditional": %}}; None where a group was not run.
    """
    out = {}
    for metric in METRICS:
        values = {name: r[metric] for name, r in red.items()}
        worst_rec = _extreme(values, GROUPS["recurrent"], min)
        best_sh, worst_sh = _extreme(values, GROUPS["shallow"], max), _extreme(values, GROUPS["shallow"], min)
        trad = values.get("traditional")
        out[metric] = {
            "recurrent_over_shallow": None if worst_rec is None or best_sh is None else bool(worst_rec[0] > best_sh[0]),
            "shallow_over_traditional": None if worst_sh is None or trad is None else bool(worst_sh[0] > trad),
            "worst_recurrent": None if worst_rec is None else [worst_rec[1], worst_rec[0]],
            "best_shallow": None if best_sh is None else [best_sh[1], best_sh[0]],
            "worst_shallow": None if worst_sh is None else [worst_sh[1], worst_sh[0]],
            "traditional": trad}
    return out


def ordered_metrics(order: dict) -> list:
    """Metrics on which the whole order recurrent > shallow > traditional holds."""
    return [m for m, o in order.items() if o["recurrent_over_shallow"] and o["shallow_over_traditional"]]


def term_rms(full_x: np.ndarray, ablated_x: np.ndarray) -> np.ndarray:
    """Rms (6,) of one time-correlated term on a recording: the measured outputs with the term minus
    those without it (same seed, so the noise cancels exactly), SI units."""
    d = np.asarray(full_x, float)[:, :6] - np.asarray(ablated_x, float)[:, :6]
    return np.sqrt(np.mean(d ** 2, axis=0))
