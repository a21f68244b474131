"""Stepping aside on the swarm engine's tables (``sidestep_ask``, ``sidestep_mark``): the Rust
kernels against their NumPy reference and the rule of :mod:`dream.rules`, to the bit, in place,
and their bad input named with nothing written."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import _core, _reference, kernels, rules
from dream.kernels import _dispatch


def scene(rng, n):
    """Tables of n robots, a scattered part of them deciding, wishes and HRVO's answers with
    zeros, negative zeros and NaN components (a NaN wish counts as moving)."""
    counters = rng.integers(0, 3, n).astype(np.int64)
    sides = rng.choice([-1.0, 1.0], n)
    rows = np.flatnonzero(rng.random(n) < 0.4)
    k = len(rows)
    want = rng.normal(size=(k, 2))
    want[rng.random(k) < 0.2] = 0.0
    want[rng.random(k) < 0.05, 1] = -0.0
    want[rng.random(k) < 0.05, 0] = np.nan
    chosen = rng.normal(size=(k, 2))
    chosen[rng.random(k) < 0.4] = 0.0
    chosen[rng.random(k) < 0.1, 0] = -0.0
    return counters, sides, rows, want, chosen


def bits(a):
    return np.asarray(a).view(np.uint64 if np.asarray(a).dtype == np.float64 else np.int64)


@pytest.mark.parametrize("n", [1, 7, 1000, 200_000])  # 80,000 rows: on every core
def test_sidestep_kernels_are_the_reference_and_the_rule(rng, n):
    counters, sides, rows, want, chosen = scene(rng, n)
    results = []
    for module in (_core, _reference):
        c, s = counters.copy(), sides.copy()
        asked = module.sidestep_ask(want, rows, c, s)
        after_ask = c.copy()
        module.sidestep_mark(chosen, want, rows, c, s, 10)
        results.append((asked, after_ask, c, s))
    for mine, theirs in zip(*results, strict=True):
        assert_array_equal(bits(mine), bits(theirs))
    # The rule of dream.rules on the gathered rows, and the rows not deciding left as they were.
    asked, after_ask, c, s = results[0]
    wanted, counted = rules.sidestep_preference(want, counters[rows], sides[rows])
    assert_array_equal(bits(asked), bits(wanted))
    assert_array_equal(after_ask[rows], counted)
    marked, turned = rules.sidestep_update(chosen, want, counted, sides[rows], 10)
    assert_array_equal(c[rows], marked)
    assert_array_equal(s[rows], turned)
    others = np.setdiff1d(np.arange(n), rows)
    assert_array_equal(c[others], counters[others])
    assert_array_equal(s[others], sides[others])
    if len(rows):  # the scene exercises every branch
        assert (counters[rows] > 0).any() or n < 100
        assert (marked != counted).any() or n < 100


@pytest.mark.parametrize("n", [7, 1000, 200_000])
def test_sidestep_of_the_rows_steered_is_the_kernels_on_those_rows(rng, n):
    counters, sides, rows, want, chosen = scene(rng, n)
    steer = rng.random(len(rows)) < 0.7
    subset = counters.copy(), sides.copy()
    asked = _core.sidestep_ask(want[steer], rows[steer], *subset)
    _core.sidestep_mark(chosen[steer], want[steer], rows[steer], *subset, 10)
    for module in (_core, _reference):
        c, s = counters.copy(), sides.copy()
        flagged = module.sidestep_ask(want, rows, c, s, steer)
        module.sidestep_mark(chosen, want, rows, c, s, 10, steer)
        assert_array_equal(bits(flagged[steer]), bits(asked))
        assert_array_equal(bits(flagged[~steer]), bits(want[~steer]))  # the others ask for their wish
        assert_array_equal(c, subset[0])
        assert_array_equal(s, subset[1])
    with pytest.raises(ValueError, match="steer"):
        kernels.sidestep_ask(want, rows, counters, sides, steer[1:])


@pytest.mark.parametrize("core", [_core, None], ids=["rust", "numpy"])
def test_sidestep_bad_input_is_named_and_writes_nothing(rng, core):
    counters, sides, rows, want, chosen = scene(rng, 50)
    kept = counters.copy(), sides.copy()
    read_only = counters.copy()
    read_only.flags.writeable = False
    cases = [
        (dict(rows=rows[::-1].copy()), "rows"),
        (dict(rows=np.r_[rows[:-1], 50]), "rows"),
        (dict(want=want[:-1]), "want"),
        (dict(counters=counters.astype(np.int32)), "counters"),
        (dict(counters=read_only), "counters"),
        (dict(sides=sides[:-1]), "sides"),
        (dict(sides=np.ones((50, 2))[:, 0]), "sides"),
    ]
    _dispatch._core, saved = core, _dispatch._core
    try:
        for change, name in cases:
            args = dict(want=want, rows=rows, counters=counters, sides=sides) | change
            with pytest.raises(ValueError, match=name):
                kernels.sidestep_ask(args["want"], args["rows"], args["counters"], args["sides"])
            with pytest.raises(ValueError, match=name):
                kernels.sidestep_mark(chosen, args["want"], args["rows"], args["counters"], args["sides"], 10)
            assert_array_equal(counters, kept[0])
            assert_array_equal(sides, kept[1])
    finally:
        _dispatch._core = saved
