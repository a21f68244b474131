"""What a renderer needs to draw one step of an experiment, independent of the experiment.

An experiment run with ``record=callback`` calls ``callback(frame)`` once per step with a
:class:`Frame`; :mod:`dream.viz` draws frames live or into a video.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dream.specs import ArenaSpec

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
        The experiment's name and main measures so far (e.g. ``"coverage cost 0.41"``).
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
