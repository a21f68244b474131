"""What part of the world a picture shows: the whole arena, or the swarm's box when it is small in
a large arena or robots would be specks, or the focus robot's surroundings."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream.specs import ArenaSpec
from dream.viz.marks import RADIUS
from dream.viz.style import AXES_RECT, ROBOT_DIAMETER

ARENA_MARGIN = 0.04  #: empty border around the arena, as a fraction of its larger side
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


def fit(view: View, aspect: float) -> View:
    """``view`` grown about its centre along one axis so that width / height == ``aspect``."""
    xmin, xmax, ymin, ymax = view
    width, height = xmax - xmin, ymax - ymin
    if width < aspect * height:
        grow = (aspect * height - width) / 2
        return (xmin - grow, xmax + grow, ymin, ymax)
    grow = (width / aspect - height) / 2
    return (xmin, xmax, ymin - grow, ymax + grow)


class Framing:
    """The figure, its axes and the view of a :class:`~dream.viz.Renderer`; the drawing parts
    (robots, overlays, legend) build on it."""

    figure: Any
    axes: Any
    arena: ArenaSpec
    focus: int | None
    view: View
    following: str
    _text: float  # text scale: 1 at the default image size
    _colours: np.ndarray  # the robots' colours (n, 4)

    def _axes_pixels(self) -> tuple[float, float]:
        box = self.figure.bbox
        return box.width * AXES_RECT[2], box.height * AXES_RECT[3]

    def _whole_view(self) -> View:
        arena, (width, height) = self.arena, self._axes_pixels()
        margin = ARENA_MARGIN * max(arena.width, arena.height)
        return fit((arena.xmin - margin, arena.xmax + margin, arena.ymin - margin, arena.ymax + margin), width / height)

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
            pad = max(SWARM_MARGIN, SWARM_MARGIN_FRACTION * float(np.max(high - low))) + RADIUS
            return fit((low[0] - pad, high[0] + pad, low[1] - pad, high[1] + pad), width / height), pad

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

    def robot_pixels(self) -> float:
        """How many pixels across a robot is drawn in the current view."""
        return ROBOT_DIAMETER / (self.view[1] - self.view[0]) * self._axes_pixels()[0]

    # -- drawing ------------------------------------------------------------------------------
