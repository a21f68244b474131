"""Voronoi coverage (thesis 3.3): robots spread over the arena, each to its cell's centroid.

Fifteen robots start packed in the bottom-right corner, among two large static rectangles and
two small rectangles that wander and bounce off the walls. Each robot knows its own pose
(odometry), the positions of the robots within radio range (range radio) and the closest
points of the obstacles it senses (obstacle sensor). Its cell is the disc of radius 1 m around
it clipped by the arena, by the bisectors with the robots it hears, and by virtual agents that
keep the cell (and the robot's body) off the obstacles; it moves to the cell's centroid and
stops within 0.05 m of it. No HRVO: the cells themselves keep the robots apart.

Success: no robot-robot collision, no contact with the static obstacles, the locational
coverage cost falls, and without moving obstacles the team comes to rest.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream import kernels
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.obstacles import Obstacle
from dream.radios import RangeRadio
from dream.robot import Robot
from dream.sensors import ObstacleSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec
from dream.timers import create_timer

NAME = "voronoi-coverage"
CELL_RADIUS = 1.0  #: radius of the disc a robot's cell starts from (m)
ARRIVAL = 0.05  #: a robot this close to its centroid stops (m; 0.02 on the real lab)
MARGIN = 0.02  #: extra clearance kept from obstacles beyond the robot's radius (m)
GAIN = 1.0  #: proportional gain towards the centroid (1/s)
REST_STEPS = 60  #: steps without any command after which the team is at rest


def scale_for(n: int) -> float:
    """How much the arena and the obstacles grow for ``n`` robots (1 up to the thesis's 15)."""
    return max(1.0, math.sqrt(n / 15))


def coverage_arena(n: int) -> ArenaSpec:
    """The Robotarium for up to 15 robots; beyond, an arena of its shape with the same density."""
    scale = scale_for(n)
    return ROBOTARIUM if scale == 1.0 else ArenaSpec.centred(ROBOTARIUM.width * scale, ROBOTARIUM.height * scale)


def thesis_obstacles(rng: np.random.Generator, moving: bool = True, scale: float = 1.0) -> list[Obstacle]:
    """Two large static rectangles and (optionally) two small ones moving in random directions,
    placed and sized for an arena ``scale`` times the Robotarium's."""
    obstacles = [
        Obstacle((-0.75 * scale, 0.45 * scale), (0.6 * scale, 0.3 * scale)),
        Obstacle((0.25 * scale, -0.3 * scale), (0.3 * scale, 0.55 * scale)),
    ]
    if moving:
        for centre in ((-0.9, -0.55), (0.9, 0.6)):
            angle = rng.uniform(-math.pi, math.pi)
            obstacles.append(
                Obstacle(
                    np.array(centre) * scale,
                    (0.15 * scale, 0.15 * scale),
                    velocity=0.05 * np.array([math.cos(angle), math.sin(angle)]),
                )
            )
    return obstacles


def corner_poses(n: int, rng: np.random.Generator, arena: ArenaSpec = ROBOTARIUM, spacing: float = 0.2) -> np.ndarray:
    """Poses ``(3, n)`` packed in rows from the bottom-right corner (five per row in the
    Robotarium, more in a larger arena), random headings."""
    columns = max(5, math.ceil(5 * arena.width / ROBOTARIUM.width))
    k = np.arange(n)
    x = arena.xmax - 0.15 - spacing * (k % columns)
    y = arena.ymin + 0.15 + spacing * (k // columns)
    return np.vstack((x, y, rng.uniform(-math.pi, math.pi, n)))


def coverage_cost(positions: np.ndarray, arena: ArenaSpec, obstacles: list[Obstacle], step: float = 0.02) -> float:
    """Locational cost: the integral over the free arena of the squared distance to the nearest robot.

    Approximated on a grid of ``step`` (m); points inside obstacles are not counted. ``positions``
    is ``(2, n)``.
    """
    xs = np.arange(arena.xmin + step / 2, arena.xmax, step)
    ys = np.arange(arena.ymin + step / 2, arena.ymax, step)
    qx, qy = (g.ravel() for g in np.meshgrid(xs, ys))
    free = np.ones(len(qx), dtype=bool)
    for obstacle in obstacles:
        local = np.column_stack((qx, qy)) - obstacle.center
        c, s = math.cos(obstacle.angle), math.sin(obstacle.angle)
        u, v = local[:, 0] * c + local[:, 1] * s, -local[:, 0] * s + local[:, 1] * c
        free &= ~((np.abs(u) < obstacle.size[0] / 2) & (np.abs(v) < obstacle.size[1] / 2))
    squared = (qx[free, None] - positions[0]) ** 2 + (qy[free, None] - positions[1]) ** 2
    return float(squared.min(axis=1).sum() * step * step)


class CoverageRobot(Robot):
    """A robot that moves to the centroid of its obstacle-aware Voronoi cell.

    Callbacks: :meth:`update_odom`, :meth:`update_radio` (``(id, x, y)`` messages in, its own
    out), :meth:`update_obstacles` (closest points from the obstacle sensor) and :meth:`update`.
    """

    def __init__(self, robot_id: int, tag: str, arena: ArenaSpec = ROBOTARIUM, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.arena = arena
        self.others = np.zeros((0, 2))
        self.obstacle_points = np.zeros((0, 2))
        self.centroid: np.ndarray | None = None
        self.cell = np.zeros((0, 2))  # the last cell computed, for drawing

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        self.others = np.array([(x, y) for _, x, y in messages]).reshape(-1, 2)
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update_obstacles(self, closest_points: np.ndarray) -> None:
        self.obstacle_points = closest_points

    def update(self, dxu: np.ndarray) -> None:
        self.dxi = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            agents = kernels.obstacle_agents(here, self.obstacle_points, robot_radius=self.spec.radius, margin=MARGIN)
            self.centroid, _, self.cell = kernels.voronoi_cell(
                here, self.others, radius=CELL_RADIUS, bounds=self.arena.bounds, virtual=agents
            )
            offset = self.centroid - here
            distance = math.hypot(offset[0], offset[1])
            if distance >= ARRIVAL:
                self.dxi = GAIN * offset * min(1.0, self.v_max / (GAIN * distance))
        self.command(dxu)


class VoronoiCoverage(Experiment):
    """The coverage experiment (see the module docs)."""

    name = NAME
    default_n = 15
    success = (
        "the team comes to rest with zero collisions and no contact with the static obstacles "
        "(with moving obstacles, it never rests: turn them off with moving_obstacles=false)"
    )
    moving_obstacles: bool = param(True, "two small obstacles wander and bounce off the walls")

    def arena_for(self, n: int) -> ArenaSpec:
        return coverage_arena(n)

    def build(self, n: int) -> None:
        self.obstacles = thesis_obstacles(self.world.rng, self.moving_obstacles, scale_for(n))
        for i in range(n):
            robot = CoverageRobot(i, f"robot_{i}", arena=self.arena)
            self.robots.append(robot)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            sensor = ObstacleSensor(i, f"obstacles_{i}", robot.update_obstacles, self.obstacles, range=CELL_RADIUS)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio, range=2 * CELL_RADIUS)
            create_timer(
                i,
                10 + i % 5,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "obstacles", "call": sensor.update},
                    {"delay": 5, "tag": "radio", "call": radio.update},
                    {"delay": 5, "tag": "robot", "call": robot.update},
                ],
            )
        self.static = [o for o in self.obstacles if not o.moving]
        self.sampling = 0.02 * scale_for(n)
        self.contacts, self.still = 0, 0

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return corner_poses(n, rng, self.arena)

    def steps(self, n: int) -> int:
        return 1500

    def timer_params(self, x: np.ndarray, dxu: np.ndarray) -> dict[str, tuple[Any, ...]]:
        return {"odom": (x,), "obstacles": (x,), "radio": (x,), "robot": (dxu,)}

    def before_step(self, step: int) -> None:
        if step == 0:
            self.cost_start = coverage_cost(self.sim.poses[:2], self.arena, self.obstacles, self.sampling)

    def after_step(self, step: int, poses: np.ndarray) -> None:
        for obstacle in self.obstacles:
            obstacle.step(self.sim.time_step, self.arena)
        self.contacts += any(o.distance(poses[:2, i]) < GRITSBOT.radius for o in self.static for i in range(self.n))
        self.still = self.still + 1 if step > 21 + self.n % 5 and not self.dxu.any() else 0

    def done(self, step: int, poses: np.ndarray) -> bool:
        return self.still >= REST_STEPS

    def measures(self) -> dict[str, Any]:
        """Coverage cost at the start and the end (m^4), iterations in which a robot's body
        touched a static obstacle, robots still moving at the end."""
        return {
            "cost_start": self.cost_start,
            "cost_end": coverage_cost(self.sim.poses[:2], self.arena, self.obstacles, self.sampling),
            "static_contacts": self.contacts,
            "moving_at_end": int(np.count_nonzero(np.any(self.dxu != 0, axis=0))),
        }

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        return Frame(
            step,
            self.arena,
            poses,
            goals=np.array([np.full(2, np.nan) if r.centroid is None else r.centroid for r in self.robots]),
            obstacles=[o.polygon for o in self.obstacles],
            cells=[r.cell for r in self.robots],
            title=f"{NAME}: static contacts {self.contacts}, collisions {self.sim.violations.collision}",
        )


run = VoronoiCoverage.run
