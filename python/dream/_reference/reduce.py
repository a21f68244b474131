"""Reductions over ragged rows (CSR): sums, means, extremes and nearest entries of each row.

Row r of a neighbourhood holds entries ``offsets[r]:offsets[r + 1]``. Empty rows give 0 for a
sum and NaN for a mean, a minimum or a maximum; the minimum, the maximum and the nearest skip
NaN entries, the sum and the mean carry them. One row at a time, for clarity.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from dream._checks import FloatArray, check_rows


def _in_order(column: FloatArray) -> float:
    """The sum of ``column`` added in entry order from +0.0 (``np.sum`` adds pairwise), as the
    Rust kernel adds: the same bits on both paths."""
    return float(0.0 + np.cumsum(column)[-1])


_OPS: dict[str, Callable[..., Any]] = {
    "sum": _in_order,
    "mean": lambda column: _in_order(column) / len(column),
    "min": np.nanmin,
    "max": np.nanmax,
}


def segment_reduce(values: FloatArray, offsets: np.ndarray, op: str, index: np.ndarray | None = None) -> FloatArray:
    """``op`` ("sum", "mean", "min", "max") of each row's entries of ``values`` ``(k, w)``: ``(m, w)``;
    with ``index`` ``(e,)``, entry e is ``values[index[e]]``."""
    if op not in _OPS:
        raise ValueError(f"`op` must be sum, mean, min or max, got {op!r}")
    if index is not None:
        check_rows(index, "index", len(values))
        values = values[index]
    rows, width = len(offsets) - 1, values.shape[1]
    out = np.full((rows, width), 0.0 if op == "sum" else np.nan)
    for r in range(rows):
        row = values[offsets[r] : offsets[r + 1]]
        for c in range(width):
            column = row[:, c]
            if op in ("min", "max"):
                column = column[~np.isnan(column)]
            if len(column):
                out[r, c] = _OPS[op](column)
    return out


def segment_any(flags: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Whether any entry of each row of ``flags`` ``(k,)`` is set: ``(m,)`` bool."""
    return np.array([bool(flags[offsets[r] : offsets[r + 1]].any()) for r in range(len(offsets) - 1)], dtype=bool)


def segment_nearest(keys: FloatArray, offsets: np.ndarray, k: int | None = None) -> np.ndarray:
    """The entry of each row with the smallest of ``keys`` ``(e,)`` (the first of equals), as an
    index into them, -1 for a row that is empty or all NaN: ``(m,)``; with ``k``, each row's
    ``k`` smallest, smallest first, -1 in the slots left: ``(m, k)``."""
    slots = 1 if k is None else k
    out = np.full((len(offsets) - 1, slots), -1, dtype=np.int64)
    for r in range(len(offsets) - 1):
        row = keys[offsets[r] : offsets[r + 1]]
        kept = np.flatnonzero(~np.isnan(row))
        best = kept[np.argsort(row[kept], kind="stable")][:slots]
        out[r, : len(best)] = offsets[r] + best
    return out[:, 0] if k is None else out


def segment_nearest_to(
    points: FloatArray, offsets: np.ndarray, origins: FloatArray, k: int, index: np.ndarray | None = None
) -> np.ndarray:
    """Each row's ``k`` entries whose point (``points[e]``, or ``points[index[e]]``) lies nearest
    the row's origin: :func:`segment_nearest` of the squared distances ``dx * dx + dy * dy``."""
    if index is not None:
        check_rows(index, "index", len(points))
        points = points[index]
    if len(origins) != len(offsets) - 1:
        raise ValueError(f"`origins` must hold one point per row, {len(offsets) - 1}, got {len(origins)}")
    count = np.diff(offsets)
    dx = points[:, 0] - np.repeat(origins[:, 0], count)
    dy = points[:, 1] - np.repeat(origins[:, 1], count)
    return segment_nearest(dx * dx + dy * dy, offsets, k)
