"""Rows of per-robot tables copied out and back, every table at once (``take_rows``, ``put_rows``):
the Rust kernel against its NumPy reference, to the byte, and its bad input named."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import _core, _reference, kernels
from dream.kernels import _dispatch
from dream.swarm import put_all, take_all


def tables_scene(rng, n):
    """A robot's memory fields of several types and shapes, as the affine formation's: rows of 1,
    8 and 16 bytes (which the kernel copies a move each) and of other widths."""
    return [
        rng.normal(size=n),
        rng.random(n) < 0.5,
        rng.normal(size=(n, 2)),
        rng.integers(-100, 100, (n, 7), dtype=np.int8),
        rng.random((n, 7)) < 0.5,
        rng.normal(size=(n, 3, 3, 2)),
        rng.integers(0, 1 << 30, n, dtype=np.int32),
        np.zeros((n, 0)),
    ]


@pytest.mark.parametrize("n", [1, 10, 5000, 100_000])
def test_rows_out_and_back_are_the_references(rng, n):
    tables = tables_scene(rng, n)
    rows = np.flatnonzero(rng.random(n) < 0.3)
    as_bytes = [kernels._tables._bytes(t, "tables", k) for k, t in enumerate(tables)]
    for mine, theirs in zip(_core.take_rows(as_bytes, rows), _reference.take_rows(as_bytes, rows), strict=True):
        assert_array_equal(mine, theirs)
    taken = kernels.take_rows(tables, rows)
    for table, values in zip(tables, taken, strict=True):
        assert values.dtype == table.dtype and not np.shares_memory(values, table)
        assert_array_equal(values, table[rows])
    fresh = tables_scene(rng, len(rows))
    for core in (_core, None):
        into = [t.copy() for t in tables]
        _dispatch._core, saved = core, _dispatch._core
        try:
            kernels.put_rows(into, rows, fresh)
        finally:
            _dispatch._core = saved
        for table, before, values in zip(into, tables, fresh, strict=True):
            assert_array_equal(table[rows], values)
            others = np.setdiff1d(np.arange(n), rows)
            assert_array_equal(table[others], before[others])


def test_tables_by_name_through_slices_and_indices(rng):
    memory = {"x": rng.normal(size=50), "seen": rng.random((50, 4)) < 0.5}
    rows = np.array([3, 7, 40])
    for at in (rows, slice(None)):
        taken = take_all(memory, at)
        assert_array_equal(taken["seen"], memory["seen"][at])
        taken["x"] += 1.0  # a copy: the table is untouched until put back
        assert not np.array_equal(taken["x"], memory["x"][at])
        put_all(memory, at, {"x": taken["x"]})
        assert_array_equal(memory["x"][at], taken["x"])


@pytest.mark.parametrize("core", [_core, None], ids=["rust", "reference"])
@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda t, v: kernels.take_rows(t, [2, 1]), "`rows`"),
        (lambda t, v: kernels.take_rows(t, [0, 10]), "`rows`"),
        (lambda t, v: kernels.take_rows(t, [-1, 3]), "`rows`"),
        (lambda t, v: kernels.take_rows(t, [0.5]), "`rows` must be 1-D integer"),
        (lambda t, v: kernels.take_rows([t[0], t[1][:5]], [0]), "rows"),
        (lambda t, v: kernels.take_rows([t[1][:, ::2]], [0]), "C-contiguous"),
        (lambda t, v: kernels.put_rows(t, [1, 2], [v[0], v[1][:1]]), r"`values` 1 must have shape \(2, 3\)"),
        (lambda t, v: kernels.put_rows(t, [1, 2], v[:1]), "one array a table"),
        (lambda t, v: kernels.put_rows([t[0][::-1]], [1, 2], v[:1]), "C-contiguous"),
        (lambda t, v: kernels.put_rows(t, [2, 2], v), "`rows`"),
    ],
)
def test_bad_rows_and_tables_are_named_and_nothing_is_written(core, call, message):
    tables = [np.arange(10.0), np.arange(30).reshape(10, 3)]
    values = [np.full(2, -1.0), np.full((2, 3), -1)]
    before = [t.copy() for t in tables]
    saved, _dispatch._core = _dispatch._core, core
    try:
        with pytest.raises(ValueError, match=message):
            call(tables, values)
    finally:
        _dispatch._core = saved
    for table, old in zip(tables, before, strict=True):
        assert_array_equal(table, old)


def test_a_read_only_table_is_named():
    table = np.zeros(4)
    table.flags.writeable = False
    with pytest.raises(ValueError, match="read-only"):
        kernels.put_rows([table], [1], [np.ones(1)])
