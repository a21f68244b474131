"""The motion guard: which robots, driving on along their heading, would come too close to a
robot they see (taken as standing) within a short horizon; and its pair test."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream._checks import FloatArray


def in_reach(distances: np.ndarray, speeds: Any, near: float, horizon: float) -> np.ndarray:
    """``(k,)`` bool: which robots at ``distances`` ``(k,)`` (m) a robot driving at ``speeds``
    ``(k,)`` or ``()`` (m/s) could come within ``near`` (m) of in the next ``horizon`` seconds;
    the guard need not look at the others (the margin covers rounding)."""
    return distances < near + np.abs(speeds) * horizon + 1e-9


def closing_in(offsets: Any, closing: Any, distance: float, horizon: float) -> np.ndarray:
    """For pairs of robots, whether each comes closer than ``distance`` (m) within ``horizon``
    seconds while closing in, if both keep their velocities; a pair already closer only counts
    when it closes in further.

    ``offsets`` ``(k, 2)``: this robot's position less the other's (m); ``closing`` ``(k, 2)``:
    this robot's velocity less the other's (m/s).
    """
    offsets = np.asarray(offsets, dtype=np.float64).reshape(-1, 2)
    closing = np.asarray(closing, dtype=np.float64).reshape(-1, 2)
    speed2 = closing[:, 0] * closing[:, 0] + closing[:, 1] * closing[:, 1]
    along = offsets[:, 0] * closing[:, 0] + offsets[:, 1] * closing[:, 1]
    when = np.clip(-along / np.where(speed2 > 0, speed2, 1.0), 0.0, horizon)
    nearest = np.hypot(offsets[:, 0] + closing[:, 0] * when, offsets[:, 1] + closing[:, 1] * when)
    return nearest < np.minimum(distance, np.hypot(offsets[:, 0], offsets[:, 1]))


def motion_guard(
    speeds: FloatArray,
    headings: FloatArray,
    offsets: np.ndarray,
    dx: FloatArray,
    dy: FloatArray,
    *,
    near: float,
    horizon: float,
) -> np.ndarray:
    """``(m,)`` bool: which robots stop; row r drives at ``speeds[r]`` along ``headings[r]`` and
    sees robots at ``dx``, ``dy`` ``[offsets[r]:offsets[r + 1]]`` (their positions less its own)."""
    owners = np.repeat(np.arange(len(speeds)), np.diff(offsets))
    apart = -np.column_stack((dx, dy))  # the robot's position less the other's
    close = np.flatnonzero(in_reach(np.hypot(apart[:, 0], apart[:, 1]), speeds[owners], near, horizon))
    owners, apart = owners[close], apart[close]
    moving = speeds[owners, None] * np.column_stack((np.cos(headings[owners]), np.sin(headings[owners])))
    hit = closing_in(apart, moving, near, horizon)
    return np.bincount(owners[hit], minlength=len(speeds)) > 0
