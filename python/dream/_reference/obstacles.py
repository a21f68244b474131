"""Obstacles as virtual agents (reference: every robot against every obstacle edge).

For robot p and a convex obstacle whose closest point c is within ``range`` (distance d, unit
direction n from p to c), the virtual agent sits at ``p + 2 t n`` with
``t = max(d - offset, GAP)``: the bisector lies ``offset`` before the surface, or ``GAP`` ahead
of a robot already closer than that. A robot inside or on an obstacle gets no agent for it.
Each obstacle is the convex hull of its vertices; a hull of area <= ``MIN_AREA`` is degenerate.
"""

from __future__ import annotations

import numpy as np

from dream._checks import FloatArray
from dream.errors import GeometryError

GAP = 1e-6  #: least distance (m) from a robot to the bisector of its virtual agent
MIN_AREA = 1e-12  #: obstacles with a smaller convex hull (m^2) have no extent


def convex_hull(points: FloatArray) -> FloatArray:
    """Counter-clockwise convex hull ``(h, 2)`` (Andrew's monotone chain; collinear points dropped)."""
    ordered = sorted({(float(x), float(y)) for x, y in points})
    if len(ordered) < 3:
        return np.array(ordered, dtype=np.float64).reshape(-1, 2)

    def turn(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    chains = []
    for sequence in (ordered, ordered[::-1]):
        chain: list[tuple[float, float]] = []
        for p in sequence:
            while len(chain) >= 2 and turn(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        chains.append(chain[:-1])
    return np.array(chains[0] + chains[1], dtype=np.float64)


def polygon_area(polygon: FloatArray) -> float:
    """Area of a counter-clockwise polygon (shoelace)."""
    x, y = polygon[:, 0], polygon[:, 1]
    return float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) / 2


def closest_point(hull: FloatArray, p: FloatArray) -> FloatArray | None:
    """Closest point of the convex ``hull`` (counter-clockwise) to ``p``; ``None`` if p is inside."""
    starts, ends = hull, np.roll(hull, -1, axis=0)
    edges = ends - starts
    to_p = p - starts
    if np.all(edges[:, 0] * to_p[:, 1] - edges[:, 1] * to_p[:, 0] >= 0):
        return None
    t = np.clip((to_p * edges).sum(axis=1) / (edges * edges).sum(axis=1), 0.0, 1.0)
    candidates = starts + t[:, None] * edges
    return candidates[np.argmin(((candidates - p) ** 2).sum(axis=1))]


def virtual_agents(
    positions: FloatArray,
    vertices: FloatArray,
    offsets: np.ndarray,
    *,
    range: float,
    offset: float,  # noqa: A002
) -> tuple[np.ndarray, FloatArray]:
    """Virtual agents of every robot as CSR ``(indptr (n + 1,), points (m, 2))``, obstacles in order.

    Obstacle k is the convex hull of ``vertices[offsets[k]:offsets[k + 1]]``.

    Raises
    ------
    GeometryError
        If an obstacle's hull has no area (fewer than 3 distinct points, or collinear).
    """
    hulls = []
    for k, (start, stop) in enumerate(zip(offsets[:-1], offsets[1:])):
        hull = convex_hull(vertices[start:stop])
        if len(hull) < 3 or polygon_area(hull) <= MIN_AREA:
            raise GeometryError(f"obstacle {k} is degenerate: its vertices enclose no area")
        hulls.append(hull)
    indptr = [0]
    points: list[FloatArray] = []
    for p in positions:
        sensed = [c for c in (closest_point(hull, p) for hull in hulls) if c is not None]
        agents = agents_from_closest(p, np.array(sensed).reshape(-1, 2), offset, range)
        points.extend(agents)
        indptr.append(len(points))
    return np.array(indptr, dtype=np.int64), np.array(points, dtype=np.float64).reshape(-1, 2)


def agents_from_closest(p: FloatArray, closest: FloatArray, offset: float, range: float = np.inf) -> FloatArray:  # noqa: A002
    """Virtual agents ``(k, 2)`` of a robot at ``p`` for obstacle closest points ``(m, 2)``
    within ``range`` (points at distance 0, i.e. touching, give none)."""
    agents = mirrored(p, closest, offset, range)
    return agents[~np.isnan(agents[:, 0])]


def mirrored(p: FloatArray, closest: FloatArray, offset: float, range: float = np.inf) -> FloatArray:  # noqa: A002
    """The virtual agent ``(m, 2)`` of each robot at ``p`` ``(m, 2)`` (or one robot, ``(2,)``) for
    the obstacle closest point ``closest`` ``(m, 2)``: ``p`` mirrored across the point ``offset``
    before it; NaN for a point beyond ``range``, at distance 0 or NaN (none sensed)."""
    d = np.asarray(closest, dtype=np.float64).reshape(-1, 2) - p
    distance = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        agents = p + (2 * np.maximum(distance - offset, GAP))[:, None] * (d / distance[:, None])
    return np.where(((distance <= range) & (distance != 0))[:, None], agents, np.nan)
