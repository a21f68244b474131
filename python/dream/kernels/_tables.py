"""Rows of per-robot arrays copied out and back, every array at once: a swarm's memory."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from dream.kernels._dispatch import core_checks, implementation


def take_rows(tables: Sequence[np.ndarray], rows: Any) -> list[np.ndarray]:
    """``[table[rows] for table in tables]``: the rows ``rows`` (increasing indices below n) of each
    of ``tables`` (per-robot arrays ``(n, ...)`` of any type, C-contiguous), each an array of its
    own, copied on every core. The robots deciding now are a scattered part of a swarm: their
    rows of a dozen memory fields, copied one field after the other, took a fifth of a step.

    Raises
    ------
    ValueError
        Tables of different lengths or not C-contiguous, or rows that are not increasing indices
        below their length.
    """
    index = _rows(rows, tables)
    if not tables:
        return []
    taken = implementation("take_rows")([_bytes(table, "tables", t) for t, table in enumerate(tables)], index)
    return [block.view(table.dtype).reshape((len(index), *table.shape[1:])) for block, table in zip(taken, tables)]


def put_rows(tables: Sequence[np.ndarray], rows: Any, values: Sequence[Any]) -> None:
    """``table[rows] = value`` for each of ``tables`` (as :func:`take_rows`'s, writable) and of
    ``values`` (``(len(rows), ...)`` each, taken as its table's type), on every core.

    Raises
    ------
    ValueError
        As :func:`take_rows`, a table that is read-only, or values of another shape (then nothing
        is written).
    """
    index = _rows(rows, tables)
    if len(values) != len(tables):
        raise ValueError(f"`values` must hold one array a table ({len(tables)}), got {len(values)}")
    sources = []
    for t, (table, value) in enumerate(zip(tables, values)):
        source = np.ascontiguousarray(value, dtype=table.dtype)
        if source.shape != (len(index), *table.shape[1:]):
            raise ValueError(f"`values` {t} must have shape {(len(index), *table.shape[1:])}, got {source.shape}")
        if not table.flags.writeable:
            raise ValueError(f"`tables` {t} is read-only")
        sources.append(_bytes(source, "values", t))
    if tables:
        implementation("put_rows")([_bytes(table, "tables", t) for t, table in enumerate(tables)], index, sources)


def _bytes(table: np.ndarray, name: str, t: int) -> np.ndarray:
    """The C-contiguous ``table`` ``(n, ...)`` as its rows' bytes ``(n, width)`` uint8 (a view)."""
    if not table.flags.c_contiguous or table.ndim == 0:
        raise ValueError(f"`{name}` {t} must be a C-contiguous array of rows, got shape {table.shape}")
    return table.reshape(len(table), math.prod(table.shape[1:])).view(np.uint8)


def _rows(rows: Any, tables: Sequence[np.ndarray]) -> np.ndarray:
    """``rows`` as int64 indices; checked here for the reference (the Rust binding checks its own)."""
    index = np.asarray(rows)
    if index.ndim != 1 or not (index.dtype.kind in "iu" or len(index) == 0):
        raise ValueError(f"`rows` must be 1-D integer row indices, got {index.dtype} of shape {index.shape}")
    index = index.astype(np.int64, copy=False)
    if core_checks() or not tables:
        return index
    n = len(tables[0])
    if any(len(table) != n for table in tables):
        raise ValueError(f"`tables` must all hold {n} rows, got {[len(table) for table in tables]}")
    if len(index) and (index[0] < 0 or index[-1] >= n or (np.diff(index) <= 0).any()):
        raise ValueError(f"`rows` must be increasing indices below {n}")
    return index
