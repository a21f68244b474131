"""Drawing experiment frames: headless images, GIF/MP4 videos and a live window.

An experiment run with ``record=callback`` calls ``callback(frame)`` once per step with a
:class:`dream.frames.Frame`. A :class:`Recorder` is such a callback: it draws frames with a
:class:`Renderer` into a :class:`VideoWriter` and/or a live matplotlib window::

    >>> from dream.viz import Recorder
    >>> with Recorder(video="run.gif", every=2, focus=0) as recorder:      # doctest: +SKIP
    ...     hrvo_circle.run(n=10, record=recorder)

What a picture shows, to scale (metres on the axes): each robot as a disc of its real diameter
(0.11 m) with a dark notch at the front (its heading), its chosen velocity as an arrow (none for a
crashed robot), goals, radio links, Voronoi cells, static (grey) and moving (hatched brown)
obstacles, roles (the most common plain, the others marked), faults (crashed: grey with a cross;
stuck: orange square; Byzantine: red ring), optionally one robot's ranges and the robots it
hears, and a legend of what is on screen. The title gives the step, the simulated time and the
experiment's measures (:attr:`~dream.frames.Frame.title`). When the swarm occupies a small part
of a large arena, or robots would be only a few pixels wide, the view follows the swarm's
bounding box.

Everything is headless by default: a :class:`Renderer` draws on a ``matplotlib.figure.Figure``
with an Agg canvas, and :mod:`matplotlib.pyplot` is imported only when a live window is asked
for, so importing this module needs no display (it imports matplotlib only when drawing).
Each frame only the robots, overlays and title are redrawn, over a cached image of the rest
(blitting), in the video and in the window alike.

Units: metres in the world (the axes are in metres), pixels in images. Images are
``(H, W, 3)`` uint8 RGB arrays.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import math
import os
import signal
import threading
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from dream._files import check_writable
from dream.frames import STATUSES, Frame
from dream.specs import GRITSBOT, TIME_STEP, ArenaSpec

__all__ = ["Recorder", "Renderer", "VideoWriter", "parse_size", "robot_colours"]

ROBOT_DIAMETER = GRITSBOT.diameter  #: drawn size of a robot (m)
VELOCITY_SCALE = 1.0  #: metres of arrow per m/s of velocity: 0.2 m/s is drawn 0.2 m long
SIZE = (1280, 800)  #: default image size (pixels)
DPI = 100  #: text and line widths are given for this many pixels per inch at the default size
OBSTACLE_COLOUR = "0.25"
MOVING_OBSTACLE_COLOUR = "#a0522d"
LINK_COLOUR = "0.6"
CRASHED_COLOUR = "0.72"
STUCK_COLOUR = "#ff7f0e"
BYZANTINE_COLOUR = "#d62728"
RANGE_COLOURS = ("#1f77b4", "#9467bd", "#17becf", "#2ca02c")
ROLE_MARKERS = ("*", "D", "^", "P", "v", "s")
DEFAULT_RANGE = 1.0  #: range drawn around the focus robot when the frame gives none (m)
ARENA_MARGIN = 0.04  #: empty border around the arena, as a fraction of its larger side
#: Where the axes sit in the figure (left, bottom, width, height as fractions); the legend is
#: to their right, so that it never hides a robot.
AXES_RECT = (0.055, 0.07, 0.70, 0.86)
LEGEND_ANCHOR = (0.77, 0.93)
#: The view follows the swarm when its box (with margin) needs less than this fraction of the
#: whole arena's view, or when robots would be drawn smaller than MIN_ROBOT_PIXELS across.
FOLLOW_FRACTION = 0.5
MIN_ROBOT_PIXELS = 6.0
SWARM_MARGIN = 0.3  #: least margin around the swarm's box when following it (m) ...
SWARM_MARGIN_FRACTION = 0.1  #: ... or this fraction of the box's larger side, if more
#: A followed view is kept while the swarm stays inside it and it is at most this much larger
#: than needed: the picture does not jitter, and fewer frames need the axes redrawn.
FOLLOW_SLACK = 1.5

View = tuple[float, float, float, float]  # xmin, xmax, ymin, ymax (m)


def robot_colours(n: int) -> np.ndarray:
    """RGBA colours ``(n, 4)`` of robots ``0..n-1``.

    ``tab10`` for up to 10 robots, ``tab20`` beyond, cycling (robot ``i`` and ``i + 20``
    share a colour in swarms of more than 10).
    """
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return np.asarray(cmap(np.arange(n) % cmap.N), dtype=np.float64).reshape(n, 4)


def parse_size(text: str) -> tuple[int, int]:
    """An image size ``"WIDTHxHEIGHT"`` in pixels, e.g. ``"1280x800"``, as ``(width, height)``.

    >>> parse_size("640x400")
    (640, 400)

    Raises
    ------
    ValueError
        For anything else, or a side outside ``[64, 7680]``.
    """
    width, x, height = text.strip().lower().partition("x")
    try:
        if not x:
            raise ValueError
        size = (int(width), int(height))
    except ValueError:
        raise ValueError(f"size must be WIDTHxHEIGHT in pixels, e.g. 1280x800, got {text!r}") from None
    return _checked_size(size)


def _checked_size(size: Any) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in size)
        ok = all(float(v) == int(v) for v in size) and 64 <= width <= 7680 and 64 <= height <= 7680
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"size must be (width, height) in whole pixels, each in [64, 7680], got {size!r}")
    return width, height


def _polygons(polygons: list[np.ndarray]) -> list[np.ndarray]:
    out = []
    for polygon in polygons:
        points = np.asarray(polygon, dtype=np.float64).reshape(-1, 2)
        if len(points) >= 2 and np.isfinite(points).all():
            out.append(points)
    return out


def _shape(points: np.ndarray, positions: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """``points`` ``(k, 2)`` of a shape in the robot's frame (x forward, m) placed at every robot:
    ``(n, k, 2)``."""
    cos, sin = np.cos(headings)[:, None], np.sin(headings)[:, None]
    x, y = points[:, 0][None, :], points[:, 1][None, :]
    return np.stack((positions[:, :1] + cos * x - sin * y, positions[:, 1:] + sin * x + cos * y), axis=2)


_R = ROBOT_DIAMETER / 2
#: The heading notch: a dark triangle at the front of the body, clear of the centre (where the
#: role marks go).
NOTCH = np.array([[0.95 * _R, 0.0], [0.45 * _R, 0.4 * _R], [0.45 * _R, -0.4 * _R]])
#: A stuck robot's square and a crashed robot's cross, around and over the body.
STUCK_SQUARE = 0.7 * ROBOT_DIAMETER * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
CROSS = 0.85 * _R * np.array([[[-1.0, -1.0], [1.0, 1.0]], [[-1.0, 1.0], [1.0, -1.0]]])
#: Velocity arrows: shaft half-width, head length and head half-width (m), to the robots' scale.
ARROW_SHAFT, ARROW_HEAD, ARROW_HALF = 0.006, 0.035, 0.02


def _arrows(starts: np.ndarray, vectors: np.ndarray) -> np.ndarray:
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


def _fit(view: View, aspect: float) -> View:
    """``view`` grown about its centre along one axis so that width / height == ``aspect``."""
    xmin, xmax, ymin, ymax = view
    width, height = xmax - xmin, ymax - ymin
    if width < aspect * height:
        grow = (aspect * height - width) / 2
        return (xmin - grow, xmax + grow, ymin, ymax)
    grow = (width / aspect - height) / 2
    return (xmin, xmax, ymin - grow, ymax + grow)


def _labels(values: Any, n: int, name: str) -> np.ndarray | None:
    if values is None:
        return None
    labels = np.asarray(values).astype(str).reshape(-1)
    if len(labels) != n:
        raise ValueError(f"frame.{name} has {len(labels)} labels, expected {n} (one per robot)")
    return labels


class Renderer:
    """Draws :class:`~dream.frames.Frame` objects of one arena on one reused figure.

    The artists are created once and updated in place by :meth:`draw`. :meth:`render` draws only
    the frame's artists over a cached image of the axes, legend and arena (redrawn when anything
    else on the figure changed: the view, the legend, an artist you added), ~3 ms a frame for 10
    robots at 1280 x 800; ``figure.savefig`` draws everything.

    Parameters
    ----------
    arena : ArenaSpec
        The arena drawn as a rectangle; the axes show it with a small margin, or follow the swarm.
    size : (int, int)
        Image size (width, height) in pixels; text scales with it.
    focus : int, optional
        A robot whose ranges (:attr:`Frame.ranges`, else a 1 m circle) and the robots it hears
        (its links, else the robots within its largest range) are drawn.
    live : bool
        Create the figure with :mod:`matplotlib.pyplot` (for a window) instead of a headless
        Agg figure.

    Attributes
    ----------
    figure : matplotlib.figure.Figure
    axes : matplotlib.axes.Axes
        Add your own artists here; :meth:`draw` only updates its own.
    view : (xmin, xmax, ymin, ymax)
        The part of the world shown (m).
    following : {"arena", "swarm", "focus"}
        What the view shows: the whole arena, the swarm's box, or the focus robot's surroundings.
    legend_labels : list of str
        The legend's entries for the last frame drawn.

    Raises
    ------
    ValueError
        For a bad ``size`` or a negative ``focus``.
    """

    def __init__(
        self, arena: ArenaSpec, *, size: tuple[int, int] = SIZE, focus: int | None = None, live: bool = False
    ) -> None:
        # matplotlib is imported here, not with the module: `import dream.viz` stays cheap.
        from matplotlib.collections import EllipseCollection, LineCollection, PolyCollection
        from matplotlib.patches import Rectangle

        width, height = _checked_size(size)
        if focus is not None and (isinstance(focus, bool) or not isinstance(focus, (int, np.integer)) or focus < 0):
            raise ValueError(f"focus must be a robot id (an integer >= 0), got {focus!r}")
        self.arena = arena
        self.focus = None if focus is None else int(focus)
        # A quarter pixel more, so that matplotlib's int() of inches * dpi never truncates to one less.
        figsize = ((width + 0.25) / DPI, (height + 0.25) / DPI)
        if live:
            import matplotlib.pyplot as plt

            self.figure = plt.figure(figsize=figsize, dpi=DPI)
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            self.figure = Figure(figsize=figsize, dpi=DPI)
            FigureCanvasAgg(self.figure)
        self._text = max(0.6, min(width / SIZE[0], height / SIZE[1]))  # text scale
        self.axes = self.figure.add_axes(AXES_RECT)
        ax = self.axes
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x (m)", fontsize=10 * self._text)
        ax.set_ylabel("y (m)", fontsize=10 * self._text)
        ax.tick_params(labelsize=9 * self._text)
        self._arena_patch = Rectangle(
            (arena.xmin, arena.ymin),
            arena.width,
            arena.height,
            fill=False,
            edgecolor="black",
            linewidth=1.0,
            zorder=0.5,
        )
        ax.add_patch(self._arena_patch)
        self.view: View = (0.0, 1.0, 0.0, 1.0)
        self.following = "arena"  # what the view shows: "arena", "swarm" or "focus"

        def ellipses(**style: Any) -> EllipseCollection:
            return EllipseCollection(
                ROBOT_DIAMETER,
                ROBOT_DIAMETER,
                0.0,
                units="xy",
                offsets=np.empty((0, 2)),
                offset_transform=ax.transData,
                **style,
            )

        # Listed bottom to top: arrows under the bodies show only outside them.
        self._cells = PolyCollection([], facecolors="none", edgecolors="0.5", linewidths=0.8)
        self._obstacles = PolyCollection([], facecolors=OBSTACLE_COLOUR, edgecolors=OBSTACLE_COLOUR, linewidths=0.5)
        self._moving = PolyCollection(
            [], facecolors=MOVING_OBSTACLE_COLOUR, edgecolors="0.15", linewidths=0.8, hatch="//"
        )
        self._links = LineCollection([], colors=LINK_COLOUR, linewidths=0.7)
        self._ranges = ellipses(facecolors="none", linewidths=1.4, linestyles="--")
        self._heard = LineCollection([], colors=RANGE_COLOURS[0], linewidths=1.2, alpha=0.8)
        self._goals = ax.scatter([], [], marker="x", s=40 * self._text**2, linewidths=1.5)
        self._velocities = PolyCollection([], linewidths=0.4, edgecolors="black")
        self._robots = ellipses(edgecolors="black", linewidths=0.7)
        self._notches = PolyCollection([], facecolors="0.1", edgecolors="none")
        self._crosses = LineCollection([], colors="black", linewidths=1.6)
        self._stuck = PolyCollection([], facecolors="none", edgecolors=STUCK_COLOUR, linewidths=2.0)
        self._byzantine = ellipses(facecolors="none", edgecolors=BYZANTINE_COLOUR, linewidths=2.0)
        self._focus_ring = ellipses(facecolors="none", edgecolors="black", linewidths=2.2)
        self._roles: dict[str, tuple[str, Any]] = {}  # role -> (marker, its scatter), made when first seen
        layers = [
            self._cells, self._obstacles, self._moving, self._links, self._ranges, self._heard, self._goals,
            self._velocities, self._robots, self._notches, self._crosses, self._stuck, self._byzantine,
            self._focus_ring,
        ]  # fmt: skip
        for z, artist in enumerate(layers, start=1):
            artist.set_zorder(z)
            if artist is not self._goals:  # scatter added itself
                ax.add_collection(artist, autolim=False)
        self._role_zorder = len(layers) + 1
        self._marks_for = 0.0  # the robot size (pixels) the marks were last scaled for
        self._by_offsets = [self._ranges, self._goals, self._robots, self._byzantine, self._focus_ring]
        ax.set_title("step 0", fontsize=12 * self._text)  # text while laying out, so that the title has room
        self._colours = robot_colours(0)
        self._legend: Any = None
        self._legend_key: tuple[Any, ...] = ()
        self.legend_labels: list[str] = []
        # The frame's artists are "animated": drawn over a cached image of the rest (axes,
        # ticks, arena, legend), which is redrawn only when something else changed.
        self._dynamic = list(layers)
        for layer in self._dynamic:
            layer.set_animated(True)
        ax.title.set_animated(True)
        self._title_text: str | None = None
        self._title_pixels = np.empty((0, 0, 4), dtype=np.uint8)
        self._background: Any = None
        self._background_size: tuple[int, int] | None = None
        self._set_view(self._whole_view())

    # -- the view -----------------------------------------------------------------------------

    def _axes_pixels(self) -> tuple[float, float]:
        box = self.figure.bbox
        return box.width * AXES_RECT[2], box.height * AXES_RECT[3]

    def _whole_view(self) -> View:
        arena, (width, height) = self.arena, self._axes_pixels()
        margin = ARENA_MARGIN * max(arena.width, arena.height)
        return _fit(
            (arena.xmin - margin, arena.xmax + margin, arena.ymin - margin, arena.ymax + margin), width / height
        )

    def _view_for(self, positions: np.ndarray, reach: float) -> View:
        """The whole arena; or the swarm's box with a margin, when it needs less than
        FOLLOW_FRACTION of the arena's view or robots would be specks (narrower than
        MIN_ROBOT_PIXELS); or, when robots would be specks even so and a robot is in focus, the
        disc of radius ``reach`` (m) around it. A followed view is kept while what it follows
        stays inside it and it is at most FOLLOW_SLACK times larger than needed."""
        whole = self._whole_view()
        shown = positions[np.isfinite(positions).all(axis=1)]
        self.following = "arena"
        if not len(shown):
            return whole
        width, height = self._axes_pixels()

        def box_around(low: np.ndarray, high: np.ndarray) -> tuple[View, float]:
            pad = max(SWARM_MARGIN, SWARM_MARGIN_FRACTION * float(np.max(high - low))) + _R
            return _fit((low[0] - pad, high[0] + pad, low[1] - pad, high[1] + pad), width / height), pad

        def specks(view: View) -> bool:
            return ROBOT_DIAMETER / (view[1] - view[0]) * width < MIN_ROBOT_PIXELS

        low, high = shown.min(axis=0), shown.max(axis=0)
        box, pad = box_around(low, high)
        whole_width, box_width = whole[1] - whole[0], box[1] - box[0]
        self.following = "swarm"
        if specks(box) and self.focus is not None:
            self.following = "focus"
            low, high = positions[self.focus] - reach, positions[self.focus] + reach
            box, pad = box_around(low, high)
            box_width = box[1] - box[0]
        elif box_width >= whole_width or (box_width > FOLLOW_FRACTION * whole_width and not specks(whole)):
            self.following = "arena"
            return whole
        xmin, xmax, ymin, ymax = now = self.view
        inside = xmin <= low[0] - pad / 2 and high[0] + pad / 2 <= xmax
        inside &= ymin <= low[1] - pad / 2 and high[1] + pad / 2 <= ymax
        same_shape = math.isclose((xmax - xmin) / (ymax - ymin), width / height, rel_tol=1e-3)
        if inside and same_shape and box_width <= xmax - xmin <= FOLLOW_SLACK * box_width:
            return now
        return box

    def _set_view(self, view: View) -> None:
        if view != self.view:
            self.view = view
            self.axes.set_xlim(view[0], view[1])
            self.axes.set_ylim(view[2], view[3])

    def _scale_marks(self) -> None:
        """Marks in points (goals, outlines) shrink with robots drawn small, so as not to hide them."""
        pixels = self.robot_pixels()
        if pixels == self._marks_for:
            return
        self._marks_for = pixels
        small = min(1.0, pixels / 20)  # 1 from 20 pixels a robot up
        self._goals.set_sizes([(12 * small * self._text) ** 2])
        self._goals.set_linewidth(0.5 + small)
        self._robots.set_linewidth(0.2 + 0.5 * small)
        self._velocities.set_linewidth(0.4 * small)
        self._notches.set_visible(pixels >= 8)  # smaller, a notch is a smudge

    def robot_pixels(self) -> float:
        """How many pixels across a robot is drawn in the current view."""
        return ROBOT_DIAMETER / (self.view[1] - self.view[0]) * self._axes_pixels()[0]

    # -- drawing ------------------------------------------------------------------------------

    def draw(self, frame: Frame) -> None:
        """Update the figure to show ``frame`` (the canvas is redrawn by :meth:`render`).

        Raises
        ------
        ValueError
            When ``roles``, ``status`` or ``obstacle_moving`` do not have one entry per robot
            (obstacle), a status is unknown, or the focus robot is not in the frame.
        """
        poses = np.asarray(frame.poses, dtype=np.float64).reshape(3, -1)
        n = poses.shape[1]
        roles = _labels(frame.roles, n, "roles")
        status = _labels(frame.status, n, "status")
        if status is not None and not np.isin(status, STATUSES).all():
            unknown = sorted(set(status.tolist()) - set(STATUSES))
            raise ValueError(f"frame.status has {unknown}; expected {', '.join(STATUSES)}")
        moving = np.zeros(len(frame.obstacles), dtype=bool)
        if frame.obstacle_moving is not None:
            moving = np.asarray(frame.obstacle_moving, dtype=bool).reshape(-1)
            if len(moving) != len(frame.obstacles):
                raise ValueError(
                    f"frame.obstacle_moving has {len(moving)} entries, expected {len(frame.obstacles)} "
                    "(one per obstacle)"
                )
        if self.focus is not None and self.focus >= n:
            raise ValueError(f"focus={self.focus}: the frame has {n} robots (ids 0..{n - 1})")
        for name, value in frame.ranges.items():
            if not (isinstance(value, (int, float, np.number)) and math.isfinite(value) and value > 0):
                raise ValueError(f"frame.ranges[{name!r}] must be a distance > 0 (m), got {value!r}")
        ranges = {name: float(r) for name, r in frame.ranges.items()} or {"": DEFAULT_RANGE}

        if frame.arena != self.arena:
            self.arena = frame.arena
            self._arena_patch.set_bounds(frame.arena.xmin, frame.arena.ymin, frame.arena.width, frame.arena.height)
        positions = poses[:2].T
        self._set_view(self._view_for(positions, 1.2 * max(ranges.values())))
        self._scale_marks()
        if len(self._colours) != n:
            self._colours = robot_colours(n)
        colours = self._colours
        legend: list[tuple[str, Any]] = [("robot (to scale; notch: heading)", ("robot",))]
        if self.following != "arena":
            around = "the swarm" if self.following == "swarm" else f"robot {self.focus} (too many to show all)"
            legend.append((f"view: follows {around}", ("view",)))

        faces = colours
        if status is not None:
            faces = colours.copy()
            faces[status == "crashed"] = _rgba(CRASHED_COLOUR)
        self._robots.set_offsets(positions)
        self._robots.set_facecolor(faces)
        self._notches.set_verts(_shape(NOTCH, positions, poses[2]))
        self._draw_status(status, positions, legend)
        self._draw_roles(roles, positions, legend)

        if frame.goals is not None and n:
            goals = np.asarray(frame.goals, dtype=np.float64).reshape(-1, 2)[:n]
            shown = np.isfinite(goals).all(axis=1)
            self._goals.set_offsets(goals[shown])
            self._goals.set_color(colours[: len(goals)][shown])
            if shown.any():
                legend.append(("goal", ("goal",)))
        else:
            self._goals.set_offsets(np.empty((0, 2)))

        self._velocities.set_verts([])
        if frame.velocities is not None and n:
            velocities = np.asarray(frame.velocities, dtype=np.float64).reshape(-1, 2)[:n]
            shown = np.isfinite(velocities).all(axis=1)
            if status is not None:  # a crashed robot goes nowhere, whatever it last chose
                shown &= status[: len(velocities)] != "crashed"
            starts = positions[: len(velocities)][shown]
            self._velocities.set_verts(_arrows(starts, VELOCITY_SCALE * velocities[shown]))
            self._velocities.set_facecolor(colours[: len(velocities)][shown])
            if shown.any():
                legend.append((f"velocity (arrow: the way in {VELOCITY_SCALE:g} s)", ("velocity",)))

        pairs = np.empty((0, 2), dtype=np.intp)
        if frame.links is not None and len(frame.links) and n:
            pairs = np.asarray(frame.links, dtype=np.intp).reshape(-1, 2)
            pairs = pairs[((pairs >= 0) & (pairs < n)).all(axis=1)]
        self._links.set_segments(positions[pairs])
        if len(pairs):
            legend.append(("radio link", ("link",)))
        self._draw_focus(ranges, positions, pairs if frame.links is not None else None, legend)

        obstacles = _polygons([o for o, m in zip(frame.obstacles, moving) if not m])
        moving_obstacles = _polygons([o for o, m in zip(frame.obstacles, moving) if m])
        self._obstacles.set_verts(obstacles)
        self._moving.set_verts(moving_obstacles)
        if obstacles:
            legend.append(("static obstacle", ("obstacle",)))
        if moving_obstacles:
            legend.append(("moving obstacle", ("moving",)))
        cells = _polygons(frame.cells)
        self._cells.set_verts(cells)
        self._cells.set_edgecolor(colours if len(cells) == n and n else "0.5")
        if cells:
            legend.append(("cell", ("cell",)))

        heading = f"step {frame.step}"
        if frame.time is not None:
            heading += f", t = {frame.time:.2f} s"
        self.axes.title.set_text(f"{heading}  |  {frame.title}" if frame.title else heading)
        self._set_legend(legend)

    def _draw_status(self, status: np.ndarray | None, positions: np.ndarray, legend: list[tuple[str, Any]]) -> None:
        crashed = stuck = byzantine = np.zeros(len(positions), dtype=bool)
        if status is not None:
            crashed, stuck, byzantine = (status == "crashed"), (status == "stuck"), (status == "byzantine")
        self._crosses.set_segments(
            (positions[crashed][:, None, None, :] + CROSS[None]).reshape(-1, 2, 2) if crashed.any() else []
        )
        self._stuck.set_verts(_shape(STUCK_SQUARE, positions[stuck], np.zeros(int(stuck.sum()))))
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

    def _set_legend(self, entries: list[tuple[str, Any]]) -> None:
        key = tuple(entries)
        if key == self._legend_key:
            return
        self._legend_key = key
        if self._legend is not None:
            self._legend.remove()
        handles = [self._proxy(style) for _, style in entries]
        self.legend_labels = [label for label, _ in entries]
        self._legend = self.figure.legend(
            handles,
            self.legend_labels,
            loc="upper left",
            bbox_to_anchor=LEGEND_ANCHOR,
            fontsize=9.5 * self._text,
            frameon=False,
            handlelength=2.2,
            borderaxespad=0.0,
        )

    def _proxy(self, style: tuple[Any, ...]) -> Any:
        """A legend handle that looks like what ``style`` (a legend key) draws."""
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch

        first = tuple(self._colours[0]) if len(self._colours) else "C0"
        kind = style[0]

        def marker(symbol: str, **kw: Any) -> Line2D:
            return Line2D([], [], linestyle="none", marker=symbol, **{"markersize": 11 * self._text, **kw})

        if kind == "robot":
            return marker("o", markerfacecolor=first, markeredgecolor="black")
        if kind == "goal":
            return marker("x", color=first, markeredgewidth=1.5)
        if kind == "velocity":
            return marker(r"$\rightarrow$", color=first, markersize=16 * self._text)
        if kind == "link":
            return Line2D([], [], color=LINK_COLOUR, linewidth=1.0)
        if kind == "obstacle":
            return Patch(facecolor=OBSTACLE_COLOUR, edgecolor=OBSTACLE_COLOUR)
        if kind == "moving":
            return Patch(facecolor=MOVING_OBSTACLE_COLOUR, edgecolor="0.15", hatch="//")
        if kind == "cell":
            return Patch(facecolor="none", edgecolor="0.5")
        if kind == "crashed":
            return marker("X", markerfacecolor=CRASHED_COLOUR, markeredgecolor="black")
        if kind == "stuck":
            return marker("s", markerfacecolor="none", markeredgecolor=STUCK_COLOUR, markeredgewidth=2.0)
        if kind == "byzantine":
            return marker("o", markerfacecolor="none", markeredgecolor=BYZANTINE_COLOUR, markeredgewidth=2.0)
        if kind == "role":
            return marker(style[1], markerfacecolor="white", markeredgecolor="black")
        if kind == "view":
            return Line2D([], [], linestyle="none")
        if kind == "focus":
            return marker("o", markerfacecolor="none", markeredgecolor="black", markeredgewidth=2.2)
        if kind == "range":
            return Line2D([], [], color=RANGE_COLOURS[style[1] % len(RANGE_COLOURS)], linestyle="--", linewidth=1.4)
        return Line2D([], [], color=RANGE_COLOURS[0], linewidth=1.2)  # "heard"

    def render(self) -> None:
        """Draw the current frame into the canvas: the frame's artists over the cached rest."""
        canvas: Any = self.figure.canvas  # an Agg canvas (headless or under a window): it blits
        if not hasattr(canvas, "copy_from_bbox"):  # a closed window leaves a bare canvas: draw headless
            from matplotlib.backends.backend_agg import FigureCanvasAgg

            canvas = FigureCanvasAgg(self.figure)
        # Axes, ticks, legend and labels are most of a redraw: redraw them only when stale (an
        # animated artist's change does not make the figure stale, anything else does).
        size = canvas.get_width_height(physical=True)
        if self._background is None or self.figure.stale or self._background_size != size:
            canvas.draw()
            self._background = canvas.copy_from_bbox(self.figure.bbox)
            self._background_size = size
        else:
            canvas.restore_region(self._background)
        for artist in self._dynamic:
            if self._drawn(artist):
                self.figure.draw_artist(artist)
        self._paint_title()

    def _paint_title(self) -> None:
        """Paint the title into the strip above the axes with Pillow: matplotlib's text drawing
        would be most of a frame's cost (~5 ms), and the title changes every frame."""
        text = self.axes.title.get_text()
        buffer = np.asarray(self.figure.canvas.buffer_rgba())  # type: ignore[attr-defined]  # Agg's
        height, width = buffer.shape[:2]
        strip = int(height * (1 - AXES_RECT[1] - AXES_RECT[3])) - 2  # rows above the axes
        if text != self._title_text or self._title_pixels.shape[:2] != (strip, width):
            from PIL import Image, ImageDraw

            points = float(self.axes.title.get_fontsize()) * self.figure.dpi / 72  # the pixels matplotlib would use
            font = _font(round(points))
            image = Image.new("RGBA", (width, strip), (255, 255, 255, 255))
            centre = width * (AXES_RECT[0] + AXES_RECT[2] / 2)
            ImageDraw.Draw(image).text(
                (centre, strip - 0.45 * points), text, font=font, fill=(0, 0, 0, 255), anchor="ms"
            )
            self._title_text, self._title_pixels = text, np.asarray(image)
        buffer[:strip] = self._title_pixels

    def changing(self) -> list[Any]:
        """The regions (display-space ``Bbox``) a new frame changes without a full redraw: the
        axes and the title's strip. The legend and tick labels change only with a full redraw."""
        from matplotlib.transforms import Bbox

        figure = self.figure.bbox
        strip = Bbox.from_extents(0, figure.y1 * (AXES_RECT[1] + AXES_RECT[3]), figure.x1, figure.y1)
        return [self.axes.bbox, strip]

    def _drawn(self, artist: Any) -> bool:
        """Whether ``artist`` has anything to draw (an empty collection still costs a draw)."""
        if not artist.get_visible():
            return False
        if artist in self._by_offsets:  # one path, drawn at each offset
            return len(artist.get_offsets()) > 0
        return len(artist.get_paths()) > 0

    def to_rgb(self) -> np.ndarray:
        """Redraw and return the current image, ``(H, W, 3)`` uint8."""
        return self.to_rgba()[..., :3].copy()

    def to_rgba(self) -> np.ndarray:
        """Redraw and return the canvas' own buffer, ``(H, W, 4)`` uint8: no copy, so valid only
        until the next redraw."""
        self.render()
        return np.asarray(self.figure.canvas.buffer_rgba())  # type: ignore[attr-defined]  # Agg's

    def show_all(self) -> None:
        """Make the frame's artists ordinary ones, so that a full redraw (a resized window, a
        saved figure) shows them too; :meth:`render` is then no faster than a full redraw."""
        for artist in (*self._dynamic, self.axes.title):
            artist.set_animated(False)
        self._background = None


@functools.cache
def _font(pixels: int) -> Any:
    """matplotlib's default font (DejaVu Sans) for Pillow, ``pixels`` high."""
    from matplotlib import font_manager, rcParams
    from PIL import ImageFont

    return ImageFont.truetype(
        font_manager.findfont(font_manager.FontProperties(family=rcParams["font.family"])), pixels
    )


def _rgba(colour: str) -> np.ndarray:
    from matplotlib.colors import to_rgba

    return np.asarray(to_rgba(colour))


class VideoWriter:
    """Writes ``(H, W, 3)`` uint8 images to an animated GIF or an MP4 video, frame by frame.

    ``.gif`` is written with Pillow, one frame at a time (only the pixels that changed since
    the previous frame, each frame with its own 256-colour palette; loops forever). ``.mp4``
    is H.264 through the ffmpeg binary bundled with ``imageio-ffmpeg``; images with an odd
    width or height are padded with white by one pixel (H.264 needs even sizes). All images
    of a video must have the size of the first. Nothing is written until the first image.

    Parameters
    ----------
    path : str or PathLike
        Output file; its suffix chooses the format.
    fps : float
        Frames per second of playback (a GIF stores delays in 1/100 s, so 30 fps plays at
        ~33 fps).

    Attributes
    ----------
    frames_written : int
        Images added so far.

    Raises
    ------
    ValueError
        For a suffix other than ``.gif`` or ``.mp4``, or a non-positive ``fps``.
    FileNotFoundError
        When the directory of ``path`` does not exist.
    """

    SUPPORTED = (".gif", ".mp4")

    def __init__(self, path: str | os.PathLike[str], fps: float = 30) -> None:
        self.path = Path(path)
        self.format = check_video_path(self.path)
        if not (math.isfinite(fps) and fps > 0):
            raise ValueError(f"fps must be finite and > 0, got {fps}")
        self.fps = fps
        self.frames_written = 0
        self._size: tuple[int, int] | None = None  # (width, height) of the images
        self._channels = 3
        self._previous: np.ndarray | None = None
        self._file: Any = None
        self._ffmpeg: Any = None
        self._closed = False

    @property
    def size(self) -> tuple[int, int] | None:
        """``(width, height)`` of the frames, once the first is added."""
        return self._size

    def add(self, image: np.ndarray) -> None:
        """Append one image ``(H, W, 3)`` uint8 (RGB), or ``(H, W, 4)`` (RGBA, alpha ignored: a
        canvas buffer goes in without a copy), as the next frame."""
        if self._closed:
            raise ValueError(f"VideoWriter for {self.path} is closed")
        image = np.asarray(image)
        if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
            raise ValueError(f"image must be (H, W, 3) or (H, W, 4) uint8, got shape {image.shape} dtype {image.dtype}")
        height, width, channels = image.shape
        if self._size is None:
            self._size, self._channels = (width, height), channels
        elif self._size != (width, height):
            raise ValueError(
                f"image is {width}x{height} pixels, but this video's frames are {self._size[0]}x{self._size[1]}"
            )
        elif channels != self._channels:
            raise ValueError(f"image has {channels} channels, but this video's frames have {self._channels}")
        with _signals_deferred():  # Ctrl-C in the middle of a frame's bytes would break the file
            if self.format == ".gif":
                self._add_gif(image)
            else:
                self._add_mp4(image)
        self.frames_written += 1

    def _add_gif(self, image: np.ndarray) -> None:
        from PIL import GifImagePlugin, Image

        delay = max(1, round(1000 / self.fps / 10)) * 10  # ms, whole centiseconds as GIF stores them
        if self._previous is None:
            frame = Image.fromarray(np.ascontiguousarray(image[..., :3])).quantize(256, method=_FAST_OCTREE)
            header, _ = GifImagePlugin.getheader(frame, info={"loop": 0, "duration": delay})
            self._file = open(self.path, "wb")  # noqa: SIM115 - closed by close()
            self._file.writelines(header)
            offset = (0, 0)
        else:
            # Only the rectangle that changed: smaller files, and less to quantise.
            height, width, channels = image.shape
            changed = (image != self._previous).reshape(height, width * channels)
            rows = np.flatnonzero(changed.any(axis=1))
            if rows.size:
                columns = np.flatnonzero(changed[rows[0] : rows[-1] + 1].any(axis=0)) // channels  # byte -> pixel
                top, bottom, left, right = rows[0], rows[-1] + 1, columns[0], columns[-1] + 1
            else:  # identical: one unchanged pixel keeps the frame (and its delay) in the file
                top, bottom, left, right = 0, 1, 0, 1
            frame = Image.fromarray(np.ascontiguousarray(image[top:bottom, left:right, :3])).quantize(
                256, method=_FAST_OCTREE
            )
            offset = (int(left), int(top))
        # disposal 1: leave the frame in place, the next one draws over it
        self._file.writelines(
            GifImagePlugin.getdata(frame, offset, duration=delay, disposal=1, include_color_table=True)
        )
        self._previous = image.copy()

    def _add_mp4(self, image: np.ndarray) -> None:
        height, width = image.shape[:2]
        if height % 2 or width % 2:
            image = np.pad(image, ((0, height % 2), (0, width % 2), (0, 0)), constant_values=255)
        if self._ffmpeg is None:
            import imageio_ffmpeg

            self._ffmpeg = imageio_ffmpeg.write_frames(
                str(self.path),
                (image.shape[1], image.shape[0]),
                fps=self.fps,
                pix_fmt_in="rgba" if image.shape[2] == 4 else "rgb24",
                codec="libx264",
                # One encoder thread at the veryfast preset keeps up with drawing and leaves the
                # other cores to the simulation: on 2 cores, x264's default threads and preset
                # slowed the drawing process itself by half (benches/bench_viz.py).
                output_params=["-preset", "veryfast", "-threads", "1"],
                macro_block_size=2,
                ffmpeg_log_level="error",
            )
            self._ffmpeg.send(None)  # start ffmpeg
        self._ffmpeg.send(np.ascontiguousarray(image))  # the pipe takes the array's buffer: no copy

    def close(self) -> None:
        """Finish the file (idempotent). With no frames added, no file is written."""
        if self._closed:
            return
        self._closed = True
        if self._file is not None:
            self._file.write(b";")  # GIF trailer
            self._file.close()
            self._file = None
        if self._ffmpeg is not None:
            self._ffmpeg.close()  # waits for ffmpeg to finish the file
            self._ffmpeg = None
        self._previous = None

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """SIGINT and SIGTERM caught in the block are acted on when it ends: a frame is written whole.

    Blocking the signals is not enough: one that arrived just before is raised by the first check
    for signals, which may be inside the pipe's write. So the block records them instead.
    """
    if threading.current_thread() is not threading.main_thread():  # only it can set handlers
        yield
        return
    received: list[signal.Signals] = []
    previous = {
        signum: signal.signal(signum, lambda number, _frame: received.append(signal.Signals(number)))
        for signum in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for signum in received[:1]:  # e.g. KeyboardInterrupt from Python's SIGINT handler
            handler = previous[signum]
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(signum)


_FAST_OCTREE = 2  #: ``PIL.Image.Quantize.FASTOCTREE``: 4x faster than median cut, as good on plots


def check_video_path(path: str | os.PathLike[str]) -> str:
    """The format (``".gif"`` or ``".mp4"``) of a video path, checked before anything runs.

    Raises
    ------
    ValueError
        For any other suffix, or a path that :func:`dream._files.check_writable` refuses (not a
        regular file or a new path, a name too long, a folder where no file can be made).
    FileNotFoundError
        When the directory of ``path`` does not exist.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VideoWriter.SUPPORTED:
        shown = f"suffix {path.suffix!r}" if path.suffix else "no suffix"
        raise ValueError(f"cannot write video {str(path)!r}: {shown}; supported: {', '.join(VideoWriter.SUPPORTED)}")
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise FileNotFoundError(f"cannot write video {str(path)!r}: directory {str(directory)!r} does not exist")
    check_writable(path, "video")
    return suffix


class Recorder:
    """The ``record=`` callback of an experiment: draws frames into a video and/or a window.

    The :class:`Renderer` is created on the first frame, from ``frame.arena``. Of the frames
    received, the 1st, the ``(every + 1)``-th, the ``(2 * every + 1)``-th, ... are rendered:
    call ``i`` (counting from 0) is rendered when ``i % every == 0``, so ``every=3`` over 10
    frames renders calls 0, 3, 6 and 9. Use as a context manager, or call :meth:`close`.

    Parameters
    ----------
    video : str or PathLike, optional
        A ``.gif`` or ``.mp4`` path (see :class:`VideoWriter`); checked here, before any run.
    show : bool
        Also show the frames in a live matplotlib window, updated by blitting (only the frame's
        artists are redrawn and copied to the screen). Without an interactive backend (no
        display) a warning says so and nothing is shown.
    every : int
        Render one frame in ``every``.
    fps : float
        Playback speed of the video.
    size : (int, int)
        Image size in pixels (see :class:`Renderer`).
    focus : int, optional
        The robot whose ranges and links are drawn (see :class:`Renderer`).
    realtime : bool
        Pace the run to wall time: a rendered frame is not shown before its simulated time
        (``frame.time``, else ``step * 0.033`` s) has passed since the first; the window stays
        responsive while waiting.
    hold : bool
        At :meth:`close`, keep the live window open (then :meth:`hold` blocks until the user
        closes it); by default the window closes with the recorder.

    Attributes
    ----------
    frames_rendered : int
        Frames drawn so far.
    frames_seen : int
        Frames received so far.
    renderer : Renderer or None
        ``None`` until the first frame.
    writer : VideoWriter or None
    waited : float
        Seconds spent waiting for wall time (``realtime``).
    """

    def __init__(
        self,
        *,
        video: str | os.PathLike[str] | None = None,
        show: bool = False,
        every: int = 1,
        fps: float = 30,
        size: tuple[int, int] = SIZE,
        focus: int | None = None,
        realtime: bool = False,
        hold: bool = False,
    ) -> None:
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
            raise ValueError(f"every must be an integer >= 1, got {every!r}")
        if focus is not None and (isinstance(focus, bool) or not isinstance(focus, (int, np.integer)) or focus < 0):
            raise ValueError(f"focus must be a robot id (an integer >= 0), got {focus!r}")
        self.every = int(every)
        self.show = show
        self.size = _checked_size(size)
        self.focus = focus
        self.realtime = realtime
        self.keep_open = hold
        self.writer = VideoWriter(video, fps=fps) if video is not None else None
        self.renderer: Renderer | None = None
        self.frames_seen = 0
        self.frames_rendered = 0
        self.waited = 0.0
        self._interactive = False
        self._origin: tuple[float, float] | None = None  # (wall clock, simulated time) of the first frame
        # The clock and the wait, replaceable so that tests can pace without waiting.
        self._clock: Callable[[], float] = time.perf_counter
        self._sleep: Callable[[float], None] = time.sleep

    def __call__(self, frame: Frame) -> None:
        index = self.frames_seen
        self.frames_seen += 1
        if index % self.every:
            return
        if self.renderer is None:
            self._start(frame.arena)
        assert self.renderer is not None
        self.renderer.draw(frame)
        if self.writer is not None:
            image = self.renderer.to_rgba()
            if self.writer.size is not None and (image.shape[1], image.shape[0]) != self.writer.size:
                image = _resized(image, self.writer.size)  # the live window was resized
            self.writer.add(image)
        if self.realtime:
            self._pace(frame)
        if self.live:
            if self.writer is None:  # else to_rgb has rendered already
                self.renderer.render()
            canvas = self.renderer.figure.canvas
            for region in self.renderer.changing():  # copy what changes to the window
                canvas.blit(region)
            canvas.flush_events()  # let the window repaint and handle input
        self.frames_rendered += 1

    def _pace(self, frame: Frame) -> None:
        simulated = frame.time if frame.time is not None else frame.step * TIME_STEP
        now = self._clock()
        if self._origin is None:
            self._origin = (now, simulated)
        wait = self._origin[0] + (simulated - self._origin[1]) - now
        if wait <= 0:
            return
        self.waited += wait
        if self.live:
            self.renderer.figure.canvas.start_event_loop(wait)  # type: ignore[union-attr]  # responsive while waiting
        else:
            self._sleep(wait)

    def _start(self, arena: ArenaSpec) -> None:
        if self.show:
            import matplotlib.pyplot as plt

            self.renderer = Renderer(arena, size=self.size, focus=self.focus, live=True)
            canvas = self.renderer.figure.canvas
            self._interactive = _interactive(canvas)
            if self._interactive:
                plt.show(block=False)
                canvas.flush_events()  # the window appears before the first frame is drawn
            else:
                import matplotlib

                warnings.warn(
                    f"no live window: matplotlib backend {matplotlib.get_backend()!r} is not interactive (no display?)",
                    RuntimeWarning,
                    stacklevel=3,
                )
        else:
            self.renderer = Renderer(arena, size=self.size, focus=self.focus)

    @staticmethod
    def add_arguments(parser: argparse.ArgumentParser) -> None:
        """Add a script's drawing options to ``parser``: ``--video PATH`` (a ``.gif`` or ``.mp4``),
        ``--show`` (a live window) and ``--every K`` (draw one step in K); :meth:`from_args` reads
        them back."""
        parser.add_argument("--video", metavar="PATH", help="record the run to a video: .gif (Pillow) or .mp4 (H.264)")
        parser.add_argument("--show", action="store_true", help="show the run in a live window")
        parser.add_argument("--every", metavar="K", type=int, default=1, help="draw one step in K (default: 1)")

    @classmethod
    def from_args(cls, args: argparse.Namespace, parser: argparse.ArgumentParser | None = None) -> Recorder | None:
        """The recorder that a script's options (:meth:`add_arguments`) ask for, or ``None`` when
        they ask for neither a video nor a window.

        With ``--show`` the window outlives :meth:`close`: call :meth:`hold` after it to keep the
        last frame on screen until the user closes the window.

        Parameters
        ----------
        args : argparse.Namespace
            Parsed options with ``video``, ``show`` and, optionally, ``every``.
        parser : argparse.ArgumentParser, optional
            If given, a bad ``--video`` path or ``--every`` ends the script through
            ``parser.error`` (one line, exit code 2) instead of raising.

        Raises
        ------
        ValueError, FileNotFoundError
            Without ``parser``: an unsupported video suffix or missing folder, or ``every < 1``.

        Examples
        --------
        >>> parser = argparse.ArgumentParser()
        >>> Recorder.add_arguments(parser)
        >>> Recorder.from_args(parser.parse_args([])) is None
        True
        >>> Recorder.from_args(parser.parse_args(["--video", "run.gif", "--every", "2"])).every
        2
        """
        if args.video is None and not args.show:
            return None
        try:
            return cls(video=args.video, show=args.show, every=getattr(args, "every", 1), hold=args.show)
        except (ValueError, OSError) as err:
            if parser is None:
                raise
            parser.error(str(err))

    @property
    def video(self) -> Path | None:
        """The video's path, if any."""
        return None if self.writer is None else self.writer.path

    @property
    def live(self) -> bool:
        """Whether frames are shown in an open live window (``show`` with an interactive backend)."""
        if not (self.show and self._interactive and self.renderer is not None):
            return False
        import matplotlib.pyplot as plt

        return plt.fignum_exists(self.renderer.figure.number)  # the user may have closed it

    def close(self) -> None:
        """Finish the video and close the live window, unless ``hold`` (idempotent)."""
        if self.writer is not None:
            self.writer.close()
        if self.live and not self.keep_open:
            import matplotlib.pyplot as plt

            plt.close(self.renderer.figure)  # type: ignore[union-attr]

    def hold(self) -> None:
        """Block until the live window is closed (returns at once without one)."""
        if self.live:
            import matplotlib.pyplot as plt

            assert self.renderer is not None
            self.renderer.show_all()  # a repaint of the held window (e.g. resized) keeps the robots
            self.renderer.figure.canvas.draw_idle()
            plt.show(block=True)

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


def _interactive(canvas: Any) -> bool:
    """Whether ``canvas`` is a window's (an interactive backend's) canvas."""
    return getattr(canvas, "required_interactive_framework", None) is not None


def _resized(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.fromarray(image).resize(size, Image.Resampling.BILINEAR))
