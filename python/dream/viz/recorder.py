"""The :class:`Recorder`: an experiment's ``record=`` callback that draws its frames into a video
and/or a live window."""

from __future__ import annotations

import argparse
import os
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from dream.frames import Frame
from dream.specs import TIME_STEP, ArenaSpec
from dream.viz.renderer import Renderer
from dream.viz.style import SIZE, checked_size
from dream.viz.video import VideoWriter


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
        self.size = checked_size(size)
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
