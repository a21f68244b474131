"""Lengths of 2-D vectors, rounded as a robot's scalar rules round them."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream._checks import FloatArray
from dream.kernels._dispatch import implementation


def hypot(x: Any, y: Any) -> FloatArray:
    """``math.hypot(x, y)`` elementwise: the lengths of the vectors ``(x, y)`` (arrays of one shape),
    to the bit as Python rounds them (``numpy.hypot`` can differ in the last bit). NaN and inf go
    through as :func:`math.hypot` takes them (inf if either is, else NaN if either is).

    Raises
    ------
    ValueError
        ``x`` and ``y`` of different shapes, or not numbers.
    """
    try:
        xs, ys = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"`x` and `y` must be float arrays: {err}") from None
    if xs.shape != ys.shape:
        raise ValueError(f"`x` and `y` must have one shape, got {xs.shape} and {ys.shape}")
    x_flat, y_flat = np.ascontiguousarray(xs.ravel()), np.ascontiguousarray(ys.ravel())
    flat = implementation("hypot")(x_flat, y_flat)
    # Subnormal lengths: the one case Python versions take differently (see dream-core's length.rs).
    for i in np.flatnonzero((flat > 0.0) & (flat < _SMALLEST_NORMAL)):
        flat[i] = math.hypot(x_flat[i], y_flat[i])
    return flat.reshape(xs.shape)


_SMALLEST_NORMAL = float(np.finfo(np.float64).smallest_normal)
