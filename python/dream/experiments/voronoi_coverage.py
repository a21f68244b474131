"""Voronoi coverage (thesis 3.3): robots spread over the arena, each to its cell's centroid.

Fifteen robots start packed in the bottom-right corner, among two large static rectangles and
two small rectangles that wander and bounce off the walls. Each robot knows its own pose
(odometry), the positions of the robots within radio range (range radio) and the closest
points of the obstacles it senses (obstacle sensor). Its cell is the disc of radius 1 m around
it clipped by the arena, by the bisectors with the robots it hears, and by virtual agents that
keep the cell (and the robot's body) off the obstacles; it moves to the cell's centroid and
stops within 0.05 m of it. No HRVO: the cells themselves keep the robots apart.

Success: no robot-robot collision, no contact with the static obstacles, and the locational
coverage cost falls: without moving obstacles the team comes to rest with a lower cost; with
them it never rests (the wandering obstacles keep reshaping the cells), so the cost must stay
below ``COVERED`` (0.2) of its start for ``HOLD_STEPS`` (10 s). Beyond 15 robots the arena and
the obstacles grow so that the density stays the thesis's, and the step cap with the arena's side.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream import kernels, rules
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.obstacles import Obstacle, touching
from dream.radios import RangeRadio
from dream.robot import GUARD_MARGIN, Robot
from dream.sensors import MovementSensor, ObstacleSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec
from dream.world import create_timer

NAME = "voronoi-coverage"
CELL_RADIUS = 1.0  #: radius of the disc a robot's cell starts from (m)
ARRIVAL = 0.05  #: a robot this close to its centroid stops (m; 0.02 on the real lab)
MARGIN = 0.02  #: extra clearance kept from obstacles beyond the robot's radius (m)
GAIN = 1.0  #: proportional gain towards the centroid (1/s)
SEEN = 0.5  #: range of the movement sensor that finds robots close by (m)
SAME_ROBOT = 0.08  #: a robot seen this close to where a message put a robot is that robot (m)
REST_STEPS = 60  #: steps without any command after which the team is at rest
COVERED = 0.2  #: with moving obstacles, success is the cost staying below this fraction of its start...
HOLD_STEPS = 300  #: ...for this many steps (10 s)
COST_EVERY = 30  #: steps between two evaluations of the cost while it is watched
COST_BLOCK = 2_000_000  #: point-robot pairs per slice of the coverage cost's grid


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
    is ``(2, n)``. The grid is taken in slices of at most ``COST_BLOCK`` point-robot pairs, so
    that memory stays bounded for thousands of robots.
    """
    xs = np.arange(arena.xmin + step / 2, arena.xmax, step)
    ys = np.arange(arena.ymin + step / 2, arena.ymax, step)
    points = np.column_stack([g.ravel() for g in np.meshgrid(xs, ys)])
    for obstacle in obstacles:
        points = points[~obstacle.contains(points)]
    rows = max(1, COST_BLOCK // positions.shape[1])
    total = 0.0
    for start in range(0, len(points), rows):
        q = points[start : start + rows]
        squared = (q[:, 0, None] - positions[0]) ** 2 + (q[:, 1, None] - positions[1]) ** 2
        total += float(squared.min(axis=1).sum())
    return total * step * step


class CoverageRobot(Robot):
    """A robot that moves to the centroid of its obstacle-aware Voronoi cell.

    Callbacks: :meth:`update_odom`, :meth:`update_radio` (``(id, x, y)`` messages in, its own
    out), :meth:`update_obstacles` (closest points from the obstacle sensor),
    :meth:`update_sensor` (robots close by, from the movement sensor) and :meth:`update`.

    A robot it sees but does not hear (a crashed robot, say) bounds its cell too: otherwise the
    cell would stretch over that robot and lead straight into it.
    """

    def __init__(self, robot_id: int, tag: str, arena: ArenaSpec = ROBOTARIUM, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.arena = arena
        self.others = np.zeros((0, 2))
        self.obstacle_points = np.zeros((0, 2))
        self.centroid: np.ndarray | None = None
        self.cell = np.zeros((0, 2))  # the last cell computed, for drawing
        self.seen = np.zeros((0, 2))  # positions of the robots the movement sensor detects

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        self.others = np.array([(x, y) for _, x, y in messages]).reshape(-1, 2)
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update_obstacles(self, closest_points: np.ndarray) -> None:
        self.obstacle_points = closest_points

    def update_sensor(self, detections: np.ndarray) -> None:
        self.seen = rules.seen_positions((self.pos_x, self.pos_y), detections)

    def guard(self) -> None:
        """Cells keep the robots apart, but a unicycle drives along its heading, not straight to
        its centroid: it drives no further when that would bring it within a centimetre of a
        robot it sees (:meth:`~dream.Robot.stop_short`)."""
        if self.has_pose and len(self.seen):
            self.stop_short(np.array([self.pos_x, self.pos_y]) - self.seen, self.spec.diameter + GUARD_MARGIN)

    def silent(self) -> np.ndarray:
        """Positions ``(k, 2)`` of the robots seen that no message accounts for."""
        return self.seen[rules.far_from(self.seen, self.others, SAME_ROBOT)]

    def update(self, dxu: np.ndarray) -> None:
        self.dxi = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            agents = kernels.obstacle_agents(here, self.obstacle_points, robot_radius=self.spec.radius, margin=MARGIN)
            self.centroid, _, self.cell = kernels.voronoi_cell(
                here,
                np.vstack((self.others, self.silent())),
                radius=CELL_RADIUS,
                bounds=self.arena.bounds,
                virtual=agents,
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
        "zero collisions and no contact with the static obstacles, and: without moving obstacles the "
        "team comes to rest (no command for 60 steps) with the coverage cost below its start; with "
        "them (the team never rests) the cost stays below 0.2 of its start for 300 steps (10 s)"
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
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=SEEN)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio, range=2 * CELL_RADIUS)
            create_timer(
                i,
                10 + i % 5,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "obstacles", "call": sensor.update},
                    {"delay": 3, "tag": "movement", "call": movement.update},
                    {"delay": 5, "tag": "radio", "call": radio.update},
                    {"delay": 5, "tag": "robot", "call": robot.update},
                ],
            )
        self.static = [o for o in self.obstacles if not o.moving]
        self.sampling = 0.02 * scale_for(n)
        self.contacts, self.still = 0, 0
        self.covered_since: int | None = None

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return corner_poses(n, rng, self.arena)

    def steps(self, n: int) -> int:
        """1500 up to the thesis's 15 robots; beyond, 2000 times the arena's growth in side (coming
        to rest took 2888 steps at N = 100, whose arena is 2.6 times the Robotarium's)."""
        scale = scale_for(n)
        return 1500 if scale == 1.0 else math.ceil(2000 * scale)

    def timer_params(self, x: np.ndarray, dxu: np.ndarray) -> dict[str, tuple[Any, ...]]:
        return {"odom": (x,), "obstacles": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)}

    def cost(self, poses: np.ndarray) -> float:
        """The coverage cost of the team at ``poses`` ``(3, n)`` (m^4)."""
        return coverage_cost(poses[:2], self.arena, self.obstacles, self.sampling)

    def before_step(self, step: int) -> None:
        if step == 0:
            self.cost_start = self.last_cost = self.cost(self.sim.poses)

    def after_step(self, step: int, poses: np.ndarray) -> None:
        for obstacle in self.obstacles:
            obstacle.step(self.sim.time_step, self.arena)
        self.contacts += bool(touching(self.static, poses[:2].T, GRITSBOT.radius).any())
        self.still = self.still + 1 if step > 21 + self.n % 5 and not self.dxu.any() else 0
        if step % COST_EVERY == 0:
            self.last_cost = self.cost(poses)
        if self.moving_obstacles and step % COST_EVERY == 0:
            covered = self.last_cost < COVERED * self.cost_start
            self.covered_since = (step if self.covered_since is None else self.covered_since) if covered else None

    def done(self, step: int, poses: np.ndarray) -> bool:
        if self.contacts:
            return False
        if self.moving_obstacles:
            return self.covered_since is not None and step - self.covered_since >= HOLD_STEPS
        return self.still >= REST_STEPS and self.cost(poses) < self.cost_start

    def measures(self) -> dict[str, Any]:
        """Coverage cost at the start and the end (m^4), iterations in which a robot's body
        touched a static obstacle, robots still moving at the end."""
        return {
            "cost_start": self.cost_start,
            "cost_end": self.cost(self.sim.poses),
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
            obstacle_moving=[o.moving for o in self.obstacles],
            cells=[r.cell for r in self.robots],
            ranges={"obstacle sensing": CELL_RADIUS, "radio": 2 * CELL_RADIUS},
            title=f"{NAME}: cost {self.last_cost / self.cost_start:.0%} of its start, static contacts {self.contacts}",
        )


run = VoronoiCoverage.run
