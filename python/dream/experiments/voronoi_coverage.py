"""Voronoi coverage (thesis 3.3): robots spread over the arena, each to its cell's centroid.

Fifteen robots start packed in the bottom-right corner, among two large static rectangles and
two small rectangles that wander and bounce off the walls. Each robot knows its own pose
(odometry), the positions of the robots within radio range (range radio) and the closest
points of the obstacles it senses (obstacle sensor). Its cell is the disc of radius 1 m around
it clipped by the arena, by the bisectors with the robots it hears, and by virtual agents that
keep the cell (and the robot's body) off the obstacles; it moves to the cell's centroid and
stops within 0.05 m of it. No HRVO: the cells themselves keep the robots apart.

Swarm mode (``swarm=True``, :meth:`VoronoiCoverage.swarm_step`) runs the same robots on arrays:
each robot at its own timer's steps (:func:`dream.timers.due`), with what its sensors and radio
gave it (a radio hears the position a robot of lower id sent in the same step, as the per-robot
timers, which run by id, imply), the shared rules (:func:`dream.rules.approach`, the motion
guard of :func:`dream.robot.stopping`) and each robot's cell clipped by what it knows alone: one
:func:`dream.kernels.heard_cells` call, which gives what :func:`dream.kernels.voronoi_cell` gives
each robot from its messages, the robots it sees but does not hear (:func:`dream.rules.far_from`)
and its virtual agents. The trajectories equal the per-robot mode's to the bit (tested).

Success: no robot-robot collision, no contact with the static obstacles, and the team covers
the arena: its locational coverage cost falls below ``COVERED`` (0.2) of its packed start's and within
``SPREAD`` (5) times the cost of an ideal spread (:func:`ideal_cost`). Without moving obstacles it
must do so at rest; with them it never rests (the wandering obstacles keep reshaping the cells),
so it must do so for ``HOLD_STEPS`` (10 s). Beyond 15 robots the arena and the obstacles grow so
that the density stays the thesis's, and the step cap with the arena's side.

A team of any size spreads as fast as Lloyd's algorithm lets it: a robot heads for its centroid
at :data:`GAIN`, which covers the way in one decision, and stops within :func:`arrival_for` of
it, a tolerance that shrinks as the team widens; otherwise the middle of a large team, packed
at the start, never feels the pull of the space the edge opened. A moving robot carries
:data:`MOMENTUM` of its last step into the next and tells the others where it is going
(:data:`LEAD`), so that a wide team comes to rest flowing, not creeping in stop and go; a robot
told to stay gets no command at all (:func:`halt`).
Cells stay the robot's radius and :data:`MARGIN` off the walls (:func:`cell_bounds`), as off the
obstacles.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from dream import kernels, rules, timers
from dream._csr import offsets_of, spans
from dream.backends.startup import reachable_starts
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.obstacles import Obstacle, sensed, touching
from dream.radios import RangeRadio
from dream.robot import GUARD_MARGIN, Robot, stopping
from dream.sensors import MovementSensor, ObstacleSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, TIME_STEP, ArenaSpec, SimulatorSpec
from dream.world import create_timer

NAME = "voronoi-coverage"
CELL_RADIUS = 1.0  #: radius of the disc a robot's cell starts from (m)
ARRIVAL = 0.05  #: up to 15 robots, a robot this close to its centroid stops (m; 0.02 on the real lab)
MARGIN = 0.02  #: extra clearance kept from obstacles and walls beyond the robot's radius (m)
SEEN = 0.5  #: range of the movement sensor that finds robots close by (m)
SAME_ROBOT = 0.08  #: a robot seen this close to where a message put a robot is that robot (m)
#: Share of its last step that a moving robot adds to its way to the centroid (heavy-ball; see
#: :meth:`CoverageRobot.update`). Lloyd's steps alone spread a team as diffusion does, in
#: decisions growing with the square of its width, and the last robots crept in stop and go, each
#: started again by a neighbour's millimetre: at N = 3,000 the team came to rest after 49,791 steps
#: of a 42,427 cap; with this alone, after 31,236 (0.9: the same; twice the gain with it: unstable).
MOMENTUM = 0.8
#: How far ahead a moving robot says it is, in steps like its last (:func:`sent`): 1, where it will
#: be at its next decision if it keeps its pace. A neighbour decides up to five steps after hearing
#: it; from where it was, a flow looks slower than it is and each cell lags behind it. With
#: :data:`MOMENTUM`, N = 3,000 came to rest after 13,230 steps (0.5: half the gain; 2: never rests).
LEAD = 1.0
REST_STEPS = 60  #: steps without any command after which the team is at rest
COVERED = 0.2  #: the team covers the arena when its cost is below this fraction of its start...
SPREAD = 5.0  #: ...and below this many times the cost of an ideal spread (:func:`ideal_cost`)
HEXAGON = 5 / (18 * math.sqrt(3))  #: polar moment of a regular hexagon of unit area (Fejes Toth)
HOLD_STEPS = 300  #: with moving obstacles, success is the team covering the arena this many steps (10 s)
COST_EVERY = 30  #: steps between two evaluations of the cost while it is watched
RADIO_RANGE = 2 * CELL_RADIUS  #: robots farther apart than this do not clip each other's cells (m)
START_DELAY = 10  #: start-up delay of robot i's timer: this plus i % 5 steps
ODOM_GAP, SENSING_GAP, CONTROL_GAP = 2, 3, 5  #: steps between odometry readings, obstacle and robot
#: detections, and decisions (each after a radio round)
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


def halt(dxu: np.ndarray, dxi: np.ndarray) -> np.ndarray:
    """``dxu`` ``(2, k)``, in place, with no command for the robots whose velocity ``dxi``
    ``(k, 2)`` is zero (the swarm's :meth:`CoverageRobot.dxi_to_dxu`).

    The unicycle conversion turns a zero velocity into ``w = ang_gain atan2(+0, -0) / (pi/2)``,
    ``atan2`` of signed zeros, for a robot heading between -pi and -pi/2: ``w_max``. A robot
    within its tolerance then spun in place, back from the heading it had just turned to, and the
    rest counter saw it move: at N = 1,000 (seed 0) 44,000 of the 990,000 moving decisions were
    such spins, the last robots alternating a turn to their centroid with a spin away from it.
    """
    dxu[:, ~dxi.any(axis=1)] = 0.0
    return dxu


def sent(here: np.ndarray, last: np.ndarray) -> np.ndarray:
    """Where a moving robot at ``here`` ``(k, 2)`` or ``(2,)`` says it is, having been at ``last`` at
    its last decision: :data:`LEAD` of that step further on (a step is 33 mm at top speed, well
    within :data:`SAME_ROBOT`: a robot seen there is still the robot heard)."""
    return here + LEAD * (here - last)


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
    than measuring every point-robot pair.
    """
    # Imported here: scipy.spatial takes ~0.2 s to load, more than all the rest of `import dream`.
    from scipy.spatial import cKDTree

    distances, _ = cKDTree(positions.T).query(free_points(arena, obstacles, step))
    return float(np.sum(distances * distances)) * step * step


def ideal_cost(n: int, arena: ArenaSpec, obstacles: list[Obstacle], step: float = 0.02) -> float:
    """The coverage cost of ``n`` robots spread ideally over the free arena (m^4): each the centre
    of a regular hexagon of an equal share of it, the least cost of any spread of many robots over
    a wide region (Fejes Toth's bound). Walls and obstacles make the best real spread dearer: a few
    times this (3 to 4 times for 15 robots)."""
    area = len(free_points(arena, obstacles, step)) * step * step
    return HEXAGON * area * area / n


class CoverageRobot(Robot):
    """A robot that moves to the centroid of its obstacle-aware Voronoi cell.

    Callbacks: :meth:`update_odom`, :meth:`update_radio` (``(id, x, y)`` messages in, its own
    out), :meth:`update_obstacles` (closest points from the obstacle sensor),
    :meth:`update_sensor` (robots close by, from the movement sensor) and :meth:`update`.

    A robot it sees but does not hear (a crashed robot, say) bounds its cell too: otherwise the
    cell would stretch over that robot and lead straight into it.
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        arena: ArenaSpec = ROBOTARIUM,
        arrival: float = ARRIVAL,
        near: float = GRITSBOT.diameter + GUARD_MARGIN,
        **kwargs: Any,
    ) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.arena = arena
        self.arrival = arrival
        self.near = near
        self.others = np.zeros((0, 2))
        self.obstacle_points = np.zeros((0, 2))
        self.centroid: np.ndarray | None = None
        self.moving = False  # whether its last decision moved it
        self.last = np.full(2, np.nan)  # where it was at its last decision
        self.cell = np.zeros((0, 2))  # the last cell computed, for drawing
        self.seen = np.zeros((0, 2))  # positions of the robots the movement sensor detects

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        """Keep the positions heard; send ``(id, x, y)``: where the robot believes itself, or, moving,
        where it will be at its next decision if it keeps its pace (:func:`sent`)."""
        # The (id, x, y) triples flattened into one array: half the cost of a list of pairs, for
        # the hundreds of messages a robot in a crowd hears.
        flat = np.fromiter(itertools.chain.from_iterable(messages), np.float64, 3 * len(messages))
        self.others = flat.reshape(-1, 3)[:, 1:]
        if not self.has_pose:
            return None
        if self.moving:
            x, y = sent(np.array([self.pos_x, self.pos_y]), self.last)
            return (self.robot_id, float(x), float(y))
        return (self.robot_id, self.pos_x, self.pos_y)

    def update_obstacles(self, closest_points: np.ndarray) -> None:
        self.obstacle_points = closest_points

    def update_sensor(self, detections: np.ndarray) -> None:
        self.seen = rules.seen_positions((self.pos_x, self.pos_y), detections)

    def guard(self) -> None:
        """Cells keep the robots apart, but a unicycle drives along its heading, not straight to
        its centroid: it drives no further when that would bring it within a centimetre of a
        robot it sees (:meth:`~dream.Robot.stop_short`)."""
        if self.has_pose and len(self.seen):
            self.stop_short(np.array([self.pos_x, self.pos_y]) - self.seen, self.near)

    def dxi_to_dxu(self) -> None:
        """The unicycle command of ``dxi``, and no command at all when ``dxi`` is zero: the
        conversion alone spins a robot heading between -pi and -pi/2 (see :func:`halt`)."""
        super().dxi_to_dxu()
        if not self.dxi.any():
            self.dxu[:] = 0.0

    def silent(self) -> np.ndarray:
        """Positions ``(k, 2)`` of the robots seen that no message accounts for."""
        return self.seen[rules.far_from(self.seen, self.others, SAME_ROBOT)]

    def update(self, dxu: np.ndarray) -> None:
        """Decide: the cell and its centroid, and the way there plus :data:`MOMENTUM` of the step
        taken since the last decision if that decision moved the robot (the robot's own odometry,
        nothing more); no command once that way is within the tolerance (:func:`dream.rules.approach`)."""
        self.dxi = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            agents = kernels.obstacle_agents(here, self.obstacle_points, robot_radius=self.spec.radius, margin=MARGIN)
            self.centroid, _, self.cell = kernels.voronoi_cell(
                here,
                np.vstack((self.others, self.silent())),
                radius=CELL_RADIUS,
                bounds=cell_bounds(self.arena),
                virtual=agents,
            )
            carry = MOMENTUM * (here - self.last) if self.moving else np.zeros(2)
            self.dxi = rules.approach(here, self.centroid, GAIN, self.v_max, self.arrival, carry)
            self.moving, self.last = bool(self.dxi.any()), here
        self.command(dxu)


class Seen(NamedTuple):
    """What the movement sensors of the robots reading in one step saw (swarm mode): CSR rows
    ``indptr`` ``(n + 1,)`` (empty for robots not reading) of the positions ``(m, 2)`` where each
    put the robots within :data:`SEEN`, by increasing id, as :meth:`CoverageRobot.update_sensor`
    does: its believed position less each detection's offset."""

    indptr: np.ndarray
    positions: np.ndarray

    @classmethod
    def read(
        cls, x: np.ndarray, beliefs: np.ndarray, indptr: np.ndarray, indices: np.ndarray, distances: np.ndarray
    ) -> Seen:
        """The readings of the robots at poses ``x`` ``(3, n)``, believing themselves at ``beliefs``
        ``(3, n)``, from the neighbour index (CSR) of the robots reading, within :data:`SEEN`."""
        owners = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        angles = np.arctan2(x[1, owners] - x[1, indices], x[0, owners] - x[0, indices])
        positions = np.column_stack(
            (beliefs[0, owners] - distances * np.cos(angles), beliefs[1, owners] - distances * np.sin(angles))
        )
        return cls(indptr, positions)

    @staticmethod
    def last(seen: dict[int, Seen], step: int, who: np.ndarray, delays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """What robots ``who`` ``(k,)`` (timers' start-up delays ``delays``) saw at their last
        reading up to ``step``: positions ``(m, 2)`` and whose row of ``who`` saw each ``(m,)``."""
        last = timers.last_due(step, delays, SENSING_GAP)
        positions, rows = [np.zeros((0, 2))], [np.zeros(0, dtype=np.int64)]
        for when in np.unique(last[last >= 0]):
            reading = seen[int(when)]
            mine = np.flatnonzero(last == when)
            starts, counts = reading.indptr[who[mine]], np.diff(reading.indptr)[who[mine]]
            positions.append(reading.positions[spans(starts, counts)])
            rows.append(np.repeat(mine, counts))
        rows_all = np.concatenate(rows)
        order = np.argsort(rows_all, kind="stable")
        return np.vstack(positions)[order], rows_all[order]


@dataclass
class CoverageSwarm:
    """Every robot's state in swarm mode, one row each (see :meth:`VoronoiCoverage.swarm_step`).

    Attributes
    ----------
    delays : (n,) int ndarray
        Start-up delay of each robot's timer (steps), as in the per-robot mode.
    pose : (3, n) ndarray
        Each robot's last odometry reading (NaN before the first).
    board : (n, 2) ndarray
        The radio board: the position each robot sent last (NaN before it first spoke).
    points : (n, k, 2) ndarray
        The closest point of each obstacle at each robot's last obstacle reading (NaN: not sensed).
    centroid : (n, 2) ndarray
        Each robot's last centroid (NaN before its first decision).
    cells : list of (m, 2) ndarrays
        Each robot's last cell, for drawing.
    """

    delays: np.ndarray
    pose: np.ndarray
    board: np.ndarray
    points: np.ndarray
    centroid: np.ndarray
    moving: np.ndarray
    last: np.ndarray
    cells: list[np.ndarray]

    @classmethod
    def start(cls, n: int, obstacles: int) -> CoverageSwarm:
        """``n`` robots that know nothing yet, among ``obstacles`` obstacles."""
        return cls(
            delays=start_delays(n),
            pose=np.full((3, n), np.nan),
            board=np.full((n, 2), np.nan),
            points=np.full((n, obstacles, 2), np.nan),
            centroid=np.full((n, 2), np.nan),
            moving=np.zeros(n, dtype=bool),
            last=np.full((n, 2), np.nan),
            cells=[np.zeros((0, 2)) for _ in range(n)],
        )


def start_delays(n: int) -> np.ndarray:
    """Start-up delays ``(n,)`` of the robots' timers (steps): a fifth of the team talks and
    decides at each of five neighbouring steps."""
    return START_DELAY + np.arange(n) % 5


class VoronoiCoverage(Experiment):
    """The coverage experiment (see the module docs). Swarm mode (``swarm=True``) keeps the per-robot
    mode's schedule and decision rules with the team's state in a :class:`CoverageSwarm`."""

    name = NAME
    default_n = 15
    has_swarm_mode = True
    success = (
        "zero collisions and no contact with the static obstacles, and the team covers the arena (coverage "
        "cost below 0.2 of its packed start's and within 5 times an ideal spread's): without moving obstacles at "
        "rest (no command for 60 steps); with them (the team never rests) for 300 steps (10 s)"
    )
    moving_obstacles: bool = param(True, "two small obstacles wander and bounce off the walls")
    cost_packed: float | None = None  #: the packed start's cost, when the robots start elsewhere (m^4)

    def arena_for(self, n: int) -> ArenaSpec:
        return coverage_arena(n)

    def build(self, n: int) -> None:
        self.obstacles = thesis_obstacles(self.world.rng, self.moving_obstacles, scale_for(n))
        delays = start_delays(n)
        for i in range(n):
            robot = CoverageRobot(
                i, f"robot_{i}", arena=self.arena, arrival=arrival_for(n), near=guard_distance(self.rules)
            )
            self.robots.append(robot)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            sensor = ObstacleSensor(i, f"obstacles_{i}", robot.update_obstacles, self.obstacles, range=CELL_RADIUS)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=SEEN)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio, range=RADIO_RANGE)
            create_timer(
                i,
                int(delays[i]),
                [
                    {"delay": ODOM_GAP, "tag": "odom", "call": odometry.update},
                    {"delay": SENSING_GAP, "tag": "obstacles", "call": sensor.update},
                    {"delay": SENSING_GAP, "tag": "movement", "call": movement.update},
                    {"delay": CONTROL_GAP, "tag": "radio", "call": radio.update},
                    {"delay": CONTROL_GAP, "tag": "robot", "call": robot.update},
                ],
            )
        self._start(n)

    def _start(self, n: int) -> None:
        """What both modes keep besides the robots: the obstacles' parts and the success counters."""
        self.static = [o for o in self.obstacles if not o.moving]
        self.sampling = 0.02 * scale_for(n)
        self.ideal = ideal_cost(n, self.arena, self.static, self.sampling)
        self.contacts, self.still = 0, 0
        self.covered_since: int | None = None

    def build_swarm(self, n: int) -> None:
        self.obstacles = thesis_obstacles(self.world.rng, self.moving_obstacles, scale_for(n))
        self.team = CoverageSwarm.start(n, len(self.obstacles))
        self.seen: dict[int, Seen] = {}
        self._start(n)

    def swarm_step(self, step: int, x: np.ndarray) -> np.ndarray:
        """Every robot's part of step ``step``, at the per-robot mode's rates (:func:`dream.timers.due`
        of each robot's timer): odometry, obstacle and robot detections, a radio round and a
        decision (:meth:`_decide`); a robot that does not decide keeps its last command."""
        team = self.team
        reading = timers.due(step, team.delays, ODOM_GAP)
        team.pose[:, reading] = x[:, reading]
        sensing = timers.due(step, team.delays, SENSING_GAP)
        team.points[sensing] = sensed(self.obstacles, x[:2, sensing].T, CELL_RADIUS)
        # Neighbour rows of the robots whose movement sensors read (a third of the team at a step);
        # who hears whom is found inside `heard_cells`, near each cell only.
        positions = x[:2].T
        self.seen[step] = Seen.read(x, team.pose, *kernels.neighbours(positions, SEEN, rows=sensing))
        self.seen.pop(step - SENSING_GAP, None)
        talking = timers.due(step, team.delays, CONTROL_GAP)
        commands = self.dxu.copy()
        if talking.any():
            who = np.flatnonzero(talking)
            said = team.board.copy()
            # The radio round: each sends where it believes itself, a moving robot where it is going.
            here = team.pose[:2, who].T
            team.board[who] = np.where(team.moving[who, None], sent(here, team.last[who]), here)
            self._decide(step, who, positions, said, commands)
        return commands

    def _decide(
        self, step: int, who: np.ndarray, positions: np.ndarray, said: np.ndarray, commands: np.ndarray
    ) -> None:
        """The decisions of robots ``who`` ``(k,)``, as :meth:`CoverageRobot.update` takes them, right
        after the radio round in which the board went from ``said`` to ``team.board`` (robots at
        ``positions`` ``(n, 2)``): their cells, bounded by the robots heard, the robots seen but not
        heard and the obstacles sensed (virtual agents), in one :func:`dream.kernels.heard_cells`
        call (a robot hears the position a robot of lower id sent in this same round, as the
        per-robot radios, which talk by id, imply), their centroids and their limited, guarded
        commands, written into ``commands`` ``(2, n)``."""
        team, k = self.team, len(who)
        here = team.pose[:2, who].T
        seen, looked = Seen.last(self.seen, step, who, team.delays[who])
        points = team.points[who].reshape(-1, 2)
        owners = np.repeat(np.arange(k), team.points.shape[1])
        agents = kernels.obstacle_agents(here[owners], points, robot_radius=GRITSBOT.radius, margin=MARGIN)
        sensed_agent = ~np.isnan(agents[:, 0])
        cells = kernels.heard_cells(
            here,
            who,
            positions,
            said,
            team.board,
            range=RADIO_RANGE,
            seen=(offsets_of(looked, k), seen),
            same=SAME_ROBOT,
            virtual=(offsets_of(owners[sensed_agent], k), agents[sensed_agent]),
            radius=CELL_RADIUS,
            bounds=cell_bounds(self.arena),
            polygons=True,
        )
        assert cells.vertices is not None and cells.offsets is not None  # polygons=True
        for i, polygon in zip(who, np.split(cells.vertices, cells.offsets[1:-1]), strict=True):
            team.cells[i] = polygon
        team.centroid[who] = cells.centroids
        carry = np.where(team.moving[who, None], MOMENTUM * (here - team.last[who]), 0.0)
        dxi = rules.approach(here, team.centroid[who], GAIN, GRITSBOT.v_max, arrival_for(self.n), carry)
        team.moving[who], team.last[who] = dxi.any(axis=1), here
        new = kernels.actuator_limit(
            halt(kernels.dxi_to_dxu(dxi.T, team.pose[:, who]), dxi), GRITSBOT.within(self.sim.spec)
        )
        near = guard_distance(self.rules)
        new[0, stopping(new[0], team.pose[2, who], looked, here[looked] - seen, near)] = 0.0
        commands[:, who] = new

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return corner_poses(n, rng, self.arena)

    def reachable_poses(self, poses: np.ndarray) -> np.ndarray:
        """Spread off the obstacles; the team must still cover the arena as well as from its packed start."""
        self.cost_packed = self.cost(poses)
        return reachable_starts(poses, self.arena, obstacles=self.obstacles)

    def steps(self, n: int) -> int:
        """1500 up to the thesis's 15 robots; beyond, 3000 times the arena's growth in side. Coming
        to rest takes longest: up to 1,680 steps at N = 100 (an arena 2.6 times the Robotarium's;
        seeds 0-9), 6,176 at N = 1,000 (8.2 times; seeds 0-2), 13,230 at 3,000 and 37,656 at
        10,000 (seed 0; caps 42,427 and 77,460)."""
        scale = scale_for(n)
        return 1500 if scale == 1.0 else math.ceil(3000 * scale)

    def timer_params(self, x: np.ndarray, dxu: np.ndarray) -> dict[str, tuple[Any, ...]]:
        return {"odom": (x,), "obstacles": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)}

    def cost(self, poses: np.ndarray) -> float:
        """The coverage cost of the team at ``poses`` ``(3, n)`` (m^4)."""
        return coverage_cost(poses[:2], self.arena, self.obstacles, self.sampling)

    def before_step(self, step: int) -> None:
        if step == 0:
            self.cost_start = self.last_cost = self.cost(self.sim.poses)

    def covers(self, cost: float) -> bool:
        """Whether a team whose coverage cost is ``cost`` covers the arena: the cost fell below
        :data:`COVERED` of its start and within :data:`SPREAD` times the ideal spread's. The
        first alone says little in a wide arena (a 1000-robot team still packed in its corner
        over most of it costs 0.2 of its start, 300 times the ideal). Before rps 2.x's start-up phase
        (:meth:`reachable_poses`) the start is the packed one the robots could not start from."""
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
        if self.swarm:
            goals, cells = self.team.centroid, self.team.cells
        else:
            goals = np.array([np.full(2, np.nan) if r.centroid is None else r.centroid for r in self.robots])
            cells = [r.cell for r in self.robots]
        return Frame(
            step,
            self.arena,
            poses,
            goals=goals.reshape(-1, 2),
            obstacles=[o.polygon for o in self.obstacles],
            obstacle_moving=[o.moving for o in self.obstacles],
            cells=cells,
            ranges={"obstacle sensing": CELL_RADIUS, "radio": 2 * CELL_RADIUS},
            title=f"{NAME}: cost {self.last_cost / self.cost_start:.0%} of its start, static contacts {self.contacts}",
        )


run = VoronoiCoverage.run
