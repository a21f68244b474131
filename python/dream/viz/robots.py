"""The robots: bodies to scale in their colours, heading notches, fault marks and role marks."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from dream.viz.marks import CROSS, NOTCH, STUCK_SQUARE, ellipses, placed
from dream.viz.style import BYZANTINE_COLOUR, CRASHED_COLOUR, DPI, ROBOT_DIAMETER, ROLE_MARKERS, STUCK_COLOUR, rgba
from dream.viz.view import Framing


class Robots(Framing):
    """The robots' layers of a :class:`~dream.viz.Renderer`."""

    _dynamic: list[Any]  # the frame's artists, drawn over the cached rest
    _by_offsets: list[Any]  # those drawn as one path at each offset
    _role_zorder: int

    def _make_robots(self) -> None:
        from matplotlib.collections import LineCollection, PolyCollection

        self._robots = ellipses(self.axes, edgecolors="black", linewidths=0.7)
        self._notches = PolyCollection([], facecolors="0.1", edgecolors="none")
        self._crosses = LineCollection([], colors="black", linewidths=1.6)
        self._stuck = PolyCollection([], facecolors="none", edgecolors=STUCK_COLOUR, linewidths=2.0)
        self._byzantine = ellipses(self.axes, facecolors="none", edgecolors=BYZANTINE_COLOUR, linewidths=2.0)
        self._roles: dict[str, tuple[str, Any]] = {}  # role -> (marker, its scatter), made when first seen

    def _draw_robots(
        self, poses: np.ndarray, status: np.ndarray | None, roles: np.ndarray | None, legend: list[tuple[str, Any]]
    ) -> None:
        """Bodies (a crashed robot's grey), heading notches, then the fault and role marks."""
        positions = poses[:2].T
        faces = self._colours
        if status is not None:
            faces = self._colours.copy()
            faces[status == "crashed"] = rgba(CRASHED_COLOUR)
        self._robots.set_offsets(positions)
        self._robots.set_facecolor(faces)
        self._notches.set_verts(placed(NOTCH, positions, poses[2]))
        self._draw_status(status, positions, legend)
        self._draw_roles(roles, positions, legend)

    def _draw_status(self, status: np.ndarray | None, positions: np.ndarray, legend: list[tuple[str, Any]]) -> None:
        crashed = stuck = byzantine = np.zeros(len(positions), dtype=bool)
        if status is not None:
            crashed, stuck, byzantine = (status == "crashed"), (status == "stuck"), (status == "byzantine")
        self._crosses.set_segments(
            (positions[crashed][:, None, None, :] + CROSS[None]).reshape(-1, 2, 2) if crashed.any() else []
        )
        self._stuck.set_verts(placed(STUCK_SQUARE, positions[stuck], np.zeros(int(stuck.sum()))))
        self._byzantine.set_offsets(positions[byzantine])
        self._byzantine.set_widths(np.full(int(byzantine.sum()), 1.6 * ROBOT_DIAMETER))
        self._byzantine.set_heights(np.full(int(byzantine.sum()), 1.6 * ROBOT_DIAMETER))
        for mask, label, key in (
            (crashed, "crashed (grey, cross)", "crashed"),
            (stuck, "stuck (wheels stopped)", "stuck"),
            (byzantine, "Byzantine (lies)", "byzantine"),
        ):
            if mask.any():
                legend.append((label, (key,)))

    def _draw_roles(self, roles: np.ndarray | None, positions: np.ndarray, legend: list[tuple[str, Any]]) -> None:
        """The most common role plain; every other with a white mark at the robot's centre."""
        counts = Counter(roles.tolist()) if roles is not None else Counter()
        plain = counts.most_common(1)[0][0] if counts else None
        for role in sorted(counts):
            if role != plain and role not in self._roles:
                marker = ROLE_MARKERS[len(self._roles) % len(ROLE_MARKERS)]
                mark = self.axes.scatter([], [], marker=marker, facecolors="white", edgecolors="black", linewidths=0.6)
                mark.set_zorder(self._role_zorder)
                mark.set_animated(True)
                self._dynamic.append(mark)
                self._by_offsets.append(mark)
                self._roles[role] = (marker, mark)
        size = (0.4 * max(self.robot_pixels(), 4.0) * 72 / DPI) ** 2  # points^2: inside the notch
        for role, (_marker, mark) in self._roles.items():
            here = roles == role if roles is not None and role != plain else np.zeros(len(positions), dtype=bool)
            mark.set_offsets(positions[here])
            mark.set_sizes([size])
        if plain is not None and len(counts) > 1:
            legend.append((f"{plain} (plain)", ("role", "o")))
            legend += [(role, ("role", self._roles[role][0])) for role in sorted(counts) if role != plain]
