"""Obstacles on the arena floor: rectangles, static or moving (bouncing off the walls)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from dream._checks import FloatArray, as_array
from dream._csr import spans
from dream.specs import ArenaSpec


class Obstacle:
    """A rectangle of ``size`` (width, height) centred at ``center``, turned by ``angle`` (rad),
    moving with ``velocity`` (m/s; zero for a static obstacle).

    Examples
    --------
    >>> wall = Obstacle((0.0, 0.0), (0.4, 0.2))
    >>> wall.closest_point((1.0, 0.0)).tolist()
    [0.2, 0.0]
    >>> wall.closest_point((0.1, 0.0)) is None  # inside
    True
    """

    def __init__(self, center: Any, size: Any, angle: float = 0.0, velocity: Any = (0.0, 0.0)) -> None:
        self.center = as_array(center, "center", (2,)).copy()
        self.size = as_array(size, "size", (2,)).copy()
        if np.any(self.size <= 0):
            raise ValueError(f"obstacle `size` must be positive, got {self.size.tolist()}")
        if not math.isfinite(angle):
            raise ValueError(f"obstacle `angle` must be finite, got {angle}")
        self.angle = float(angle)
        self.velocity = as_array(velocity, "velocity", (2,)).copy()

    @property
    def moving(self) -> bool:
        return bool(np.any(self.velocity != 0))

    def _axes(self) -> FloatArray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        return np.array([[c, -s], [s, c]])

    @property
    def polygon(self) -> FloatArray:
        """Corners ``(4, 2)``, counter-clockwise."""
        half = self.size / 2
        corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) * half
        return self.center + corners @ self._axes().T

    def _local(self, points: Any) -> FloatArray:
        """``points`` ``(..., 2)`` in the obstacle's frame (centre at the origin, sides along the axes)."""
        return _local(np.asarray(points, dtype=np.float64), self.center, math.cos(self.angle), math.sin(self.angle))

    def closest_points(self, points: Any) -> FloatArray:
        """The points of the obstacle closest to ``points`` ``(..., 2)``, NaN for those inside."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        return _closest(np.asarray(points, dtype=np.float64), self.center, c, s, self.size / 2)

    def closest_point(self, point: Any) -> FloatArray | None:
        """The point of the obstacle closest to ``point`` ``(2,)``; ``None`` if ``point`` is inside."""
        closest = self.closest_points(point)
        return None if np.isnan(closest[0]) else closest

    def contains(self, points: Any) -> np.ndarray:
        """Which of ``points`` ``(m, 2)`` lie strictly inside the obstacle, ``(m,)`` bool."""
        return np.all(np.abs(self._local(points)) < self.size / 2, axis=-1)

    def distances(self, points: Any) -> FloatArray:
        """Distances ``(m,)`` (m) from ``points`` ``(m, 2)`` to the obstacle (0 inside)."""
        return _distances(self._local(points), self.size / 2)

    def distance(self, point: Any) -> float:
        """Distance from ``point`` ``(2,)`` to the obstacle (0 inside)."""
        return float(self.distances(point))

    def step(self, dt: float, arena: ArenaSpec | None = None) -> None:
        """Move by ``velocity * dt``, bouncing off the walls of ``arena`` if one is given."""
        if not self.moving:
            return
        self.center = self.center + self.velocity * dt
        if arena is None:
            return
        corners = self.polygon
        for axis, (low, high) in enumerate(((arena.xmin, arena.xmax), (arena.ymin, arena.ymax))):
            below, above = low - corners[:, axis].min(), corners[:, axis].max() - high
            if below > 0:
                self.center[axis] += 2 * below
                self.velocity[axis] = abs(self.velocity[axis])
            elif above > 0:
                self.center[axis] -= 2 * above
                self.velocity[axis] = -abs(self.velocity[axis])

    def __repr__(self) -> str:
        return (
            f"Obstacle(center={self.center.tolist()}, size={self.size.tolist()}, angle={self.angle}, "
            f"velocity={self.velocity.tolist()})"
        )


def _local(points: FloatArray, center: Any, c: Any, s: Any) -> FloatArray:
    """``points`` ``(..., 2)`` in the frames of obstacles centred at ``center`` ``(..., 2)``, turned by
    the angles of cosines ``c`` and sines ``s`` (broadcast: one obstacle or several).

    Written out rather than a matrix product, whose rounding may depend on how many points
    there are: one robot's reading and the whole swarm's must agree to the bit."""
    d = points - center
    return np.stack((d[..., 0] * c + d[..., 1] * s, d[..., 1] * c - d[..., 0] * s), axis=-1)


def _closest(points: FloatArray, center: Any, c: Any, s: Any, half: Any) -> FloatArray:
    """The points closest to ``points`` of the rectangles of half sides ``half`` (as :func:`_local`
    broadcasts), NaN for the points inside."""
    local = _local(points, center, c, s)
    q = np.clip(local, -half, half)
    closest = center + np.stack((q[..., 0] * c - q[..., 1] * s, q[..., 0] * s + q[..., 1] * c), axis=-1)
    return np.where(np.all(np.abs(local) < half, axis=-1)[..., None], np.nan, closest)


def _frames(obstacles: Sequence[Obstacle]) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The obstacles' centres ``(k, 2)``, the cosines and sines of their angles ``(k,)`` (as
    :meth:`Obstacle._local` takes them, from :func:`math.cos`) and their half sides ``(k, 2)``."""
    centres = np.array([obstacle.center for obstacle in obstacles]).reshape(-1, 2)
    cos = np.array([math.cos(obstacle.angle) for obstacle in obstacles])
    sin = np.array([math.sin(obstacle.angle) for obstacle in obstacles])
    half = np.array([obstacle.size for obstacle in obstacles]).reshape(-1, 2) / 2
    return centres, cos, sin, half


def sensed(obstacles: Sequence[Obstacle], positions: Any, range: float) -> FloatArray:  # noqa: A002 (as the sensors)
    """What obstacle sensors at ``positions`` ``(m, 2)`` read: the closest point of each obstacle
    ``(m, k, 2)``, NaN for an obstacle beyond ``range`` (m, inclusive) or around the sensor.

    All obstacles in one pass (a robot's sensor reads one position, thousands of times a run)."""
    here = np.asarray(positions, dtype=np.float64).reshape(-1, 2)
    out = np.full((len(here), len(obstacles), 2), np.nan)
    if not obstacles:
        return out
    centres, cos, sin, half = _frames(obstacles)
    # Only a sensor within an obstacle's circumcircle grown by the range can read it, and a swarm's
    # robots are mostly far from every obstacle: the closest points of the pairs that may be in
    # range only, each as the whole table would give it (elementwise).
    reach = (np.hypot(half[:, 0], half[:, 1]) + range) * (1 + 1e-9)
    gap = here[:, None, :] - centres
    rows, which = np.nonzero(gap[..., 0] * gap[..., 0] + gap[..., 1] * gap[..., 1] <= reach * reach)
    points = here[rows]
    closest = _closest(points, centres[which], cos[which], sin[which], half[which])
    far = ~(np.hypot(closest[:, 0] - points[:, 0], closest[:, 1] - points[:, 1]) <= range)
    out[rows, which] = np.where(far[:, None], np.nan, closest)
    return out


def _distances(local: FloatArray, half: Any) -> FloatArray:
    """Distances ``(...)`` (m) from points ``local`` ``(..., 2)`` in rectangles' frames to the
    rectangles of half sides ``half`` ``(..., 2)`` (0 inside)."""
    outside = np.maximum(np.abs(local) - half, 0.0)
    return np.hypot(outside[..., 0], outside[..., 1])


def touching(obstacles: Sequence[Obstacle], positions: Any, radius: float) -> np.ndarray:
    """Which robots ``(n,)`` touch an obstacle: their centre, at ``positions`` ``(n, 2)``, is closer
    than ``radius`` (m) to one of ``obstacles`` (or inside it)."""
    return _touching(_frames(obstacles) if obstacles else None, positions, radius)


def _touching(
    frames: tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None, positions: Any, radius: float
) -> np.ndarray:
    """:func:`touching` for rectangles given by their frames (:func:`_frames`; ``None``: none)."""
    points = as_array(positions, "positions", (None, 2))
    touch = np.zeros(len(points), dtype=bool)
    if frames is None or not len(frames[0]) or not len(points):
        return touch
    centres, cos, sin, half = frames
    # Only a robot within an obstacle's circumcircle grown by `radius` can be that close to it. With
    # the robots sorted along the axis they spread most on, each obstacle's candidates are one
    # slice: thousands of obstacles cost no loop, and a large one no pair of robots (a neighbour
    # query over robots and obstacles at the largest reach measured every robot pair that close).
    reach = (np.hypot(half[:, 0], half[:, 1]) + radius) * (1 + 1e-9)
    axis = int(np.ptp(points[:, 1]) > np.ptp(points[:, 0]))
    order = np.argsort(points[:, axis], kind="stable")
    along = points[order, axis]
    starts = np.searchsorted(along, centres[:, axis] - reach, side="left")
    counts = np.searchsorted(along, centres[:, axis] + reach, side="right") - starts
    owners = np.repeat(np.arange(len(centres)), counts)
    others = order[spans(starts, counts)]
    across = np.abs(points[others, 1 - axis] - centres[owners, 1 - axis]) <= reach[owners]
    owners, others = owners[across], others[across]
    local = _local(points[others], centres[owners], cos[owners], sin[owners])
    touch[others[_distances(local, half[owners]) < radius]] = True
    return touch


class Fleet:
    """Obstacles that move at constant velocities with no walls to bounce off (the affine
    experiment's thousands of bars), kept as arrays: one step moves them all, as
    :meth:`Obstacle.step` moves each (the same arithmetic, the same bits)."""

    def __init__(self, obstacles: Sequence[Obstacle] = ()) -> None:
        self.centres, self.cos, self.sin, self.half = _frames(obstacles)
        self.angles = np.array([o.angle for o in obstacles])
        self.velocities = np.array([o.velocity for o in obstacles]).reshape(-1, 2)

    def __len__(self) -> int:
        return len(self.centres)

    def step(self, dt: float) -> None:
        """Move every moving obstacle by its ``velocity * dt``."""
        moving = np.any(self.velocities != 0, axis=1)[:, None]
        self.centres = np.where(moving, self.centres + self.velocities * dt, self.centres)

    def touching(self, positions: Any, radius: float) -> np.ndarray:
        """:func:`touching` of the fleet."""
        return _touching((self.centres, self.cos, self.sin, self.half), positions, radius)

    @property
    def obstacles(self) -> list[Obstacle]:
        """The obstacles where they are now (for drawing)."""
        return [
            Obstacle(centre, 2 * half, angle, velocity)
            for centre, half, angle, velocity in zip(self.centres, self.half, self.angles, self.velocities, strict=True)
        ]


def as_csr(obstacles: list[Obstacle]) -> tuple[FloatArray, np.ndarray]:
    """The obstacles' polygons as CSR ``(vertices (4k, 2), offsets (k + 1,))`` for the kernels."""
    vertices = np.vstack([o.polygon for o in obstacles]) if obstacles else np.zeros((0, 2))
    return vertices, np.arange(0, 4 * len(obstacles) + 1, 4, dtype=np.int64)
