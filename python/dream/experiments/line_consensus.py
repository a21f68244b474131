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
import time
from typing import Any, Callable

import numpy as np

from dream.backends import make_robotarium
from dream.experiments.result import ExperimentResult
from dream.frames import Frame
from dream.radios import GraphRadio
from dream.robot import RobotHRVO
from dream.sensors import MovementSensor, OdometrySensor
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.timers import create_timer, update_timers
from dream.world import World

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


def run(
    n: int = 6,
    seed: int = 0,
    backend: str = "auto",
    steps: int | None = None,
    *,
    spacing: float = SPACING,
    radio_gap: int = 10,
    trace: bool = False,
    progress: Any = None,
    record: Callable[[Frame], None] | None = None,
) -> ExperimentResult:
    """Run until the line has formed (both errors below 0.02 m) or ``steps`` (default 3000).

    ``measures``: the final ``y_spread`` and ``spacing_error`` (m) and the convergence time (s).
    """
    cap = 3000 if steps is None else steps
    with World(seed) as world:
        adjacency = graph(n, world.rng)
        sim = make_robotarium(n, backend, arena=line_arena(n, spacing), seed=seed)
        robots = []
        for i in range(n):
            robot = LineRobot(i, f"robot_{i}", spacing, arena=sim.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor)
            radio = GraphRadio(i, f"radio_{i}", robot.update_radio, adjacency)
            create_timer(
                i,
                10 + i % 3,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "movement", "call": movement.update},
                    {"delay": radio_gap, "tag": "radio", "call": radio.update},
                    {"delay": 4, "tag": "robot", "call": robot.update},
                ],
            )
            robots.append(robot)

        dxu = np.zeros((2, n))
        poses = [sim.poses] if trace else []
        done_at = None
        start = time.perf_counter()
        for t in range(cap):
            x = sim.get_poses()
            update_timers(t, {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)})
            sim.set_velocities(np.arange(n), dxu)
            sim.step()
            if trace:
                poses.append(sim.poses)
            if progress is not None:
                progress(t + 1, cap)
            if record is not None:
                spread, error = line_errors(sim.poses, spacing)
                record(
                    Frame(
                        t + 1,
                        sim.arena,
                        sim.poses,
                        goals=np.array([np.full(2, np.nan) if r.target is None else r.target for r in robots]),
                        velocities=np.array([r.dxi for r in robots]).reshape(-1, 2),
                        links=np.argwhere(np.triu(adjacency) > 0),
                        title=f"{NAME}: y spread {spread:.3f} m, spacing error {error:.3f} m",
                    )
                )
            if max(line_errors(sim.poses, spacing)) < TOLERANCE:
                done_at = t + 1
                break
        wall = time.perf_counter() - start
    spread, error = line_errors(sim.poses, spacing)
    measures = {
        "y_spread": spread,
        "spacing_error": error,
        "convergence_time_s": None if done_at is None else done_at * sim.time_step,
    }
    return ExperimentResult.from_backend(NAME, seed, sim, done_at, wall, measures, np.array(poses) if trace else None)
