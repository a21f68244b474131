"""Distance sensors: rays cast against line-segment walls and the other robots (rps 2.1's model).

See ``crates/dream-core/src/raycast.rs`` for the criteria; this is the same computation,
vectorised over robots, rays and obstacles, in chunks of robots to bound the memory.
"""

from __future__ import annotations

import numpy as np

from dream._checks import FloatArray

NOTHING = -1.0  #: the reading of a ray that hits nothing within range
PARALLEL = 1e-10 / 1.2  #: |unit ray x wall| below this: parallel, skipped (rps 2.1's 1e-10 on 1.2 m)
CHUNK = 64  #: robots per block (memory ~ CHUNK * k * n floats per temporary)


def _cross(ux: FloatArray, uy: FloatArray, vx: FloatArray, vy: FloatArray) -> FloatArray:
    return ux * vy - uy * vx


def _nearest(
    starts: FloatArray,
    directions: FloatArray,
    centres: FloatArray,
    own: np.ndarray,
    walls: FloatArray,
    radius: float,
    range_: float,
) -> FloatArray:
    """Nearest hit ``(b, k)`` (``range_`` when none) of rays ``(b, k, 2)`` from robots ``own`` ``(b,)``."""
    sx, sy = starts[..., 0, None], starts[..., 1, None]
    dx, dy = directions[..., 0, None], directions[..., 1, None]
    nearest = np.full(starts.shape[:2], range_)
    if len(walls):
        ax, ay, ex, ey = walls[:, 0], walls[:, 1], walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1]
        denominator = _cross(dx, dy, ex, ey)
        parallel = np.abs(denominator) < PARALLEL
        safe = np.where(parallel, 1.0, denominator)
        wx, wy = ax - sx, ay - sy
        t = _cross(wx, wy, ex, ey) / safe
        u = _cross(wx, wy, dx, dy) / safe
        hit = ~parallel & (t >= 0) & (t <= range_) & (u >= 0) & (u <= 1)
        nearest = np.minimum(nearest, np.where(hit, t, np.inf).min(axis=2))
    if len(centres) > 1:
        tx, ty = centres[:, 0] - sx, centres[:, 1] - sy
        along = tx * dx + ty * dy
        off = np.hypot(sx + along * dx - centres[:, 0], sy + along * dy - centres[:, 1])
        with np.errstate(invalid="ignore"):
            distance = along - np.sqrt(radius * radius - off * off)
        others = np.arange(len(centres))[None, None, :] != own[:, None, None]
        hit = others & (along >= 0) & (along <= range_) & (off <= radius) & (distance >= 0)
        nearest = np.minimum(nearest, np.where(hit, distance, np.inf).min(axis=2))
    return nearest


def distance_rays(
    poses: FloatArray,
    walls: FloatArray,
    rays: FloatArray,
    *,
    centre_offset: float,
    robot_diameter: float,
    range: float,
    robots: np.ndarray | None = None,
) -> FloatArray:
    """Readings ``(k, n)`` of the rays ``(3, k)`` (body-frame start x, y and angle) of every robot.

    Parameters
    ----------
    poses : (3, n)
    walls : (m, 4)
        Segments ``[ax, ay, bx, by]``.
    centre_offset : float
        The sensor centre (and each robot's disc) sits this far ahead of the pose (m).
    robot_diameter : float
        Diameter of the disc other robots' rays see (m).
    range : float
        Longest distance read (m); a hit at exactly ``range`` reads as nothing.
    robots : (b,) int, optional
        Cast only these robots' rays; the other columns read -1.

    Returns
    -------
    (k, n) float64: distances (m), -1 where nothing is within range.
    """
    n, k = poses.shape[1], rays.shape[1]
    heading = poses[2]
    centres = np.column_stack((poses[0] + centre_offset * np.cos(heading), poses[1] + centre_offset * np.sin(heading)))
    sources = np.arange(n) if robots is None else np.asarray(robots, dtype=np.int64)
    readings = np.full((k, n), NOTHING)
    for first in np.arange(0, len(sources), CHUNK):  # (`range` is the sensor range here)
        own = sources[first : first + CHUNK]
        c, s = np.cos(heading[own])[:, None], np.sin(heading[own])[:, None]
        starts = np.stack(
            (centres[own, 0, None] + c * rays[0] - s * rays[1], centres[own, 1, None] + s * rays[0] + c * rays[1]),
            axis=-1,
        )
        angles = heading[own][:, None] + rays[2]
        directions = np.stack((np.cos(angles), np.sin(angles)), axis=-1)
        nearest = _nearest(starts, directions, centres, own, walls, robot_diameter / 2, range)
        readings[:, own] = np.where(nearest < range, nearest, NOTHING).T
    return readings
