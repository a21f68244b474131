"""Line consensus (thesis 3.2): robots agree, over a communication graph, on a line.

Each robot knows only the positions its graph neighbours send by radio. It heads for
``x_i = mean_j (x_j + (id_j - id_i) d)`` and ``y_i = mean_j y_j`` over its neighbours j
(spacing d), through HRVO so that the robots crossing each other's way do not collide. Where
the graph is connected, the team converges to a horizontal line ordered by id, d apart.
Six robots use the thesis's adjacency matrix; more robots use a ring with random chords.
Success: y spread and spacing error below 0.02 m, zero collisions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.radios import GraphRadio
from dream.robot import RobotHRVO
from dream.sensors import MovementSensor, OdometrySensor
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.timers import create_timer

NAME = "line-consensus"
SPACING = 0.3  #: distance between neighbours on the line (m)
TOLERANCE = 0.02  #: largest y spread and spacing error of a converged line (m)
GAIN = 1.0  #: proportional gain towards the consensus target (1/s)

#: The thesis's communication graph for six robots.
THESIS_GRAPH = np.array(
    [
        [0, 1, 1, 0, 0, 0],
        [1, 0, 1, 0, 1, 0],
        [1, 1, 0, 1, 0, 0],
        [0, 0, 1, 0, 1, 1],
        [0, 1, 0, 1, 0, 1],
        [0, 0, 0, 1, 1, 0],
    ],
    dtype=np.float64,
)


def graph(n: int, rng: np.random.Generator) -> np.ndarray:
    """The thesis's graph for six robots; otherwise a ring plus ``n // 2`` random chords."""
    if n == 6:
        return THESIS_GRAPH.copy()
    adjacency = np.zeros((n, n))
    for i in range(n):
        adjacency[i, (i + 1) % n] = adjacency[(i + 1) % n, i] = 1.0
    for _ in range(n // 2):
        i, j = rng.choice(n, size=2, replace=False)
        adjacency[i, j] = adjacency[j, i] = 1.0
    np.fill_diagonal(adjacency, 0.0)
    return adjacency


def line_arena(n: int, spacing: float = SPACING) -> ArenaSpec:
    """The Robotarium while the line fits in its central 2 m, else wider, with its proportions."""
    length = (n - 1) * spacing
    if length <= 2.0:
        return ROBOTARIUM
    scale = length / 2.0
    return ArenaSpec.centred(ROBOTARIUM.width * scale, ROBOTARIUM.height * scale)


def line_errors(poses: np.ndarray, spacing: float = SPACING) -> tuple[float, float]:
    """``(y spread, spacing error)`` of the team: robot i should be ``spacing`` right of robot i + 1."""
    x, y = poses[0], poses[1]
    gaps = x[:-1] - x[1:]
    return float(y.max() - y.min()), float(np.abs(gaps - spacing).max()) if len(gaps) else 0.0


class LineRobot(RobotHRVO):
    """A robot that moves to the consensus of its graph neighbours' positions.

    Callbacks: :meth:`update_odom`, :meth:`update_sensor`, :meth:`update_radio` (receives
    ``(id, x, y)`` messages, returns its own) and :meth:`update` (the controller).
    """

    def __init__(self, robot_id: int, tag: str, spacing: float = SPACING, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.spacing = spacing
        self.target: np.ndarray | None = None

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        if messages:
            xs = [x + (j - self.robot_id) * self.spacing for j, x, _ in messages]
            self.target = np.array([np.mean(xs), np.mean([y for _, _, y in messages])])
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update(self, dxu: np.ndarray) -> None:
        desired = np.zeros(2)
        if self.has_pose and self.target is not None:
            desired = GAIN * (self.target - (self.pos_x, self.pos_y))
            speed = math.hypot(desired[0], desired[1])
            if speed > self.v_max:
                desired *= self.v_max / speed
        self.HRVO(self.detections, desired)
        self.command(dxu)


class LineConsensus(Experiment):
    """The line-consensus experiment (see the module docs)."""

    name = NAME
    default_n = 6
    success = "y spread and spacing error below 0.02 m (the line has formed), zero violations"
    spacing: float = param(SPACING, "distance between neighbours on the line (m)")
    radio_gap: int = param(10, "steps between radio exchanges")

    def arena_for(self, n: int) -> ArenaSpec:
        return line_arena(n, self.spacing)

    def build(self, n: int) -> None:
        self.adjacency = graph(n, self.world.rng)
        for i in range(n):
            robot = LineRobot(i, f"robot_{i}", self.spacing, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor)
            radio = GraphRadio(i, f"radio_{i}", robot.update_radio, self.adjacency)
            create_timer(
                i,
                10 + i % 3,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "movement", "call": movement.update},
                    {"delay": self.radio_gap, "tag": "radio", "call": radio.update},
                    {"delay": 4, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def done(self, step: int, poses: np.ndarray) -> bool:
        self.errors = line_errors(poses, self.spacing)
        self.done_at = step if max(self.errors) < TOLERANCE else None
        return self.done_at is not None

    def measures(self) -> dict[str, Any]:
        """The final ``y_spread`` and ``spacing_error`` (m) and the convergence time (s)."""
        spread, error = line_errors(self.sim.poses, self.spacing)
        time = None if self.done_at is None else self.done_at * self.sim.time_step
        return {"y_spread": spread, "spacing_error": error, "convergence_time_s": time}

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        spread, error = line_errors(poses, self.spacing)
        return Frame(
            step,
            self.arena,
            poses,
            goals=np.array([np.full(2, np.nan) if r.target is None else r.target for r in self.robots]),
            velocities=np.array([r.dxi for r in self.robots]).reshape(-1, 2),
            links=np.argwhere(np.triu(self.adjacency) > 0),
            title=f"{NAME}: y spread {spread:.3f} m, spacing error {error:.3f} m",
        )


run = LineConsensus.run
