"""Robots' rows of per-robot arrays ``(n, ...)``: how to index them, and copies out and back.

The engine copies the memory of the robots deciding now out of its tables and back every step,
and a robot's decision may do the same with a part of them (the followers of a formation, say):
these are the fast ways to, every table at once (:func:`dream.kernels.take_rows`, on every core).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from dream import kernels


def at_rows(rows: np.ndarray, n: int) -> slice | np.ndarray:
    """How to index ``(n, ...)`` per-robot arrays at ``rows`` (increasing ids below ``n``): a slice
    when they are all ``n`` robots, so that a read is a view or a block copy and a write a block,
    not a gather or a scatter over every robot (every robot decides, in many rules)."""
    return slice(None) if len(rows) == n else rows


def take_rows(values: np.ndarray, at: slice | np.ndarray) -> np.ndarray:
    """``values[at]`` (a slice of :func:`at_rows`, or row indices), an array of its own either way."""
    return take_all({"": values}, at)[""]


def take_all(tables: Mapping[str, np.ndarray], at: slice | np.ndarray) -> dict[str, np.ndarray]:
    """:func:`take_rows` of each of ``tables`` (C-contiguous), by name."""
    if isinstance(at, slice):
        return {name: values[at].copy() for name, values in tables.items()}
    return dict(zip(tables, kernels.take_rows(list(tables.values()), at), strict=True))


def put_rows(values: np.ndarray, at: slice | np.ndarray, rows: np.ndarray) -> None:
    """``values[at] = rows`` (``values`` ``(n, ...)`` C-contiguous; ``rows`` taken as its dtype)."""
    put_all({"": values}, at, {"": rows})


def put_all(tables: Mapping[str, np.ndarray], at: slice | np.ndarray, rows: Mapping[str, np.ndarray]) -> None:
    """:func:`put_rows` of ``rows[name]`` into ``tables[name]``, for each name of ``rows``."""
    if isinstance(at, slice):
        for name, values in rows.items():
            tables[name][at] = values
        return
    kernels.put_rows([tables[name] for name in rows], at, list(rows.values()))
