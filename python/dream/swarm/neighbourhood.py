"""A neighbourhood: what each deciding robot perceives of the others, as ragged rows (CSR).

Row r belongs to the r-th robot deciding now and holds its entries ``offsets[r]:offsets[r + 1]``
of every column: its detections (distance, bearing, offsets, velocities) or the messages its
radio delivered (sender and the message's fields). Reductions run in the Rust kernels
(:func:`dream.kernels.segment_reduce` and friends), rows in parallel::

    centre = view.heard.mean(["x", "y"])       # (k, 2): the mean position each robot heard
    closest = view.seen.nearest()              # (k,): entry of the nearest detection, -1 if none
    gap = view.seen.pick("distance", closest)  # (k,): its distance, NaN if none
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from dream import kernels
from dream._checks import FloatArray


class Neighbourhood:
    """Ragged rows of named columns (see the module docs).

    Parameters
    ----------
    offsets : (k + 1,) int64
        Row r's entries are ``offsets[r]:offsets[r + 1]``.
    columns : mapping of name to (e,) array
        One value per entry.
    index, sources : (e,) int array and mapping of name to (n,) array, optional
        Columns read through ``index``: entry e's value is ``sources[name][index[e]]`` (the
        messages on the board, by sender). Reductions read them in place; a column is
        gathered only when asked for by name.
    """

    def __init__(
        self,
        offsets: np.ndarray,
        columns: Mapping[str, np.ndarray],
        index: np.ndarray | None = None,
        sources: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        self.offsets = offsets
        self.columns = dict(columns)
        self.index = index
        self.sources = {} if sources is None else dict(sources)

    def __len__(self) -> int:
        """The number of rows (robots deciding now)."""
        return len(self.offsets) - 1

    @property
    def names(self) -> list[str]:
        """The columns' names."""
        return [*self.columns, *self.sources]

    def __getitem__(self, name: str) -> np.ndarray:
        """Column ``name``, one value per entry."""
        if name not in self.columns:
            if name not in self.sources or self.index is None:
                raise KeyError(f"no column {name!r} in this neighbourhood (its columns: {', '.join(self.names)})")
            self.columns[name] = self.sources[name][self.index]
        return self.columns[name]

    def __repr__(self) -> str:
        return f"Neighbourhood({len(self)} rows, {self.offsets[-1]} entries, columns {self.names})"

    @property
    def count(self) -> np.ndarray:
        """``(k,)`` int: each row's number of entries."""
        return np.diff(self.offsets)

    @property
    def owner(self) -> np.ndarray:
        """``(e,)`` int: the row of each entry (to broadcast a robot's own values to its entries)."""
        return np.repeat(np.arange(len(self)), self.count)

    def _reduce(self, what: str | Sequence[str] | np.ndarray, op: str) -> FloatArray:
        if isinstance(what, np.ndarray):
            return kernels.segment_reduce(what, self.offsets, op)
        if not isinstance(what, str):  # several columns: each reduced where it lies
            return np.column_stack([self._reduce(name, op) for name in what]).reshape(len(self), len(what))
        if what in self.sources and what not in self.columns:
            return kernels.segment_reduce(self.sources[what], self.offsets, op, index=self.index)
        return kernels.segment_reduce(self[what], self.offsets, op)

    def sum(self, what: str | Sequence[str] | np.ndarray) -> FloatArray:
        """Each row's sum of a column (``(k,)``), of several (``(k, w)``), or of values ``(e,)`` or
        ``(e, w)``; 0 for an empty row."""
        return self._reduce(what, "sum")

    def mean(self, what: str | Sequence[str] | np.ndarray) -> FloatArray:
        """Each row's mean (NaN for an empty row); see :meth:`sum`."""
        return self._reduce(what, "mean")

    def min(self, what: str | Sequence[str] | np.ndarray) -> FloatArray:
        """Each row's minimum (NaN entries skipped; NaN for an empty row); see :meth:`sum`."""
        return self._reduce(what, "min")

    def max(self, what: str | Sequence[str] | np.ndarray) -> FloatArray:
        """Each row's maximum (NaN entries skipped; NaN for an empty row); see :meth:`sum`."""
        return self._reduce(what, "max")

    def any(self, flags: Any) -> np.ndarray:
        """``(k,)`` bool: whether any of a row's entries is flagged (``flags`` ``(e,)`` bool)."""
        return kernels.segment_any(flags, self.offsets)

    def nearest(self, key: str | np.ndarray = "distance") -> np.ndarray:
        """``(k,)`` int: the entry of each row with the smallest ``key`` (a column or values
        ``(e,)``), -1 for an empty row; use it with :meth:`pick`."""
        return kernels.segment_nearest(self[key] if isinstance(key, str) else key, self.offsets)

    def pick(self, what: str | Sequence[str] | np.ndarray, entries: np.ndarray, fill: float = np.nan) -> FloatArray:
        """The values at ``entries`` ``(k,)`` (from :meth:`nearest`), ``fill`` where it is -1."""
        if isinstance(what, str):
            values = np.asarray(self[what], dtype=np.float64)
        elif isinstance(what, np.ndarray):
            values = np.asarray(what, dtype=np.float64)
        else:
            values = np.column_stack([self[name] for name in what]).astype(np.float64)
        out = np.full((len(entries), *values.shape[1:]), fill)
        found = entries >= 0
        out[found] = values[entries[found]]
        return out

    def _entries(self, offsets: np.ndarray, chosen: slice | np.ndarray) -> Neighbourhood:
        index = None if self.index is None else self.index[chosen]
        columns = {name: column[chosen] for name, column in self.columns.items()}
        return Neighbourhood(offsets, columns, index, self.sources)

    def where(self, keep: np.ndarray) -> Neighbourhood:
        """The entries flagged in ``keep`` ``(e,)`` bool, rows kept (some may become empty)."""
        keep = np.asarray(keep, dtype=bool)
        return self._entries(np.concatenate(([0], np.cumsum(keep)))[self.offsets], keep)

    def rows(self, first: int, last: int) -> Neighbourhood:
        """Rows ``first:last`` alone (the neighbourhood of some of the robots)."""
        start, end = self.offsets[first], self.offsets[last]
        return self._entries(self.offsets[first : last + 1] - start, slice(start, end))
