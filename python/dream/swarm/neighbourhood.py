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

import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

from dream import kernels, rules
from dream._checks import FloatArray


class Neighbourhood:
    """Ragged rows of named columns (see the module docs).

    Parameters
    ----------
    offsets : (k + 1,) int64
        Row r's entries are ``offsets[r]:offsets[r + 1]``.
    columns : mapping of name to (e,) array
        One value per entry.
    gathered : (index, sources), optional
        More columns, read from per-robot arrays ``sources`` (name to ``(n,)``) at the robots
        ``index`` ``(e,)``: a message field on the board, say. They are copied out only when
        read whole; reductions read them in place.
    derived : mapping of name to function, optional
        More columns, each worked out entry by entry from the others (``derived[name](self)``)
        the first time it is read: the bearings of the robots seen, from their offsets.
    """

    def __init__(
        self,
        offsets: np.ndarray,
        columns: Mapping[str, np.ndarray],
        gathered: tuple[np.ndarray, Mapping[str, np.ndarray]] | None = None,
        derived: Mapping[str, Callable[[Neighbourhood], np.ndarray]] | None = None,
    ) -> None:
        self.offsets = offsets
        self.columns = dict(columns)
        self.index: np.ndarray | None = None if gathered is None else gathered[0]
        self.sources: Mapping[str, np.ndarray] = {} if gathered is None else gathered[1]
        self.derived: Mapping[str, Callable[[Neighbourhood], np.ndarray]] = {} if derived is None else derived
        self.read_only = False

    def __len__(self) -> int:
        """The number of rows (robots deciding now)."""
        return len(self.offsets) - 1

    def __getitem__(self, name: str) -> np.ndarray:
        """Column ``name``, one value per entry."""
        if name not in self.columns:
            if name in self.derived:
                column = self.derived[name](self)
            elif name in self.sources:
                column = self.sources[name][self.index]
            else:
                raise KeyError(f"no column {name!r} in this neighbourhood (its columns: {', '.join(self.names)})")
            column.flags.writeable = not self.read_only
            self.columns[name] = column
        return self.columns[name]

    @property
    def names(self) -> list[str]:
        """The names of the columns."""
        later = (name for name in (*self.derived, *self.sources) if name not in self.columns)
        return [*self.columns, *later]

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

    def broadcast(self, values: Any) -> np.ndarray:
        """Each row's value of ``values`` ``(k, ...)`` at each of its entries ``(e, ...)``: what
        ``values[owner]`` gives, several times faster for rows of several values (NumPy copies
        an indexed row value by value): ``here`` ``(k, 2)`` at each robot seen, say."""
        values = np.asarray(values)
        if values.ndim == 0 or len(values) != len(self):
            raise ValueError(f"values of shape {values.shape} for a neighbourhood of {len(self)} rows")
        return np.repeat(values, self.count, axis=0)

    def points(self, origins: Any, x: str = "dx", y: str = "dy") -> np.ndarray:
        """``(e, 2)``: each row's origin of ``origins`` ``(k, 2)`` plus its entries' offsets (the
        columns ``x`` and ``y``): where the robots seen lie, say. ``broadcast(origins) +
        column_stack((dx, dy))`` to the bit, added in place: three times faster at 400,000
        entries, with no second ``(e, 2)`` array to fault in."""
        origins = np.asarray(origins, dtype=np.float64)
        if origins.shape != (len(self), 2):
            raise ValueError(f"origins of shape {origins.shape} for a neighbourhood of {len(self)} rows: (k, 2)")
        out = self.broadcast(origins)
        out[:, 0] += self[x]
        out[:, 1] += self[y]
        return out

    def _values(self, what: str | Sequence[str] | np.ndarray) -> np.ndarray:
        if isinstance(what, str):
            return self[what]
        if isinstance(what, np.ndarray):
            return what
        return np.column_stack([self[name] for name in what]).reshape(-1, len(what))

    def _board(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray] | None:
        """The fields ``names`` side by side on the board ``(n, w)`` with the index that reads them
        (each entry's sender), if all of them are still there: read in place, in one pass over
        the senders (each a memory access anywhere in the board: at a million robots, cache
        misses), with no ``(e, w)`` copy of them."""
        if self.index is None or not names or any(name in self.columns or name not in self.sources for name in names):
            return None
        return np.column_stack([self.sources[name] for name in names]), self.index

    def _reduce(self, what: str | Sequence[str] | np.ndarray, op: str) -> FloatArray:
        if not isinstance(what, (str, np.ndarray)):
            names = list(what)
            board = self._board(names)
            if board is not None:
                return kernels.segment_reduce(board[0], self.offsets, op, board[1])
            # Column by column: no (e, w) copy of them.
            return np.column_stack([self._reduce(name, op) for name in names]).reshape(len(self), len(names))
        if isinstance(what, str) and what not in self.columns and what in self.sources:
            return kernels.segment_reduce(self.sources[what], self.offsets, op, self.index)
        values = self._values(what)
        if len(values) != self.offsets[-1]:
            raise ValueError(f"values of shape {values.shape} for a neighbourhood of {self.offsets[-1]} entries")
        return kernels.segment_reduce(values, self.offsets, op)

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

    def wmsr_mean(self, what: str | np.ndarray, own: Any, trimmed: int) -> FloatArray:
        """``(k,)``: W-MSR's update, each row's values (a column, or values ``(e,)``) without the
        ``trimmed`` largest above the robot's ``own`` ``(k,)`` value and the ``trimmed`` smallest
        below it (:func:`dream.rules.wmsr_kept`), averaged with ``own``. A robot with at most
        ``trimmed`` lying neighbours on a robust enough graph stays within the correct values."""
        values = np.asarray(self._values(what), dtype=np.float64)
        own = np.asarray(own, dtype=np.float64)
        if values.shape != (self.offsets[-1],) or own.shape != (len(self),):
            raise ValueError(
                f"wmsr_mean takes values ({self.offsets[-1]},) and own ({len(self)},), "
                f"got {values.shape} and {own.shape}"
            )
        keep = rules.wmsr_kept(values, self.offsets, own, trimmed)
        kept = self.where(keep)
        return (kept.sum(values[keep]) + own) / (kept.count + 1)

    def any(self, flags: Any) -> np.ndarray:
        """``(k,)`` bool: whether any of a row's entries is flagged (``flags`` ``(e,)`` bool)."""
        return kernels.segment_any(flags, self.offsets)

    def nearest(self, key: str | np.ndarray = "distance") -> np.ndarray:
        """``(k,)`` int: the entry of each row with the smallest ``key`` (a column or values
        ``(e,)``), -1 for an empty row; use it with :meth:`pick`."""
        return kernels.segment_nearest(self._values(key), self.offsets)

    def nearest_to(self, names: Sequence[str], origins: Any, k: int) -> np.ndarray:
        """``(m, k)`` int: each row's ``k`` entries whose point (the two columns ``names``: the
        position a message gives, say) lies nearest the row's origin of ``origins`` ``(m, 2)``,
        nearest first, -1 in the slots a row cannot fill; use them with :meth:`pick`. Message
        fields are read on the board, in place."""
        board = self._board(list(names))
        points, index = board if board is not None else (self._values(names), None)
        return kernels.segment_nearest_to(points, self.offsets, origins, k, index)

    def pick(self, what: str | Sequence[str] | np.ndarray, entries: np.ndarray, fill: float = np.nan) -> FloatArray:
        """The values at ``entries`` (from :meth:`nearest` ``(k,)`` or :meth:`nearest_to` ``(m, k)``,
        or any entries), ``fill`` where it is -1; several columns side by side ``(..., w)``.
        Message fields are read on the board at the entries picked only."""
        entries = np.asarray(entries)
        found = entries >= 0
        at = entries[found]
        if isinstance(what, np.ndarray):
            picked = np.asarray(what, dtype=np.float64)[at]
        elif isinstance(what, str):
            picked = self._at(what, at)
        else:
            picked = np.column_stack([self._at(name, at) for name in what]).reshape(len(at), len(what))
        shape = (*entries.shape, *picked.shape[1:])
        if len(at) == entries.size:  # every entry found: nothing to fill
            return np.asarray(picked, dtype=np.float64).reshape(shape)
        out = np.full(shape, fill)
        out[found] = picked
        return out

    def _at(self, name: str, entries: np.ndarray) -> np.ndarray:
        """Column ``name`` at ``entries`` only: a message field still on the board is read there."""
        if name not in self.columns and name in self.sources:
            assert self.index is not None  # sources come with their index
            return self.sources[name][self.index[entries]]
        return self[name][entries]

    def where(self, keep: np.ndarray) -> Neighbourhood:
        """The entries flagged in ``keep`` ``(e,)`` bool, rows kept (some may become empty)."""
        keep = np.asarray(keep, dtype=bool)
        if keep.shape != (self.offsets[-1],):
            raise ValueError(f"`keep` must have shape ({self.offsets[-1]},), one flag per entry, got {keep.shape}")
        kept = np.concatenate(([0], np.cumsum(keep)))[self.offsets]
        columns = {name: column[keep] for name, column in self.columns.items()}
        gathered = None
        if self.index is not None:  # often a column itself (an inbox's senders): taken once
            same = next((name for name, column in self.columns.items() if column is self.index), None)
            gathered = (self.index[keep] if same is None else columns[same], self.sources)
        return Neighbourhood(kept, columns, gathered, self.derived)

    def frozen(self) -> Neighbourhood:
        """This neighbourhood with read-only arrays (what a decision gets: it reads, never writes)."""
        for array in (self.offsets, *self.columns.values(), *([] if self.index is None else [self.index])):
            array.flags.writeable = False
        self.read_only = True
        return self


class Summed:
    """Each row's ``counts`` ``(k,)`` and its ``sums`` of named per-robot columns (name to
    ``(k,)``) over its entries, added in entry order from +0.0: what a neighbourhood's count,
    sums and means give, found without its rows (a radio's inbox summed in the perception's
    pass, :func:`dream.kernels.perceive`'s ``summed``)."""

    def __init__(self, counts: np.ndarray, sums: Mapping[str, np.ndarray]) -> None:
        self.counts, self.sums = counts, dict(sums)

    def rows(self, a: int, b: int) -> Summed:
        """Rows ``a:b``."""
        return Summed(self.counts[a:b], {name: values[a:b] for name, values in self.sums.items()})

    def reduce(self, what: Any, op: str) -> FloatArray | None:
        """:meth:`Neighbourhood.sum` (``op`` "sum") or :meth:`Neighbourhood.mean` ("mean") of
        ``what``, or None where it names a column not summed here (or is not a name)."""
        names = [what] if isinstance(what, str) else None if isinstance(what, np.ndarray) else list(what)
        if not names or any(not isinstance(name, str) or name not in self.sums for name in names):
            return None
        sums = np.column_stack([self.sums[name] for name in names]).reshape(len(self.counts), len(names))
        if op == "mean":  # the division segment_reduce makes, NaN for an empty row
            count = self.counts[:, None].astype(np.float64)
            sums = np.divide(sums, count, out=np.full(sums.shape, np.nan), where=count > 0)
        return sums[:, 0].copy() if isinstance(what, str) else sums


class Deferred(Neighbourhood):
    """A neighbourhood found on first use: ``load()`` gives the one it stands for, the first time
    any of its rows or columns is read (a robot's inbox that its decision may never read). With
    ``summed``, its count and the sums and means of the columns summed are answered without it."""

    def __init__(self, load: Callable[[], Neighbourhood], summed: Summed | None = None) -> None:
        self._load, self._summed = load, summed

    def __getattr__(self, name: str) -> Any:
        # Called only for what the instance lacks: every attribute of a neighbourhood, until loaded.
        if name.startswith("__") or name in ("_load", "_summed"):
            raise AttributeError(name)
        with _LOADING:  # blocks of a swarm deciding on several threads read their inboxes at once
            if "offsets" not in self.__dict__:
                self.__dict__.update(vars(self._load()))
        return object.__getattribute__(self, name)

    @property
    def count(self) -> np.ndarray:
        if self._summed is not None:
            return self._summed.counts.copy()
        with _summing():
            return super().count

    def _reduce(self, what: str | Sequence[str] | np.ndarray, op: str) -> FloatArray:
        if op not in ("sum", "mean"):
            return super()._reduce(what, op)
        found = None if self._summed is None else self._summed.reduce(what, op)
        if found is not None:
            return found
        with _summing():
            return super()._reduce(what, op)


#: Held while a :class:`Deferred` loads (reentrant: a block's inbox loads the whole one's).
_LOADING = threading.RLock()
#: Whether this thread is loading a :class:`Deferred` for its count, a sum or a mean.
_SUMMING = threading.local()


@contextmanager
def _summing() -> Iterator[None]:
    before = getattr(_SUMMING, "on", False)
    _SUMMING.on = True
    try:
        yield
    finally:
        _SUMMING.on = before


def summing() -> bool:
    """Whether a :class:`Deferred` loading now on this thread was read for its count, a sum or a
    mean only (what a perception can find without its rows, see :class:`Summed`)."""
    return bool(getattr(_SUMMING, "on", False))


class Loaded(Mapping[str, np.ndarray]):
    """Per-robot arrays ``names``, all given by ``load()`` the first time one is read: a
    neighbourhood's gathered sources that its decision may never read (the velocities of the
    robots seen, every robot's command converted)."""

    def __init__(self, names: Sequence[str], load: Callable[[], Sequence[np.ndarray]]) -> None:
        self._names, self._load = tuple(names), load
        self._values: dict[str, np.ndarray] = {}

    def __getitem__(self, name: str) -> np.ndarray:
        with _LOADING:  # blocks of a swarm deciding on several threads may read them at once
            if not self._values:
                self._values = dict(zip(self._names, self._load(), strict=True))
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)
