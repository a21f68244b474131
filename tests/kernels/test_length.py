"""Lengths rounded as Python's math.hypot: the Rust kernel against its reference (math.hypot
itself) to the bit, on random vectors of every magnitude, and the edges math.hypot defines."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import _core, _reference, kernels, rules


def magnitudes(rng, n):
    """Random coordinates from subnormal to near overflow, and pairs of close magnitudes."""
    wide = rng.standard_normal(n) * 10.0 ** rng.integers(-320, 308, n)
    close = rng.standard_normal(n) * 10.0 ** rng.integers(-3, 3, n)
    return np.concatenate((wide, close, close * 1e-310, close * 1e300))


def test_rust_rounds_as_math_hypot(rng):
    x, y = magnitudes(rng, 50_000), magnitudes(rng, 50_000)
    with np.errstate(over="ignore"):
        want = _reference.hypot(x, y)
    normal = ~((want > 0) & (want < np.finfo(np.float64).smallest_normal))
    assert normal.sum() > 150_000
    assert_array_equal(_core.hypot(x, y)[normal], want[normal])  # subnormal: see the next test
    assert np.any(np.hypot(x, y) != want)  # where NumPy's rounding differs, the kernel's does not


def test_the_dispatched_kernel_is_math_hypot_at_every_magnitude(rng):
    x, y = magnitudes(rng, 20_000), magnitudes(rng, 20_000)
    with np.errstate(over="ignore"):
        assert_array_equal(kernels.hypot(x, y), _reference.hypot(x, y))


EDGES = [
    (3.0, 4.0),
    (-0.0, 0.0),
    (math.inf, math.nan),
    (-math.inf, 1.0),
    (math.nan, 2.0),
    (1.7976931348623157e308, 1.7976931348623157e308),
    (5e-324, 1e-323),
    (2.2250738585072014e-308, 1e-320),
    (1.0, 1e-200),
]


@pytest.mark.parametrize(("x", "y"), EDGES)
def test_edges_as_math_hypot(x, y):
    got = float(_core.hypot(np.array([x]), np.array([y]))[0])
    want = math.hypot(x, y)
    assert got == want or (math.isnan(got) and math.isnan(want))


def test_the_kernel_keeps_the_shape_and_names_bad_input():
    x = np.arange(6.0).reshape(2, 3)
    assert kernels.hypot(x, x).shape == (2, 3)
    assert kernels.hypot(3.0, 4.0).shape == ()
    assert float(kernels.hypot(3.0, 4.0)) == 5.0
    with pytest.raises(ValueError, match="one shape"):
        kernels.hypot(np.zeros(2), np.zeros(3))
    with pytest.raises(ValueError, match="float arrays"):
        kernels.hypot(["a"], [1.0])
    with pytest.raises(ValueError, match="`y`"):
        _core.hypot(np.zeros(2), np.zeros(3))


def test_rules_length_is_math_hypot_on_each_vector(rng):
    vectors = rng.standard_normal((1000, 2)) * 10.0 ** rng.integers(-5, 5, (1000, 1))
    assert_array_equal(rules.length(vectors), [math.hypot(*v) for v in vectors])
    assert rules.length(np.array([3.0, 4.0])) == 5.0
