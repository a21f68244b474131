"""Voronoi coverage (thesis 3.3): robots spread over the arena, each to its cell's centroid.

Robots start packed in a corner among two static and two wandering rectangles. Each knows its
odometry, the positions it hears by radio, the robots it sees and the obstacles it senses; its
cell (a disc clipped by the arena, those robots and virtual agents for the obstacles) gives it
its goal. One :class:`CoverageRobot`, written on arrays (:mod:`dream.swarm`), runs robot by
robot and as one swarm with the same poses at every step.

The story, the rules and the figures: ``docs/experiments/voronoi-coverage.md``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream import kernels, rules, timers
from dream.backends.startup import reachable_starts
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.obstacles import Obstacle, touching
from dream.robot import GUARD_MARGIN
from dream.specs import GRITSBOT, ROBOTARIUM, TIME_STEP, ArenaSpec, SimulatorSpec
from dream.swarm import Guard, Movement, Obstacles, Radio, SwarmRobot, View

NAME = "voronoi-coverage"
CELL_RADIUS = 1.0  #: radius of the disc a robot's cell starts from (m)
ARRIVAL = 0.05  #: up to 15 robots, a robot this close to its centroid stops (m; 0.02 on the real lab)
MARGIN = 0.02  #: extra clearance kept from obstacles and walls beyond the robot's radius (m)
SEEN = 0.5  #: range of the movement sensor that finds robots close by (m)
SAME_ROBOT = 0.08  #: a robot seen this close to where a message put a robot is that robot (m)
#: Share of its last step that a moving robot adds to its way to the centroid (heavy-ball,
#: :func:`dream.rules.momentum`): a wide team then comes to rest flowing, not creeping in stop and go.
MOMENTUM = 0.8
#: How far ahead a moving robot says it is, in steps like its last: 1, where it will be at its
#: next decision if it keeps its pace (its neighbours decide up to a period after hearing it).
LEAD = 1.0
REST_STEPS = 60  #: steps without any command after which the team is at rest
COVERED = 0.2  #: the team covers the arena when its cost is below this fraction of its start...
SPREAD = 5.0  #: ...and below this many times the cost of an ideal spread (:func:`ideal_cost`)
HEXAGON = 5 / (18 * math.sqrt(3))  #: polar moment of a regular hexagon of unit area (Fejes Toth)
HOLD_STEPS = 300  #: with moving obstacles, success is the team covering the arena this many steps (10 s)
COST_EVERY = 30  #: steps between two evaluations of the cost while it is watched
RADIO_RANGE = 2 * CELL_RADIUS  #: robots farther apart than this do not clip each other's cells (m)
START_DELAY = 10  #: start-up delay of robot i: this plus i % 5 steps
CONTROL_GAP = 5  #: steps between two decisions (and radio rounds) of a robot
#: Gain towards the centroid (1/s): a robot covers the way to it in one decision period (Lloyd's
#: step), no faster than its top speed. A smaller gain spreads a large team as many times slower.
GAIN = 1 / (CONTROL_GAP * TIME_STEP)


def scale_for(n: int) -> float:
    """How much the arena and the obstacles grow for ``n`` robots (1 up to the thesis's 15)."""
    return max(1.0, math.sqrt(n / 15))


def arrival_for(n: int) -> float:
    """How close to its centroid a robot of a team of ``n`` stops (m): :data:`ARRIVAL` up to 15
    robots, then shrinking with the team's width. A robot moves only when its neighbours are
    uneven enough to shift its centroid beyond this, so a team can freeze while its spacing grows
    by about four times this from one robot to the next: across a wide team, a crowd still
    packed at the start (cells of 0.2 m in a 1000-robot team would stay so with 0.05 m)."""
    return ARRIVAL / scale_for(n)


def guard_distance(rules: SimulatorSpec) -> float:
    """How close (centre to centre, m) a robot's motion guard lets it drive to a robot it sees: as
    close as two bodies, or two of the lab's colliders where they sit ahead of the centre (rps 2.1:
    0.135 m discs 0.025 m ahead touch at 0.185 m), and :data:`GUARD_MARGIN`. No HRVO keeps these
    robots apart, only their cells and this guard."""
    return max(GRITSBOT.diameter, rules.diameter + 2 * abs(rules.collider_offset)) + GUARD_MARGIN


def cell_bounds(arena: ArenaSpec) -> tuple[float, float, float, float]:
    """The bounds a cell is clipped by: the arena less the robot's radius and :data:`MARGIN`, so
    that a robot pressed against a wall (by a moving obstacle, say) keeps its body in the arena."""
    return arena.shrunk(GRITSBOT.radius + MARGIN)


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


def free_points(arena: ArenaSpec, obstacles: list[Obstacle], step: float) -> np.ndarray:
    """The centres ``(m, 2)`` of a grid of ``step`` (m) over the arena, less those inside obstacles."""
    xs = np.arange(arena.xmin + step / 2, arena.xmax, step)
    ys = np.arange(arena.ymin + step / 2, arena.ymax, step)
    points = np.column_stack([g.ravel() for g in np.meshgrid(xs, ys)])
    for obstacle in obstacles:
        points = points[~obstacle.contains(points)]
    return points


def coverage_cost(positions: np.ndarray, arena: ArenaSpec, obstacles: list[Obstacle], step: float = 0.02) -> float:
    """Locational cost: the integral over the free arena of the squared distance to the nearest robot.

    Approximated on a grid of ``step`` (m) (:func:`free_points`). ``positions`` is ``(2, n)``. A
    k-d tree of the robots finds each point's nearest robot: at 10,000 robots, 100 times faster
    than measuring every point-robot pair. The tree is built unbalanced (twice as fast at 100,000
    robots, built for one query) and queried on every core: the same distances either way.
    """
    # Imported here: scipy.spatial takes ~0.2 s to load, more than all the rest of `import dream`.
    from scipy.spatial import cKDTree

    tree = cKDTree(positions.T, balanced_tree=False, compact_nodes=False)
    distances, _ = tree.query(free_points(arena, obstacles, step), workers=-1)
    return float(np.sum(distances * distances)) * step * step


def ideal_cost(n: int, arena: ArenaSpec, obstacles: list[Obstacle], step: float = 0.02) -> float:
    """The coverage cost of ``n`` robots spread ideally over the free arena (m^4): each the centre
    of a regular hexagon of an equal share of it, the least cost of any spread of many robots over
    a wide region (Fejes Toth's bound). Walls and obstacles make the best real spread dearer: a few
    times this (3 to 4 times for 15 robots)."""
    area = len(free_points(arena, obstacles, step)) * step * step
    return HEXAGON * area * area / n


class CoverageRobot(SwarmRobot):
    """A robot that moves to the centroid of its obstacle-aware Voronoi cell.

    Each decision it sends where it is (moving: where it will be at its next decision,
    :data:`LEAD`), clips its cell by the positions it hears, the robots it sees that no message
    accounts for (a crashed robot, say: otherwise its cell would lead straight into it) and
    virtual agents for the obstacles it senses (:meth:`dream.swarm.View.cells`), and heads for
    the centroid with :data:`MOMENTUM` of its last step (:func:`dream.rules.approach`). No HRVO:
    the cells keep the robots apart, and the motion guard (:class:`~dream.swarm.Guard`) stops a
    unicycle whose turn would close in on a robot it sees. A robot that wants no velocity gets no
    command (``halts``). ``keep_cells`` keeps each robot's last cell in :attr:`cells`, for drawing.
    """

    period = CONTROL_GAP
    # Its decision reads its view alone, but its cells query the whole board, built once a call: in blocks
    # on 16 threads a million robots' step took 591 ms against 492 in one call.
    threaded = False
    movement = Movement(range=SEEN)
    radio = Radio(range=RADIO_RANGE, fields=("x", "y"))
    halts = True
    memory = {"moving": 0, "last_x": math.nan, "last_y": math.nan, "goal_x": math.nan, "goal_y": math.nan}

    def __init__(self, obstacles: list[Obstacle], arena: ArenaSpec, arrival: float, near: float) -> None:
        self.obstacles = Obstacles(obstacles, range=CELL_RADIUS)
        self.guard = Guard(near)
        self.bounds, self.arrival = cell_bounds(arena), arrival
        self.keep_cells = False
        self.cells: dict[int, np.ndarray] = {}

    def start(self, ids: np.ndarray) -> np.ndarray:
        """Staggered: a fifth of the team talks and decides at each of five neighbouring steps."""
        return timers.staggered(ids, START_DELAY, 5)

    def decide(self, view: View) -> np.ndarray:
        here, memory, seen, sensed = view.pose[:, :2], view.memory, view.seen, view.obstacles
        assert sensed is not None  # the engine's view has every reading
        last = np.column_stack((memory["last_x"], memory["last_y"]))
        moving = memory["moving"].astype(bool)
        said = here + rules.momentum(here, last, moving, LEAD)
        view.send(x=said[:, 0], y=said[:, 1])
        sighted = seen.points(here)
        near = sensed.broadcast(here)
        points = near + np.column_stack((sensed["dx"], sensed["dy"]))
        agents = kernels.obstacle_agents(near, points, robot_radius=self.spec.radius, margin=MARGIN)
        real = ~np.isnan(agents[:, 0])  # none for an obstacle the robot touches
        cells = view.cells(
            seen=(seen.offsets, sighted),
            same=SAME_ROBOT,
            virtual=(sensed.where(real).offsets, agents[real]),
            radius=CELL_RADIUS,
            bounds=self.bounds,
            polygons=self.keep_cells,
        )
        if cells.vertices is not None and cells.offsets is not None:
            self.cells.update(zip(view.ids.tolist(), np.split(cells.vertices, cells.offsets[1:-1]), strict=True))
        carry = rules.momentum(here, last, moving, MOMENTUM)
        wished = rules.approach(here, cells.centroids, GAIN, self.spec.v_max, self.arrival, carry)
        memory["moving"] = rules.nonzero(wished)
        memory["last_x"], memory["last_y"] = here[:, 0], here[:, 1]
        memory["goal_x"], memory["goal_y"] = cells.centroids[:, 0], cells.centroids[:, 1]
        return wished


class VoronoiCoverage(Experiment):
    """The coverage experiment (see the module docs): its robots are one :class:`CoverageRobot`."""

    name = NAME
    default_n = 15
    success = (
        "zero collisions and no contact with the static obstacles, and the team covers the arena (coverage "
        "cost below 0.2 of its packed start's and within 5 times an ideal spread's): without moving obstacles at "
        "rest (no command for 60 steps); with them (the team never rests) for 300 steps (10 s)"
    )
    moving_obstacles: bool = param(True, "two small obstacles wander and bounce off the walls")
    cost_packed: float | None = None  #: the packed start's cost, when the robots start elsewhere (m^4)

    def arena_for(self, n: int) -> ArenaSpec:
        return coverage_arena(n)

    def swarm_robot(self, n: int) -> CoverageRobot:
        """The robots among the thesis's obstacles, grown with the arena; the success counters."""
        self.obstacles = thesis_obstacles(self.world.rng, self.moving_obstacles, scale_for(n))
        self.static = [o for o in self.obstacles if not o.moving]
        self.sampling = 0.02 * scale_for(n)
        self.ideal = ideal_cost(n, self.arena, self.static, self.sampling)
        self.contacts, self.still = 0, 0
        self.covered_since: int | None = None
        self.team = CoverageRobot(self.obstacles, self.arena, arrival_for(n), guard_distance(self.rules))
        return self.team

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return corner_poses(n, rng, self.arena)

    def reachable_poses(self, poses: np.ndarray) -> np.ndarray:
        """Spread off the obstacles; the team must still cover the arena as well as from its packed start."""
        self.cost_packed = self.cost(poses)
        return reachable_starts(poses, self.arena, obstacles=self.obstacles)

    def steps(self, n: int) -> int:
        """1500 up to the thesis's 15 robots; beyond, 3000 times the arena's growth in side (the
        steps runs took: ``docs/experiments/voronoi-coverage.md``)."""
        scale = scale_for(n)
        return 1500 if scale == 1.0 else math.ceil(3000 * scale)

    def cost(self, poses: np.ndarray) -> float:
        """The coverage cost of the team at ``poses`` ``(3, n)`` (m^4)."""
        return coverage_cost(poses[:2], self.arena, self.obstacles, self.sampling)

    def before_step(self, step: int) -> None:
        if step == 0:
            self.cost_start = self.last_cost = self.cost(self.sim.poses)

    def covers(self, cost: float) -> bool:
        """Whether a team whose coverage cost is ``cost`` covers the arena: the cost fell below
        :data:`COVERED` of its start (its packed start's, :meth:`reachable_poses`) and within
        :data:`SPREAD` times the ideal spread's (the first alone passes a wide team still packed
        in its corner)."""
        return cost < min(COVERED * (self.cost_packed or self.cost_start), SPREAD * self.ideal)

    def after_step(self, step: int, poses: np.ndarray) -> None:
        for obstacle in self.obstacles:
            obstacle.step(self.sim.time_step, self.arena)
        self.contacts += bool(touching(self.static, poses[:2].T, GRITSBOT.radius).any())
        self.still = self.still + 1 if step > 21 + self.n % 5 and not self.dxu.any() else 0
        if step % COST_EVERY == 0:
            self.last_cost = self.cost(poses)
        if self.moving_obstacles and step % COST_EVERY == 0:
            covered = self.covers(self.last_cost)
            self.covered_since = (step if self.covered_since is None else self.covered_since) if covered else None

    def done(self, step: int, poses: np.ndarray) -> bool:
        if self.contacts:
            return False
        if self.moving_obstacles:
            return self.covered_since is not None and step - self.covered_since >= HOLD_STEPS
        return self.still >= REST_STEPS and self.covers(self.cost(poses))

    def measures(self) -> dict[str, Any]:
        """Coverage cost at the start and the end and that of the ideal spread (m^4), iterations
        in which a robot's body touched a static obstacle, robots still moving at the end."""
        return {
            "cost_start": self.cost_start,
            "cost_end": self.cost(self.sim.poses),
            "cost_ideal": self.ideal,
            "static_contacts": self.contacts,
            "moving_at_end": int(np.count_nonzero(np.any(self.dxu != 0, axis=0))),
        }

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        """The robots' centroids and their last cells (kept from the first frame on; none when a
        learner, :mod:`dream.rl`, drives the robots)."""
        assert self.engine is not None
        self.team.keep_cells = True
        memory, cells = self.engine.memory, self.team.cells
        return Frame(
            step,
            self.arena,
            poses,
            goals=np.column_stack((memory["goal_x"], memory["goal_y"])) if "goal_x" in memory else None,
            obstacles=[o.polygon for o in self.obstacles],
            obstacle_moving=[o.moving for o in self.obstacles],
            cells=[cells.get(i, np.zeros((0, 2))) for i in range(self.n)],
            ranges={"obstacle sensing": CELL_RADIUS, "radio": RADIO_RANGE},
            title=f"{NAME}: cost {self.last_cost / self.cost_start:.0%} of its start, static contacts {self.contacts}",
        )
