"""HRVO circle (thesis 3.1): robots cross a ring three times without touching.

Each robot heads for its goal on a ring, then the antipode, then its goal again, avoiding the
others with HRVO on its movement sensor; it moves on once it knows that every robot has got as
far, from range-radio messages of nine integers whatever N (an arc barrier with a bounded
failure detector, :mod:`dream.rules.ring`). One :class:`CircleRobot`, written on arrays, runs
robot by robot and as one swarm (``swarm=True``) with the same poses at every step. The story
(roundabout, side-step, settling, squeezing, the packed ring) is in docs/experiments/hrvo-circle.md.
Success: every robot finishes the third circle with zero collisions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from dream import kernels, rules, timers
from dream.backends import initial_poses
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.robot import GUARD_HORIZON, SIDESTEP_UPDATES, guard_distance
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec, SimulatorSpec
from dream.swarm import Avoid, Movement, Radio, SwarmRobot, View

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
SQUEEZE_MARGIN = 0.01  #: what a squeezing robot keeps between the colliders (m; see squeeze_radius)
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
SILENCE = 20  #: radio rounds without news of a robot after which it is taken for crashed
STILL = 1e-3  #: a detected robot slower than this (m/s) stands still
STALL = 120  #: decisions without :data:`PROGRESS` towards its goal after which a robot is stalled
PROGRESS = 0.1  #: what counts as progress towards a goal (m)
CONTROL_GAP = 4  #: steps between two decisions of a robot
START_DELAY = 20  #: robot i decides first after this plus i % 10 steps
RADIO_RANGE = 1.0  #: the range radio's reach (m)
#: A message: the sender's level, its arc, the level it knows complete, and the two robots it
#: watches beyond its arc with their ages (:func:`dream.rules.watch_ends`), and whether it knows of a crash.
MESSAGE = ("state", "left", "right", "released", "watch_left", "age_left", "watch_right", "age_right", "suspects")


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
    """The least safety radius (m) of a robot squeezing through the ring (:func:`dream.rules.squeezes`)
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


class CircleRobot(SwarmRobot):
    """The robots of the circle experiment (see the module docs), on arrays.

    Every :data:`CONTROL_GAP` steps a robot counts its arrival (or takes a goal a standing robot
    holds, once it suspects a crash: :func:`dream.rules.goal_taken`); at the first decision of
    every ``radio_gap`` steps of its clock it merges the arcs heard (:func:`dream.rules.arc_merge`),
    grows its arc over a robot silent for :data:`SILENCE` rounds (:func:`dream.rules.watch_ends`),
    moves on once its level is released, and sends its :data:`MESSAGE`. Then it aims around the
    roundabout, squeezing while stalled outside the ring (:func:`dream.rules.squeezes`); on a
    packed ring it docks instead, stepping aside only inwards, and parks once arrived.
    """

    period = CONTROL_GAP
    threaded = True  # decide reads its view alone: blocks of a swarm decide on several threads
    memory = {
        "heading": 0,  # the goal it heads for: 0, 1 (the antipode) or 2
        "unreached": 1,  # that goal is not reached yet
        "state": 0,  # goals reached
        "left": 0,  # the arc of robots known to have reached `state`...
        "right": 0,
        "released": 0,  # ...and the level every robot is known to have reached
        "slot": -1,  # its last radio round
        "watch_left": -1,  # the robots watched beyond its arc, and their ages (rounds)
        "age_left": 0,
        "watch_right": -1,
        "age_right": 0,
        "suspects": 0,  # it took a robot for crashed, or was taken for crashed
        "closest": math.inf,  # its distance to its goal when it last made PROGRESS (m)
        "stalled": 0,  # decisions since
        "squeezing": 0,  # it plans with the least safety radius
    }

    def __init__(self, layout: CircleLayout, squeeze_to: float, radio_gap: int, sensing: float) -> None:
        self.layout, self.n, self.radio_gap = layout, len(layout.goals), radio_gap
        self.squeeze_to = min(squeeze_to, layout.safety)
        self.movement = Movement(range=sensing)
        self.radio = Radio(range=RADIO_RANGE, fields=dict.fromkeys(MESSAGE, int))
        horizon = PACKED_GUARD_HORIZON if layout.packed else GUARD_HORIZON
        self.avoid = Avoid(safety=layout.safety, sidestep=SIDESTEP_UPDATES, horizon=horizon)

    def start(self, ids: np.ndarray) -> np.ndarray:
        return timers.staggered(ids, START_DELAY, 10)

    def goals(self, ids: np.ndarray, heading: np.ndarray) -> np.ndarray:
        """The goals ``(k, 2)`` robots ``ids`` head for (``heading``: 0, 1 or 2; see :func:`circle_goals`)."""
        return np.take(self.layout.goals, ids, axis=0) * np.where(heading == 1, -1.0, 1.0)[:, None]

    def decide(self, view: View) -> np.ndarray:
        ids, here, memory, seen, layout = view.ids, view.pose[:, :2], view.memory, view.seen, self.layout
        unreached = memory["unreached"].astype(bool)
        goal = self.goals(ids, memory["heading"])
        _, reached = rules.arrival(here, goal, unreached, layout.arrival)
        doubting = unreached & (memory["suspects"] > 0)  # it may take a goal a standing robot holds
        if doubting.any():
            still = np.hypot(seen["vx"], seen["vy"]) < STILL
            reach = np.where(memory["stalled"] >= STALL, 2 * layout.safety, layout.safety) + layout.arrival
            offsets = np.column_stack((seen["dx"], seen["dy"]))
            reached |= doubting & rules.goal_taken(here, goal, seen.offsets, offsets, still, reach, layout.safety)
        memory["state"] = memory["state"] + reached
        memory["left"], memory["right"] = (np.where(reached, 0, memory[key]) for key in ("left", "right"))
        memory["unreached"] = (unreached & ~reached).astype(np.int64)
        slot = np.floor((view.clock - self.start(ids)) / self.radio_gap).astype(np.int64)
        talking = slot > memory["slot"]
        if talking.any():
            self.talk(view, talking)
            memory["slot"] = np.where(talking, slot, memory["slot"])
        goal = self.goals(ids, memory["heading"])
        if layout.packed:
            return self.dock(view, here, goal)
        closest, memory["stalled"] = rules.stall(
            np.hypot(*(goal - here).T), memory["closest"], memory["stalled"], memory["unreached"], PROGRESS
        )
        memory["closest"] = closest
        outside = rules.outside_ring(here, layout.semi_axes)
        squeezing = rules.squeezes(
            memory["squeezing"], memory["stalled"], STALL, outside, seen.min("distance"), layout.safety
        )
        memory["squeezing"] = squeezing.astype(np.int64)
        if squeezing.any():
            view.keep_apart(np.where(squeezing, self.squeeze_to, layout.safety))
        aim = rules.roundabout_aim(here, goal, layout.semi_axes, ISLAND)
        return rules.preferred_velocity(here, aim, goal, self.spec.v_max, APPROACH_GAIN)

    def talk(self, view: View, talking: np.ndarray) -> None:
        """One radio round of the robots flagged ``talking``: merge, watch, release, move on, send."""
        n, ids, memory, heard = self.n, view.ids, view.memory, view.heard
        rows = heard.owner
        keep = talking[rows]
        rows, senders = rows[keep], heard["sender"][keep]
        fields = np.column_stack([heard[key][keep] for key in MESSAGE]).reshape(-1, len(MESSAGE))
        state, unreached = memory["state"], memory["unreached"].astype(bool)
        left, right, released = rules.arc_merge(
            n,
            state,
            memory["left"],
            memory["right"],
            memory["released"],
            rows,
            (senders - ids[rows]) % n,
            fields[:, :4],
        )
        watched = np.column_stack((memory["watch_left"], memory["watch_right"]))
        ages = np.column_stack((memory["age_left"], memory["age_right"]))
        ends, ages = rules.watch_ends(n, ids, left, right, watched, ages, rows, senders, fields[:, 4:8])
        # A robot silent for SILENCE rounds is taken for crashed: the arc grows over it.
        left, right, quiet = rules.grow_over(n, left, right, (ages > SILENCE) & talking[:, None])
        released = rules.arc_release(n, state, left, right, released)
        # At least its own level, not equal to it: the others may have gone ahead of a robot
        # taken for crashed while out of radio reach.
        go = talking & rules.moves_on(state, released >= state, unreached, CIRCLES)
        # Whether some robot is taken for crashed (news of it spreads), or this one was.
        told = np.zeros(len(ids), dtype=bool)
        told[rows[fields[:, 8] > 0]] = True
        suspects = (memory["suspects"] > 0) | told | quiet.any(axis=1) | (released > state)
        for key, value in (("left", left), ("right", right), ("released", released), ("suspects", suspects)):
            memory[key] = np.where(talking, value, memory[key]).astype(np.int64)
        for at, side in enumerate(("left", "right")):
            memory[f"watch_{side}"] = np.where(talking, ends[:, at], memory[f"watch_{side}"])
            memory[f"age_{side}"] = np.where(talking, ages[:, at], memory[f"age_{side}"])
        memory["heading"] = np.where(go, state, memory["heading"])
        memory["unreached"] = (unreached | go).astype(np.int64)
        memory["closest"] = np.where(go, math.inf, memory["closest"])
        memory["stalled"] = np.where(go, 0, memory["stalled"])
        view.send(where=talking, **{key: memory[key] for key in MESSAGE})

    def dock(self, view: View, here: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """The packed ring's wish: through the dock and corridor of :func:`dream.rules.dock`,
        stepping aside only inwards in the ring's band and not at all near the goal, straight to
        the goal over the last :data:`FINAL_REACH` when the way is clear; parked once arrived."""
        layout, seen = self.layout, view.seen
        target, band = rules.dock(here, goal, layout.semi_axes, DOCK_DEPTH, DOCK_WIDTH, DOCK_LEAD)
        aim = rules.roundabout_aim(here, target, layout.semi_axes, ISLAND)
        desired = rules.preferred_velocity(here, aim, goal, self.spec.v_max, APPROACH_GAIN)
        near = np.hypot(*(goal - here).T) < FINAL_REACH
        outwards = here / np.square(layout.semi_axes)
        right = desired[:, 1] * outwards[:, 0] - desired[:, 0] * outwards[:, 1]
        view.aside(np.where(band & ~near, np.where(right <= 0.0, 1.0, -1.0), 0.0), stop=near)
        clearance = guard_distance(self.spec.diameter, layout.safety)
        others = np.column_stack((seen["dx"], seen["dy"])) + seen.broadcast(here)
        clear = near & rules.clear_way(here, goal, others, clearance, seen.offsets)
        parked = view.memory["unreached"] == 0  # neighbours dock beside a robot that keeps its place
        view.direct(clear | parked)
        return np.where(parked[:, None], 0.0, desired)


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


class HrvoCircle(Experiment):
    """The circle experiment (see the module docs): its robots are one :class:`CircleRobot`."""

    name = NAME
    default_n = 10
    success = "every robot finishes the third circle with zero collisions, boundary and actuator violations"

    radio_gap: int = param(30, "steps between two radio exchanges of progress", ge=1)

    def check(self, n: int, backend: str) -> None:
        # On the real Robotarium the arena cannot grow: the goals close up instead (circle_layout,
        # which refuses more robots than the ring holds).
        self.grow = backend != "robotarium"
        self.layout = circle_layout(n, self.grow)
        self.sensing = PACKED_SENSING if self.layout.packed else SENSING

    def arena_for(self, n: int) -> ArenaSpec:
        return self.layout.arena

    def swarm_robot(self, n: int) -> CircleRobot:
        if self.layout.packed and (self.rules.collider_offset > 0 or self.rules.diameter >= self.layout.safety):
            raise ValueError(
                f"n={n} robots pack the Robotarium's ring (goals {self.layout.spacing:.3f} m apart), which only "
                f"rps 0.0.0's rules leave room for: {self.rules.rules}'s colliders ({self.rules.diameter} m, "
                f"{self.rules.collider_offset} m ahead of the centre) would touch; at most "
                f"{circle_capacity(packed=False)} robots run by them"
            )
        return CircleRobot(self.layout, squeeze_radius(self.rules), self.radio_gap, self.sensing)

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
        """The goals each robot has reached ``(n,)``."""
        assert self.engine is not None
        return self.engine.memory["state"]

    def done(self, step: int, poses: np.ndarray) -> bool:
        return bool(np.all(self.states()[self.correct] >= CIRCLES))

    def measures(self) -> dict[str, Any]:
        """``circles_completed`` (by every correct robot: crashed, stuck or lying ones are left
        out) and ``circle_radius``, the ring's larger semi-axis (m)."""
        circles = int(np.min(self.states()[self.correct], initial=CIRCLES))
        return {"circles_completed": circles, "circle_radius": self.layout.semi_axes[0]}

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        assert self.engine is not None
        robot, memory = self.engine.robot, self.engine.memory
        assert isinstance(robot, CircleRobot)
        goals = robot.goals(np.arange(self.n), memory["heading"])
        return circle_frame(step, self.sim, goals, self.engine.dxi, memory["state"], sensing=self.sensing)
