"""Lengths of 2-D vectors rounded as Python's :func:`math.hypot` rounds them (the definition)."""

from __future__ import annotations

import math

import numpy as np

from dream._checks import FloatArray

_HYPOT = np.frompyfunc(math.hypot, 2, 1)


def hypot(x: FloatArray, y: FloatArray) -> FloatArray:
    """``math.hypot(x[i], y[i])`` for the float arrays ``x`` and ``y`` ``(n,)``."""
    return np.asarray(_HYPOT(x, y), dtype=np.float64)
