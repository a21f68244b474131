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

Under faults (:mod:`dream.faults`) success is the same for the correct robots, in the formation
of the survivors: the followers' error is that of the correct followers, to the affine image that
the leaders span, a crashed leader counting at its place in the plan (where the surviving
leaders have it); bar contacts are those of the correct robots (a crashed robot is an obstacle
where it stopped, which the bars sweep through); every collision counts, with the crashed
robots too. Each robot decides from its own radio, sensors and clock:

- Every robot hears its whole formation (the law still uses the weighted neighbours only) and
  keeps a heartbeat failure detector (:class:`~dream.heartbeats.Heartbeats`).
- A crash: the leaders send, with their position, where the plan has the other leaders now;
  the followers put that in the law for a leader taken for crashed, and for a crashed follower
  its place in the affine image of the nominal shape that the leaders span, so the survivors
  keep the planned formation with one place empty. The leaders, who ignore the followers, steer
  clear of the robots taken for crashed (movement sensor) and shift the formation along the
  bars' way (x) until no survivor's place lies within :data:`CLEAR` of one.
- A liar (its radio values replaced by an adversary's): a follower checks every claimed position
  within reach of its movement sensor (:data:`VERIFY`), and every claim against where a correct
  robot can be (its formation's tile; for a leader, within :data:`PLAN_SLACK` of the other
  leaders' plans for it); a robot whose claims match no robot seen or no such place (or, when
  the follower sees close by a robot that no claim accounts for, the one robot whose claim lies
  out of its sight) :data:`STRIKES` decisions in a row is taken for a liar, its radio
  values are ignored from then on, and the follower puts in the law where it sees it (the one
  robot seen that no other claim accounts for), or, out of sight, its place in the plan (a
  leader) or in the affine image.
  The liar itself moves as a correct robot (it decides from true inputs) but is not judged.

Without faults every decision is as before: runs are the same to the last bit.

Swarm mode (``swarm=True``, :meth:`AffineFormation.swarm_step`) runs the same leaders and followers
on arrays (:class:`AffineSwarm`), for thousands of formations: each robot at its own timer's steps
(:func:`dream.timers.due`), radio rounds in which a robot hears the position a robot of lower id
sent in that very step (the per-robot timers run by id), the same rules (:func:`morph` and
:func:`dream.rules.toward` for the leaders; :func:`dream.rules.stress`, :func:`dream.rules.capped`,
settling and stepping aside for the followers; the motion guard) and one HRVO call for the robots
deciding in a step, in the per-robot mode's order (:mod:`dream.experiments.sightings`). The
trajectories equal the per-robot mode's to the bit (the tests compare whole runs). It has no
failure detector and no claim checks, and no radio or sensor model to lose, delay or corrupt
messages and readings: it takes the faults of the wheels only (``stuck``, ``actuator_noise``,
which reach it as they reach the robots) and refuses the others (crash, byzantine, radio, sensor
and clock faults) with the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from dream import rules, timers
from dream._checks import Bounds
from dream.experiments.sightings import Nearby, Sight, decide_in_order, last_detections
from dream.experiments.spec import Experiment
from dream.frames import Frame
from dream.heartbeats import Heartbeats
from dream.obstacles import Fleet, Obstacle
from dream.radios import GraphRadio
from dream.robot import SIDESTEP_UPDATES, RobotHRVO
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
LEADER_GAIN = 1.5  #: a leader's gain towards its aim (1/s)
# The same under rps 2.1's rules, whose colliders touch at 0.185 m: with the gathering and the
# steady changes of shape below, no two robots came closer than 0.175 m (seeds 0-39, both
# rules); a safety of 0.2 m made the followers lag, and a leader, which does not avoid them,
# ran into one (rps 2.1, seed 24).
SAFETY = 0.15  #: the followers' HRVO safety radius (m): the formation's robots are 0.3 m apart
FINE = 0.03  #: below this desired speed (m/s) a follower moves without HRVO
RANGE = 0.6  #: robots within this distance (m) are the ones a follower's HRVO avoids
VERIFY = 1.0  #: a follower's movement sensor sees this far (m), to check claimed positions
MATCH = 0.15  #: a claimed position this close (m) to a robot seen matches it (radio lag, latency)
STRIKES = 3  #: decisions in a row whose claims match no robot seen make a liar
PLAN_SLACK = 0.5  #: a leader claiming to be this far (m) from every place the other leaders plan for it lies
SILENCE = 20  #: radio rounds without a heartbeat after which a robot is taken for crashed
#: A place closer than this (m) to a crashed robot is taken: the follower's HRVO (safety 0.15 m)
#: would keep it off. The leaders then shift the formation along the bars' way (x) until no
#: survivor's place is, within the tile less ``WALL`` (m).
CLEAR = 0.2
WALL = 0.15
START_DELAY = 10  #: start-up delay of robot i's timer: this plus its place in its formation (i % 7) steps
#: Steps between a robot's odometry readings, its detections, and its radio rounds and decisions.
ODOM_GAP, MOVEMENT_GAP, CONTROL_GAP = 2, 3, 4
#: The faults a swarm takes (see :meth:`AffineFormation.swarm_step`): those of the wheels alone.
SWARM_FAULTS = frozenset({"stuck", "stuck_at", "actuator_noise"})
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
    """Where the followers converge ``(..., 4, 2)`` for leaders at ``leaders`` ``(..., 3, 2)`` (one
    formation, or a stack of them): ``-Omega_ff^-1 Omega_fl p_l``."""
    omega = stress_matrix(weights)
    pulled = omega[LEADERS:, :LEADERS] @ leaders
    return -np.linalg.solve(np.broadcast_to(omega[LEADERS:, LEADERS:], (*pulled.shape[:-2], 4, 4)), pulled)


def morph(start: np.ndarray, goals: np.ndarray, decisions: Any) -> np.ndarray:
    """Where leaders' aims stand after ``decisions`` ``(k,)`` or ``()`` of their ``MORPH`` decisions
    from the places ``start`` to ``goals`` ``(k, 2)`` (m): a steady pace along straight lines."""
    return start + np.minimum(np.asarray(decisions) / MORPH, 1.0)[..., None] * (goals - start)


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


def tile_bounds(centre: np.ndarray) -> Bounds:
    """``(xmin, xmax, ymin, ymax)`` of the Robotarium-sized tile centred at ``centre`` ``(2,)`` (m)."""
    (x, y), half_width, half_height = centre, ROBOTARIUM.width / 2, ROBOTARIUM.height / 2
    return (float(x - half_width), float(x + half_width), float(y - half_height), float(y + half_height))


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


def follower_positions(anchors: np.ndarray) -> np.ndarray:
    """Each formation's follower targets ``(4 g, 2)`` for leaders at ``anchors`` ``(7 g, 2)`` (rows
    of followers unused)."""
    return follower_targets(anchors.reshape(-1, 7, 2)[:, :LEADERS]).reshape(-1, 2)


def affine_image(known: dict[int, np.ndarray], indices: list[int]) -> dict[int, np.ndarray]:
    """Where robots ``indices`` (0-6) belong ``{index: (2,)}`` in the affine image of the nominal
    configuration that the robots ``known`` ``{index: (2,)}`` span: from the three leaders when
    known (three points fix the map), else the least-squares fit to all known (none when those
    do not fix it)."""
    base = {k: known[k] for k in range(LEADERS)} if all(k in known for k in range(LEADERS)) else known
    rows = list(base)
    nominal = np.column_stack((NOMINAL[rows], np.ones(len(rows))))
    if np.linalg.matrix_rank(nominal) < 3:
        return {}
    fit = np.linalg.lstsq(nominal, np.array([base[k] for k in rows]), rcond=None)[0]
    return {k: np.append(NOMINAL[k], 1.0) @ fit for k in indices}


def clearing_shift(places: np.ndarray, crashed: np.ndarray, centre: float) -> float:
    """The shift along x (m) of least size that leaves every place of ``places`` ``(k, 2)`` at least
    :data:`CLEAR` from every crashed robot at ``crashed`` ``(m, 2)`` and within the tile centred at
    x = ``centre`` (less :data:`WALL`); 0 when none does."""
    room = ROBOTARIUM.width / 2 - WALL
    shifts = [0.0]
    for dx, dy in (crashed[:, None, :] - places[None, :, :]).reshape(-1, 2):
        if abs(dy) < CLEAR:
            half = math.sqrt(CLEAR**2 - dy**2)
            shifts += [dx - half, dx + half]
    for shift in sorted(shifts, key=abs):
        x = places[:, 0] + shift
        clear = (
            not len(crashed) or np.hypot(*(crashed[:, None, :] - places[None] - (shift, 0.0)).T).min() >= CLEAR - 1e-9
        )
        if clear and x.min() >= centre - room and x.max() <= centre + room:
            return shift
    return 0.0


#: A robot's radio message: its id, position (m), the heartbeats it knows of its formation and
#: (leaders only) where the plan has the other leaders head now, ``{id: (x, y)}``.
Message = tuple[int, float, float, tuple[int, ...], dict[int, tuple[float, float]]]


class Leader(RobotHRVO):
    """A leader: goes to its place in the planned shape; ignores the followers.

    A new shape (:meth:`head_for`) is not taken at once: the aims of the formation's three
    leaders move from the old places to the new ones at a steady pace over the leader's next
    ``MORPH`` decisions (its own clock), so the three leaders, which all plan the same shapes,
    stay (nearly) an affine image of the nominal shape while they change it, and the followers
    keep up with them. A leader knows where the plan puts every leader and sends the other
    leaders' aims with its position: a follower puts them in the law for a leader that has
    crashed or lies out of its sight, so the formation keeps three leaders. A leader steers
    clear of the robots it takes for crashed, which stand where they stopped (it sees them with
    its movement sensor); it ignores the others.
    """

    def __init__(self, robot_id: int, tag: str, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.index = robot_id % 7  # its place in its formation
        self.goals = formation("nominal")[:LEADERS]  # the planned places of its formation's leaders
        self.start = self.goals  # the places the aims left from
        self.decisions = MORPH  # decisions since then
        self.heartbeats = Heartbeats(7, self.index, SILENCE)
        self.heard: dict[int, np.ndarray] = {}  # the last position heard from each robot of its formation
        self.silent: list[int] = []  # the robots it takes for crashed
        self.plan = formation("nominal")  # the planned formation's places (7, 2) (m)
        self.shift = 0.0  # how far (m) along x it shifts them clear of crashed robots
        self.sensor: MovementSensor | None = None  # its movement sensor, read by `watch`

    @property
    def goal(self) -> np.ndarray:
        """Its own planned place ``(2,)`` (m)."""
        return self.goals[self.index]

    def head_for(self, places: np.ndarray) -> None:
        """Move the aims from where they are now to the leaders' places of the planned formation
        ``places`` ``(7, 2)`` (m), shifted clear of the robots taken for crashed (:func:`clearing_shift`),
        over the next ``MORPH`` decisions."""
        self.plan = np.asarray(places, dtype=np.float64)
        self.shift = self.clearing()
        self.start, self.goals, self.decisions = self.aims, self.plan[:LEADERS] + (self.shift, 0.0), 0

    def clearing(self) -> float:
        """The shift (m) along x of the plan clear of the robots taken for crashed (:func:`clearing_shift`)."""
        survivors = np.ones(7, dtype=bool)
        survivors[[j % 7 for j in self.silent]] = False
        crashed = np.array([self.heard[j] for j in self.silent]).reshape(-1, 2)
        return clearing_shift(self.plan[survivors], crashed, self.plan.mean(axis=0)[0])

    @property
    def aims(self) -> np.ndarray:
        """The points ``(3, 2)`` (m) the plan has the formation's leaders head for now."""
        return morph(self.start, self.goals, self.decisions)

    @property
    def aim(self) -> np.ndarray:
        """The point ``(2,)`` (m) this leader heads for now."""
        return self.aims[self.index]

    def update_radio(self, messages: list[Message]) -> Message | None:
        self.heartbeats.round([beats for _, _, _, beats, _ in messages])
        for j, x, y, _, _ in messages:
            self.heard[j] = np.array([x, y])
        alive = self.heartbeats.alive
        silent = [j for j in self.heard if not alive[j % 7]]
        if silent != self.silent:
            self.silent = silent
            if self.clearing() != self.shift:  # else the aims keep their pace
                self.head_for(self.plan)
        first = self.robot_id - self.index
        plan = {first + k: (float(x), float(y)) for k, (x, y) in enumerate(self.aims) if k != self.index}
        return (self.robot_id, self.pos_x, self.pos_y, self.heartbeats.sent(), plan) if self.has_pose else None

    def watch(self, x: Any, v: Any) -> None:
        """The movement sensor's timer call (poses ``x``, commands ``v``): a leader reads its sensor
        only while it takes some robot for crashed, the only robots it avoids."""
        if self.silent and self.sensor is not None:
            self.sensor.update(x, v)
        else:
            self.detections = self.detections[:0]

    def update_sensor(self, detections: Any) -> None:
        """Keep the detections of robots taken for crashed (where they were heard last)."""
        rows = np.asarray(detections, dtype=np.float64).reshape(-1, 4)
        if self.silent and self.has_pose:
            crashed = np.array([self.heard[j] for j in self.silent])
            self.detections = rows[
                ~rules.far_from(rules.seen_positions((self.pos_x, self.pos_y), rows), crashed, MATCH)
            ]
        else:
            self.detections = rows[:0]

    def update(self, dxu: np.ndarray) -> None:
        self.decisions += 1
        desired = np.zeros(2)
        if self.has_pose:
            desired = rules.toward((self.pos_x, self.pos_y), self.aim, LEADER_GAIN, self.v_max)
        self.HRVO(self.detections, desired)
        self.command(dxu)


class Follower(RobotHRVO):
    """A follower: the stress control law on the positions received by radio, through HRVO.

    It hears every robot of its formation and keeps a heartbeat failure detector. In the law
    it puts, for a neighbour it takes for crashed, the leader's place in the plan (sent by the
    other leaders) or, for a follower, its place in the affine image of the nominal shape that
    the leaders span. It checks every claimed position within reach of its movement sensor: a
    robot blamed :data:`STRIKES` decisions in a row (:meth:`check_claims`) is taken for a liar;
    from then on its radio values are ignored, and the follower uses where it sees it
    (the one robot it sees that no other claim accounts for), else, out of sight, its place in
    the plan (a leader) or in the affine image (a follower).
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        weights: np.ndarray = WEIGHTS,
        tile: Bounds | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.weights = weights[robot_id]
        self.tile = tile  # its formation's tile, which none leaves (None: its arena)
        self.first = robot_id - robot_id % 7  # the first robot of its formation
        self.heard: dict[int, np.ndarray] = {}  # the last position each robot of its formation claimed
        self.plans: dict[int, dict[int, tuple[float, float]]] = {}  # each leader's last word on the others' places
        self.heartbeats = Heartbeats(7, robot_id % 7, SILENCE)
        self.seen = np.zeros((0, 2))  # robots detected within VERIFY (m)
        self.strikes: dict[int, int] = {}  # decisions in a row in which a robot's claim matched nothing seen
        self.liars: dict[int, np.ndarray | None] = {}  # robots taken for liars, and where last seen
        self.sensed: dict[int, np.ndarray] = {}  # where it sees liars at this decision

    def update_radio(self, messages: list[Message]) -> Message | None:
        self.heartbeats.round([beats for _, _, _, beats, _ in messages])
        for j, x, y, _, plan in messages:
            self.heard[j] = np.array([x, y])
            if plan:
                self.plans[j] = plan
        return (self.robot_id, self.pos_x, self.pos_y, self.heartbeats.sent(), {}) if self.has_pose else None

    def update_sensor(self, detections: Any) -> None:
        """HRVO avoids the robots within ``RANGE``; claims are checked against all detected."""
        rows = np.asarray(detections, dtype=np.float64).reshape(-1, 4)
        self.detections = rows[rows[:, 0] <= RANGE]
        seen = rules.seen_positions((self.pos_x, self.pos_y), rows)
        # Robots beyond its tile belong to other formations: neither claimed nor liars.
        self.seen = seen[self.in_tile(seen)]

    def check_claims(self, here: np.ndarray) -> None:
        """Take for a liar a robot blamed :data:`STRIKES` decisions in a row; find the liars among
        the robots seen now.

        Blamed: a robot whose claimed position, close enough to be checked, matches no robot seen;
        else, when it sees within ``RANGE`` a robot that no claim accounts for, the one robot whose
        claim lies out of its sight, if only one does (a liar that claims to be far away).
        """
        trusted = [j for j in self.heard if j not in self.liars]
        claims = np.array([self.heard[j] for j in trusted]).reshape(-1, 2)
        checkable = np.hypot(*(claims - here).T) < VERIFY - MATCH
        missed = (checkable & rules.far_from(claims, self.seen, MATCH)) | self.implausible(trusted, claims)
        if not missed.any() and (~checkable).sum() == 1 and all(last is not None for last in self.liars.values()):
            # Robots seen nearby that neither a claim nor a liar found before accounts for.
            accounted = np.vstack([claims, *(p for p in self.liars.values() if p is not None)])
            near = np.hypot(*(self.seen - here).T) <= RANGE
            if (near & rules.far_from(self.seen, accounted, MATCH)).any():
                missed = ~checkable
        for j, blamed in zip(trusted, missed):
            self.strikes[j] = self.strikes.get(j, 0) + 1 if blamed else 0
            if self.strikes[j] >= STRIKES:
                self.liars[j] = None
        self.sensed = {}
        if not self.liars:
            return
        claims = np.array([claim for j, claim in self.heard.items() if j not in self.liars]).reshape(-1, 2)
        unclaimed_seen = self.seen[rules.far_from(self.seen, claims, MATCH)]
        for j, last in self.liars.items():
            if last is None and len(unclaimed_seen) == 1 and len(self.liars) == 1:
                self.liars[j] = self.sensed[j] = unclaimed_seen[0]
            elif last is not None and len(unclaimed_seen):
                gaps = np.hypot(*(unclaimed_seen - last).T)
                if gaps.min() < 2 * MATCH:  # the same robot, moved on a little
                    self.liars[j] = self.sensed[j] = unclaimed_seen[np.argmin(gaps)]

    def in_tile(self, points: np.ndarray) -> np.ndarray:
        """Which ``points`` ``(k, 2)`` (m) lie in its formation's tile, give or take :data:`MATCH`
        (claims lag; a robot of the next formation that close to the edge passes too)."""
        xmin, xmax, ymin, ymax = self.arena.bounds if self.tile is None else self.tile
        x, y = np.reshape(points, (-1, 2)).T
        return (x >= xmin - MATCH) & (x <= xmax + MATCH) & (y >= ymin - MATCH) & (y <= ymax + MATCH)

    def living_plans(self) -> list[dict[int, tuple[float, float]]]:
        """The last plans of the leaders it takes for neither crashed nor liars."""
        alive = self.heartbeats.alive
        return [plan for j, plan in self.plans.items() if alive[j % 7] and j not in self.liars]

    def implausible(self, ids: list[int], claims: np.ndarray) -> np.ndarray:
        """Which ``claims`` ``(k, 2)`` of robots ``ids`` no correct robot makes, seen or not: a place
        outside the formation's tile, or a living leader's place :data:`PLAN_SLACK` from every place
        the other (correct, living) leaders' plans give it.

        Only claims within sight can be checked against the sensor, and a liar that claims a
        place metres away defeated every seed at N = 98 (seed 0: a leader claimed the arena's
        centre, three tiles off; the followers followed it). One liar among three leaders
        cannot outvote two: a correct leader agrees with the other correct one's plan."""
        out = ~self.in_tile(claims)
        alive, plans = self.heartbeats.alive, self.living_plans()
        for row, j in enumerate(ids):
            places = [plan[j] for plan in plans if j in plan]
            # A crashed leader stands where it stopped, off the plan that moves on.
            if places and alive[j % 7]:
                out[row] |= bool(rules.far_from(claims[row], places, PLAN_SLACK)[0])
        return out

    def positions(self) -> dict[int, np.ndarray]:
        """Where it takes the robots of its formation to be ``{id: (2,)}`` (m), for the law: what
        they claim; liars where it sees them; crashed leaders, and lying ones out of sight, where
        the plan has them (the correct leaders say); the others (crashed followers, lying ones
        out of sight) at their places in the affine image of the nominal shape that the rest span."""
        alive = self.heartbeats.alive
        planned = {k: np.array(place) for plan in self.living_plans() for k, place in plan.items()}
        known: dict[int, np.ndarray] = {}
        for j, claim in self.heard.items():
            if j in self.liars:
                if j in self.sensed:
                    known[j] = self.sensed[j]
                elif j in planned:
                    known[j] = planned[j]
            elif alive[j % 7]:
                known[j] = claim
            elif j % 7 < LEADERS:
                known[j] = planned.get(j, claim)  # a crashed robot stands where it last said
        unknown = [j for j in self.heard if j not in known]
        if unknown:
            image = affine_image({j % 7: p for j, p in known.items()}, [j % 7 for j in unknown])
            for j in unknown:
                if j % 7 in image:
                    known[j] = image[j % 7]
                elif j not in self.liars:
                    known[j] = self.heard[j]  # too few to span the image: where it last said
        return known

    def update(self, dxu: np.ndarray) -> None:
        desired = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            self.check_claims(here)
            known = self.positions()
            there = np.array(list(known.values())).reshape(-1, 2)
            desired = rules.capped(-GAIN * rules.stress(here, there, self.weights[list(known)]), self.v_max)
        # Close to its place (the formation keeps robots >= 0.25 m apart) HRVO would forbid the
        # last centimetres towards a neighbour. The thesis's followers check no clearance.
        self.settle_or_steer(desired, FINE, clearance=0.0)
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


def tile_places(robots: np.ndarray, shape: str, centres: np.ndarray) -> np.ndarray:
    """The places ``(k, 2)`` (m) of ``robots`` ``(k,)`` (ids) in ``shape`` about their tiles' ``centres``
    ``(g, 2)``, as the per-robot leaders compute them (the formation, then the tile's centre)."""
    return formation(shape)[robots % 7] + centres[robots // 7]


def start_delays(n: int) -> np.ndarray:
    """Start-up delays ``(n,)`` of the robots' timers (steps): staggered by the place in the formation."""
    return START_DELAY + np.arange(n) % 7


@dataclass
class AffineSwarm:
    """Every robot's state in swarm mode, one row or column each (see :meth:`AffineFormation.swarm_step`).

    Attributes
    ----------
    delays : (n,) int ndarray
        Start-up delay of each robot's timer (steps), as in the per-robot mode.
    leader : (n,) bool ndarray
        Who leads (places 0-2 of each formation).
    pose : (3, n) ndarray
        Each robot's last odometry reading (NaN before the first).
    board : (n, 2) ndarray
        The radio board: the position each robot sent last (m; NaN before it first spoke).
    dxi : (n, 2) ndarray
        The velocities chosen last (m/s).
    sidestep, side : (n,) ndarrays
        A follower's decisions left stepping aside, and to which side (see :meth:`~dream.RobotHRVO.steer`).
    origin, goal : (n, 2) ndarrays
        A leader's aim moves from ``origin`` to ``goal`` (m) over ``MORPH`` decisions (:func:`morph`;
        rows of followers unused).
    decisions : (n,) int ndarray
        A leader's decisions since it took its goal.
    """

    delays: np.ndarray
    leader: np.ndarray
    pose: np.ndarray
    board: np.ndarray
    dxi: np.ndarray
    sidestep: np.ndarray
    side: np.ndarray
    origin: np.ndarray
    goal: np.ndarray
    decisions: np.ndarray

    @classmethod
    def start(cls, n: int, centres: np.ndarray) -> AffineSwarm:
        """``n`` robots that know nothing yet, in the tiles centred at ``centres`` ``(n / 7, 2)``, the
        leaders heading for their gathering places (as :meth:`AffineFormation.build` sets them)."""
        leader = np.arange(n) % 7 < LEADERS
        leaders = np.flatnonzero(leader)
        team = cls(
            delays=start_delays(n),
            leader=leader,
            pose=np.full((3, n), np.nan),
            board=np.full((n, 2), np.nan),
            dxi=np.zeros((n, 2)),
            sidestep=np.zeros(n, dtype=np.int64),
            side=np.ones(n),
            origin=np.zeros((n, 2)),
            goal=np.zeros((n, 2)),
            decisions=np.full(n, MORPH, dtype=np.int64),
        )
        team.goal[leaders] = team.origin[leaders] = tile_places(leaders, "nominal", centres)
        team.head_for(team.goal[leaders] + (SHIFT, 0.0))
        return team

    def head_for(self, places: np.ndarray) -> None:
        """:meth:`Leader.head_for` for every leader: its aim moves from where it is now to its place
        ``places`` ``(g * 3, 2)`` (m, by id) over its next ``MORPH`` decisions."""
        leaders = np.flatnonzero(self.leader)
        self.origin[leaders] = morph(self.origin[leaders], self.goal[leaders], self.decisions[leaders])
        self.goal[leaders] = places
        self.decisions[leaders] = 0


class AffineFormation(Experiment):
    """The affine-formation experiment (see the module docs).

    ``n`` is 7 (the thesis's formation) or a multiple of 7: then each group of seven has its
    own Robotarium-sized tile of a larger arena, its own bars and the same manoeuvres.
    """

    name = NAME
    default_n = 7
    has_swarm_mode = True
    success = (
        "follower error below 0.05 m before the first bars, no robot touching a bar, zero violations, "
        "through both passes and back to the nominal shape; under faults, the correct robots hold the "
        "formation of the survivors (a crashed leader counts at its planned place), no correct robot "
        "touches a bar, and a crashed robot is an obstacle where it stopped (collisions with it count)"
    )

    def check(self, n: int, backend: str) -> None:
        if n % 7:
            raise ValueError(
                "the affine formation has 7 robots (3 leaders, 4 followers) per group: "
                f"n must be a multiple of 7, got n={n}"
            )

    def arena_for(self, n: int) -> ArenaSpec:
        return tiled_arena(n // 7)

    def _prepare(self, n: int) -> None:
        """What both modes keep: the tiles, who leads, the passes, the bars and the measures."""
        self.centres = tile_centres(n // 7)
        self.leader = np.arange(n) % 7 < LEADERS
        self.passes = schedule()
        self.bars = Fleet()
        self.contacts, self.settled_error, self.deformed_error, self.error = 0, math.nan, 0.0, math.nan

    def build(self, n: int) -> None:
        self._prepare(n)
        self.weights = np.kron(np.eye(n // 7), WEIGHTS)
        delays = start_delays(n)
        # Every robot hears its whole formation (the law uses the weighted neighbours only): the
        # heartbeats, the leaders' plans and the claims a follower checks come from all.
        adjacency = np.kron(np.eye(n // 7), np.ones((7, 7)))
        for i in range(n):
            robot: Leader | Follower
            if self.leader[i]:
                robot = Leader(i, f"leader_{i}", safety=SAFETY, arena=self.arena)
                robot.plan = formation("nominal") + self.centres[i // 7]
                robot.goals = robot.start = robot.plan[:LEADERS]
                robot.head_for(robot.plan + (SHIFT, 0.0))
            else:
                robot = Follower(
                    i, f"follower_{i}", self.weights, tile_bounds(self.centres[i // 7]), safety=SAFETY, arena=self.arena
                )
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            radio = GraphRadio(i, f"radio_{i}", robot.update_radio, adjacency)
            # One range for all, so that the world builds one neighbour index per step.
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=VERIFY)
            look = movement.update
            if isinstance(robot, Leader):
                robot.sensor, look = movement, robot.watch
            entries = [
                {"delay": ODOM_GAP, "tag": "odom", "call": odometry.update},
                {"delay": MOVEMENT_GAP, "tag": "movement", "call": look},
                {"delay": CONTROL_GAP, "tag": "radio", "call": radio.update},
                {"delay": CONTROL_GAP, "tag": "robot", "call": robot.update},
            ]
            create_timer(i, int(delays[i]), entries)
            self.robots.append(robot)

    def build_swarm(self, n: int) -> None:
        self._prepare(n)
        self.team = AffineSwarm.start(n, self.centres)
        self.bounds = self.arena.shrunk(GRITSBOT.radius)
        self.sights: dict[int, Sight] = {}

    def swarm_step(self, step: int, x: np.ndarray) -> np.ndarray:
        """Every robot's part of step ``step``, at the per-robot mode's rates (:func:`dream.timers.due`
        of each robot's timer): odometry, the followers' movement sensors, a radio round
        (:meth:`_talk`) and a decision (:meth:`_decide`); a robot that does not decide keeps its last
        command."""
        team = self.team
        if step == 0:
            self._refuse_faults()
            self.nearby = Nearby(RANGE, GRITSBOT.within(self.sim.spec).v_max, self.sim.time_step)
        # What the followers' movement sensors see (the leaders read theirs only to avoid crashed
        # robots): the poses, the commands before this step's decisions, who is within RANGE.
        looking = np.flatnonzero(timers.due(step, team.delays, MOVEMENT_GAP) & ~team.leader)
        self.sights[step] = Sight(x, self.dxu.copy(), *self.nearby.rows(step, x, looking))
        self.sights.pop(step - MOVEMENT_GAP, None)
        reading = timers.due(step, team.delays, ODOM_GAP)
        team.pose[:, reading] = x[:, reading]
        # The radio and the controller share their gap and start: a robot talks, then decides.
        deciding = np.flatnonzero(timers.due(step, team.delays, CONTROL_GAP))
        commands = self.dxu.copy()
        if len(deciding):
            self._decide(step, deciding, self._talk(deciding), commands)
        return commands

    def _refuse_faults(self) -> None:
        """Refuse faults other than the wheels' (:data:`SWARM_FAULTS`), saying why."""
        state = self.world.fault_state
        others = sorted(set(state.faults.to_dict()) - SWARM_FAULTS) if state is not None else []
        if others:
            raise ValueError(
                f"affine-formation's swarm mode takes faults of the wheels only (stuck, actuator_noise), got "
                f"{', '.join(others)}: crashes and liars need each robot's failure detector and claim checks, "
                "and the swarm has no radio or sensor model to lose, delay or corrupt messages, readings or "
                "clocks; run it robot by robot"
            )

    def _talk(self, who: np.ndarray) -> np.ndarray:
        """The radio round of robots ``who`` ``(k,)`` (ids, increasing): the positions ``(k, 7, 2)`` each
        has heard last from the robots of its formation, by place (NaN: not yet); then they send
        their own. The per-robot radios talk one after the other by id, so a robot of lower id
        talking in the same step has already sent its position of now."""
        team = self.team
        members = (who - who % 7)[:, None] + np.arange(7)
        talking = np.zeros(self.n, dtype=bool)
        talking[who] = True
        fresh = talking[members] & (members < who[:, None])
        heard = team.board[members]
        heard[fresh] = team.pose[:2, members[fresh]].T
        team.board[who] = team.pose[:2, who].T
        return heard

    def _decide(self, step: int, who: np.ndarray, heard: np.ndarray, commands: np.ndarray) -> None:
        """The decisions of robots ``who`` ``(k,)`` (ids, increasing) as :meth:`Leader.update` and
        :meth:`Follower.update` take them: a leader heads for its aim (:func:`morph`,
        :func:`dream.rules.toward`) through HRVO, avoiding nobody; a follower obeys the stress law
        on the positions ``heard`` ``(k, 7, 2)`` (:func:`dream.rules.stress`), settles or steers
        (:meth:`~dream.robot.RobotHRVO.settle_or_steer`); one HRVO call for them all,
        in the per-robot mode's order (:func:`~dream.experiments.sightings.decide_in_order`), puts
        their limited and guarded commands into ``commands`` ``(2, n)``."""
        team, k = self.team, len(who)
        own = team.pose[:2, who].T
        lead = team.leader[who]
        leaders, followers = who[lead], who[~lead]
        desired = np.zeros((k, 2))
        team.decisions[leaders] += 1
        aims = morph(team.origin[leaders], team.goal[leaders], team.decisions[leaders])
        desired[lead] = rules.toward(own[lead], aims, LEADER_GAIN, GRITSBOT.v_max)
        pull = rules.stress(own[~lead], heard[~lead], WEIGHTS[followers % 7])
        desired[~lead] = rules.capped(-GAIN * pull, GRITSBOT.v_max)
        # The leaders read no sensor (they avoid only crashed robots): their rows are empty.
        seen = last_detections(self.sights, team.delays[who], step, who, MOVEMENT_GAP)
        nearest = np.full(k, np.inf)
        np.minimum.at(nearest, seen.owners, seen.distances)
        # Leaders always go through HRVO, and never step aside (their counters stay at 0).
        settle = ~lead & rules.settles(desired, nearest, FINE, 0.0)
        wanted, sidestep = rules.sidestep_preference(desired, team.sidestep[who], team.side[who])
        chosen = decide_in_order(
            who,
            team.pose[:, who],
            team.dxi[who],
            desired,
            wanted,
            settle,
            seen,
            commands,
            safety=SAFETY,
            v_max=GRITSBOT.v_max,
            bounds=self.bounds,
            limits=GRITSBOT.within(self.sim.spec),
        )
        steered = ~lead & ~settle
        sidestep, side = rules.sidestep_update(chosen, desired, sidestep, team.side[who], SIDESTEP_UPDATES)
        team.sidestep[who[steered]], team.side[who[steered]] = sidestep[steered], side[steered]
        team.dxi[who] = np.where(settle[:, None], desired, chosen)

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
                self.bars = Fleet(
                    [bar for centre in self.centres for bar in bars(gap, ROBOTARIUM.xmax + ENTRY, centre)]
                )
            if step == leave:
                self.bars = Fleet()

    def _lead(self, shape: str) -> None:
        """Send every leader towards its place in ``shape`` (the leaders know the plan)."""
        if self.swarm:
            self.team.head_for(tile_places(np.flatnonzero(self.leader), shape, self.centres))
            return
        for robot in self.robots:
            if isinstance(robot, Leader):
                robot.head_for(formation(shape) + self.centres[robot.robot_id // 7])

    def after_step(self, step: int, poses: np.ndarray) -> None:
        self.bars.step(self.sim.time_step)
        correct = self.correct
        self.targets = follower_positions(self.anchors(poses))
        errors = np.linalg.norm(poses[:2, ~self.leader].T - self.targets, axis=1)
        self.error = float(errors[correct[~self.leader]].max(initial=0.0))
        if step == self.passes[0][0]:
            self.settled_error = self.error
        if len(self.bars):
            self.deformed_error = max(self.deformed_error, self.error)
            self.contacts += bool(self.bars.touching(poses[:2, correct].T, GRITSBOT.radius).any())

    def anchors(self, poses: np.ndarray) -> np.ndarray:
        """The leaders' positions ``(n, 2)`` (rows of followers unused) that the survivors' formation
        is the affine image of: where the leaders are, and for a crashed leader its place in the
        plan (what the surviving leaders of its formation stand in for)."""
        anchors = poses[:2].T.copy()
        state = self.world.fault_state
        if state is None:
            return anchors
        for robot in self.robots:
            if isinstance(robot, Leader) and not state.crashed[robot.robot_id]:
                first = robot.robot_id - robot.index
                crashed = state.crashed[first : first + LEADERS]
                anchors[first : first + LEADERS][crashed] = robot.aims[crashed]
        return anchors

    def done(self, step: int, poses: np.ndarray) -> bool:
        return step >= self.steps(self.n) and self.contacts == 0 and self.settled_error < TOLERANCE

    def measures(self) -> dict[str, Any]:
        """The correct followers' error to their affine target just before the first bars set off
        and at the end (m, largest over the formations), the iterations in which a correct robot
        touched a bar, and the largest error while bars are on the arena."""
        return {
            "error_before_bars": self.settled_error,
            "error_end": self.error,
            "error_while_deformed": self.deformed_error,
            "bar_contacts": self.contacts,
        }

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        goals = np.zeros((self.n, 2))
        if self.swarm:
            goals[self.leader], velocities = self.team.goal[self.leader], self.team.dxi
        else:
            goals[self.leader] = [r.goal for r in self.robots if isinstance(r, Leader)]
            velocities = np.array([r.dxi for r in self.robots])
        goals[~self.leader] = self.targets
        links = np.argwhere(np.triu(WEIGHTS) != 0)
        return Frame(
            step,
            self.arena,
            poses,
            goals=goals,
            velocities=velocities,
            links=(links[None] + 7 * np.arange(self.n // 7)[:, None, None]).reshape(-1, 2),
            obstacles=[bar.polygon for bar in self.bars.obstacles],
            obstacle_moving=[True] * len(self.bars),
            roles=np.where(self.leader, "leader", "follower"),
            title=f"{NAME}: follower error {self.error:.3f} m, bar contacts {self.contacts}",
        )


run = AffineFormation.run
