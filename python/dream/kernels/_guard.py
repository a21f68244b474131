"""The motion guard of the robots deciding now: the last check of their commands."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream._checks import FloatArray, as_array, as_offsets
from dream.kernels._dispatch import implementation


def motion_guard(
    speeds: Any, headings: Any, offsets: Any, dx: Any, dy: Any, *, near: float, horizon: float
) -> np.ndarray:
    """Which robots stop: ``(m,)`` bool.

    Row r drives at ``speeds[r]`` (m/s) along ``headings[r]`` (rad) and sees robots at ``dx``,
    ``dy`` ``[offsets[r]:offsets[r + 1]]`` (their positions less its own, m: a movement sensor's
    offsets). It stops when, driving on, it would come closer than ``near`` (m) to one of them,
    taken as standing, within ``horizon`` (s) while closing in; one already closer only counts
    if it closes in further.
    """
    v = as_array(speeds, "speeds", (None,))
    theta = as_array(headings, "headings", (len(v),))
    x = as_array(dx, "dx", (None,))
    y = as_array(dy, "dy", (len(x),))
    cuts = as_offsets(offsets, "offsets", len(x), rows=len(v))
    return motion_guard_trusted(v, theta, cuts, x, y, near=near, horizon=horizon)


def motion_guard_trusted(
    speeds: FloatArray,
    headings: FloatArray,
    offsets: np.ndarray,
    dx: FloatArray,
    dy: FloatArray,
    *,
    near: float,
    horizon: float,
) -> np.ndarray:
    """:func:`motion_guard` of arrays its caller built and vouches for: finite float64 of the
    right shapes, cut into rows by int64 ``offsets`` (the swarm engine's own commands and
    perception), so that they are not checked again, entry by entry; ``near`` and ``horizon``
    are."""
    for name, value in (("near", near), ("horizon", horizon)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"`{name}` must be finite and > 0, got {value}")
    return implementation("motion_guard")(speeds, headings, offsets, dx, dy, near=near, horizon=horizon)
