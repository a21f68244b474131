"""Obstacles as virtual agents (reference: every robot against every obstacle edge).

For robot p and a convex obstacle whose closest point c is within ``range``, the virtual agent
is the mirror image of p across ``c - n * offset`` (n the unit vector from p to c), so the
bisector lies ``offset`` before the surface. A robot inside or on an obstacle gets no agent.
"""

from __future__ import annotations

import numpy as np

from dream._checks import FloatArray
from dream.errors import GeometryError


def _counter_clockwise(polygon: FloatArray) -> FloatArray:
    centre = polygon.mean(axis=0)
    return polygon[np.argsort(np.arctan2(polygon[:, 1] - centre[1], polygon[:, 0] - centre[0]))]


def closest_point(polygon: FloatArray, p: FloatArray) -> FloatArray | None:
    """Closest point of the convex ``polygon`` ``(k, 2)`` to ``p``; ``None`` if p is inside."""
    ring = _counter_clockwise(polygon)
    starts, ends = ring, np.roll(ring, -1, axis=0)
    edges = ends - starts
    to_p = p - starts
    if np.all(edges[:, 0] * to_p[:, 1] - edges[:, 1] * to_p[:, 0] >= 0):
        return None
    t = np.clip((to_p * edges).sum(axis=1) / (edges * edges).sum(axis=1), 0.0, 1.0)
    candidates = starts + t[:, None] * edges
    return candidates[np.argmin(((candidates - p) ** 2).sum(axis=1))]


def virtual_agents(
    positions: FloatArray, vertices: FloatArray, offsets: np.ndarray, *, range: float, offset: float  # noqa: A002
) -> tuple[np.ndarray, FloatArray]:
    """Virtual agents of every robot as CSR ``(indptr (n + 1,), points (m, 2))``, obstacles in order.

    Obstacle k is the convex polygon ``vertices[offsets[k]:offsets[k + 1]]``.
    """
    for k, (start, stop) in enumerate(zip(offsets[:-1], offsets[1:])):
        ring = _counter_clockwise(vertices[start:stop])
        twice_area = np.sum(ring[:, 0] * np.roll(ring[:, 1], -1) - np.roll(ring[:, 0], -1) * ring[:, 1])
        if len(ring) < 3 or twice_area <= 1e-12:
            raise GeometryError(f"obstacle {k} is degenerate: its vertices enclose no area")
    indptr = [0]
    points: list[FloatArray] = []
    for p in positions:
        for start, stop in zip(offsets[:-1], offsets[1:]):
            c = closest_point(vertices[start:stop], p)
            if c is None:
                continue
            distance = float(np.hypot(*(c - p)))
            if distance > range or distance == 0:
                continue
            surface = c - (c - p) / distance * offset
            points.append(2 * surface - p)
        indptr.append(len(points))
    return np.array(indptr, dtype=np.int64), np.array(points, dtype=np.float64).reshape(-1, 2)
