"""Voronoi cells bounded by a disc and the arena: every robot's (:func:`voronoi_cells`), one robot's, or
those of robots that know the others by radio (:func:`heard_cells`)."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from dream._checks import Bounds, FloatArray, as_array, as_offsets, as_shaped, checked_bounds
from dream._reference.draws import Loss
from dream._reference.voronoi import MAX_COORDINATE
from dream.kernels._dispatch import core_checks, implementation, kernel_input
from dream.kernels._neighbours import checked_loss
from dream.specs import ROBOTARIUM


def _within_reach(array: FloatArray, name: str) -> FloatArray:
    """``array`` unless a coordinate exceeds what the Voronoi kernels compute without overflow."""
    if array.size and np.abs(array).max() > MAX_COORDINATE:
        raise ValueError(f"`{name}` must be finite and at most 1e100 in magnitude, got {np.abs(array).max()}")
    return array


def _points(value: Any, name: str) -> FloatArray:
    """``value`` as ``(n, 2)`` points: as it lies for the Rust kernels, whose bindings check every
    coordinate finite and within reach (a pass of each over 100,000 robots' arrays, every step),
    checked here for the reference."""
    array = kernel_input(value, name, (None, 2))
    return array if core_checks() else _within_reach(array, name)


def _checked_box(bounds: Any) -> Bounds:
    """The arena ``bounds`` of a cell, within reach."""
    box = checked_bounds(bounds)
    assert box is not None
    _within_reach(np.array(box), "bounds")
    return box


class VoronoiCells(NamedTuple):
    """Cells of :func:`voronoi_cells`; ``vertices``/``offsets`` are ``None`` unless requested."""

    centroids: FloatArray  #: (n, 2)
    areas: FloatArray  #: (n,)
    vertices: FloatArray | None  #: (m, 2): robot i's polygon is vertices[offsets[i]:offsets[i+1]]
    offsets: np.ndarray | None  #: (n + 1,) int64


def voronoi_cells(
    positions: Any,
    *,
    radius: float = 1.0,
    bounds: Bounds = ROBOTARIUM.bounds,
    virtual: tuple[Any, Any] | None = None,
    resolution: int = 64,
    polygons: bool = False,
    neighbours: bool = True,
) -> VoronoiCells:
    """Each robot's Voronoi cell within a disc: centroid, area and optionally the polygon.

    Robot i's cell is the disc of ``radius`` (a regular polygon of ``resolution`` vertices)
    intersected with the arena ``bounds``, clipped by the perpendicular bisector of every other
    robot within ``2 radius`` and of each of its virtual agents (exact polygon clipping). An
    empty cell (robot outside the arena) has area 0 and the robot's position as centroid. A
    radius beyond the arena's reach is shrunk to one that still covers it (same cells, no loss
    of precision), so any finite radius works; coordinates are limited to 1e100 in magnitude.

    Parameters
    ----------
    positions : (n, 2)
    virtual : (indptr (n + 1,), points (m, 2)), optional
        Virtual agents per robot, e.g. from :func:`virtual_agents`.
    polygons : bool
        Also return the cells' vertices (counter-clockwise) as CSR.
    neighbours : bool
        Clip each cell by the other robots (default). Without, each cell is clipped by its
        virtual agents alone: the cells of robots that each know only what they were told, e.g.
        the positions their radio heard, given as virtual agents (as :func:`voronoi_cell` for
        every robot in one call).
    """
    p = _within_reach(as_array(positions, "positions", (None, 2)), "positions")
    n = p.shape[0]
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"`radius` must be finite and > 0, got {radius}")
    if resolution < 3:
        raise ValueError(f"`resolution` must be >= 3, got {resolution}")
    box = _checked_box(bounds)
    indptr, points = None, None
    if virtual is not None:
        points = _within_reach(as_array(virtual[1], "virtual points", (None, 2)), "virtual points")
        indptr = as_offsets(virtual[0], "virtual", len(points), n, part="indptr")
    centroids, areas, vertices, offsets = implementation("voronoi_cells")(
        p,
        radius=radius,
        bounds=box,
        virtual_indptr=indptr,
        virtual_points=points,
        resolution=resolution,
        neighbours=neighbours,
    )
    return VoronoiCells(centroids, areas, vertices if polygons else None, offsets if polygons else None)


def _messages(value: Any, name: str, n: int) -> FloatArray:
    """``value`` as ``(n, 2)`` messages: finite points within reach, or rows of NaN (nothing said);
    the Rust kernels' bindings check the values themselves."""
    if core_checks():
        return as_shaped(value, name, (n, 2))
    try:
        array = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"`{name}` must be a float array of shape ({n}, 2): {err}") from None
    if array.shape != (n, 2):
        raise ValueError(f"`{name}` must have shape ({n}, 2), got {array.shape}")
    unsaid = np.isnan(array)
    half = np.flatnonzero(unsaid[:, 0] != unsaid[:, 1])
    if len(half):
        raise ValueError(f"`{name}` row {half[0]} is half NaN: a message is a finite point, or NaN in both coordinates")
    _within_reach(array[~unsaid[:, 0]], name)
    return array


def _rows(value: Any, name: str, rows: int) -> tuple[np.ndarray, FloatArray]:
    """CSR ``(indptr (rows + 1,), points (m, 2))``, empty rows when ``value`` is ``None``."""
    if value is None:
        return np.zeros(rows + 1, dtype=np.int64), np.zeros((0, 2))
    points = _points(value[1], f"{name} points")
    return as_offsets(value[0], name, len(points), rows, part="indptr"), points


def heard_cells(
    here: Any,
    hearers: Any,
    positions: Any,
    said: Any,
    said_now: Any = None,
    *,
    range: float,
    seen: tuple[Any, Any] | None = None,
    same: float = 0.0,
    virtual: tuple[Any, Any] | None = None,
    radius: float = 1.0,
    bounds: Bounds = ROBOTARIUM.bounds,
    resolution: int = 64,
    polygons: bool = False,
    loss: Loss | None = None,
    lost: Any = None,
) -> VoronoiCells:
    """The cells of robots that know the others only by what a range radio tells them, each as
    :func:`voronoi_cell` computes it from what its robot knows.

    Robot ``hearers[r]``'s cell is its disc around ``here[r]`` within the arena, clipped by the
    messages it hears, then by the robots it sees that no message accounts for, then by its
    virtual agents. It hears robot j when their ``positions`` are within ``range`` (as
    :func:`neighbours` measures): ``said_now[j]`` when j is below it (the robots of one step take
    their turns by index, so the lower ones have spoken), else ``said[j]``. What
    :func:`neighbours` (of the hearers), :func:`far_from` and :func:`voronoi_cells` give one after
    the other, to the bit, in one pass that looks only at the messages near each cell.

    Parameters
    ----------
    here : (k, 2)
        Where each hearer believes itself: its cell's site.
    hearers : (k,) int
        The hearers' indices among ``positions``, strictly increasing.
    positions : (n, 2)
        Where every robot is: who hears whom.
    said, said_now : (n, 2)
        What each robot said before and after its turn in this round; a row of NaN is nothing
        said. ``said_now`` defaults to ``said``.
    seen : (indptr (k + 1,), points (m, 2)), optional
        The positions each hearer sees; those farther than ``same`` (m) from every message it
        hears clip its cell too.
    virtual : (indptr (k + 1,), points (j, 2)), optional
        Each hearer's virtual agents (see :func:`obstacle_agents`).
    loss : Loss, optional
        The radio's losses: a message lost is not heard, drawn as :func:`perceive` draws it.
    lost : (m,) int, optional
        Links ``i * n + j`` (each in ``[0, n^2)``) whose message robot i does not hear (lost
        otherwise: a loss burst's), strictly increasing.
    """
    p = _points(here, "here")
    k = p.shape[0]
    ids = np.asarray(hearers)
    if ids.size and ids.dtype.kind not in "iu":
        raise ValueError(f"`hearers` must hold robot indices, got dtype {ids.dtype}")
    ids = np.ascontiguousarray(ids, dtype=np.int64)
    x = _points(positions, "positions")
    n = x.shape[0]
    if ids.shape != (k,):
        raise ValueError(f"`hearers` must have shape ({k},) (one per row of `here`), got {ids.shape}")
    if k and (ids[0] < 0 or ids[-1] >= n or np.any(np.diff(ids) <= 0)):
        raise ValueError(f"`hearers` must be strictly increasing indices below {n}, got {ids.tolist()[:8]}")
    before = _messages(said, "said", n)
    after = before if said_now is None else _messages(said_now, "said_now", n)
    for name, value in (("range", range), ("same", same)):
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"`{name}` must be finite and >= 0, got {value}")
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"`radius` must be finite and > 0, got {radius}")
    if not 3 <= resolution <= 2**20:
        raise ValueError(f"`resolution` must be between 3 and 2^20, got {resolution}")
    seen_indptr, seen_points = _rows(seen, "seen", k)
    virtual_indptr, virtual_points = _rows(virtual, "virtual", k)
    centroids, areas, vertices, offsets = implementation("heard_cells")(
        p,
        ids,
        x,
        before,
        after,
        range=range,
        seen_indptr=seen_indptr,
        seen_points=seen_points,
        same=same,
        virtual_indptr=virtual_indptr,
        virtual_points=virtual_points,
        radius=radius,
        bounds=_checked_box(bounds),
        resolution=resolution,
        loss=checked_loss(loss),
        lost=None if lost is None else _links(lost, n),
    )
    return VoronoiCells(centroids, areas, vertices if polygons else None, offsets if polygons else None)


def _links(lost: Any, n: int) -> np.ndarray:
    """``lost`` as a strictly increasing int64 array of links of ``n`` robots (in ``[0, n^2)``)."""
    links = np.asarray(lost)
    if links.ndim != 1 or (links.size and links.dtype.kind not in "iu"):
        raise ValueError(f"`lost` must be a 1-D array of links (integers), got {links.dtype} of shape {links.shape}")
    if links.size and (int(links.min()) < 0 or int(links.max()) >= n * n):
        raise ValueError(f"`lost` links must lie in [0, n^2) = [0, {n * n}) for n = {n} robots")
    links = np.ascontiguousarray(links, dtype=np.int64)
    wrong = np.flatnonzero(links[1:] <= links[:-1])
    if wrong.size:
        raise ValueError(f"`lost` must be strictly increasing, but the link at index {wrong[0] + 1} is not")
    return links


def voronoi_cell(
    position: Any,
    others: Any,
    *,
    radius: float = 1.0,
    bounds: Bounds = ROBOTARIUM.bounds,
    virtual: Any = None,
    resolution: int = 64,
) -> tuple[FloatArray, float, FloatArray]:
    """One robot's cell, as :func:`voronoi_cells` computes it, from what that robot knows.

    Parameters
    ----------
    position : (2,)
    others : (k, 2)
        Positions of the other robots it knows of (those beyond ``2 radius`` change nothing).
    virtual : (j, 2), optional
        Its virtual agents (see :func:`obstacle_agents`).

    Returns
    -------
    centroid : (2,), area : float, vertices : (m, 2)
        The centroid is ``position`` when the cell is empty.
    """
    p = _within_reach(as_array(position, "position", (2,)), "position")
    q = _within_reach(as_array(others, "others", (None, 2)), "others")
    v = np.zeros((0, 2)) if virtual is None else _within_reach(as_array(virtual, "virtual", (None, 2)), "virtual")
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"`radius` must be finite and > 0, got {radius}")
    if not 3 <= resolution <= 2**20:
        raise ValueError(f"`resolution` must be between 3 and 2^20, got {resolution}")
    box = _checked_box(bounds)
    return implementation("voronoi_cell")(p, q, v, radius=radius, bounds=box, resolution=resolution)
