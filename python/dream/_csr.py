"""Gathering rows of CSR arrays (``indptr``, then each row's entries one after the other)."""

from __future__ import annotations

from typing import Any

import numpy as np


def spans(starts: Any, counts: Any) -> np.ndarray:
    """The indices ``(counts.sum(),)`` of the runs ``starts[i] .. starts[i] + counts[i] - 1``, one
    run after the other: the entries of several rows of a CSR array, gathered without a loop."""
    counts = np.asarray(counts, dtype=np.int64)
    first = np.asarray(starts, dtype=np.int64) - np.cumsum(counts) + counts
    return np.repeat(first, counts) + np.arange(counts.sum())


def offsets_of(rows: Any, count: int) -> np.ndarray:
    """The offsets ``(count + 1,)`` of CSR rows from the row ``rows`` ``(m,)`` (sorted ints below
    ``count``) of each entry: row r's entries are ``offsets[r]:offsets[r + 1]``."""
    return np.concatenate(([0], np.cumsum(np.bincount(rows, minlength=count))))
