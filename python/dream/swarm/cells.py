"""Each deciding robot's Voronoi cell from what that robot alone knows.

A robot knows its own position and, row by row, points of several kinds: the positions its radio
heard, the robots its movement sensor sees, virtual agents for the obstacles it senses. Its cell
is the disc around it within the bounds, clipped by those points alone (nearest first), never by
the swarm's true positions: one :func:`dream.kernels.voronoi_cells` call for every deciding robot,
in parallel in Rust, each row what :func:`dream.kernels.voronoi_cell` gives that robot::

    heard = view.heard.offsets, np.column_stack((view.heard["x"], view.heard["y"]))
    cells = known_cells(view.pose[:, :2], heard, radius=1.0, bounds=arena.bounds)
    goals = cells.centroids  # (k, 2)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dream import kernels
from dream._checks import Bounds, as_array, as_offsets
from dream._csr import merged
from dream.kernels import VoronoiCells


def known_cells(
    here: Any,
    *known: tuple[Any, Any],
    radius: float,
    bounds: Bounds,
    resolution: int = 64,
    polygons: bool = False,
) -> VoronoiCells:
    """The cells of robots at ``here`` ``(k, 2)`` (where each believes itself), each clipped by what
    its robot knows: ``known``, CSR rows ``(offsets (k + 1,), points (m, 2))`` over the same ``k``
    robots (heard, seen, virtual agents...), taken for each robot one kind after the other.

    Row r is :func:`dream.kernels.voronoi_cell` of ``here[r]`` with row r's points in that order
    (the kernel clips nearest first, ties in the given order); ``polygons`` also returns the
    vertices, as :func:`dream.kernels.voronoi_cells` does."""
    p = as_array(here, "here", (None, 2))
    rows = []
    for number, (offsets, points) in enumerate(known):
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 2:
            raise ValueError(f"`known[{number}]` points must have shape (m, 2), got {points.shape}")
        rows.append((as_offsets(offsets, f"known[{number}]", len(points), len(p), part="offsets"), points))
    offsets, points = merged(*rows) if rows else (np.zeros(len(p) + 1, dtype=np.int64), np.zeros((0, 2)))
    return kernels.voronoi_cells(
        p,
        radius=radius,
        bounds=bounds,
        virtual=(offsets, points),
        resolution=resolution,
        polygons=polygons,
        neighbours=False,
    )
