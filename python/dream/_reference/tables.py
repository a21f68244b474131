"""Rows of per-robot tables copied out and back (the definition of :mod:`dream._core`'s).

A table is the bytes of a per-robot array: ``(n, width)`` uint8, C-contiguous, one row a robot."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def take_rows(tables: Sequence[np.ndarray], rows: np.ndarray) -> list[np.ndarray]:
    """The rows ``rows`` of each of ``tables``, one ``(len(rows), width)`` array each."""
    return [np.take(table, rows, axis=0) for table in tables]


def put_rows(tables: Sequence[np.ndarray], rows: np.ndarray, values: Sequence[np.ndarray]) -> None:
    """``values[t]`` written into ``tables[t]`` at the rows ``rows``."""
    for table, value in zip(tables, values, strict=True):
        table[rows] = value
