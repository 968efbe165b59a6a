"""The comparison table every campaign report carries: paper value against our distribution.

One row per headline claim of a paper: the paper's value, the median and the
5-95 % range of our runs, and the paper's percentile in our runs.

**Percentile of a value in a sample** (mid-rank definition): with n sample
values, P(v) = 100 (#{x < v} + 1/2 #{x = v}) / n.  So a value below every run
is at 0 %, above every run at 100 %, and equal to the median of an odd-sized
sample at 50 %.  The 5-95 % range is numpy's linear-interpolation percentile
(``np.percentile``, method 'linear').

A claim whose sample has fewer than :data:`MIN_RUNS` runs is listed with
"too few runs to test" instead of a percentile (the quick profiles): a
median of two runs says nothing about where the paper's value falls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

MIN_RUNS = 5  # fewer runs than this: the row states that the claim is not tested


def percentile_of(value: float, sample) -> float:
    """Mid-rank percentile (0..100) of ``value`` in ``sample`` (see the module docstring)."""
    x = np.asarray(sample, float).ravel()
    if x.size == 0:
        raise ValueError("empty sample")
    if not (math.isfinite(value) and np.isfinite(x).all()):
        raise ValueError("percentile_of needs finite values")
    return float(100.0 * (np.sum(x < value) + 0.5 * np.sum(x == value)) / x.size)


@dataclass(frozen=True)
class Claim:
    """One headline claim of a paper and our runs' values of the same quantity.

    name : what is compared (with its unit); paper : the paper's value, or a
    (low, high) band; sample : our runs' values (one per run); paper_text :
    how the paper states it (default the number); note : why a row is not
    tested (e.g. the profile does not run it), shown instead of the numbers
    when ``sample`` is empty.
    """

    name: str
    paper: float | tuple
    sample: tuple = field(default_factory=tuple)
    paper_text: str = ""
    note: str = ""
    digits: int = 4

    def __post_init__(self):
        if "|" in self.name + self.paper_text + self.note:
            raise ValueError(f"a comparison row's text may not contain '|' (Markdown cell): {self.name!r}")
        object.__setattr__(self, "sample", tuple(float(v) for v in np.asarray(self.sample, float).ravel()))

    @property
    def tested(self) -> bool:
        return len(self.sample) >= MIN_RUNS

    def _num(self, v: float) -> str:
        return f"{v:.{self.digits}g}"

    def cells(self) -> list:
        paper = self.paper_text or (f"{self._num(self.paper[0])} .. {self._num(self.paper[1])}"
                                    if isinstance(self.paper, tuple) else self._num(self.paper))
        n = len(self.sample)
        if n == 0:
            return [self.name, paper, "-", "-", f"not tested: {self.note or 'no runs'}"]
        x = np.asarray(self.sample)
        lo, hi = np.percentile(x, [5.0, 95.0])
        med, rng = f"{self._num(float(np.median(x)))} (n = {n})", f"{self._num(lo)} .. {self._num(hi)}"
        if not self.tested:
            return [self.name, paper, med, rng, f"not tested: too few runs ({n} < {MIN_RUNS})"]
        if isinstance(self.paper, tuple):
            pct = f"{percentile_of(self.paper[0], x):.0f} .. {percentile_of(self.paper[1], x):.0f} %"
        else:
            pct = f"{percentile_of(self.paper, x):.0f} %"
        return [self.name, paper, med, rng, pct]


HEADER = ["claim", "paper value", "ours (median)", "ours 5-95 %", "paper's percentile in ours"]
CALIBRATED_HEADER = ["claim", "paper value", "sourced unit: ours (median)", "sourced: paper's percentile",
                     "calibrated unit: ours (median)", "calibrated: ours 5-95 %", "calibrated: paper's percentile"]


def calibrated_rows(sourced, calibrated, fitted: int, rename=lambda name: name) -> list:
    """Rows under :data:`CALIBRATED_HEADER`: each claim of the sourced unit beside the same claim on a
    calibrated unit (same order); row ``fitted`` is the figure the unit was fitted to, marked as no test.
    ``rename`` maps the sourced claim's name to the row's."""
    rows = []
    for i, (a, b) in enumerate(zip(sourced, calibrated)):
        ca, cb = a.cells(), b.cells()
        name = rename(ca[0]) + (" -- **fitted to this: not a test**" if i == fitted else "")
        rows.append([name, ca[1], ca[2], ca[4], cb[2], cb[3], cb[4]])
    return rows


def comparison_lines(claims, *, title: str = "## The paper against our runs", profile: str | None = None) -> list:
    """Markdown section: the comparison table, its definitions, and (quick profiles) the
    claims the profile is too small to test."""
    claims = list(claims)
    lines = [title, "", "| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    lines += ["| " + " | ".join(c.cells()) + " |" for c in claims]
    lines += ["", "Median and 5-95 % over our runs (numpy linear-interpolation percentiles); the paper's "
              "percentile is its value's mid-rank in our runs, 100 (#{x < v} + #{x = v}/2) / n: 50 % means the "
              "paper sits at our median, 0 % or 100 % that it lies outside every run "
              f"(`sarins.comparison`). Rows with fewer than {MIN_RUNS} runs are not tested.", ""]
    untested = [c.name for c in claims if not c.tested]
    if untested:
        lines += [f"**{'The ' + profile + ' profile is' if profile else 'These runs are'} too small to test:** "
                  + "; ".join(untested) + ".", ""]
    return lines
