"""The :class:`Renderer`: frames of one arena drawn on one reused figure, over a cached image of
what does not change."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream.frames import STATUSES, Frame
from dream.specs import ArenaSpec
from dream.viz.legend import Legend
from dream.viz.overlays import Overlays
from dream.viz.robots import Robots
from dream.viz.style import AXES_RECT, DEFAULT_RANGE, DPI, SIZE, checked_size, robot_colours, title_font


class Renderer(Robots, Overlays, Legend):
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
        width, height = checked_size(size)
        if focus is not None and (isinstance(focus, bool) or not isinstance(focus, (int, np.integer)) or focus < 0):
            raise ValueError(f"focus must be a robot id (an integer >= 0), got {focus!r}")
        self.arena = arena
        self.focus = None if focus is None else int(focus)
        self._make_figure(width, height, live)
        self.view = (0.0, 1.0, 0.0, 1.0)
        self.following = "arena"  # what the view shows: "arena", "swarm" or "focus"
        self._make_overlays()
        self._make_robots()
        ax = self.axes
        # Listed bottom to top: arrows under the bodies show only outside them.
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
        self._legend = None
        self._legend_key = ()
        self.legend_labels = []
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

    def _make_figure(self, width: int, height: int, live: bool) -> None:
        """The figure (a window's with ``live``, else a headless Agg one), its axes and the arena."""
        # matplotlib is imported here, not with the module: `import dream.viz` stays cheap.
        from matplotlib.patches import Rectangle

        arena = self.arena
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

    # -- drawing ------------------------------------------------------------------------------

    def draw(self, frame: Frame) -> None:
        """Update the figure to show ``frame`` (the canvas is redrawn by :meth:`render`).

        Raises
        ------
        ValueError
            When ``roles``, ``status`` or ``obstacle_moving`` do not have one entry per robot
            (obstacle), a status is unknown, or the focus robot is not in the frame.
        """
        poses, roles, status, moving, ranges = self._checked(frame)
        n = poses.shape[1]
        if frame.arena != self.arena:
            self.arena = frame.arena
            self._arena_patch.set_bounds(frame.arena.xmin, frame.arena.ymin, frame.arena.width, frame.arena.height)
        positions = poses[:2].T
        self._set_view(self._view_for(positions, 1.2 * max(ranges.values())))
        self._scale_marks()
        if len(self._colours) != n:
            self._colours = robot_colours(n)
        legend: list[tuple[str, Any]] = [("robot (to scale; notch: heading)", ("robot",))]
        if self.following != "arena":
            around = "the swarm" if self.following == "swarm" else f"robot {self.focus} (too many to show all)"
            legend.append((f"view: follows {around}", ("view",)))
        self._draw_robots(poses, status, roles, legend)
        self._draw_goals(frame.goals, n, legend)
        self._draw_velocities(frame.velocities, positions, status, legend)
        pairs = self._draw_links(frame.links, positions, legend)
        self._draw_focus(ranges, positions, pairs if frame.links is not None else None, legend)
        self._draw_areas(frame.obstacles, moving, frame.cells, n, legend)
        heading = f"step {frame.step}"
        if frame.time is not None:
            heading += f", t = {frame.time:.2f} s"
        self.axes.title.set_text(f"{heading}  |  {frame.title}" if frame.title else heading)
        self._set_legend(legend)

    def _checked(
        self, frame: Frame
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, np.ndarray, dict[str, float]]:
        """The frame's poses ``(3, n)``, roles and status (one label per robot, or ``None``), which
        obstacles move, and its ranges by name (m; ``{"": DEFAULT_RANGE}`` when it gives none)."""
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
        return poses, roles, status, moving, ranges

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
            font = title_font(round(points))
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


def _labels(values: Any, n: int, name: str) -> np.ndarray | None:
    if values is None:
        return None
    labels = np.asarray(values).astype(str).reshape(-1)
    if len(labels) != n:
        raise ValueError(f"frame.{name} has {len(labels)} labels, expected {n} (one per robot)")
    return labels
