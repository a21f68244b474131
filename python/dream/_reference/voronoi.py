"""Voronoi cells bounded by a disc and the arena (reference: one robot, one half-plane at a time).

Robot i's cell is the disc of ``radius`` around it (a regular polygon of ``resolution``
vertices, the first at angle 0), clipped by the arena and then by the perpendicular-bisector
half-plane of every other robot within ``2 radius`` and of each of robot i's virtual agents,
nearest first (ties: robots by increasing index, then virtual agents in the given order). A
robot whose cell is empty (outside the arena) gets area 0 and its own position as centroid.

A disc far larger than the arena clips nothing but ruins the clipping's precision (at a radius
of 1e20 the intersections with the walls lose every digit), so each robot's disc is first
shrunk to :func:`covering_radius`, which still contains the whole arena.
"""

from __future__ import annotations

import numpy as np

from dream._checks import FloatArray
from dream._csr import offsets_of, spans
from dream._reference.draws import Loss, delivered
from dream._reference.neighbours import far_from, neighbours, neighbours_of

#: Largest coordinate magnitude (m) of robots, agents and bounds (the public API rejects more):
#: the centroid sums products of three coordinates, which overflow beyond ~1e102.
MAX_COORDINATE = 1e100


def clip(
    polygon: list[tuple[float, float]], point: tuple[float, float], normal: tuple[float, float]
) -> list[tuple[float, float]]:
    """The part of a convex ``polygon`` where ``(q - point) . normal <= 0`` (Sutherland-Hodgman)."""
    out: list[tuple[float, float]] = []
    count = len(polygon)
    for k in range(count):
        a, b = polygon[k], polygon[(k + 1) % count]
        sa = (a[0] - point[0]) * normal[0] + (a[1] - point[1]) * normal[1]
        sb = (b[0] - point[0]) * normal[0] + (b[1] - point[1]) * normal[1]
        if sa <= 0:
            out.append(a)
        if (sa <= 0) != (sb <= 0):
            t = sa / (sa - sb)
            out.append((a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t))
    return out


def area_centroid(
    polygon: list[tuple[float, float]], fallback: tuple[float, float]
) -> tuple[float, tuple[float, float]]:
    """Area and centroid of a simple polygon (shoelace); ``fallback`` as centroid when empty."""
    twice, cx, cy = 0.0, 0.0, 0.0
    count = len(polygon)
    for k in range(count):
        a, b = polygon[k], polygon[(k + 1) % count]
        cross = a[0] * b[1] - b[0] * a[1]
        twice += cross
        cx += (a[0] + b[0]) * cross
        cy += (a[1] + b[1]) * cross
    if count < 3 or twice <= 0:
        return 0.0, fallback
    return twice / 2, (cx / (3 * twice), cy / (3 * twice))


def covering_radius(position: tuple[float, float], bounds: tuple[float, float, float, float]) -> float:
    """A disc radius (m) around ``position`` whose polygon (any resolution >= 3) contains ``bounds``.

    The bounds lie in the disc of ``|position - centre| + half diagonal``, and a regular polygon
    of at least 3 vertices contains the disc of half its radius. Only ``+ - * sqrt``, in the Rust
    core's order, so that both get the same bits; infinite only for coordinates beyond ~1e154.
    """
    xmin, xmax, ymin, ymax = bounds
    dx, dy = position[0] - (0.5 * xmin + 0.5 * xmax), position[1] - (0.5 * ymin + 0.5 * ymax)
    width, height = xmax - xmin, ymax - ymin
    return 2.0 * (float(np.sqrt(dx * dx + dy * dy)) + 0.5 * float(np.sqrt(width * width + height * height)))


def cell(
    position: tuple[float, float],
    agents: list[tuple[float, float]],
    radius: float,
    bounds: tuple[float, float, float, float],
    resolution: int,
) -> list[tuple[float, float]]:
    """The cell of a robot at ``position`` clipped by ``agents`` (robots, then virtual agents),
    nearest first: a counter-clockwise vertex list (empty if nothing is left)."""
    px, py = position
    radius = min(radius, covering_radius(position, bounds))
    angles = 2 * np.pi * np.arange(resolution) / resolution
    polygon = [(px + radius * float(np.cos(a)), py + radius * float(np.sin(a))) for a in angles]
    xmin, xmax, ymin, ymax = bounds
    for point, normal in (
        ((xmin, 0.0), (-1.0, 0.0)),
        ((xmax, 0.0), (1.0, 0.0)),
        ((0.0, ymin), (0.0, -1.0)),
        ((0.0, ymax), (0.0, 1.0)),
    ):
        polygon = clip(polygon, point, normal)
    # Nearest first (a stable sort: ties keep the given order), as the Rust core clips.
    nearest = sorted(agents, key=lambda q: (q[0] - px) * (q[0] - px) + (q[1] - py) * (q[1] - py))
    for qx, qy in nearest:
        polygon = clip(polygon, ((px + qx) / 2, (py + qy) / 2), (qx - px, qy - py))
    return polygon


def voronoi_cell(
    position: FloatArray,
    others: FloatArray,
    virtual_points: FloatArray,
    *,
    radius: float,
    bounds: tuple[float, float, float, float],
    resolution: int = 64,
) -> tuple[FloatArray, float, FloatArray]:
    """One robot's cell: ``(centroid (2,), area, vertices (m, 2))``, clipped by ``others`` ``(k, 2)``
    then ``virtual_points`` ``(j, 2)``."""
    p = (float(position[0]), float(position[1]))
    agents = [(float(x), float(y)) for x, y in others] + [(float(x), float(y)) for x, y in virtual_points]
    polygon = cell(p, agents, radius, bounds, resolution)
    area, centroid = area_centroid(polygon, p)
    return np.array(centroid), area, np.array(polygon, dtype=np.float64).reshape(-1, 2)


def voronoi_cells(
    positions: FloatArray,
    *,
    radius: float,
    bounds: tuple[float, float, float, float],
    virtual_indptr: np.ndarray | None = None,
    virtual_points: FloatArray | None = None,
    resolution: int = 64,
    neighbours: bool = True,
) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray]:
    """Centroids ``(n, 2)``, areas ``(n,)`` and the cells as CSR ``(vertices (m, 2), offsets (n + 1,))``.

    The virtual agents are CSR ``virtual_indptr`` ``(n + 1,)``, ``virtual_points`` ``(k, 2)`` (both
    or neither): robot i's are ``virtual_points[virtual_indptr[i]:virtual_indptr[i + 1]]``. Without
    ``neighbours``, a cell is clipped by its virtual agents alone.
    """
    n = len(positions)
    # Robots beyond twice a robot's (shrunk) disc radius cannot clip its cell.
    points = [(float(x), float(y)) for x, y in positions]
    reach = max((min(radius, covering_radius(p, bounds)) for p in points), default=0.0)
    search = min(2 * reach, np.finfo(np.float64).max)
    centroids = np.zeros((n, 2))
    areas = np.zeros(n)
    offsets = np.zeros(n + 1, dtype=np.int64)
    vertices: list[tuple[float, float]] = []
    for i in range(n):
        mine = (
            np.zeros((0, 2))
            if virtual_indptr is None or virtual_points is None
            else virtual_points[virtual_indptr[i] : virtual_indptr[i + 1]]
        )
        others = neighbours_of(positions, i, search)[0] if neighbours else np.zeros(0, dtype=np.int64)
        agents = [points[j] for j in others] + [(float(x), float(y)) for x, y in mine]
        polygon = cell(points[i], agents, radius, bounds, resolution)
        areas[i], centroids[i] = area_centroid(polygon, points[i])
        vertices.extend(polygon)
        offsets[i + 1] = len(vertices)
    return centroids, areas, np.array(vertices, dtype=np.float64).reshape(-1, 2), offsets


def heard_cells(
    here: FloatArray,
    hearers: np.ndarray,
    positions: FloatArray,
    said: FloatArray,
    said_now: FloatArray,
    *,
    range: float,
    seen_indptr: np.ndarray,
    seen_points: FloatArray,
    same: float,
    virtual_indptr: np.ndarray,
    virtual_points: FloatArray,
    radius: float,
    bounds: tuple[float, float, float, float],
    resolution: int = 64,
    loss: Loss | None = None,
    lost: np.ndarray | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray]:
    """The cells of robots ``hearers`` ``(k,)`` (increasing) at ``here`` ``(k, 2)``, as
    :func:`voronoi_cells` without neighbours, each clipped by what it hears, then the robots it
    sees that nothing it hears accounts for (:func:`far_from`), then its virtual agents.

    Robot i hears robot j within ``range`` (:func:`neighbours`, of the true ``positions``
    ``(n, 2)``): ``said_now[j]`` when j < i (robots of lower index took their turn first), else
    ``said[j]``; a NaN message is nothing said, and one lost to the radio's ``loss``
    (:func:`~dream._reference.draws.delivered`) or on a link of ``lost`` (``i * n + j``) is not
    heard.
    """
    k, n = len(hearers), len(positions)
    rows = np.zeros(n, dtype=bool)
    rows[hearers] = True
    indptr, indices, distances = neighbours(positions, range, rows=rows)
    counts = np.diff(indptr)[hearers]
    owners = np.repeat(np.arange(k), counts)
    at = spans(indptr[hearers], counts)
    senders = indices[at]
    heard = np.where((senders < hearers[owners])[:, None], said_now[senders], said[senders])
    spoken = ~np.isnan(heard[:, 0])
    if loss is not None:
        spoken &= delivered(loss, hearers[owners], senders, distances[at])
    if lost is not None:
        spoken &= ~np.isin(hearers[owners] * n + senders, lost)
    heard, owners = heard[spoken], owners[spoken]
    silent = far_from(seen_points, heard, same, seen_indptr, offsets_of(owners, k))
    seen_owners = np.repeat(np.arange(k), np.diff(seen_indptr))
    agent_owners = np.repeat(np.arange(k), np.diff(virtual_indptr))
    # Each row's points in clipping order: messages, robots seen but not heard, virtual agents.
    owners_all = np.concatenate((owners, seen_owners[silent], agent_owners))
    order = np.argsort(owners_all, kind="stable")
    points = np.vstack((heard, seen_points[silent], virtual_points))[order]
    return voronoi_cells(
        here,
        radius=radius,
        bounds=bounds,
        virtual_indptr=offsets_of(owners_all[order], k),
        virtual_points=points,
        resolution=resolution,
        neighbours=False,
    )
