"""Drawing experiment frames: headless images, GIF/MP4 videos and a live window.

An experiment run with ``record=callback`` calls ``callback(frame)`` once per step with a
:class:`dream.frames.Frame`. A :class:`Recorder` is such a callback: it draws frames with a
:class:`Renderer` into a :class:`VideoWriter` and/or a live matplotlib window::

    >>> from dream.viz import Recorder
    >>> with Recorder(video="run.gif", every=2) as recorder:      # doctest: +SKIP
    ...     hrvo_circle.run(n=10, record=recorder)

Everything is headless by default: a :class:`Renderer` draws on a ``matplotlib.figure.Figure``
with an Agg canvas, and :mod:`matplotlib.pyplot` is imported only when a live window is asked
for, so importing this module needs no display (it imports matplotlib only when drawing).

Units: metres in the world (the axes are in metres), pixels in images. Images are
``(H, W, 3)`` uint8 RGB arrays.
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from dream.frames import Frame
from dream.specs import GRITSBOT, ArenaSpec

__all__ = ["Recorder", "Renderer", "VideoWriter", "robot_colours"]

ROBOT_DIAMETER = GRITSBOT.diameter  #: drawn size of a robot (m)
VELOCITY_SCALE = 1.0  #: metres of arrow per m/s of velocity: 0.2 m/s is drawn 0.2 m long
OBSTACLE_COLOUR = "0.25"
LINK_COLOUR = "0.6"
ARENA_MARGIN = 0.04  #: empty border around the arena, as a fraction of its larger side


def robot_colours(n: int) -> np.ndarray:
    """RGBA colours ``(n, 4)`` of robots ``0..n-1``.

    ``tab10`` for up to 10 robots, ``tab20`` beyond, cycling (robot ``i`` and ``i + 20``
    share a colour in swarms of more than 10).
    """
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return np.asarray(cmap(np.arange(n) % cmap.N), dtype=np.float64).reshape(n, 4)


def _polygons(polygons: list[np.ndarray]) -> list[np.ndarray]:
    out = []
    for polygon in polygons:
        points = np.asarray(polygon, dtype=np.float64).reshape(-1, 2)
        if len(points) >= 2 and np.isfinite(points).all():
            out.append(points)
    return out


class Renderer:
    """Draws :class:`~dream.frames.Frame` objects of one arena on one reused figure.

    The artists are created once and updated in place by :meth:`draw`. Headless, :meth:`to_rgb`
    draws only the frame's artists over a cached image of the axes (redrawn when anything else
    on the figure changed), ~5 ms a frame for 10 robots; ``figure.savefig`` draws everything.

    Parameters
    ----------
    arena : ArenaSpec
        The arena drawn as a rectangle; the axes show it with a small margin.
    figsize : (float, float)
        Figure size in inches.
    dpi : int
        Pixels per inch; an image is ``round(figsize * dpi)`` pixels (640 x 400 by default).
    live : bool
        Create the figure with :mod:`matplotlib.pyplot` (for a window) instead of a headless
        Agg figure.

    Attributes
    ----------
    figure : matplotlib.figure.Figure
    axes : matplotlib.axes.Axes
        Add your own artists here; :meth:`draw` only updates its own.
    """

    def __init__(
        self, arena: ArenaSpec, *, figsize: tuple[float, float] = (6.4, 4.0), dpi: int = 100, live: bool = False
    ) -> None:
        # matplotlib is imported here, not with the module: `import dream.viz` stays cheap.
        from matplotlib.collections import EllipseCollection, LineCollection, PolyCollection
        from matplotlib.patches import Rectangle

        self.arena = arena
        if live:
            import matplotlib.pyplot as plt

            self.figure = plt.figure(figsize=figsize, dpi=dpi)
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            self.figure = Figure(figsize=figsize, dpi=dpi)
            FigureCanvasAgg(self.figure)
        self.axes = self.figure.add_subplot()
        ax = self.axes
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x (m)", fontsize=8)
        ax.set_ylabel("y (m)", fontsize=8)
        ax.tick_params(labelsize=7)
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
        self._set_limits(arena)

        # zorder: cells < obstacles < links < goals < robots < headings < velocities
        self._cells = PolyCollection([], facecolors="none", edgecolors="0.5", linewidths=0.6, zorder=1)
        self._obstacles = PolyCollection(
            [], facecolors=OBSTACLE_COLOUR, edgecolors=OBSTACLE_COLOUR, linewidths=0.5, zorder=2
        )
        self._links = LineCollection([], colors=LINK_COLOUR, linewidths=0.5, zorder=3)
        self._goals = ax.scatter([], [], marker="x", s=25, linewidths=1.2, zorder=4)
        self._robots = EllipseCollection(
            ROBOT_DIAMETER,
            ROBOT_DIAMETER,
            0.0,
            units="xy",
            offsets=np.empty((0, 2)),
            offset_transform=ax.transData,
            edgecolors="black",
            linewidths=0.6,
            zorder=5,
        )
        self._headings = LineCollection([], colors="black", linewidths=1.0, zorder=6)
        self._velocities = LineCollection([], linewidths=1.5, zorder=7, capstyle="round")
        for artist in (self._cells, self._obstacles, self._links, self._robots, self._headings, self._velocities):
            ax.add_collection(artist, autolim=False)
        ax.set_title("step 0", fontsize=9)  # text while laying out, so that the title has room
        self._colours = robot_colours(0)
        self.figure.tight_layout()
        # Headless, the frame's artists are "animated": drawn over a cached image of the rest
        # (axes, ticks, arena), which is redrawn only when something else changed.
        self._dynamic = [
            self._cells,
            self._obstacles,
            self._links,
            self._goals,
            self._robots,
            self._headings,
            self._velocities,
            ax.title,
        ]
        self._blit = not live
        if self._blit:
            for artist in self._dynamic:
                artist.set_animated(True)
        self._background: Any = None
        self._background_size: tuple[int, int] | None = None

    def _set_limits(self, arena: ArenaSpec) -> None:
        margin = ARENA_MARGIN * max(arena.width, arena.height)
        self.axes.set_xlim(arena.xmin - margin, arena.xmax + margin)
        self.axes.set_ylim(arena.ymin - margin, arena.ymax + margin)

    def draw(self, frame: Frame) -> None:
        """Update the figure to show ``frame`` (the canvas is redrawn by :meth:`to_rgb`).

        Draws the arena, each robot as a circle of diameter 0.11 m with a heading tick, goals
        as crosses in the robot's colour (NaN rows skipped), chosen velocities as segments
        from the robot (0.2 m/s drawn 0.2 m long), radio links as thin grey lines, obstacle
        polygons filled dark grey, cells as thin outlines, and ``step`` and ``title`` above.
        """
        if frame.arena != self.arena:
            self.arena = frame.arena
            self._arena_patch.set_bounds(frame.arena.xmin, frame.arena.ymin, frame.arena.width, frame.arena.height)
            self._set_limits(frame.arena)

        poses = np.asarray(frame.poses, dtype=np.float64).reshape(3, -1)
        n = poses.shape[1]
        if len(self._colours) != n:
            self._colours = robot_colours(n)
        colours = self._colours
        positions = poses[:2].T

        self._robots.set_offsets(positions)
        self._robots.set_facecolor(colours)
        tips = positions + (ROBOT_DIAMETER / 2) * np.column_stack((np.cos(poses[2]), np.sin(poses[2])))
        self._headings.set_segments(np.stack((positions, tips), axis=1))

        if frame.goals is not None and n:
            goals = np.asarray(frame.goals, dtype=np.float64).reshape(-1, 2)[:n]
            shown = np.isfinite(goals).all(axis=1)
            self._goals.set_offsets(goals[shown])
            self._goals.set_color(colours[: len(goals)][shown])
        else:
            self._goals.set_offsets(np.empty((0, 2)))

        if frame.velocities is not None and n:
            velocities = np.asarray(frame.velocities, dtype=np.float64).reshape(-1, 2)[:n]
            shown = np.isfinite(velocities).all(axis=1)
            ends = positions[: len(velocities)] + VELOCITY_SCALE * velocities
            self._velocities.set_segments(np.stack((positions[: len(velocities)], ends), axis=1)[shown])
            self._velocities.set_color(colours[: len(velocities)][shown])
        else:
            self._velocities.set_segments([])

        if frame.links is not None and len(frame.links) and n:
            pairs = np.asarray(frame.links, dtype=np.intp).reshape(-1, 2)
            pairs = pairs[((pairs >= 0) & (pairs < n)).all(axis=1)]
            self._links.set_segments(positions[pairs])
        else:
            self._links.set_segments([])

        self._obstacles.set_verts(_polygons(frame.obstacles))
        cells = _polygons(frame.cells)
        self._cells.set_verts(cells)
        self._cells.set_edgecolor(colours if len(cells) == n and n else "0.5")

        title = f"step {frame.step}"
        if frame.title:
            title += f"  |  {frame.title}"
        self.axes.title.set_text(title)  # not set_title: that would make the whole figure stale

    def to_rgb(self) -> np.ndarray:
        """Redraw and return the current image, ``(H, W, 3)`` uint8."""
        canvas = self.figure.canvas
        if self._blit:
            # Axes, ticks and labels are most of a redraw: redraw them only when stale (an
            # animated artist's change does not make the figure stale, anything else does).
            size = canvas.get_width_height(physical=True)
            if self._background is None or self.figure.stale or self._background_size != size:
                canvas.draw()
                self._background = canvas.copy_from_bbox(self.figure.bbox)
                self._background_size = size
            else:
                canvas.restore_region(self._background)
            for artist in self._dynamic:
                self.figure.draw_artist(artist)
            return np.asarray(canvas.buffer_rgba())[..., :3].copy()
        if hasattr(canvas, "buffer_rgba"):  # Agg and the Agg-based window canvases
            canvas.draw()
            return np.asarray(canvas.buffer_rgba())[..., :3].copy()
        import io

        buffer = io.BytesIO()
        self.figure.savefig(buffer, format="rgba", dpi=self.figure.dpi)
        width, height = (round(v) for v in self.figure.get_size_inches() * self.figure.dpi)
        return np.frombuffer(buffer.getvalue(), dtype=np.uint8).reshape(height, width, 4)[..., :3].copy()


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
        self._previous: np.ndarray | None = None
        self._file: Any = None
        self._ffmpeg: Any = None
        self._closed = False

    def add(self, image: np.ndarray) -> None:
        """Append one image ``(H, W, 3)`` uint8 (RGB) as the next frame."""
        if self._closed:
            raise ValueError(f"VideoWriter for {self.path} is closed")
        image = np.asarray(image)
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"image must be (H, W, 3) uint8, got shape {image.shape} dtype {image.dtype}")
        height, width = image.shape[:2]
        if self._size is None:
            self._size = (width, height)
        elif self._size != (width, height):
            raise ValueError(
                f"image is {width}x{height} pixels, but this video's frames are {self._size[0]}x{self._size[1]}"
            )
        if self.format == ".gif":
            self._add_gif(image)
        else:
            self._add_mp4(image)
        self.frames_written += 1

    def _add_gif(self, image: np.ndarray) -> None:
        from PIL import GifImagePlugin, Image

        delay = max(1, round(1000 / self.fps / 10)) * 10  # ms, whole centiseconds as GIF stores them
        if self._previous is None:
            frame = Image.fromarray(image).quantize(256, method=_FAST_OCTREE)
            header, _ = GifImagePlugin.getheader(frame, info={"loop": 0, "duration": delay})
            self._file = open(self.path, "wb")  # noqa: SIM115 - closed by close()
            self._file.writelines(header)
            offset = (0, 0)
        else:
            # Only the rectangle that changed: smaller files, and less to quantise.
            height, width = image.shape[:2]
            changed = (image != self._previous).reshape(height, width * 3)
            rows = np.flatnonzero(changed.any(axis=1))
            if rows.size:
                columns = np.flatnonzero(changed[rows[0] : rows[-1] + 1].any(axis=0)) // 3  # byte -> pixel
                top, bottom, left, right = rows[0], rows[-1] + 1, columns[0], columns[-1] + 1
            else:  # identical: one unchanged pixel keeps the frame (and its delay) in the file
                top, bottom, left, right = 0, 1, 0, 1
            frame = Image.fromarray(np.ascontiguousarray(image[top:bottom, left:right])).quantize(
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
                codec="libx264",
                macro_block_size=2,
                ffmpeg_log_level="error",
            )
            self._ffmpeg.send(None)  # start ffmpeg
        self._ffmpeg.send(np.ascontiguousarray(image).tobytes())

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


_FAST_OCTREE = 2  #: ``PIL.Image.Quantize.FASTOCTREE``: 4x faster than median cut, as good on plots


def check_video_path(path: str | os.PathLike[str]) -> str:
    """The format (``".gif"`` or ``".mp4"``) of a video path, checked before anything runs.

    Raises
    ------
    ValueError
        For any other suffix.
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
        Also show the frames in a live matplotlib window (``plt.ion()``, ``plt.pause``).
        Without an interactive backend (no display) a warning says so and nothing is shown.
    every : int
        Render one frame in ``every``.
    fps : float
        Playback speed of the video.
    figsize, dpi
        Passed to :class:`Renderer`.

    Attributes
    ----------
    frames_rendered : int
        Frames drawn so far.
    frames_seen : int
        Frames received so far.
    renderer : Renderer or None
        ``None`` until the first frame.
    writer : VideoWriter or None
    """

    def __init__(
        self,
        *,
        video: str | os.PathLike[str] | None = None,
        show: bool = False,
        every: int = 1,
        fps: float = 30,
        figsize: tuple[float, float] = (6.4, 4.0),
        dpi: int = 100,
    ) -> None:
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
            raise ValueError(f"every must be an integer >= 1, got {every!r}")
        self.every = int(every)
        self.show = show
        self.figsize = figsize
        self.dpi = dpi
        self.writer = VideoWriter(video, fps=fps) if video is not None else None
        self.renderer: Renderer | None = None
        self.frames_seen = 0
        self.frames_rendered = 0
        self._interactive = False

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
            image = self.renderer.to_rgb()
            if self.writer._size is not None and (image.shape[1], image.shape[0]) != self.writer._size:
                image = _resized(image, self.writer._size)  # the live window was resized
            self.writer.add(image)
        if self.show and self._interactive:
            import matplotlib.pyplot as plt

            if self.writer is None:  # else to_rgb has drawn the canvas already
                self.renderer.figure.canvas.draw_idle()
            plt.pause(0.001)  # shows the window and lets it repaint
        self.frames_rendered += 1

    def _start(self, arena: ArenaSpec) -> None:
        if self.show:
            import matplotlib.pyplot as plt

            plt.ion()
            self.renderer = Renderer(arena, figsize=self.figsize, dpi=self.dpi, live=True)
            canvas = self.renderer.figure.canvas
            self._interactive = getattr(canvas, "required_interactive_framework", None) is not None
            if not self._interactive:
                import matplotlib

                warnings.warn(
                    f"no live window: matplotlib backend {matplotlib.get_backend()!r} is not interactive (no display?)",
                    RuntimeWarning,
                    stacklevel=3,
                )
        else:
            self.renderer = Renderer(arena, figsize=self.figsize, dpi=self.dpi)

    @property
    def video(self) -> Path | None:
        """The video's path, if any."""
        return None if self.writer is None else self.writer.path

    @property
    def live(self) -> bool:
        """Whether frames are shown in a live window (``show`` with an interactive backend)."""
        return self.show and self._interactive and self.renderer is not None

    def close(self) -> None:
        """Finish the video (idempotent). A live window stays open; see :meth:`hold`."""
        if self.writer is not None:
            self.writer.close()

    def hold(self) -> None:
        """Block until the live window is closed (returns at once without one)."""
        if self.live:
            import matplotlib.pyplot as plt

            plt.ioff()
            plt.show()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


def _resized(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.fromarray(image).resize(size, Image.Resampling.BILINEAR))
