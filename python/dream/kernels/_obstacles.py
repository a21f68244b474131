"""Obstacles as virtual agents, which keep the robots' Voronoi cells off them."""

from __future__ import annotations

from typing import Any

import numpy as np

import dream._reference as _reference
from dream._checks import FloatArray, as_array, check_nonnegative
from dream.kernels._dispatch import implementation
from dream.specs import GRITSBOT


def _mirror_offset(robot_radius: float, margin: float, mirror_at_surface: bool) -> float:
    """How far before an obstacle's surface a robot's cell stops (m)."""
    if mirror_at_surface:
        return 0.0
    return check_nonnegative(robot_radius, "robot_radius") + check_nonnegative(margin, "margin")


def obstacle_agents(
    position: Any,
    closest_points: Any,
    *,
    robot_radius: float = GRITSBOT.radius,
    margin: float = 0.0,
    mirror_at_surface: bool = False,
) -> FloatArray:
    """One robot's virtual agents ``(k, 2)`` from the closest points ``(k, 2)`` of the obstacles it
    senses (an :class:`~dream.sensors.ObstacleSensor` reading); see :func:`virtual_agents`.

    With one position per closest point (``position`` ``(k, 2)``, of the robot that sensed it; a
    swarm's readings at once), the agents come row for row, NaN for a point that gives none
    (a robot touching the obstacle, or a NaN point: nothing sensed)."""
    offset = _mirror_offset(robot_radius, margin, mirror_at_surface)
    if np.ndim(position) == 2:
        p = as_array(position, "position", (None, 2))
        c = np.asarray(closest_points, dtype=np.float64)
        if c.shape != p.shape:
            raise ValueError(f"`closest_points` must have the shape of `position` {p.shape}, got {c.shape}")
        return _reference.mirrored(p, c, offset)
    p = as_array(position, "position", (2,))
    c = as_array(closest_points, "closest_points", (None, 2))
    if not len(c):  # most robots of a large arena sense no obstacle at a given step
        return np.zeros((0, 2))
    return _reference.agents_from_closest(p, c, offset)


def virtual_agents(
    positions: Any,
    obstacles: tuple[Any, Any],
    *,
    range: float = 1.0,  # noqa: A002 (a sensor's range, as elsewhere in the API)
    robot_radius: float = GRITSBOT.radius,
    margin: float = 0.0,
    mirror_at_surface: bool = False,
) -> tuple[np.ndarray, FloatArray]:
    """Virtual agents that keep each robot's Voronoi cell off the obstacles it senses.

    For robot p and each convex obstacle whose closest point c is within ``range``, the agent
    is p mirrored across ``c - n (robot_radius + margin)`` (n the unit vector from p to c): the
    cell's boundary then stays ``robot_radius + margin`` before the obstacle, so the robot's
    body does not touch it. A robot already closer than that gets its boundary 1 um ahead of
    itself (its cell keeps to its own side and its centroid leads it away).
    ``mirror_at_surface=True`` mirrors across c itself, as the original did. A robot inside an
    obstacle gets no agent for it.

    Parameters
    ----------
    positions : (n, 2)
    obstacles : (vertices (v, 2), offsets (k + 1,))
        Convex obstacles as CSR: obstacle k is the convex hull of
        ``vertices[offsets[k]:offsets[k + 1]]``.

    Returns
    -------
    indptr : (n + 1,) int64, points : (m, 2)
        Robot i's agents are ``points[indptr[i]:indptr[i + 1]]``, by obstacle.

    Raises
    ------
    GeometryError
        If an obstacle's vertices enclose no area.
    """
    p = as_array(positions, "positions", (None, 2))
    vertices = as_array(obstacles[0], "obstacle vertices", (None, 2))
    offsets = np.ascontiguousarray(obstacles[1], dtype=np.int64)
    if (
        offsets.ndim != 1
        or len(offsets) < 1
        or offsets[0] != 0
        or np.any(np.diff(offsets) < 0)
        or offsets[-1] != len(vertices)
    ):
        raise ValueError("obstacle `offsets` must be non-decreasing from 0 to the number of vertices")
    check_nonnegative(range, "range")
    offset = _mirror_offset(robot_radius, margin, mirror_at_surface)
    return implementation("virtual_agents")(p, vertices, offsets, range=range, offset=offset)
