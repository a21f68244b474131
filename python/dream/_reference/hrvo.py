"""Hybrid Reciprocal Velocity Obstacles with candidate sampling (reference implementation).

For robot A (own previous velocity v_A, preferred velocity v_pref) and each neighbour B at
distance d in unit direction u (from A to B; (1, 0) for a co-located B) moving with v_B, with
safety radius r:

* half-angle phi with ``sin phi = r / max(d, r)``; the cone's left edge is u turned by +phi,
  its right edge u turned by -phi (computed with ``sin phi`` and ``sqrt(1 - sin^2 phi)``,
  without trigonometry, exactly as the Rust kernel);
* the VO's apex is v_B, the RVO's apex (v_A + v_B) / 2;
* HRVO keeps the RVO edge on the side v_A is closer to and the VO edge on the other side
  (if v_A is equally close to both, within ``TIE`` relative to ``|v_A - RVO apex|``, both
  edges are the VO's, as in the original);
* a velocity v is forbidden by B if it lies strictly inside both half-planes:
  ``left x (v - apex_left) < 0`` and ``right x (v - apex_right) > 0``.

The result is the candidate closest to v_pref (first in candidate order on ties) that no
neighbour forbids and, when ``bounds`` is given, keeps ``position + v`` strictly inside the
bounds; the zero velocity if no candidate qualifies.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from numpy.typing import NDArray

from dream._checks import FloatArray
from dream._reference.neighbours import neighbours as find_neighbours

#: Relative tolerance under which v_A is equally close to both RVO edges.
TIE = 1e-9


def candidate_grid(v_max: float, n_angles: int = 20, n_speeds: int = 10) -> FloatArray:
    """The original polar sampling of velocities, without its duplicates: ``(m, 2)``.

    The original samples ``n_angles`` angles in [0, 2 pi] (both ends) times ``n_speeds``
    speeds in [0, v_max] (both ends), plus the zero velocity: 201 samples of which only 172
    differ. Here the zero velocity comes first, then for each distinct angle every non-zero
    speed: the same set, in the original's order, each velocity once.
    """
    angles = np.linspace(0.0, 2 * np.pi, n_angles)
    if n_angles > 1:
        angles = angles[:-1]
    speeds = np.linspace(0.0, v_max, n_speeds)[1:]
    vv, thth = np.meshgrid(speeds, angles)
    polar = np.column_stack(((vv * np.cos(thth)).ravel(), (vv * np.sin(thth)).ravel()))
    return np.vstack((np.zeros((1, 2)), polar))


def unit_directions(offsets: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit vectors ``(k, 2)`` along ``offsets`` ``(k, 2)`` ((1, 0) for a zero offset) and their lengths."""
    distances = np.sqrt(offsets[:, 0] * offsets[:, 0] + offsets[:, 1] * offsets[:, 1])
    return along(offsets, distances), distances


def along(offsets: FloatArray, distances: FloatArray) -> FloatArray:
    """Unit vectors ``(k, 2)`` along ``offsets`` ``(k, 2)`` of lengths ``distances`` ``(k,)``: each offset
    over its length, (1, 0) at length 0."""
    units = np.tile([1.0, 0.0], (len(offsets), 1))
    apart = distances > 0
    units[apart] = offsets[apart] / distances[apart, None]
    return units


def detection_directions(detections: FloatArray) -> FloatArray:
    """Unit vectors ``(k, 2)`` towards the robots of seed-format detections ``[distance, angle, vx, vy]``
    (whose angle points from the detected robot towards the sensing one)."""
    towards = detections[:, 1] + np.pi
    return np.column_stack((np.cos(towards), np.sin(towards)))


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """z of the cross product of 2-vectors along the last axis."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _forbidden(
    candidates: FloatArray,
    velocity: FloatArray,
    directions: FloatArray,
    distances: FloatArray,
    neighbour_velocities: FloatArray,
    safety: float,
) -> NDArray[np.bool_]:
    """Boolean ``(m,)``: candidates inside the HRVO of at least one neighbour."""
    if len(directions) == 0:
        return np.zeros(len(candidates), dtype=bool)
    sin = safety / np.maximum(distances, safety) if safety > 0 else np.zeros(len(distances))
    cos = np.sqrt(1.0 - sin * sin)
    ux, uy = directions[:, 0], directions[:, 1]
    left = np.column_stack((ux * cos - uy * sin, ux * sin + uy * cos))
    right = np.column_stack((ux * cos + uy * sin, uy * cos - ux * sin))
    vo_apex = neighbour_velocities
    rvo_apex = (velocity[None, :] + neighbour_velocities) / 2
    offset = velocity[None, :] - rvo_apex
    dist_left = np.abs(_cross(left, offset))
    dist_right = np.abs(_cross(right, offset))
    # Near-ties (relative to |v_A - apex|) are ties: symmetric scenes must not hang on rounding.
    tie = np.abs(dist_left - dist_right) <= TIE * np.hypot(offset[:, 0], offset[:, 1])
    left_apex = np.where((~tie & (dist_left < dist_right))[:, None], rvo_apex, vo_apex)
    right_apex = np.where((~tie & (dist_left > dist_right))[:, None], rvo_apex, vo_apex)
    # (k, m): strictly right of the left edge and strictly left of the right edge.
    inside_left = _cross(left[:, None, :], candidates[None, :, :] - left_apex[:, None, :]) < 0
    inside_right = _cross(right[:, None, :], candidates[None, :, :] - right_apex[:, None, :]) > 0
    return np.any(inside_left & inside_right, axis=0)


def hrvo_velocity(
    velocity: FloatArray,
    preferred: FloatArray,
    directions: FloatArray,
    distances: FloatArray,
    neighbour_velocities: FloatArray,
    *,
    safety: float = 0.24,
    v_max: float = 0.2,
    position: FloatArray | None = None,
    bounds: tuple[float, float, float, float] | None = None,
    candidates: FloatArray | None = None,
    include_preferred: bool = True,
) -> FloatArray:
    """One robot's HRVO velocity ``(2,)``.

    Parameters
    ----------
    velocity, preferred : (2,)
        The robot's previous velocity v_A and its preferred velocity (m/s).
    directions : (k, 2)
        Unit vectors from the robot towards each neighbour (see :func:`unit_directions`).
    distances : (k,)
        Distance to each neighbour (m).
    neighbour_velocities : (k, 2)
        Each neighbour's velocity (m/s).
    position : (2,), optional
        The robot's position; needed with ``bounds``.
    bounds : (xmin, xmax, ymin, ymax), optional
        Keep ``position + v`` strictly inside; ``None`` skips the check.
    candidates : (m, 2), optional
        Velocities to choose from; default :func:`candidate_grid` of ``v_max``.
    include_preferred : bool
        Also try ``preferred`` itself (clamped to ``v_max``) before the grid.
    """
    grid = candidate_grid(v_max) if candidates is None else candidates
    if include_preferred:
        norm = np.hypot(preferred[0], preferred[1])
        first = preferred * (v_max / norm) if norm > v_max else preferred
        grid = np.vstack((first[None, :], grid))
    valid = ~_forbidden(grid, velocity, directions, distances, neighbour_velocities, safety)
    if bounds is not None:
        if position is None:
            raise ValueError("`position` is required when `bounds` is given")
        ahead = position[None, :] + grid
        xmin, xmax, ymin, ymax = bounds
        valid &= (xmin < ahead[:, 0]) & (ahead[:, 0] < xmax) & (ymin < ahead[:, 1]) & (ahead[:, 1] < ymax)
    if not valid.any():
        return np.zeros(2)
    dx = grid[:, 0] - preferred[0]
    dy = grid[:, 1] - preferred[1]
    cost = np.where(valid, dx * dx + dy * dy, np.inf)
    return np.array(grid[int(np.argmin(cost))], dtype=np.float64)


def hrvo(
    positions: FloatArray,
    velocities: FloatArray,
    preferred: FloatArray,
    indptr: np.ndarray | None = None,
    indices: np.ndarray | None = None,
    *,
    radius: float = 1.0,
    safety: float = 0.24,
    v_max: float = 0.2,
    bounds: tuple[float, float, float, float] | None = None,
    candidates: FloatArray | None = None,
    include_preferred: bool = True,
) -> FloatArray:
    """HRVO velocities ``(n, 2)`` for the whole swarm, one robot at a time.

    ``indptr``, ``indices`` are CSR neighbour lists (both or neither); without them every other
    robot within ``radius`` is a neighbour. Neighbour velocities are the rows of ``velocities``.
    ``candidates`` ``(m, 2)`` default to :func:`candidate_grid` of ``v_max``.
    """
    n = len(positions)
    if indptr is None or indices is None:
        indptr, indices, _ = find_neighbours(positions, radius)
    grid = candidate_grid(v_max) if candidates is None else candidates
    steer = partial(
        hrvo_velocity, safety=safety, v_max=v_max, bounds=bounds, candidates=grid, include_preferred=include_preferred
    )
    out = np.zeros((n, 2))
    for i in range(n):
        js = np.asarray(indices[indptr[i] : indptr[i + 1]], dtype=np.int64)
        directions, distances = unit_directions(positions[js] - positions[i])
        out[i] = steer(velocities[i], preferred[i], directions, distances, velocities[js], position=positions[i])
    return out


def hrvo_rows(
    velocities: FloatArray,
    preferred: FloatArray,
    positions: FloatArray,
    offsets: np.ndarray,
    detections: FloatArray | tuple[FloatArray, ...],
    *,
    safety: float,
    v_max: float,
    bounds: tuple[float, float, float, float] | None,
    candidates: FloatArray,
    include_preferred: bool,
    relative: bool = False,
    steer: np.ndarray | None = None,
) -> FloatArray:
    """HRVO velocities ``(m, 2)`` of the deciding robots, row r from its own detections
    ``detections[offsets[r]:offsets[r + 1]]`` ``(k, 4)``, or its four columns (:meth:`HrvoPlanner.velocity`'s
    answer); with ``relative``, ``(k, 5)`` or five columns: distance, the offset ``(dx, dy)`` of the robot
    detected (its direction: :func:`along` it) and its velocity. With ``steer`` ``(m,)`` bool, only the
    rows it flags; the others get their preferred velocity as it is."""
    if isinstance(detections, tuple):
        detections = np.column_stack(detections)
    if relative:
        distances, velocities_seen = detections[:, 0], detections[:, 3:5]
        directions = along(detections[:, 1:3], distances)
    else:
        distances, velocities_seen = detections[:, 0], detections[:, 2:4]
        directions = detection_directions(detections)
    choose = partial(
        hrvo_velocity,
        safety=safety,
        v_max=v_max,
        bounds=bounds,
        candidates=candidates,
        include_preferred=include_preferred,
    )
    out = np.array(preferred, dtype=np.float64)
    for r in range(len(positions)) if steer is None else np.flatnonzero(steer):
        row = slice(offsets[r], offsets[r + 1])
        out[r] = choose(
            velocities[r], preferred[r], directions[row], distances[row], velocities_seen[row], position=positions[r]
        )
    return out


class HrvoPlanner:
    """One robot's HRVO: parameters and candidates ``(m, 2)`` fixed, one :meth:`velocity` call per decision."""

    def __init__(
        self,
        candidates: FloatArray,
        *,
        safety: float,
        v_max: float,
        bounds: tuple[float, float, float, float] | None,
        include_preferred: bool,
    ) -> None:
        self.candidates = candidates
        self.safety = safety
        self.v_max = v_max
        self.bounds = bounds
        self.include_preferred = include_preferred

    def velocity(
        self, detections: FloatArray, velocity: FloatArray, preferred: FloatArray, position: FloatArray
    ) -> FloatArray:
        """Velocity ``(2,)`` for seed-format detections ``(k, 4)`` ``[distance, angle, vx, vy]``."""
        return hrvo_velocity(
            velocity,
            preferred,
            detection_directions(detections),
            detections[:, 0],
            detections[:, 2:4],
            safety=self.safety,
            v_max=self.v_max,
            position=position,
            bounds=self.bounds,
            candidates=self.candidates,
            include_preferred=self.include_preferred,
        )
