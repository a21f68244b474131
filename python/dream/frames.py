"""What a renderer needs to draw one step of an experiment, independent of the experiment.

An experiment run with ``record=callback`` calls ``callback(frame)`` once per step with a
:class:`Frame`; :mod:`dream.viz` draws frames live or into a video.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dream.specs import ArenaSpec

#: The most characters of a :func:`measures_title`: the renderer adds the step and time to it.
TITLE_LENGTH = 80

#: The values of :attr:`Frame.status`, from the mildest to the worst.
STATUSES = ("ok", "byzantine", "stuck", "crashed")


@dataclass
class Frame:
    """One step of a run. Arrays are copies owned by the frame.

    Only ``step``, ``arena`` and ``poses`` are required; what is left out is not drawn.

    Attributes
    ----------
    step : int
        Steps run so far.
    arena : ArenaSpec
    poses : (3, n) ndarray
        Robot poses ``[x; y; theta]`` (m, m, rad).
    goals : (n, 2) ndarray, optional
        Each robot's current goal (NaN rows: none).
    velocities : (n, 2) ndarray, optional
        Each robot's chosen single-integrator velocity (m/s, e.g. HRVO's), drawn from the robot.
    links : (m, 2) int ndarray, optional
        Pairs of robot ids that communicate.
    obstacles : list of (k, 2) ndarrays
        Obstacle polygons (m).
    cells : list of (k, 2) ndarrays
        Per-robot polygons (e.g. Voronoi cells).
    title : str
        The experiment's name and main measures so far (e.g. ``"coverage cost 0.41"``); left
        empty, the runner fills it with :func:`measures_title`.
    roles : (n,) str ndarray, optional
        A short label per robot, e.g. ``"leader"`` / ``"follower"``; the most common role is
        drawn plain, every other one with its own mark.
    status : (n,) str ndarray, optional
        Each robot's fault status, one of :data:`STATUSES` (see :func:`fault_status`).
    obstacle_moving : list of bool, optional
        Per obstacle: whether it moves (drawn hatched). ``None``: all static.
    ranges : dict of str to float
        Named ranges of the robots (m), e.g. ``{"sensing": 1.0, "radio": 1.5}``, drawn around
        the robot a renderer focuses on.
    time : float, optional
        Simulated time (s) at this step; the runner fills it.
    """

    step: int
    arena: ArenaSpec
    poses: np.ndarray
    goals: np.ndarray | None = None
    velocities: np.ndarray | None = None
    links: np.ndarray | None = None
    obstacles: list[np.ndarray] = field(default_factory=list)
    cells: list[np.ndarray] = field(default_factory=list)
    title: str = ""
    roles: np.ndarray | None = None
    status: np.ndarray | None = None
    obstacle_moving: list[bool] | None = None
    ranges: dict[str, float] = field(default_factory=dict)
    time: float | None = None


def fault_status(crashed: np.ndarray, stuck: np.ndarray, byzantine: np.ndarray) -> np.ndarray:
    """Each robot's :attr:`Frame.status` from the ``(n,)`` bool masks of a fault state.

    A robot with several faults shows the worst: crashed, then stuck, then Byzantine.

    >>> fault_status(np.array([True, False, False]), np.array([True, True, False]), np.zeros(3, bool)).tolist()
    ['crashed', 'stuck', 'ok']
    """
    status = np.full(len(crashed), "ok", dtype=object)
    for mask, name in ((byzantine, "byzantine"), (stuck, "stuck"), (crashed, "crashed")):
        status[np.asarray(mask, dtype=bool)] = name
    return status.astype(str)


def measures_title(name: str, measures: Mapping[str, Any]) -> str:
    """The default :attr:`Frame.title`: the experiment's ``name`` and its ``measures`` so far,
    compactly (whole numbers as they are, others to 3 significant digits, nested measures as
    ``outer.inner``, values that are not a number, a boolean or a text left out), cut with "…" at
    :data:`TITLE_LENGTH`.

    >>> measures_title("drift", {"mean_x": 0.123456, "steps": {"held": 3}, "done": True, "trace": [1, 2]})
    'drift: mean_x 0.123, steps.held 3, done True'
    """
    parts = [f"{key} {value}" for key, value in _compact(measures, "")]
    title = f"{name}: " + ", ".join(parts) if parts else name
    return title if len(title) <= TITLE_LENGTH else title[: TITLE_LENGTH - 1].rstrip(", ") + "…"


def _compact(measures: Mapping[str, Any], prefix: str) -> list[tuple[str, str]]:
    found: list[tuple[str, str]] = []
    for key, value in measures.items():
        if isinstance(value, Mapping):
            found += _compact(value, f"{prefix}{key}.")
        elif isinstance(value, (bool, np.bool_, str, int, np.integer)):
            found.append((f"{prefix}{key}", str(value)))
        elif isinstance(value, (float, np.floating)):
            found.append((f"{prefix}{key}", f"{value:.3g}"))
    return found
