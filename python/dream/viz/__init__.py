"""Drawing experiment frames: headless images, GIF/MP4 videos and a live window.

An experiment run with ``record=callback`` calls ``callback(frame)`` once per step with a
:class:`dream.frames.Frame`. A :class:`Recorder` is such a callback: it draws frames with a
:class:`Renderer` into a :class:`VideoWriter` and/or a live matplotlib window::

    >>> from dream.viz import Recorder
    >>> with Recorder(video="run.gif", every=2, focus=0) as recorder:      # doctest: +SKIP
    ...     dream.run("hrvo-circle", n=10, record=recorder)

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

The package's modules, by what they draw: :mod:`~dream.viz.robots` (bodies, notches, fault and
role marks), :mod:`~dream.viz.overlays` (goals, velocities, links, obstacles, cells, the focus
robot's ranges), :mod:`~dream.viz.legend`, :mod:`~dream.viz.view` (what part of the world is
shown), :mod:`~dream.viz.renderer` (the figure they are drawn on), :mod:`~dream.viz.video` and
:mod:`~dream.viz.recorder`; :mod:`~dream.viz.style` and :mod:`~dream.viz.marks` hold how things
look.
"""

from dream.viz.marks import ARROW_HALF, ARROW_HEAD, ARROW_SHAFT, CROSS, NOTCH, STUCK_SQUARE
from dream.viz.recorder import Recorder
from dream.viz.renderer import Renderer
from dream.viz.style import (
    AXES_RECT,
    BYZANTINE_COLOUR,
    CRASHED_COLOUR,
    DEFAULT_RANGE,
    DPI,
    LEGEND_ANCHOR,
    LINK_COLOUR,
    MOVING_OBSTACLE_COLOUR,
    OBSTACLE_COLOUR,
    RANGE_COLOURS,
    ROBOT_DIAMETER,
    ROLE_MARKERS,
    SIZE,
    STUCK_COLOUR,
    VELOCITY_SCALE,
    parse_size,
    robot_colours,
)
from dream.viz.video import VideoWriter, check_video_path
from dream.viz.view import (
    ARENA_MARGIN,
    FOLLOW_FRACTION,
    FOLLOW_SLACK,
    MIN_ROBOT_PIXELS,
    SWARM_MARGIN,
    SWARM_MARGIN_FRACTION,
    View,
)

__all__ = [
    "Recorder",
    "Renderer",
    "VideoWriter",
    "parse_size",
    "robot_colours",
    # the look, the view's rules and the video path check, as the single module viz.py had them
    "ARENA_MARGIN",
    "ARROW_HALF",
    "ARROW_HEAD",
    "ARROW_SHAFT",
    "AXES_RECT",
    "BYZANTINE_COLOUR",
    "CRASHED_COLOUR",
    "CROSS",
    "DEFAULT_RANGE",
    "DPI",
    "FOLLOW_FRACTION",
    "FOLLOW_SLACK",
    "LEGEND_ANCHOR",
    "LINK_COLOUR",
    "MIN_ROBOT_PIXELS",
    "MOVING_OBSTACLE_COLOUR",
    "NOTCH",
    "OBSTACLE_COLOUR",
    "RANGE_COLOURS",
    "ROBOT_DIAMETER",
    "ROLE_MARKERS",
    "SIZE",
    "STUCK_COLOUR",
    "STUCK_SQUARE",
    "SWARM_MARGIN",
    "SWARM_MARGIN_FRACTION",
    "VELOCITY_SCALE",
    "View",
    "check_video_path",
]
