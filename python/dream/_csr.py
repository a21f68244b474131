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


def merged(*rows: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """CSR arrays over the same rows, ``(offsets (k + 1,), values (e, ...))`` each, as one: row r
    holds the first array's entries of row r, then the second's, and so on (no sort: linear)."""
    counts = [np.diff(offsets) for offsets, _ in rows]
    total = np.sum(counts, axis=0)
    out_offsets = np.concatenate(([0], np.cumsum(total))).astype(np.int64)
    out = np.empty((int(out_offsets[-1]), *rows[0][1].shape[1:]), dtype=rows[0][1].dtype)
    start = out_offsets[:-1].copy()
    for (_, values), count in zip(rows, counts, strict=True):
        out[spans(start, count)] = values
        start += count
    return out_offsets, out
