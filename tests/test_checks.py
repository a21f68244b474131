"""The shared input checks: what counts as finite, for a robot's small arrays and a swarm's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from dream._checks import all_finite


@pytest.mark.parametrize("size", [3, 64, 65, 200_000])
def test_all_finite_finds_any_nan_or_infinity_whatever_the_size(rng, size):
    values = rng.uniform(-1e3, 1e3, size)
    assert all_finite(values)
    for bad in (np.nan, np.inf, -np.inf):
        spoiled = values.copy()
        spoiled[rng.integers(size)] = bad
        assert not all_finite(spoiled)


def test_all_finite_holds_for_values_whose_sum_overflows_and_fails_for_opposite_infinities():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the overflow of the sum stays silent
        assert all_finite(np.full(1000, 1e308))
        assert all_finite(np.full((2, 500), -1e308))
        assert not all_finite(np.array([np.inf, -np.inf] * 100))  # their sum is NaN, not inf
