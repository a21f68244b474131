"""HRVO circle (thesis 3.1): robots cross a circle three times without touching.

N robots start at random poses. Each has a goal on a circle, then the antipodal point, then
its first goal again. A robot that reaches its goal (within 0.05 m) raises its state; when it
knows that every robot has reached at least its state, it heads for its next goal. Robots
avoid each other with HRVO using a movement sensor. Success: every robot finishes the third
circle with zero collisions.

Barrier. Robot ids run around the ring (robot i's goals are neighbours of robot i+1's), and a
range-radio message holds four integers whatever N (:func:`dream.rules.arc_merge`): the
sender's state, the arc of ids ``i - left .. i + right`` it knows to have reached that state,
and the highest state it knows every robot to have reached (``released``). Arcs that overlap
or touch merge; an arc covering all N releases its state, and releases spread to all. Each
message states facts that stay true (states only rise), so stale, late, repeated or lost
messages and a split radio graph can delay a release but never make one early: a robot never
moves on while a robot has not arrived. The price: a robot keeps one arc, not a set, so what
it hears of robots beyond a gap in its arc is dropped and must be heard again once the gap
closes. On the ring, whose neighbouring goals are within radio range, arcs grow as fast as
the N-entry vectors of known states spread: once the last robot arrives, the release reaches
every robot in the radio hops half-way round the ring. Robot by robot, the heartbeat failure
detector still holds N entries a robot; an arc grows over a robot taken for crashed.

Robots choose their preferred velocity, step aside and count arrivals with the shared rules
of :mod:`dream.rules` (the per-robot :class:`CircleRobot` and the swarm mode,
:meth:`HrvoCircle.swarm_step`, call the same functions):

- Roundabout. HRVO alone leaves the robots that cross through the centre from every side
  circling or frozen there: each meets a wall of robots head-on, and symmetric crowds have no
  way out. The centre is therefore an island (half the ring's size) that every robot keeps on
  its left: a robot whose straight way passes through it aims past the island's
  counter-clockwise tangent point, so the robots merge into one stream turning the same way.
- Side-step. A robot that HRVO stops while it wants to move keeps to its right for a few
  decisions (:meth:`~dream.RobotHRVO.steer`), so blocked robots circulate around each other.
- Settling. Near its goal a robot slows down in proportion to the distance left, so that it
  settles on the goal rather than anywhere within the tolerance.
- Squeezing (per robot). Robots parked on the ring form a wall that a robot outside it cannot
  pass with the ring's safety radius. A robot that has come no :data:`PROGRESS` closer to its
  goal for :data:`STALL` decisions while outside the ring takes the least safety radius its
  rules allow (:func:`squeeze_radius`) until no robot it sees is within the ring's
  (:meth:`CircleRobot.squeeze`).

Up to 10 robots use the thesis's circle (radius 0.85 m) and safety radius (0.24 m). Beyond,
the goals lie equally spaced along the ellipse that fills the arena. A Fast arena grows with
the ring once goals would be closer than 0.34 m, keeping the thesis's safety radius (and
then leaves a corridor around the ring); the real Robotarium's cannot, so there the goals
close up and the safety radius shrinks with them. Robots within the arrival tolerance
of neighbouring goals must not block each other, so the safety radius is at most the
spacing less twice the tolerance.

Packed ring. Up to 30 robots on the Robotarium keep a safety radius of a robot's diameter
plus 4 cm (:data:`MIN_SAFETY`) with the 5 cm tolerance. Beyond, up to 50, the ring is packed:
goals 0.155 m apart (at 50) for robots 0.11 m wide. Traces showed what HRVO alone does there:
robots that park first wall in the others, robots meeting the ring beside their goal cannot
slide along it, a robot that slips between the ring and a wall is shut out for good, and a
robot a centimetre off its goal may not move towards it (HRVO forbids any velocity that would
ever close on the parked neighbour beyond it). So on a packed ring:

- the tolerance is 1.5 cm and the safety radius the spacing less twice that, at least the
  robot's diameter plus 1 cm (:data:`PACKED_SAFETY`; rps 0.0.0 counts a collision at 0.11 m)
  and at most what 50 robots leave (:data:`PACKED_SAFETY_CAP`): with more, the motion guard
  (0.12 m) lets robots come within each other's safety radius, where HRVO forbids every way
  but apart, and two robots in the ring's band each blocked the other's way out for good
  (40 robots, 1 seed of 10, with 0.164 m);
- robots start on grid points inside the ring, not in the corners outside it;
- a robot reaches its goal only through its corridor from a dock 0.3 m inside
  (:func:`dream.rules.dock`); in the ring's band it steps aside only inwards (stepping aside
  to its right pushed robots out into the corners; not stepping aside at all left two robots
  in the band blocking each other's way for good, 1 seed of 10 at 50 robots), and near its
  goal not at all;
- within 5 cm of its goal, a robot whose straight way there is clear drives it
  (:func:`dream.rules.clear_way`);
- a robot that has arrived stands still until it moves on, so that the others dock beside a
  neighbour that keeps its place;
- the motion guard looks twice as far ahead (:data:`PACKED_GUARD_HORIZON`): it takes the others
  for standing, and two robots turning towards each other between their decisions closed the
  1.5 cm between the safety radius and a collision (1 of 8 runs at 50 robots without it);
- the movement sensor reaches 0.5 m (:data:`PACKED_SENSING`), not 1 m. HRVO's cones reach to
  infinity: from the centre, the parked robots of a packed ring within 1 m closed every way
  towards it (cones 15 degrees wide, neighbours 9 degrees apart), and the last robots to arrive
  circled for thousands of steps (three crossings took 8,500-19,300 steps, one seed of 20 none;
  with 0.5 m, 4,550-5,900).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from dream import kernels, rules
from dream.backends import initial_poses
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.heartbeats import Heartbeats
from dream.radios import RangeRadio
from dream.robot import GUARD_HORIZON, RobotHRVO, guard_distance, guard_swarm
from dream.sensors import MovementSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec, SimulatorSpec
from dream.world import create_timer

NAME = "hrvo-circle"
CIRCLES = 3
THESIS_N = 10  #: up to this many robots, the thesis's circle and parameters
RADIUS = 0.85  #: the thesis's circle (m)
SAFETY = 0.24  #: the thesis's combined safety radius (m)
ARRIVAL = 0.05  #: a robot within this distance of its goal has arrived (m)
GOAL_SPACING = SAFETY + 2 * ARRIVAL  #: goal spacing a grown arena keeps (m)
EDGE = 0.08  #: distance from the ring's ends to the walls when the ring fills the arena (m)
MIN_SAFETY = GRITSBOT.diameter + 0.04  #: the least safety radius: a robot's diameter plus a margin (m)
PACKED_SAFETY = GRITSBOT.diameter + 0.01  #: the least safety radius of a packed ring (m)
SQUEEZE_MARGIN = 0.01  #: what a squeezing robot keeps between the colliders (m; see CircleRobot.squeeze)
PACKED_SAFETY_CAP = 0.125  #: the most safety radius of a packed ring: what 50 robots leave (m)
PACKED_ARRIVAL = 0.015  #: the arrival tolerance on a packed ring (m)
DOCK_DEPTH = 0.3  #: on a packed ring, how far inside its goal a robot's dock lies (m)
DOCK_WIDTH = 0.05  #: the half-width of the corridor from a dock to its goal (m)
DOCK_LEAD = 0.15  #: how far ahead a robot in the packed ring's band aims as it goes back in (rad)
FINAL_REACH = 0.05  #: on a packed ring, a robot this close to its goal drives there if the way is clear (m)
START_INSIDE = 0.85  #: on a packed ring, robots start on grid points within this fraction of it
SENSING = 1.0  #: the movement sensor's range (m)
PACKED_SENSING = 0.5  #: the movement sensor's range on a packed ring (m)
PACKED_GUARD_HORIZON = 2 * GUARD_HORIZON  #: how far ahead a packed ring's motion guard looks (s)
CORRIDOR = 2 * SAFETY  #: free width between the ring and the walls of a grown arena (m)
ISLAND = 0.5  #: the roundabout's island, as a fraction of the ring (see dream.rules.roundabout_aim)
APPROACH_GAIN = 1.0  #: preferred speed per metre left to the goal near it (1/s)
SIDESTEP_UPDATES = 10  #: decisions a blocked robot steps aside for
SILENCE = 20  #: radio rounds without a heartbeat after which a robot is taken for crashed
STILL = 1e-3  #: a detected robot slower than this (m/s) stands still
STALL = 120  #: decisions without :data:`PROGRESS` towards its goal after which a robot is stalled
PROGRESS = 0.1  #: what counts as progress towards a goal (m)


@dataclass(frozen=True)
class CircleLayout:
    """Where the goals are and the parameters that follow from their spacing.

    Attributes
    ----------
    goals : (n, 2) ndarray
        Each robot's first goal (m); its second is the point reflection ``-goals``.
    semi_axes : (float, float)
        Semi-axes of the ring the goals lie on (m); equal for a circle.
    spacing : float
        Least distance between neighbouring goals (m).
    safety : float
        Combined safety radius of HRVO (m).
    arena : ArenaSpec
    arrival : float
        The arrival tolerance (m).
    packed : bool
        Whether the ring is packed (see the module docs).
    """

    goals: np.ndarray
    semi_axes: tuple[float, float]
    spacing: float
    safety: float
    arena: ArenaSpec
    arrival: float = ARRIVAL
    packed: bool = False


def circle_layout(n: int, grow: bool = True) -> CircleLayout:
    """The goals, safety radius and arena for ``n`` robots.

    Up to :data:`THESIS_N` robots: the thesis's circle of radius 0.85 m in the Robotarium arena
    with safety radius 0.24 m. Beyond, the goals lie on the ellipse that fills the arena (its
    ends :data:`EDGE` from the walls), equally spaced along it; antipodes stay point
    reflections through the centre. If ``grow``, the arena and the ring grow together when
    neighbouring goals would be closer than :data:`GOAL_SPACING`; else (the real Robotarium,
    whose arena cannot grow) the goals close up. The safety radius is the thesis's, or the
    spacing less twice the arrival tolerance if smaller (so that robots anywhere within the
    tolerance of neighbouring goals do not block each other). Below :data:`MIN_SAFETY` the ring
    is packed: the tolerance is :data:`PACKED_ARRIVAL`.

    Raises
    ------
    ValueError
        If ``n`` is negative, or the fixed arena cannot hold ``n`` robots on its ring (their
        safety radius would fall below :data:`PACKED_SAFETY`).
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"the number of robots `n` must be an integer >= 0, got {n!r}")
    if n <= THESIS_N:
        angles = 2 * np.pi * np.arange(n) / max(n, 1)
        goals = RADIUS * np.column_stack((np.cos(angles), np.sin(angles)))
        return CircleLayout(goals, (RADIUS, RADIUS), _least_gap(goals), SAFETY, ROBOTARIUM)
    semi_axes = (ROBOTARIUM.width / 2 - EDGE, ROBOTARIUM.height / 2 - EDGE)
    goals = _ellipse_points(n, *semi_axes)
    spacing = _least_gap(goals)
    scale = max(1.0, GOAL_SPACING / spacing) if grow else 1.0
    # Two robots anywhere within the arrival tolerance of neighbouring goals must not block
    # each other: HRVO keeps them a safety radius apart.
    safety, arrival = min(SAFETY, scale * spacing - 2 * ARRIVAL), ARRIVAL
    packed = safety < MIN_SAFETY
    if packed:
        safety, arrival = min(PACKED_SAFETY_CAP, spacing - 2 * PACKED_ARRIVAL), PACKED_ARRIVAL
    if safety < PACKED_SAFETY:
        most = circle_capacity()
        raise ValueError(
            f"n={n} robots do not fit on the ring of the {ROBOTARIUM.width} x {ROBOTARIUM.height} m arena: "
            f"their goals would be {spacing:.3f} m apart, less than the {PACKED_SAFETY + 2 * PACKED_ARRIVAL:.2f} m "
            f"that robots of diameter {GRITSBOT.diameter} m need to reach neighbouring goals (within "
            f"{PACKED_ARRIVAL} m) keeping a safety radius of {PACKED_SAFETY:.2f} m; "
            f"at most {most} robots fit (or use a backend whose arena can grow)"
        )
    # A grown arena leaves a corridor around the ring, so that robots starting outside it can
    # reach any goal without passing between robots already parked at theirs.
    extra = 0.0 if scale == 1.0 else 2 * CORRIDOR
    arena = ArenaSpec.centred(ROBOTARIUM.width * scale + extra, ROBOTARIUM.height * scale + extra)
    ring = (scale * semi_axes[0], scale * semi_axes[1])
    return CircleLayout(scale * goals, ring, scale * spacing, safety, arena, arrival, packed)


def circle_capacity(packed: bool = True) -> int:
    """The most robots the Robotarium arena's ring holds (see :func:`circle_layout`), packed or
    (``packed=False``) with the 5 cm tolerance and a safety radius of :data:`MIN_SAFETY`."""
    a, b = ROBOTARIUM.width / 2 - EDGE, ROBOTARIUM.height / 2 - EDGE
    gap = PACKED_SAFETY + 2 * PACKED_ARRIVAL if packed else MIN_SAFETY + 2 * ARRIVAL
    n = int(_ellipse_arc(a, b)[1][-1] / gap) + 1  # chords are shorter than arcs
    while n > THESIS_N and _least_gap(_ellipse_points(n, a, b)) < gap:
        n -= 1
    return n


def squeeze_radius(rules: SimulatorSpec) -> float:
    """The least safety radius (m) of a robot squeezing through the ring (:meth:`CircleRobot.squeeze`)
    under ``rules``: two colliders ``collider_offset`` ahead of facing robots stay
    :data:`SQUEEZE_MARGIN` apart (0.12 m under rps 0.0.0's rules, 0.195 m under rps 2.1's)."""
    return rules.diameter + 2 * rules.collider_offset + SQUEEZE_MARGIN


def circle_radius(n: int, grow: bool = True) -> float:
    """The ring's larger semi-axis (m): the circle's radius up to :data:`THESIS_N` robots."""
    return circle_layout(n, grow).semi_axes[0]


def circle_arena(n: int, grow: bool = True) -> ArenaSpec:
    """The Robotarium arena while it holds the ring, else a larger arena of its shape."""
    return circle_layout(n, grow).arena


def circle_goals(n: int, grow: bool = True) -> np.ndarray:
    """Goals ``(n, 3, 2)``: robot i's point on the ring, its antipode, then the point again."""
    here = circle_layout(n, grow).goals
    return np.stack((here, -here, here), axis=1)


def _least_gap(points: np.ndarray) -> float:
    """Least distance between consecutive points of a closed ring ``(n, 2)`` (inf below 2)."""
    if len(points) < 2:
        return math.inf
    return float(np.hypot(*(points - np.roll(points, 1, axis=0)).T).min())


def _ellipse_arc(a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """Parameter angles ``t`` and the arc length from (a, 0) to each, finely sampled."""
    t = np.linspace(0.0, 2 * np.pi, 8193)
    arc = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(a * np.cos(t)), np.diff(b * np.sin(t))))))
    return t, arc


def _ellipse_points(n: int, a: float, b: float) -> np.ndarray:
    """``n`` points ``(n, 2)`` equally spaced by arc length on the ellipse of semi-axes (a, b),
    the first at (a, 0).

    Equal arc length keeps the set centrally symmetric: the arc from a point to its
    reflection is half the perimeter, whatever the point.
    """
    t, arc = _ellipse_arc(a, b)
    at = np.interp(arc[-1] * np.arange(n) / n, arc, t)
    return np.column_stack((a * np.cos(at), b * np.sin(at)))


class CircleRobot(RobotHRVO):
    """A robot of the circle experiment (see the module docs).

    Callbacks: :meth:`update_odom` (odometry), :meth:`update_sensor` (movement sensor),
    :meth:`update_radio` (range radio) and :meth:`update` (the controller, writes ``dxu``).

    Parameters
    ----------
    goals : (3, 2) array_like
        Its goals in order (m).
    n : int
        Number of robots (ids ``0 .. n - 1`` around the ring of goals: see :func:`dream.rules.arc_merge`).
    semi_axes : (float, float), optional
        The ring's semi-axes (m), which size the roundabout; default: :func:`circle_layout`'s.
    island : float
        The roundabout's island as a fraction of the ring (0: go straight).
    arrival : float
        The arrival tolerance (m).
    packed : bool
        Whether its goals lie on a packed ring (docks, parking and the clear final approach of
        the module docs).
    squeeze_to : float
        The safety radius it takes while stalled outside the ring (m; :meth:`squeeze`): what
        keeps two colliders :data:`SQUEEZE_MARGIN` apart (:func:`squeeze_radius`).
    **kwargs
        Passed to :class:`~dream.RobotHRVO` (e.g. ``safety``, ``arena``).
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        goals: np.ndarray,
        n: int,
        *,
        semi_axes: tuple[float, float] | None = None,
        island: float = ISLAND,
        arrival: float = ARRIVAL,
        packed: bool = False,
        squeeze_to: float = PACKED_SAFETY,
        **kwargs: Any,
    ) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.goals = np.asarray(goals, dtype=np.float64)
        self.current_goal = self.goals[0]
        self.n = n
        # The arrival barrier (dream.rules.arc_merge): robots robot_id - left .. robot_id + right have
        # reached this robot's state, and every robot has reached `released`.
        self.left, self.right, self.released = 0, 0, 0
        self.heartbeats = Heartbeats(n, robot_id, SILENCE)
        self.suspects = False  # whether it takes some robot for crashed, or was taken for crashed
        self.state = 0  # goals reached so far
        self.change_state = True  # the current goal has not been reached yet
        self.desired_velocity = np.zeros(2)
        self.semi_axes = circle_layout(n).semi_axes if semi_axes is None else semi_axes
        self.island = island
        self.arrival = arrival
        self.packed = packed
        if packed:
            self.guard_horizon = PACKED_GUARD_HORIZON
        self.ring_safety = self.safety  # the safety radius it squeezes from (see squeeze)
        self.squeeze_to = min(squeeze_to, self.ring_safety)
        self.closest = math.inf  # its distance to its current goal when it last made PROGRESS (m)
        self.stalled = 0  # decisions since it last came PROGRESS closer

    def update_radio(self, messages: list[tuple[Any, ...]]) -> tuple[Any, ...]:
        """Merge the arcs and released levels heard (:func:`dream.rules.arc_merge`) and the
        heartbeats; move on once every robot not taken for crashed has reached at least this
        robot's state. Sends ``(id, state, left, right, released, heartbeats)``.

        A heartbeat failure detector (:class:`~dream.heartbeats.Heartbeats`, silent for
        :data:`SILENCE` of this robot's rounds) lets the survivors stop waiting for crashed robots:
        an arc grows over a robot taken for crashed as if it had arrived.
        """
        if messages:
            ids = np.array([message[0] for message in messages])
            heard = np.array([message[1:5] for message in messages])
            self.left, self.right, self.released = (
                int(v)
                for v in rules.arc_merge(
                    self.n,
                    self.state,
                    self.left,
                    self.right,
                    self.released,
                    np.zeros(len(ids), dtype=np.intp),
                    (ids - self.robot_id) % self.n,
                    heard,
                )
            )
        self.heartbeats.round([message[5] for message in messages])
        alive = self.heartbeats.alive
        self.skip_crashed(alive)
        self.released = int(rules.arc_release(self.n, self.state, self.left, self.right, self.released))
        # Released beyond its own level means this robot was taken for crashed and the others
        # went on: a robot parked on its goal may then be one that has finished there (seen at
        # N = 100 under 30 % loss: it waited beside its goal for good).
        self.suspects = not alive.all() or self.released > self.state
        # At least its own state, not equal to it: a robot taken for crashed while out of radio
        # reach (a 100-robot ring is tens of hops across) lets the others go ahead, and a robot
        # waiting for equal states would then wait for good (seen at N = 100, no fault).
        if rules.moves_on(self.state, self.released >= self.state, self.change_state, len(self.goals)):
            self.current_goal = self.goals[self.state]
            self.change_state = True
            self.closest, self.stalled = math.inf, 0
        return self.robot_id, self.state, self.left, self.right, self.released, self.heartbeats.beats

    def skip_crashed(self, alive: np.ndarray) -> None:
        """Grow the arc over the robots beyond either end that it takes for crashed (``alive``
        ``(n,)`` bool): the survivors do not wait for them."""
        while self.left + self.right + 1 < self.n and not alive[(self.robot_id - self.left - 1) % self.n]:
            self.left += 1
        while self.left + self.right + 1 < self.n and not alive[(self.robot_id + self.right + 1) % self.n]:
            self.right += 1

    def goal_taken(self, position: np.ndarray) -> bool:
        """Whether a robot standing still (one taken for crashed stops where it is, one that has
        finished stays) sits within the safety radius of this robot's goal while this robot is as
        close as HRVO lets it come: the goal then counts as reached, else a crash on a goal would
        stop the circles for good."""
        rows = np.asarray(self.detections)
        # As close as HRVO lets it come; a stalled robot may be held further off by others parked
        # beside the goal (traced under a crash at N = 100: 0.39 m, walled off by a finished robot).
        reach = (2 * self.ring_safety if self.stalled >= STALL else self.ring_safety) + self.arrival
        if not len(rows) or math.dist(position, self.current_goal) > reach:
            return False
        others = rules.seen_positions(position, rows)
        still = np.hypot(rows[:, 2], rows[:, 3]) < STILL
        return bool(np.any(still & (np.hypot(*(others - self.current_goal).T) < self.ring_safety)))

    def squeeze(self, position: np.ndarray) -> None:
        """At ``position`` ``(2,)`` (m): take the least safety radius (:attr:`squeeze_to`, under
        rps 0.0.0's rules the body plus 1 cm) while stalled outside the ring, and the ring's again
        once no robot seen is within it.

        Robots parked on a ring (goals 0.34 m apart with a safety radius of 0.24 m) form a wall
        that a robot outside cannot pass. Traces at N = 100 under latency and clock drift: a robot
        still waiting on its goal when the robot whose last goal it is arrived (its news came
        late) was pushed outwards, slid along the outside of the ring for 7,000 steps and missed
        the cap.
        """
        distance = math.dist(position, self.current_goal)
        if not self.change_state:  # waiting on a goal reached is not being stalled
            self.stalled = 0
        elif distance < self.closest - PROGRESS:
            self.closest, self.stalled = distance, 0
        else:
            self.stalled += 1
        if self.stalled >= STALL and rules.outside_ring(position, self.semi_axes):
            self.safety = self.squeeze_to
        elif self.safety != self.ring_safety:
            rows = np.asarray(self.detections)
            if not len(rows) or rows[:, 0].min() >= self.ring_safety:
                self.safety = self.ring_safety

    def update(self, dxu: np.ndarray) -> None:
        if not self.has_pose:
            self.steer(self.detections, self.desired_velocity, SIDESTEP_UPDATES)
        else:
            position = np.array([self.pos_x, self.pos_y])
            _, reached = rules.arrival(position, self.current_goal, self.change_state, self.arrival)
            if reached or (self.change_state and self.suspects and self.goal_taken(position)):
                self.state += 1
                self.change_state = False
                self.left = self.right = 0  # a new level: it knows only itself there
            if not self.packed:
                self.squeeze(position)
                aim = rules.roundabout_aim(position, self.current_goal, self.semi_axes, self.island)
                self.desired_velocity = rules.preferred_velocity(
                    position, aim, self.current_goal, self.v_max, APPROACH_GAIN
                )
                self.steer(self.detections, self.desired_velocity, SIDESTEP_UPDATES)
            elif self.change_state:
                self.dock(position, self.current_goal)
            else:  # parked: neighbours dock beside a robot that keeps its place
                self.desired_velocity, self.dxi = np.zeros(2), np.zeros(2)
        self.command(dxu)

    def dock(self, position: np.ndarray, goal: np.ndarray) -> None:
        """Choose ``dxi`` on a packed ring: through the dock and corridor of :func:`dream.rules.dock`,
        stepping aside only inwards in the ring's band and not at all near the goal, and straight
        to the goal over the last :data:`FINAL_REACH` when the way is clear of the robots seen."""
        target, band = rules.dock(position, goal, self.semi_axes, DOCK_DEPTH, DOCK_WIDTH, DOCK_LEAD)
        aim = rules.roundabout_aim(position, target, self.semi_axes, self.island)
        self.desired_velocity = rules.preferred_velocity(position, aim, goal, self.v_max, APPROACH_GAIN)
        near = math.dist(position, goal) < FINAL_REACH
        if near:  # a robot beside its goal has nowhere aside to go
            self.sidestep = 0
        elif band:  # aside, then, to whichever side points inwards: outwards a robot is shut out
            outwards = position / np.square(self.semi_axes)
            right = self.desired_velocity[1] * outwards[0] - self.desired_velocity[0] * outwards[1]
            self.side = 1.0 if right <= 0.0 else -1.0
        self.steer(self.detections, self.desired_velocity, SIDESTEP_UPDATES)
        if near:
            clearance = guard_distance(self.spec.diameter, self.safety)
            if rules.clear_way(position, goal, rules.seen_positions(position, self.detections), clearance):
                self.dxi = self.desired_velocity.copy()


def circle_frame(
    step: int,
    sim: Any,
    goals: Any,
    velocities: Any,
    states: np.ndarray,
    radio_range: float = 1.0,
    sensing: float = SENSING,
) -> Frame:
    """What a renderer shows of the circle experiment: goals, HRVO velocities, radio links.

    ``goals`` and ``velocities``, array_like ``(n, 2)``: each robot's current goal (m) and chosen velocity
    (m/s); ``states`` ``(n,)``: the goals each has reached.
    """
    poses = sim.poses
    n = poses.shape[1]
    indptr, indices, _ = kernels.neighbours(poses[:2].T, radio_range)
    links = np.column_stack((np.repeat(np.arange(n), np.diff(indptr)), indices))
    return Frame(
        step,
        sim.arena,
        poses,
        goals=np.asarray(goals, dtype=np.float64).reshape(-1, 2),
        velocities=np.asarray(velocities, dtype=np.float64).reshape(-1, 2),
        links=links[links[:, 0] < links[:, 1]],
        ranges={"sensing": sensing, "radio": radio_range},
        title=f"{NAME}: circles {int(np.min(states, initial=CIRCLES))}/{CIRCLES}, "
        f"collisions {sim.violations.collision}",
    )


def default_steps(n: int) -> int:
    """An iteration cap that every seed finishes well within (the run stops when done).

    Three crossings of the ring take about ``520 (a + b)`` steps at full speed (``a``, ``b``
    its semi-axes in m, roundabout included); the cap allows three times that, plus the
    start and the radio rounds.
    """
    a, b = circle_layout(n).semi_axes
    return 4000 + int(1500 * (a + b))


@dataclass
class CircleSwarm:
    """Every robot's decision state in swarm mode, one row each (see :meth:`HrvoCircle.swarm_step`).

    The barrier (see the module docs) is :class:`CircleRobot`'s, exchanged every ``radio_gap`` steps.

    Attributes
    ----------
    goals : (n, 3, 2) ndarray
        Each robot's goals in order (m).
    state : (n,) int ndarray
        Goals reached.
    heading_for : (n,) int ndarray
        Index of the goal being approached...
    unreached : (n,) bool ndarray
        ...which has not been reached yet.
    left, right, released : (n,) int ndarrays
        The arcs of robots known to have reached each robot's state, and the level known complete.
    sidestep, side : (n,) ndarrays
        Decisions left stepping aside, and to which side (1.0: right, -1.0: left).
    dxi : (n, 2) ndarray
        The velocities HRVO chose last (m/s): what the neighbours' velocities are taken to be.
    """

    goals: np.ndarray
    state: np.ndarray
    heading_for: np.ndarray
    unreached: np.ndarray
    left: np.ndarray
    right: np.ndarray
    released: np.ndarray
    sidestep: np.ndarray
    side: np.ndarray
    dxi: np.ndarray

    @classmethod
    def start(cls, goals: np.ndarray) -> CircleSwarm:
        """Robots that have reached nothing yet and know only themselves, heading for ``goals[:, 0]``."""
        n = len(goals)
        return cls(
            goals=goals,
            state=np.zeros(n, dtype=np.int64),
            heading_for=np.zeros(n, dtype=np.int64),
            unreached=np.ones(n, dtype=bool),
            left=np.zeros(n, dtype=np.int64),
            right=np.zeros(n, dtype=np.int64),
            released=np.zeros(n, dtype=np.int64),
            sidestep=np.zeros(n, dtype=np.int64),
            side=np.ones(n),
            dxi=np.zeros((n, 2)),
        )

    @property
    def goal(self) -> np.ndarray:
        """The goal each robot heads for ``(n, 2)`` (m)."""
        return self.goals[np.arange(len(self.goals)), self.heading_for]


class HrvoCircle(Experiment):
    """The circle experiment (see the module docs).

    Swarm mode (``swarm=True``) keeps the behaviour of the per-robot mode (the same layout and
    HRVO parameters, and the decision rules of :mod:`dream.rules` that :class:`CircleRobot`
    calls: arrival, roundabout, settling, stepping aside; progress spread by range radio every
    ``radio_gap`` steps), but every robot decides every step through one
    :func:`dream.kernels.hrvo` call, with its state in a :class:`CircleSwarm`. Not carried over:
    the squeeze and the stalled robot's wider reach for a taken goal (:meth:`CircleRobot.squeeze`),
    since one HRVO call takes one safety radius for all.
    """

    name = NAME
    default_n = 10
    success = "every robot finishes the third circle with zero collisions, boundary and actuator violations"
    has_swarm_mode = True

    radio_gap: int = param(30, "steps between two radio exchanges of progress (both modes)", ge=1)

    def check(self, n: int, backend: str) -> None:
        # On the real Robotarium the arena cannot grow: the goals close up instead (circle_layout,
        # which refuses more robots than the ring holds).
        self.grow = backend != "robotarium"
        self.layout = circle_layout(n, self.grow)
        self.sensing = PACKED_SENSING if self.layout.packed else SENSING

    def arena_for(self, n: int) -> ArenaSpec:
        return self.layout.arena

    def build(self, n: int) -> None:
        if self.layout.packed and (self.rules.collider_offset > 0 or self.rules.diameter >= self.layout.safety):
            raise ValueError(
                f"n={n} robots pack the Robotarium's ring (goals {self.layout.spacing:.3f} m apart), which only "
                f"rps 0.0.0's rules leave room for: {self.rules.rules}'s colliders ({self.rules.diameter} m, "
                f"{self.rules.collider_offset} m ahead of the centre) would touch; at most "
                f"{circle_capacity(packed=False)} robots run by them"
            )
        goals = circle_goals(n, self.grow)
        for i in range(n):
            robot = CircleRobot(
                i,
                f"robot_{i}",
                goals[i],
                n,
                semi_axes=self.layout.semi_axes,
                arrival=self.layout.arrival,
                packed=self.layout.packed,
                squeeze_to=squeeze_radius(self.rules),
                safety=self.layout.safety,
                arena=self.arena,
            )
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=self.sensing)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio)
            create_timer(
                i,
                20 + i % 10,
                [
                    {"delay": 2 + i % 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3 + i % 2, "tag": "movement", "call": movement.update},
                    {"delay": self.radio_gap, "tag": "radio", "call": radio.update},
                    {"delay": 4 + i % 2, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def build_swarm(self, n: int) -> None:
        if self.layout.packed:
            raise ValueError(
                f"n={n} robots pack the Robotarium's ring: run them robot by robot (swarm mode is for rings that "
                f"grow; the packed ring's docking and parking are per robot); at most "
                f"{circle_capacity(packed=False)} robots run in swarm mode on the Robotarium"
            )
        self.team = CircleSwarm.start(circle_goals(n, self.grow))
        self.bounds = self.arena.shrunk(GRITSBOT.radius)

    def swarm_step(self, step: int, x: np.ndarray) -> np.ndarray:
        """Every robot's decision: count arrivals, exchange progress by radio every
        ``radio_gap`` steps (and move on), aim around the roundabout, step aside when blocked,
        one HRVO call, then the unicycle commands within the wheel limits and the motion guard."""
        team = self.team
        p = x[:2].T
        goal = team.goal
        arrived, reached = rules.arrival(p, goal, team.unreached, self.layout.arrival)
        team.state += reached
        team.unreached &= ~arrived
        team.left[reached] = team.right[reached] = 0  # a new level: it knows only itself there
        if step % self.radio_gap == 0:
            _radio_round(team, p)
            moving_on = rules.moves_on(team.state, team.released >= team.state, team.unreached, CIRCLES)
            team.heading_for[moving_on] = team.state[moving_on]
            team.unreached |= moving_on
            goal = team.goal
        aim = rules.roundabout_aim(p, goal, self.layout.semi_axes, ISLAND)
        desired = rules.preferred_velocity(p, aim, goal, GRITSBOT.v_max, APPROACH_GAIN)
        wanted, team.sidestep = rules.sidestep_preference(desired, team.sidestep, team.side)
        # One neighbour search for HRVO and the motion guard (whose reach, 0.17 m, is within it).
        seen = kernels.neighbours(p, self.sensing)
        team.dxi = kernels.hrvo(
            p, team.dxi, wanted, seen[:2], radius=self.sensing, safety=self.layout.safety, bounds=self.bounds
        )
        team.sidestep, team.side = rules.sidestep_update(team.dxi, desired, team.sidestep, team.side, SIDESTEP_UPDATES)
        dxu = kernels.actuator_limit(kernels.dxi_to_dxu(team.dxi.T, x), GRITSBOT.within(self.sim.spec))
        return guard_swarm(dxu, x, guard_distance(GRITSBOT.diameter, self.layout.safety), seen)

    def steps(self, n: int) -> int:
        return default_steps(n)

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """rps's random grid poses; on a packed ring only grid points well inside it (a robot
        starting in a corner outside the ring is shut out once its neighbours park)."""
        if not self.layout.packed:
            return super().initial_poses(n, rng)
        a, b = self.layout.semi_axes
        return initial_poses(n, rng, self.arena, where=lambda x, y: np.hypot(x / a, y / b) <= START_INSIDE)

    def states(self) -> np.ndarray:
        """The goals each robot has reached ``(n,)``, in either mode."""
        if self.swarm:
            return self.team.state
        return np.array([robot.state for robot in self.robots], dtype=np.int64)

    def done(self, step: int, poses: np.ndarray) -> bool:
        return bool(np.all(self.states()[self.correct] >= CIRCLES))

    def measures(self) -> dict[str, Any]:
        """``circles_completed`` (by every correct robot: crashed, stuck or lying ones are left
        out) and ``circle_radius``, the ring's larger semi-axis (m)."""
        circles = int(np.min(self.states()[self.correct], initial=CIRCLES))
        return {"circles_completed": circles, "circle_radius": self.layout.semi_axes[0]}

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        if self.swarm:
            return circle_frame(step, self.sim, self.team.goal, self.team.dxi, self.team.state)
        goals = [robot.current_goal for robot in self.robots]
        velocities = [robot.dxi for robot in self.robots]
        return circle_frame(step, self.sim, goals, velocities, self.states(), sensing=self.sensing)


run = HrvoCircle.run


def _radio_round(team: CircleSwarm, positions: np.ndarray, radio_range: float = 1.0) -> None:
    """One radio exchange of the arrival barrier between the robots in range (at once: each
    hears what the others held before the round)."""
    n = len(team.state)
    indptr, senders, _ = kernels.neighbours(positions, radio_range)
    rows = np.repeat(np.arange(n), np.diff(indptr))
    heard = np.column_stack((team.state[senders], team.left[senders], team.right[senders], team.released[senders]))
    merged = rules.arc_merge(n, team.state, team.left, team.right, team.released, rows, (senders - rows) % n, heard)
    team.left, team.right, released = merged
    team.released = rules.arc_release(n, team.state, team.left, team.right, released)
