"""Affine formation manoeuvres (thesis 3.4): followers track what three leaders do, by stress.

Seven robots: leaders 0-2 know the planned manoeuvres, followers 3-6 only the positions their
weighted neighbours send by radio. Followers obey ``p_i' = -k sum_j w_ij (p_i - p_j)`` with the
thesis's stress weights w (forward Euler, dt = their timer gap), through HRVO so that they do
not run into the leaders, who ignore them. The nominal configuration (formation units)
``(2,0), (1,1), (1,-1), (0,1), (0,-1), (-1,1), (-1,-1)`` is in stress equilibrium with w, so
the followers converge to the affine image of it that the leaders span:
``-Omega_ff^-1 Omega_fl p_leaders``.

The leaders start in their triangle at the centre, the followers at the arena's corners.
While the followers gather, the leaders stand ``SHIFT`` to the right and come back (see
:data:`SHIFT`). Then two pairs of bars sweep from right to left: for the wide gap the leaders
compress the formation, for the narrow gap they make it collinear (sheared, so that
neighbours on the line are 0.375 m apart), and after each they return to the nominal shape.
A leader moves its place from one shape to the next at a steady pace over ``MORPH`` of its
decisions, so that the leaders keep an affine image of the nominal shape on the way and the
followers, tracking it, do not cut across each other.

Success: follower error below 0.05 m before the first bars arrive, no robot touching a bar,
zero collisions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream.experiments.line_consensus import settle_or_steer
from dream.experiments.spec import Experiment
from dream.frames import Frame
from dream.obstacles import Obstacle, touching
from dream.radios import GraphRadio
from dream.robot import RobotHRVO
from dream.sensors import MovementSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, RPS, ArenaSpec
from dream.world import create_timer

NAME = "affine-formation"
LEADERS = 3
#: Stress weights from the thesis (symmetric; leaders 0-2, followers 3-6).
WEIGHTS = np.array(
    [
        [0, 0.2741, 0.2741, -0.137, -0.137, 0, 0],
        [0.2741, 0, 0, 0.5482, 0, 0, -0.137],
        [0.2741, 0, 0, 0, 0.5482, -0.137, 0],
        [-0.137, 0.5482, 0, 0, 0.0685, 0.2741, 0],
        [-0.137, 0, 0.5482, 0.0685, 0, 0, 0.2741],
        [0, 0, -0.137, 0.2741, 0, 0, 0.137],
        [0, -0.137, 0, 0, 0.2741, 0.137, 0],
    ]
)
#: The nominal configuration, in formation units.
NOMINAL = np.array([[2, 0], [1, 1], [1, -1], [0, 1], [0, -1], [-1, 1], [-1, -1]], dtype=np.float64)
SCALE = 0.3  #: metres per formation unit
GAIN = 8.0  #: the followers' stress gain k (1/s)
# The same under rps 2.1's rules, whose colliders touch at 0.185 m: with the gathering and the
# steady changes of shape below, no two robots came closer than 0.175 m (seeds 0-39, both
# rules); a safety of 0.2 m made the followers lag, and a leader, which does not avoid them,
# ran into one (rps 2.1, seed 24).
SAFETY = 0.15  #: the followers' HRVO safety radius (m): the formation's robots are 0.3 m apart
FINE = 0.03  #: below this desired speed (m/s) a follower moves without HRVO
SETTLE = 1200  #: steps for the followers to take their places before the first manoeuvre
#: How far (m) to the right the leaders stand while the followers gather from the corners, until
#: step ``GATHER``. The followers from the right-hand corners have the longer way and must pass
#: the leaders; with the formation centred, the left-hand followers, pulled towards them, got
#: there first, into the places meant for them, and walled them in beside a leader (a
#: follower and its stress neighbours then drifted round the formation: the tangles at the
#: start, and under rps 2.1 collisions with the leader). Standing closer to the right-hand
#: corners, the leaders let those followers arrive first.
SHIFT = 0.3
GATHER = 300  #: step at which the leaders return from their gathering places to the nominal ones
MORPH = 75  #: decisions (one every 4 steps: 10 s) over which a leader moves to its next place
LEAD = 600  #: steps between the leaders' change of shape and the bars' entry
RECOVER = 450  #: steps back in the nominal shape between two passes
ENTRY = 0.15  #: the bars enter and leave this far beyond the walls (m)
BAR_SPEED = 0.15  #: bars sweep leftwards at this speed (m/s)
BAR_WIDTH = 0.1  #: thickness of a bar (m)
TOLERANCE = 0.05  #: largest follower error of a formed formation (m)
GAPS = (0.55, 0.3)  #: the wide and the narrow gap between a pair of bars (m)
#: Affine maps (formation units -> formation units) the leaders use: nominal, for the wide gap
#: (compressed), for the narrow gap (collinear: ``x -> 4 a x + a y`` spaces the robots evenly,
#: 2 a = 1.25 units apart, leader 0 further; ``a = 5/6`` left two pairs 0.25 m apart, whose
#: robots met while the followers caught up with the leaders, under rps 2.1's rules in most runs).
SHAPES = {
    "nominal": np.eye(2),
    "compressed": np.diag([1.0, 0.5]),
    "collinear": np.array([[2.5, 0.625], [0.0, 0.0]]),
}


def stress_matrix(weights: np.ndarray = WEIGHTS) -> np.ndarray:
    """Omega: ``Omega_ij = -w_ij`` off the diagonal, row sums on it."""
    return np.diag(weights.sum(axis=1)) - weights


def follower_targets(leaders: np.ndarray, weights: np.ndarray = WEIGHTS) -> np.ndarray:
    """Where the followers converge for leaders at ``leaders`` ``(3, 2)``: ``-Omega_ff^-1 Omega_fl p_l``."""
    omega = stress_matrix(weights)
    return -np.linalg.solve(omega[LEADERS:, LEADERS:], omega[LEADERS:, :LEADERS] @ leaders)


def formation(shape: str) -> np.ndarray:
    """World positions ``(7, 2)`` of the formation in ``shape``, centred on the arena's centre."""
    centred = NOMINAL - NOMINAL.mean(axis=0)
    return SCALE * centred @ SHAPES[shape].T


def tile_centres(groups: int) -> np.ndarray:
    """Centres ``(groups, 2)`` of the Robotarium-sized tiles, one formation each, in a near-square grid."""
    columns = math.ceil(math.sqrt(groups))
    rows = math.ceil(groups / columns)
    k = np.arange(groups)
    return np.column_stack(
        ((k % columns - (columns - 1) / 2) * ROBOTARIUM.width, (k // columns - (rows - 1) / 2) * ROBOTARIUM.height)
    )


def tiled_arena(groups: int) -> ArenaSpec:
    """The Robotarium for one formation; for more, the grid of Robotarium-sized tiles."""
    if groups == 1:
        return ROBOTARIUM
    columns = math.ceil(math.sqrt(groups))
    return ArenaSpec.centred(columns * ROBOTARIUM.width, math.ceil(groups / columns) * ROBOTARIUM.height)


def corner_starts(rng: np.random.Generator, centres: np.ndarray | None = None) -> np.ndarray:
    """Initial poses ``(3, 7 g)``: in each tile (centred at ``centres`` ``(g, 2)``, default one tile
    at the origin), leaders in their triangle and followers in the four corners."""
    centres = np.zeros((1, 2)) if centres is None else centres
    tile = np.vstack((formation("nominal")[:LEADERS], [[1.35, 0.75], [1.35, -0.75], [-1.35, 0.75], [-1.35, -0.75]]))
    positions = np.vstack([tile + centre for centre in centres])
    return np.vstack((positions.T, rng.uniform(-math.pi, math.pi, len(positions))))


def bars(gap: float, x: float, centre: np.ndarray | None = None) -> list[Obstacle]:
    """A pair of bars at ``x`` (relative to the tile ``centre``, default the origin) leaving a gap
    of ``gap`` in the middle."""
    centre = np.zeros(2) if centre is None else centre
    height = ROBOTARIUM.ymax - gap / 2
    return [
        Obstacle(centre + (x, gap / 2 + height / 2), (BAR_WIDTH, height), velocity=(-BAR_SPEED, 0.0)),
        Obstacle(centre + (x, -gap / 2 - height / 2), (BAR_WIDTH, height), velocity=(-BAR_SPEED, 0.0)),
    ]


def follower_positions(positions: np.ndarray, leader: np.ndarray) -> np.ndarray:
    """Each formation's follower targets ``(4 g, 2)`` for robots at ``positions`` ``(7 g, 2)``."""
    groups = len(positions) // 7
    blocks = positions.reshape(groups, 7, 2)
    return np.vstack([follower_targets(block[:LEADERS]) for block in blocks])


class Leader(RobotHRVO):
    """A leader: goes to its place in the planned shape; ignores the followers.

    A new place (:meth:`head_for`) is not taken at once: the leader's aim moves from the old
    place to the new one at a steady pace over its next ``MORPH`` decisions (its own clock), so
    the three leaders, which all plan the same shapes, stay (nearly) an affine image of the
    nominal shape while they change it, and the followers keep up with them.
    """

    def __init__(self, robot_id: int, tag: str, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.goal = formation("nominal")[robot_id % 7]
        self.start = self.goal  # the place the leader's aim left from
        self.decisions = MORPH  # decisions since then

    def head_for(self, place: np.ndarray) -> None:
        """Move the aim from where it is now to ``place`` ``(2,)`` (m) over the next ``MORPH`` decisions."""
        self.start, self.goal, self.decisions = self.aim, np.asarray(place, dtype=np.float64), 0

    @property
    def aim(self) -> np.ndarray:
        """The point ``(2,)`` (m) the leader heads for now, on its way from ``start`` to ``goal``."""
        return self.start + min(self.decisions / MORPH, 1.0) * (self.goal - self.start)

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update(self, dxu: np.ndarray) -> None:
        self.decisions += 1
        desired = np.zeros(2)
        if self.has_pose:
            desired = 1.5 * (self.aim - (self.pos_x, self.pos_y))
            speed = math.hypot(desired[0], desired[1])
            if speed > self.v_max:
                desired *= self.v_max / speed
        self.HRVO(np.zeros((0, 4)), desired)
        self.command(dxu)


class Follower(RobotHRVO):
    """A follower: the stress control law on the positions received by radio, through HRVO."""

    def __init__(self, robot_id: int, tag: str, weights: np.ndarray = WEIGHTS, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.weights = weights[robot_id]
        self.heard: dict[int, np.ndarray] = {}

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        for j, x, y in messages:
            self.heard[j] = np.array([x, y])
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update(self, dxu: np.ndarray) -> None:
        desired = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            pull = sum((self.weights[j] * (here - there) for j, there in self.heard.items()), np.zeros(2))
            desired = -GAIN * pull
            speed = math.hypot(desired[0], desired[1])
            if speed > self.v_max:
                desired *= self.v_max / speed
        # Close to its place (the formation keeps robots >= 0.25 m apart) HRVO would forbid the
        # last centimetres towards a neighbour. The thesis's followers check no clearance.
        settle_or_steer(self, desired, FINE, clearance=0.0)
        self.command(dxu)


def schedule() -> list[tuple[int, int, int, str, float]]:
    """The two bar passes as ``(deform, enter, leave, shape, gap)`` steps: the leaders take the
    shape at ``deform``, the bars enter at the right wall at ``enter`` and have left at the left
    wall at ``leave``, when the leaders return to the nominal shape."""
    crossing = round((ROBOTARIUM.width + 2 * ENTRY) / (BAR_SPEED * RPS.time_step))
    passes, t = [], SETTLE
    for shape, gap in zip(("compressed", "collinear"), GAPS):
        passes.append((t, t + LEAD, t + LEAD + crossing, shape, gap))
        t += LEAD + crossing + RECOVER
    return passes


class AffineFormation(Experiment):
    """The affine-formation experiment (see the module docs).

    ``n`` is 7 (the thesis's formation) or a multiple of 7: then each group of seven has its
    own Robotarium-sized tile of a larger arena, its own bars and the same manoeuvres.
    """

    name = NAME
    default_n = 7
    success = (
        "follower error below 0.05 m before the first bars, no robot touching a bar, zero violations, "
        "through both passes and back to the nominal shape"
    )

    def check(self, n: int, backend: str) -> None:
        if n % 7:
            raise ValueError(
                "the affine formation has 7 robots (3 leaders, 4 followers) per group: "
                f"n must be a multiple of 7, got n={n}"
            )

    def arena_for(self, n: int) -> ArenaSpec:
        return tiled_arena(n // 7)

    def build(self, n: int) -> None:
        self.centres = tile_centres(n // 7)
        self.weights = np.kron(np.eye(n // 7), WEIGHTS)
        self.leader = np.arange(n) % 7 < LEADERS
        self.passes = schedule()
        adjacency = (self.weights != 0).astype(float)
        for i in range(n):
            robot: Leader | Follower
            if self.leader[i]:
                robot = Leader(i, f"leader_{i}", arena=self.arena)
                robot.goal = robot.start = formation("nominal")[i % 7] + self.centres[i // 7]
                robot.head_for(robot.goal + (SHIFT, 0.0))
            else:
                robot = Follower(i, f"follower_{i}", self.weights, safety=SAFETY, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            radio = GraphRadio(i, f"radio_{i}", robot.update_radio, adjacency)
            entries = [
                {"delay": 2, "tag": "odom", "call": odometry.update},
                {"delay": 4, "tag": "radio", "call": radio.update},
                {"delay": 4, "tag": "robot", "call": robot.update},
            ]
            if isinstance(robot, Follower):
                movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=0.6)
                entries.insert(1, {"delay": 3, "tag": "movement", "call": movement.update})
            create_timer(i, 10 + i % 7, entries)
            self.robots.append(robot)
        self.bars: list[Obstacle] = []
        self.contacts, self.settled_error, self.deformed_error, self.error = 0, math.nan, 0.0, math.nan

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return corner_starts(rng, self.centres)

    def steps(self, n: int) -> int:
        """Until 30 s after the last bars have left."""
        return self.passes[-1][2] + 2 * RECOVER

    def before_step(self, step: int) -> None:
        if step == GATHER:
            self._lead("nominal")
        for deform, enter, leave, shape, gap in self.passes:
            if step in (deform, leave):
                self._lead(shape if step == deform else "nominal")
            if step == enter:
                self.bars = [bar for centre in self.centres for bar in bars(gap, ROBOTARIUM.xmax + ENTRY, centre)]
            if step == leave:
                self.bars = []

    def _lead(self, shape: str) -> None:
        """Send every leader towards its place in ``shape`` (the leaders know the plan)."""
        for robot in self.robots:
            if isinstance(robot, Leader):
                robot.head_for(formation(shape)[robot.robot_id % 7] + self.centres[robot.robot_id // 7])

    def after_step(self, step: int, poses: np.ndarray) -> None:
        for bar in self.bars:
            bar.step(self.sim.time_step)
        self.targets = follower_positions(poses[:2].T, self.leader)
        self.error = float(np.linalg.norm(poses[:2, ~self.leader].T - self.targets, axis=1).max())
        if step == self.passes[0][0]:
            self.settled_error = self.error
        if self.bars:
            self.deformed_error = max(self.deformed_error, self.error)
            self.contacts += bool(touching(self.bars, poses[:2].T, GRITSBOT.radius).any())

    def done(self, step: int, poses: np.ndarray) -> bool:
        return step >= self.steps(self.n) and self.contacts == 0 and self.settled_error < TOLERANCE

    def measures(self) -> dict[str, Any]:
        """The followers' error to their affine target just before the first bars set off and at
        the end (m, largest over the formations), the iterations in which a robot touched a bar,
        and the largest error while bars are on the arena."""
        return {
            "error_before_bars": self.settled_error,
            "error_end": self.error,
            "error_while_deformed": self.deformed_error,
            "bar_contacts": self.contacts,
        }

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        goals = np.zeros((self.n, 2))
        goals[self.leader] = [r.goal for r in self.robots if isinstance(r, Leader)]
        goals[~self.leader] = self.targets
        return Frame(
            step,
            self.arena,
            poses,
            goals=goals,
            velocities=np.array([r.dxi for r in self.robots]),
            links=np.argwhere(np.triu(self.weights) != 0),
            obstacles=[bar.polygon for bar in self.bars],
            obstacle_moving=[True] * len(self.bars),
            roles=np.where(self.leader, "leader", "follower"),
            title=f"{NAME}: follower error {self.error:.3f} m, bar contacts {self.contacts}",
        )


run = AffineFormation.run
