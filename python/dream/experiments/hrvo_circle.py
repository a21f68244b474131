"""HRVO circle (thesis 3.1): robots cross a circle three times without touching.

N robots start at random poses. Each has a goal on a circle, then the antipodal point, then
its first goal again. A robot that reaches its goal (within 0.05 m) raises its state; range
radios spread every robot's known states (element-wise max); when a robot knows that all
states equal its own, it heads for its next goal. Robots avoid each other with HRVO using a
movement sensor. Success: every robot finishes the third circle with zero collisions.

HRVO leaves a robot standing when a robot within the safety radius blocks the way to its
goal (every free velocity points away from it); the original then waited forever, stalling
some runs. Here robots steer with :meth:`~dream.RobotHRVO.steer`: a blocked robot keeps to
its right for a few decisions, so that blocked robots circulate around each other.

For N > 10 the circle grows so that neighbouring goals stay at least 0.3 m apart (with 50
robots on the original 0.85 m circle they would be 0.107 m apart, closer than a robot's
diameter), and the arena grows with it when the circle no longer fits the Robotarium.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from dream import kernels
from dream.backends import make_robotarium
from dream.experiments.result import ExperimentResult
from dream.experiments.spec import Experiment
from dream.frames import Frame
from dream.radios import RangeRadio
from dream.robot import RobotHRVO
from dream.sensors import MovementSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec
from dream.timers import create_timer

NAME = "hrvo-circle"
CIRCLES = 3
RADIUS = 0.85  #: the thesis's circle (m)
GOAL_SPACING = 0.3  #: least distance between neighbouring goals (m)
ARRIVAL = 0.05  #: a robot within this distance of its goal has arrived (m)


def circle_radius(n: int, grow: bool = True) -> float:
    """The thesis's 0.85 m, grown (unless ``grow`` is false) so that neighbouring goals are
    >= 0.3 m apart."""
    return RADIUS if n < 2 or not grow else max(RADIUS, GOAL_SPACING / (2 * math.sin(math.pi / n)))


def circle_arena(n: int, grow: bool = True) -> ArenaSpec:
    """The Robotarium arena while the circle fits in it, else a larger arena of its shape."""
    radius = circle_radius(n, grow)
    if radius <= RADIUS:
        return ROBOTARIUM
    scale = radius / RADIUS
    return ArenaSpec.centred(ROBOTARIUM.width * scale, ROBOTARIUM.height * scale)


def circle_goals(n: int, grow: bool = True) -> np.ndarray:
    """Goals ``(n, 3, 2)``: robot i's point on the circle, its antipode, then the point again."""
    radius = circle_radius(n, grow)
    angles = 2 * np.pi * np.arange(n) / max(n, 1)
    here = radius * np.column_stack((np.cos(angles), np.sin(angles)))
    return np.stack((here, -here, here), axis=1)


class CircleRobot(RobotHRVO):
    """A robot of the circle experiment (see the module docs).

    Callbacks: :meth:`update_odom` (odometry), :meth:`update_sensor` (movement sensor),
    :meth:`update_radio` (range radio) and :meth:`update` (the controller, writes ``dxu``).
    """

    def __init__(self, robot_id: int, tag: str, goals: np.ndarray, n: int, **kwargs: Any) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.goals = np.asarray(goals, dtype=np.float64)
        self.current_goal = self.goals[0]
        self.robot_states = [0] * n  # what this robot knows of every robot's state
        self.state = 0  # goals reached so far
        self.change_state = True  # the current goal has not been reached yet
        self.desired_velocity = np.zeros(2)

    def update_radio(self, messages: list[list[int]]) -> list[int]:
        for states in messages:
            self.robot_states = [max(mine, theirs) for mine, theirs in zip(self.robot_states, states)]
        self.robot_states[self.robot_id] = self.state
        if self.state < len(self.goals) and all(s == self.state for s in self.robot_states):
            self.current_goal = self.goals[self.state]
            self.change_state = True
        return self.robot_states

    def update(self, dxu: np.ndarray) -> None:
        if self.has_pose:
            offset = self.current_goal - (self.pos_x, self.pos_y)
            distance = math.hypot(offset[0], offset[1])
            if distance < ARRIVAL:
                self.desired_velocity = np.zeros(2)
                if self.change_state:
                    self.state += 1
                    self.change_state = False
            else:
                self.desired_velocity = self.v_max * offset / distance
        self.steer(self.detections, self.desired_velocity)
        self.command(dxu)


def circle_frame(step: int, sim: Any, robots: list[CircleRobot], radio_range: float = 1.0) -> Frame:
    """What a renderer shows of the circle experiment: goals, HRVO velocities, radio links."""
    poses = sim.poses
    indptr, indices, _ = kernels.neighbours(poses[:2].T, radio_range)
    links = np.column_stack((np.repeat(np.arange(len(robots)), np.diff(indptr)), indices))
    circles = min((r.state for r in robots), default=0)
    return Frame(
        step,
        sim.arena,
        poses,
        goals=np.array([r.current_goal for r in robots]).reshape(-1, 2),
        velocities=np.array([r.dxi for r in robots]).reshape(-1, 2),
        links=links[links[:, 0] < links[:, 1]],
        title=f"{NAME}: circles {circles}/{CIRCLES}, collisions {sim.violations.collision}",
    )


def default_steps(n: int) -> int:
    """An iteration cap that every seed finishes well within (the run stops when done)."""
    return 4000 + 40 * n


class HrvoCircle(Experiment):
    """The circle experiment (see the module docs)."""

    name = NAME
    default_n = 10
    success = "every robot finishes the third circle with zero collisions, boundary and actuator violations"

    def check(self, n: int, backend: str) -> None:
        # On the real Robotarium the arena cannot grow: keep the thesis's circle (beyond 17
        # robots its goals are closer than a robot's diameter, so the robots cannot all arrive).
        self.grow = backend != "robotarium"

    def arena_for(self, n: int) -> ArenaSpec:
        return circle_arena(n, self.grow)

    def build(self, n: int) -> None:
        goals = circle_goals(n, self.grow)
        for i in range(n):
            robot = CircleRobot(i, f"robot_{i}", goals[i], n, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor)
            radio = RangeRadio(i, f"radio_{i}", robot.update_radio)
            create_timer(
                i,
                20 + i % 10,
                [
                    {"delay": 2 + i % 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3 + i % 2, "tag": "movement", "call": movement.update},
                    {"delay": 30, "tag": "radio", "call": radio.update},
                    {"delay": 4 + i % 2, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def steps(self, n: int) -> int:
        return default_steps(n)

    def done(self, step: int, poses: np.ndarray) -> bool:
        return all(robot.state >= CIRCLES for robot in self.robots)

    def measures(self) -> dict[str, Any]:
        """``circles_completed`` (by every robot) and the circle radius (m)."""
        circles = min((r.state for r in self.robots), default=CIRCLES)
        return {"circles_completed": circles, "circle_radius": circle_radius(self.n, self.grow)}

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        return circle_frame(step, self.sim, self.robots)


run = HrvoCircle.run


def run_batch(
    n: int = 10_000,
    seed: int = 0,
    steps: int | None = None,
    *,
    radio_gap: int = 30,
    progress: Any = None,
) -> ExperimentResult:
    """The circle experiment for very large swarms: whole-swarm kernel calls every step.

    The same behaviour as :func:`run` (goals, arrival, HRVO with the same parameters, stepping
    aside when blocked, progress spread by range radio every ``radio_gap`` steps), on the Fast
    backend, but every robot decides every step through one :func:`dream.kernels.hrvo` call.
    Each robot's progress vector becomes a bitset: the robots it knows to have reached at
    least its own number of goals (n^2 / 8 bytes in all, merged by bitwise OR over radio
    links, reset when the robot reaches its next goal); a robot moves on when its set is full,
    which is when every entry of the original's vector equals its own state. Neighbours'
    velocities are their last chosen velocities.
    """
    cap = default_steps(n) if steps is None else steps
    goals = circle_goals(n)
    arena = circle_arena(n)
    bounds = arena.shrunk(GRITSBOT.radius)
    sim = make_robotarium(n, "fast", arena=arena, seed=seed)
    everyone = np.arange(n)
    state = np.zeros(n, dtype=np.int64)  # goals reached
    heading_for = np.zeros(n, dtype=np.int64)  # index of the goal being approached
    unreached = np.ones(n, dtype=bool)  # ...which has not been reached yet
    known = np.zeros((n, (n + 7) // 8), dtype=np.uint8)  # robots known to have state >= own state
    known[everyone, everyone // 8] = 128 >> (everyone % 8)
    full = np.packbits(np.ones(n, dtype=bool))
    sidestep = np.zeros(n, dtype=np.int64)
    side = np.ones(n)
    dxi = np.zeros((n, 2))
    done_at = None
    start = time.perf_counter()
    for t in range(cap):
        x = sim.get_poses()
        p = x[:2].T
        offset = goals[everyone, heading_for] - p
        distance = np.hypot(offset[:, 0], offset[:, 1])
        arrived = distance < ARRIVAL
        reached = arrived & unreached
        state += reached
        unreached &= ~arrived
        known[reached] = 0  # a new level: start over from itself
        known[reached, everyone[reached] // 8] = 128 >> (everyone[reached] % 8)
        if t % radio_gap == 0:
            _merge_known(known, state, p)
            moving_on = (known == full).all(axis=1) & (state < CIRCLES) & ~unreached
            heading_for[moving_on] = state[moving_on]
            unreached |= moving_on
        desired = np.where(arrived[:, None], 0.0, offset * (GRITSBOT.v_max / np.maximum(distance, 1e-12))[:, None])
        aside = sidestep > 0
        turned = side[:, None] * np.column_stack((desired[:, 1], -desired[:, 0]))
        wanted = np.where(aside[:, None], turned, desired)
        sidestep = np.maximum(sidestep - 1, 0)
        dxi = kernels.hrvo(p, dxi, wanted, radius=1.0, bounds=bounds)
        blocked = ~dxi.any(axis=1) & desired.any(axis=1)
        side[blocked] = np.where(aside[blocked], -side[blocked], 1.0)  # as RobotHRVO.steer
        sidestep[blocked] = 10
        sim.set_velocities(everyone, kernels.actuator_limit(kernels.dxi_to_dxu(dxi.T, x)))
        sim.step()
        if progress is not None:
            progress(t + 1, cap)
        if np.all(state >= CIRCLES):
            done_at = t + 1
            break
    wall = time.perf_counter() - start
    measures = {"circles_completed": int(state.min(initial=CIRCLES)), "circle_radius": circle_radius(n)}
    return ExperimentResult.from_backend(NAME + " (batch)", seed, sim, done_at, wall, measures)


def _merge_known(known: np.ndarray, state: np.ndarray, positions: np.ndarray, radio_range: float = 1.0) -> None:
    """One radio exchange: each robot ORs in the sets of the robots in range at its level or above."""
    indptr, indices, _ = kernels.neighbours(positions, radio_range)
    rows = np.repeat(np.arange(len(state)), np.diff(indptr))
    useful = state[indices] >= state[rows]
    rows, senders = rows[useful], indices[useful]
    before = known.copy()
    # Row by row would be a Python loop; instead OR in one neighbour slot at a time.
    order = np.argsort(rows, kind="stable")
    rows, senders = rows[order], senders[order]
    slot = np.arange(len(rows)) - np.searchsorted(rows, rows)
    for k in range(int(slot.max(initial=-1)) + 1):
        pick = slot == k
        known[rows[pick]] |= before[senders[pick]]
