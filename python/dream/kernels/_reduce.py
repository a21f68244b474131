"""Reductions over ragged rows (CSR): what each robot makes of its neighbourhood, rows in parallel."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream._checks import FloatArray, as_index, as_offsets
from dream.kernels._dispatch import implementation

REDUCTIONS = ("sum", "mean", "min", "max")


def _values(values: Any, name: str) -> FloatArray:
    array = np.ascontiguousarray(values, dtype=np.float64)
    if array.ndim not in (1, 2):
        raise ValueError(f"`{name}` must have shape (k,) or (k, w), got {array.shape}")
    return array


def segment_reduce(values: Any, offsets: Any, op: str, index: Any = None) -> FloatArray:
    """``op`` of each row's entries: ``(m,)`` for values ``(k,)``, ``(m, w)`` for ``(k, w)``.

    ``op`` is one of "sum", "mean", "min", "max". Row r holds the entries
    ``offsets[r]:offsets[r + 1]``. Empty rows give 0 for a sum, NaN for the others; the minimum
    and maximum skip NaN entries, the sum and the mean carry them. Sums add in entry order, on
    both paths alike.

    With ``index`` ``(e,)`` int, entry e is ``values[index[e]]``: a per-robot array (a message
    field, say) reduced over each row's robots without gathering it first.
    """
    if op not in REDUCTIONS:
        raise ValueError(f"`op` must be one of {', '.join(REDUCTIONS)}, got {op!r}")
    array = _values(values, "values")
    if array.ndim == 2 and array.shape[1] == 0:
        raise ValueError(f"`values` must have at least one column, got shape {array.shape}")
    rows = array.reshape(-1, 1) if array.ndim == 1 else array
    if index is None:
        out = implementation("segment_reduce")(rows, as_offsets(offsets, "offsets", len(array)), op)
    else:
        at = as_index(index, "index")  # its bounds: checked by the kernel, in one pass
        out = implementation("segment_reduce")(rows, as_offsets(offsets, "offsets", len(at)), op, at)
    return out[:, 0] if array.ndim == 1 else out


def segment_any(flags: Any, offsets: Any) -> np.ndarray:
    """Whether any entry of each row of ``flags`` ``(k,)`` is set: ``(m,)`` bool."""
    array = np.ascontiguousarray(flags, dtype=np.bool_)
    if array.ndim != 1:
        raise ValueError(f"`flags` must have shape (k,), got {array.shape}")
    return implementation("segment_any")(array, as_offsets(offsets, "offsets", len(array)))


def segment_nearest(keys: Any, offsets: Any, k: int | None = None) -> np.ndarray:
    """The entry of each row with the smallest key (the first of equals, NaN skipped), as an index
    into ``keys`` ``(e,)``; -1 for a row that is empty or all NaN: ``(m,)`` int64.

    With ``k``, each row's ``k`` entries of smallest key, smallest first (of equals, the first
    entry first), -1 in the slots the row cannot fill: ``(m, k)`` int64 (the ``k`` nearest
    detections of each robot, say).
    """
    array = _values(keys, "keys")
    if array.ndim != 1:
        raise ValueError(f"`keys` must have shape (k,), got {array.shape}")
    cuts = as_offsets(offsets, "offsets", len(array))
    if k is None:
        return implementation("segment_nearest")(array, cuts)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 0:
        raise ValueError(f"`k` must be a whole number >= 0, got {k!r}")
    return implementation("segment_nearest")(array, cuts, int(k))


def segment_nearest_to(points: Any, offsets: Any, origins: Any, k: int, index: Any = None) -> np.ndarray:
    """Each row's ``k`` entries whose point lies nearest the row's origin, nearest first (of
    equals, the first entry first; NaN points skipped), -1 in the slots the row cannot fill:
    ``(m, k)`` int64 (the ``k`` nearest messages of each robot by the positions they give, say).

    ``points`` ``(e, 2)`` hold one point per entry; with ``index`` ``(e,)``, entry e's point is
    row ``index[e]`` of ``points`` ``(n, 2)`` (a per-robot array, read in place). ``origins`` are
    ``(m, 2)``, one per row. The ranking is by ``dx * dx + dy * dy``, what
    :func:`segment_nearest` gives with those squares for keys, to the bit.
    """
    p = _values(points, "points")
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"`points` must have shape (e, 2), got {p.shape}")
    o = _values(origins, "origins")
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 0:
        raise ValueError(f"`k` must be a whole number >= 0, got {k!r}")
    at = None if index is None else as_index(index, "index")
    cuts = as_offsets(offsets, "offsets", len(p) if at is None else len(at))
    if o.shape != (len(cuts) - 1, 2):
        raise ValueError(f"`origins` must have shape ({len(cuts) - 1}, 2), one per row, got {o.shape}")
    return implementation("segment_nearest_to")(p, cuts, o, int(k), at)
