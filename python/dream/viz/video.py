"""Videos: frames written one by one to an animated GIF (Pillow) or an H.264 MP4 (ffmpeg)."""

from __future__ import annotations

import contextlib
import math
import os
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from dream._files import check_writable


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
