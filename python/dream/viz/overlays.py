"""What is drawn around the robots: goals, velocity arrows, radio links, obstacles, Voronoi
cells, and the focus robot's ranges and the robots it hears."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream.viz.marks import arrows, ellipses, finite_polygons
from dream.viz.style import (
    LINK_COLOUR,
    MOVING_OBSTACLE_COLOUR,
    OBSTACLE_COLOUR,
    RANGE_COLOURS,
    ROBOT_DIAMETER,
    VELOCITY_SCALE,
)
from dream.viz.view import Framing


class Overlays(Framing):
    """The overlay layers of a :class:`~dream.viz.Renderer`: each ``_draw_*`` takes one part of a
    frame and appends what it shows to ``legend``."""

    def _make_overlays(self) -> None:
        from matplotlib.collections import LineCollection, PolyCollection

        self._cells = PolyCollection([], facecolors="none", edgecolors="0.5", linewidths=0.8)
        self._obstacles = PolyCollection([], facecolors=OBSTACLE_COLOUR, edgecolors=OBSTACLE_COLOUR, linewidths=0.5)
        self._moving = PolyCollection(
            [], facecolors=MOVING_OBSTACLE_COLOUR, edgecolors="0.15", linewidths=0.8, hatch="//"
        )
        self._links = LineCollection([], colors=LINK_COLOUR, linewidths=0.7)
        self._ranges = ellipses(self.axes, facecolors="none", linewidths=1.4, linestyles="--")
        self._heard = LineCollection([], colors=RANGE_COLOURS[0], linewidths=1.2, alpha=0.8)
        self._goals = self.axes.scatter([], [], marker="x", s=40 * self._text**2, linewidths=1.5)
        self._velocities = PolyCollection([], linewidths=0.4, edgecolors="black")
        self._focus_ring = ellipses(self.axes, facecolors="none", edgecolors="black", linewidths=2.2)

    def _draw_goals(self, goals: Any, n: int, legend: list[tuple[str, Any]]) -> None:
        if goals is not None and n:
            goals = np.asarray(goals, dtype=np.float64).reshape(-1, 2)[:n]
            shown = np.isfinite(goals).all(axis=1)
            self._goals.set_offsets(goals[shown])
            self._goals.set_color(self._colours[: len(goals)][shown])
            if shown.any():
                legend.append(("goal", ("goal",)))
        else:
            self._goals.set_offsets(np.empty((0, 2)))

    def _draw_velocities(
        self, velocities: Any, positions: np.ndarray, status: np.ndarray | None, legend: list[tuple[str, Any]]
    ) -> None:
        self._velocities.set_verts([])
        if velocities is not None and len(positions):
            velocities = np.asarray(velocities, dtype=np.float64).reshape(-1, 2)[: len(positions)]
            shown = np.isfinite(velocities).all(axis=1)
            if status is not None:  # a crashed robot goes nowhere, whatever it last chose
                shown &= status[: len(velocities)] != "crashed"
            starts = positions[: len(velocities)][shown]
            self._velocities.set_verts(arrows(starts, VELOCITY_SCALE * velocities[shown]))
            self._velocities.set_facecolor(self._colours[: len(velocities)][shown])
            if shown.any():
                legend.append((f"velocity (arrow: the way in {VELOCITY_SCALE:g} s)", ("velocity",)))

    def _draw_links(self, links: Any, positions: np.ndarray, legend: list[tuple[str, Any]]) -> np.ndarray:
        """The radio links between robots in the frame; their pairs ``(m, 2)``."""
        n = len(positions)
        pairs = np.empty((0, 2), dtype=np.intp)
        if links is not None and len(links) and n:
            pairs = np.asarray(links, dtype=np.intp).reshape(-1, 2)
            pairs = pairs[((pairs >= 0) & (pairs < n)).all(axis=1)]
        self._links.set_segments(positions[pairs])
        if len(pairs):
            legend.append(("radio link", ("link",)))
        return pairs

    def _draw_areas(
        self, obstacles: list[Any], moving: np.ndarray, cells: list[Any], n: int, legend: list[tuple[str, Any]]
    ) -> None:
        """Static and moving obstacles (``moving``: which), and the robots' cells."""
        static = finite_polygons([o for o, m in zip(obstacles, moving) if not m])
        moving_obstacles = finite_polygons([o for o, m in zip(obstacles, moving) if m])
        self._obstacles.set_verts(static)
        self._moving.set_verts(moving_obstacles)
        if static:
            legend.append(("static obstacle", ("obstacle",)))
        if moving_obstacles:
            legend.append(("moving obstacle", ("moving",)))
        shown = finite_polygons(cells)
        self._cells.set_verts(shown)
        self._cells.set_edgecolor(self._colours if len(shown) == n and n else "0.5")
        if shown:
            legend.append(("cell", ("cell",)))

    def _draw_focus(
        self, ranges: dict[str, float], positions: np.ndarray, pairs: np.ndarray | None, legend: list[tuple[str, Any]]
    ) -> None:
        """Around the focus robot: its ranges (name "": the default), a ring, and lines to the
        robots it hears (its links, or without links the robots within its largest range)."""
        if self.focus is None:
            return
        i, here = self.focus, positions[self.focus]
        self._ranges.set_offsets(np.tile(here, (len(ranges), 1)))
        self._ranges.set_widths([2 * r for r in ranges.values()])
        self._ranges.set_heights([2 * r for r in ranges.values()])
        self._ranges.set_edgecolor([RANGE_COLOURS[k % len(RANGE_COLOURS)] for k in range(len(ranges))])
        self._focus_ring.set_offsets(here[None])
        self._focus_ring.set_widths([1.5 * ROBOT_DIAMETER])
        self._focus_ring.set_heights([1.5 * ROBOT_DIAMETER])
        if pairs is not None:
            heard = np.unique(np.concatenate((pairs[pairs[:, 0] == i, 1], pairs[pairs[:, 1] == i, 0])))
            how = "links"
        else:
            distance = np.hypot(*(positions - here).T)
            heard = np.flatnonzero((distance <= max(ranges.values())) & (np.arange(len(positions)) != i))
            how = "in range"
        self._heard.set_segments([np.stack((here, positions[j])) for j in heard])
        legend.append((f"robot {i} (focus)", ("focus",)))
        for k, (name, r) in enumerate(ranges.items()):
            label = f"{name} {r:g} m" if name else f"range {r:g} m (default: none given)"
            legend.append((label, ("range", k)))
        legend.append((f"heard by robot {i} ({how})", ("heard",)))
