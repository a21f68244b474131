"""Neighbour filtering by range and field of view (reference: all pairs, O(n^2))."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from dream._checks import FloatArray
from dream._csr import spans
from dream._reference.draws import Loss, delivered
from dream._reference.reduce import segment_reduce


def neighbours_of(
    positions: FloatArray,
    i: int,
    radius: float,
    *,
    heading: float | None = None,
    direction: float = 0.0,
    fov: float = 2 * np.pi,
    max_neighbours: int | None = None,
) -> tuple[np.ndarray, FloatArray]:
    """Robot ``i``'s neighbours: ``(indices, distances)``, indices increasing.

    Robot j is a neighbour when j != i (by index: co-located robots count),
    ``|p_j - p_i| <= radius`` and, with ``heading`` given, the direction from i to j lies within
    ``fov / 2`` of ``heading + direction`` (a co-located robot is always seen). With
    ``max_neighbours`` only the nearest are kept (ties: lower index first).
    """
    dx = positions[:, 0] - positions[i, 0]
    dy = positions[:, 1] - positions[i, 1]
    with np.errstate(over="ignore"):
        dist = np.sqrt(dx * dx + dy * dy)
    far = np.isinf(dist)  # the squares overflowed (beyond ~1.3e154 m): hypot scales instead
    dist[far] = np.hypot(dx[far], dy[far])
    keep = dist <= radius
    keep[i] = False
    if heading is not None:
        rel = np.arctan2(dy, dx) - (heading + direction)
        rel = (rel + np.pi) % (2 * np.pi) - np.pi
        keep &= (np.abs(rel) <= fov / 2) | (dist == 0)
    js = np.flatnonzero(keep)
    if max_neighbours is not None and len(js) > max_neighbours:
        nearest = np.lexsort((js, dist[js]))[:max_neighbours]
        js = np.sort(js[nearest])
    return js.astype(np.int64), dist[js]


def neighbours(
    positions: FloatArray,
    radius: float,
    headings: FloatArray | None = None,
    direction: float = 0.0,
    fov: float = 2 * np.pi,
    max_neighbours: int | None = None,
    rows: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, FloatArray]:
    """Every robot's :func:`neighbours_of`, as CSR ``(indptr (n+1,), indices, distances)``; with
    ``rows`` ``(n,)`` bool, only the flagged robots' (the others' rows are empty)."""
    n = len(positions)
    none = (np.zeros(0, dtype=np.int64), np.zeros(0))
    found = [
        neighbours_of(
            positions,
            i,
            radius,
            heading=None if headings is None else float(headings[i]),
            direction=direction,
            fov=fov,
            max_neighbours=max_neighbours,
        )
        if rows is None or rows[i]
        else none
        for i in range(n)
    ]
    indptr = np.zeros(n + 1, dtype=np.int64)
    indptr[1:] = np.cumsum([len(js) for js, _ in found])
    indices = np.concatenate([js for js, _ in found]) if found else np.zeros(0, dtype=np.int64)
    distances = np.concatenate([d for _, d in found]) if found else np.zeros(0)
    return indptr, indices.astype(np.int64), distances


def far_from(
    points: FloatArray,
    others: FloatArray,
    distance: float,
    points_offsets: np.ndarray | None = None,
    others_offsets: np.ndarray | None = None,
) -> np.ndarray:
    """``(k,)`` bool: which of ``points`` ``(k, 2)`` lie farther than ``distance`` (``hypot``) from
    every one of ``others`` ``(m, 2)`` in the same row; the offsets ``(rows + 1,)`` cut both into
    rows (one row without them)."""
    points_offsets = np.array([0, len(points)]) if points_offsets is None else points_offsets
    others_offsets = np.array([0, len(others)]) if others_offsets is None else others_offsets
    far = np.ones(len(points), dtype=bool)
    for row in range(len(points_offsets) - 1):
        start, stop = points_offsets[row], points_offsets[row + 1]
        mine, theirs = points[start:stop], others[others_offsets[row] : others_offsets[row + 1]]
        gaps = np.hypot(mine[:, None, 0] - theirs[None, :, 0], mine[:, None, 1] - theirs[None, :, 1])
        far[start:stop] = np.all(gaps > distance, axis=1)
    return far


def perceive(
    positions: FloatArray,
    headings: FloatArray,
    rows: np.ndarray,
    *,
    sight: tuple[float, float, float] | None = None,
    radio_range: float | None = None,
    talking: np.ndarray | None = None,
    carried: Sequence[FloatArray] | None = None,
    bearings: bool = True,
    summed: Sequence[FloatArray] | None = None,
    loss: Loss | None = None,
) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """Who the robots ``rows`` see (``sight``: range, fov, direction) and hear (within
    ``radio_range``, among the ``talking``, through the radio's ``loss``): ``(seen, heard)``,
    ``(offsets, ids, distances, bearings, dx, dy, *carried)`` (each of ``carried`` ``(n,)`` read
    at the robots seen; the bearings empty unless ``bearings``) and ``(offsets, ids, distances,
    lost, *summed)`` over those rows, ids increasing in each row; ``lost`` each row's messages
    lost (empty without ``loss``); each of ``summed`` ``(n,)`` added up over each row heard (in
    increasing id), whose ids and distances are then left empty (as where ``summed`` is empty:
    the rows only counted)."""
    n = len(positions)
    reach = max(0.0 if sight is None else sight[0], 0.0 if radio_range is None else radio_range)
    asked = np.zeros(n, dtype=bool)
    asked[rows] = True
    indptr, indices, distances = neighbours(positions, reach, rows=asked)
    seen: list[tuple[np.ndarray, ...]] = []
    heard: list[tuple[np.ndarray, ...]] = []
    lost: list[int] = []
    for i in rows:
        js, d = indices[indptr[i] : indptr[i + 1]], distances[indptr[i] : indptr[i + 1]]
        dx, dy = positions[js, 0] - positions[i, 0], positions[js, 1] - positions[i, 1]
        bearing = np.arctan2(dy, dx)
        if sight is not None:
            keep = d <= sight[0]
            if sight[1] < 2 * np.pi:
                relative = (bearing - (headings[i] + sight[2]) + np.pi) % (2 * np.pi) - np.pi
                keep &= (np.abs(relative) <= sight[1] / 2) | (d == 0)
            seen.append((js[keep], d[keep], bearing[keep], dx[keep], dy[keep]))
        if radio_range is not None and talking is not None:
            keep = (d <= radio_range) & talking[js]
            if loss is not None:
                offered = int(keep.sum())
                keep[keep] = delivered(loss, np.full(offered, i), js[keep], d[keep])
                lost.append(offered - int(keep.sum()))
            heard.append((js[keep], d[keep]))

    def csr(parts: list[tuple[np.ndarray, ...]], columns: int) -> tuple[np.ndarray, ...]:
        counts = [len(p[0]) for p in parts] if parts else [0] * len(rows)
        offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
        if not parts:
            return offsets, np.zeros(0, dtype=np.int64), *(np.zeros(0) for _ in range(columns - 1))
        return (offsets, *(np.concatenate([p[k] for p in parts]) for k in range(columns)))

    seen_csr = csr(seen, 5)
    if not bearings:
        seen_csr = (*seen_csr[:3], np.zeros(0), *seen_csr[4:])
    ids = seen_csr[1]
    offsets, senders, gaps = csr(heard, 2)
    heard_csr: tuple[np.ndarray, ...] = (offsets, senders, gaps, np.array(lost, dtype=np.int64))
    if summed is not None:
        sums = [
            segment_reduce(np.asarray(values, dtype=np.float64)[:, None], offsets, "sum", senders)[:, 0]
            for values in summed
        ]
        heard_csr = (offsets, np.zeros(0, dtype=np.int64), np.zeros(0), heard_csr[3], *sums)
    return (*seen_csr, *(np.asarray(values, dtype=np.float64)[ids] for values in carried or ())), heard_csr


def linked(
    rows: np.ndarray,
    indptr: np.ndarray,
    indices: np.ndarray,
    talking: np.ndarray,
    positions: FloatArray | None = None,
) -> tuple[np.ndarray, ...]:
    """What the robots ``rows`` hear over the graph ``(indptr, indices)`` among the ``talking``:
    ``(offsets, ids, distances)``, each row's talking links but itself in the graph's order, the
    distances NaN without ``positions``."""
    n = len(talking)
    first, last = indptr[rows], indptr[rows + 1]
    wrong = (first < 0) | (first > last) | (last > len(indices))
    if wrong.any():
        i, a, b = rows[wrong][0], first[wrong][0], last[wrong][0]
        raise ValueError(
            f"`graph` is not a valid CSR of {n} rows: row {i}'s links run from {a} to {b}, "
            f"not within the {len(indices)} indices"
        )
    counts = last - first
    me, others = np.repeat(rows, counts), indices[spans(first, counts)]
    outside = (others < 0) | (others >= n)
    if outside.any():
        i, j = me[outside][0], others[outside][0]
        raise ValueError(
            f"`graph` is not a valid CSR of {n} rows: row {i} links {j}, which is not a robot id in [0, {n})"
        )
    heard = talking[others] & (others != me)
    offsets = np.concatenate(([0], np.cumsum(heard)))[np.concatenate(([0], np.cumsum(counts)))].astype(np.int64)
    me, others = me[heard], others[heard]
    if positions is None:
        return offsets, others.astype(np.int64), np.full(len(others), np.nan)
    gaps = positions[others] - positions[me]
    return offsets, others.astype(np.int64), np.hypot(gaps[:, 0], gaps[:, 1])
