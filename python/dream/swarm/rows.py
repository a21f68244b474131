"""Robots' rows of per-robot arrays ``(n, ...)``: how to index them, and copies out and back.

The engine copies the memory of the robots deciding now out of its tables and back every step,
and a robot's decision may do the same with a part of them (the followers of a formation, say):
these are the fast ways to, for rows of several values each.
"""

from __future__ import annotations

import math

import numpy as np


def at_rows(rows: np.ndarray, n: int) -> slice | np.ndarray:
    """How to index ``(n, ...)`` per-robot arrays at ``rows`` (increasing ids below ``n``): a slice
    when they are all ``n`` robots, so that a read is a view or a block copy and a write a block,
    not a gather or a scatter over every robot (every robot decides, in many rules)."""
    return slice(None) if len(rows) == n else rows


def take_rows(values: np.ndarray, at: slice | np.ndarray) -> np.ndarray:
    """``values[at]`` (a slice of :func:`at_rows`, or row indices), an array of its own either way
    (``numpy.take`` copies rows of several values 3-4 times faster than indexing does)."""
    return values[at].copy() if isinstance(at, slice) else np.take(values, at, axis=0)


def put_rows(values: np.ndarray, at: slice | np.ndarray, rows: np.ndarray) -> None:
    """``values[at] = rows`` (``values`` ``(n, ...)`` C-contiguous; ``rows`` taken as its dtype):
    at an index, a row of several values is copied as one block (NumPy copies it value by
    value: 1.5 times slower for the affine formation's memory rows)."""
    width = values[0].nbytes if len(values) else 0
    if isinstance(at, slice) or values.ndim == 1 or width == 0:
        values[at] = rows
        return
    if not values.flags.c_contiguous:
        raise ValueError(f"an array of shape {values.shape} to put rows into must be C-contiguous")
    _blocks(values, width)[at] = _blocks(np.ascontiguousarray(rows, dtype=values.dtype), width)


def _blocks(values: np.ndarray, width: int) -> np.ndarray:
    """The C-contiguous ``values`` ``(k, ...)`` as ``(k,)`` blocks of ``width`` bytes (a view)."""
    return (
        values.reshape(len(values), math.prod(values.shape[1:])).view(np.dtype((np.void, width))).reshape(len(values))
    )
