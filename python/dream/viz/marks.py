"""The marks drawn at robots, in world coordinates (m): body outlines, the heading notch, the
fault marks, velocity arrows, polygons."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream.viz.style import ROBOT_DIAMETER

RADIUS = ROBOT_DIAMETER / 2
#: The heading notch: a dark triangle at the front of the body, clear of the centre (where the
#: role marks go).
NOTCH = np.array([[0.95 * RADIUS, 0.0], [0.45 * RADIUS, 0.4 * RADIUS], [0.45 * RADIUS, -0.4 * RADIUS]])
#: A stuck robot's square and a crashed robot's cross, around and over the body.
STUCK_SQUARE = 0.7 * ROBOT_DIAMETER * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
CROSS = 0.85 * RADIUS * np.array([[[-1.0, -1.0], [1.0, 1.0]], [[-1.0, 1.0], [1.0, -1.0]]])
#: Velocity arrows: shaft half-width, head length and head half-width (m), to the robots' scale.
ARROW_SHAFT, ARROW_HEAD, ARROW_HALF = 0.006, 0.035, 0.02


def finite_polygons(polygons: list[np.ndarray]) -> list[np.ndarray]:
    """The polygons of at least two points, all finite, as ``(k, 2)`` arrays (m)."""
    out = []
    for polygon in polygons:
        points = np.asarray(polygon, dtype=np.float64).reshape(-1, 2)
        if len(points) >= 2 and np.isfinite(points).all():
            out.append(points)
    return out


def placed(points: np.ndarray, positions: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """``points`` ``(k, 2)`` of a shape in the robot's frame (x forward, m) placed at every robot:
    ``(n, k, 2)``."""
    cos, sin = np.cos(headings)[:, None], np.sin(headings)[:, None]
    x, y = points[:, 0][None, :], points[:, 1][None, :]
    return np.stack((positions[:, :1] + cos * x - sin * y, positions[:, 1:] + sin * x + cos * y), axis=2)


def arrows(starts: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Arrow polygons ``(n, 7, 2)`` from ``starts`` along ``vectors`` (both ``(n, 2)``, m); the
    head shrinks with arrows shorter than it."""
    length = np.hypot(vectors[:, 0], vectors[:, 1])
    head = np.minimum(ARROW_HEAD, length)
    shrink = head / ARROW_HEAD
    shaft, half, neck = ARROW_SHAFT * shrink, ARROW_HALF * shrink, length - head
    zero = np.zeros_like(length)
    x = np.stack((zero, neck, neck, length, neck, neck, zero), axis=1)
    y = np.stack((-shaft, -shaft, -half, zero, half, shaft, shaft), axis=1)
    ux = np.divide(vectors[:, 0], length, out=np.ones_like(length), where=length > 0)[:, None]
    uy = np.divide(vectors[:, 1], length, out=np.zeros_like(length), where=length > 0)[:, None]
    return np.stack((starts[:, :1] + ux * x - uy * y, starts[:, 1:] + uy * x + ux * y), axis=2)


def ellipses(axes: Any, **style: Any) -> Any:
    """An empty ``EllipseCollection`` of robot-sized circles, placed at offsets in ``axes``' data
    coordinates (the offsets, widths and heights are set when drawing)."""
    from matplotlib.collections import EllipseCollection

    return EllipseCollection(
        ROBOT_DIAMETER,
        ROBOT_DIAMETER,
        0.0,
        units="xy",
        offsets=np.empty((0, 2)),
        offset_transform=axes.transData,
        **style,
    )
