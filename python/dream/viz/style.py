"""How things look: sizes, colours, the figure's layout, the image size and the title's font."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from dream.specs import GRITSBOT

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
#: Where the axes sit in the figure (left, bottom, width, height as fractions); the legend is
#: to their right, so that it never hides a robot.
AXES_RECT = (0.055, 0.07, 0.70, 0.86)
LEGEND_ANCHOR = (0.77, 0.93)


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
    return checked_size(size)


def checked_size(size: Any) -> tuple[int, int]:
    """``size`` as ``(width, height)`` in whole pixels, each in ``[64, 7680]``; else ``ValueError``."""
    try:
        width, height = (int(v) for v in size)
        ok = all(float(v) == int(v) for v in size) and 64 <= width <= 7680 and 64 <= height <= 7680
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"size must be (width, height) in whole pixels, each in [64, 7680], got {size!r}")
    return width, height


@functools.cache
def title_font(pixels: int) -> Any:
    """matplotlib's default font (DejaVu Sans) for Pillow, ``pixels`` high."""
    from matplotlib import font_manager, rcParams
    from PIL import ImageFont

    return ImageFont.truetype(
        font_manager.findfont(font_manager.FontProperties(family=rcParams["font.family"])), pixels
    )


def rgba(colour: str) -> np.ndarray:
    from matplotlib.colors import to_rgba

    return np.asarray(to_rgba(colour))
