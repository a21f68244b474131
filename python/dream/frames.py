"""What a renderer needs to draw one step of an experiment, independent of the experiment.

An experiment run with ``record=callback`` calls ``callback(frame)`` once per step with a
:class:`Frame`; :mod:`dream.viz` draws frames live or into a video.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dream.specs import ArenaSpec


@dataclass
class Frame:
    """One step of a run. Arrays are copies owned by the frame.

    Attributes
    ----------
    step : int
        Steps run so far.
    arena : ArenaSpec
    poses : (3, n) ndarray
        Robot poses ``[x; y; theta]``.
    goals : (n, 2) ndarray, optional
        Each robot's current goal (NaN rows: none).
    velocities : (n, 2) ndarray, optional
        Each robot's chosen single-integrator velocity (e.g. HRVO's), drawn from the robot.
    links : (m, 2) int ndarray, optional
        Pairs of robot ids that communicate.
    obstacles : list of (k, 2) ndarrays
        Obstacle polygons.
    cells : list of (k, 2) ndarrays
        Per-robot polygons (e.g. Voronoi cells).
    title : str
        Text for the title (metrics so far).
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
