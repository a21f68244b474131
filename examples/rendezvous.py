"""Rendezvous: robots meet without a meeting point given, agreeing on one over the radio.

Written only on DREAM's public API, as a researcher writes a new experiment, and written once,
on arrays: the same robot runs robot by robot (the default) and as one swarm (``--swarm``),
with the same poses at every step. Every robot knows its own pose (odometry), hears the
meeting points proposed by the robots within radio range, proposes the mean of those and its
own, and heads for it; HRVO keeps it off the robots its movement sensor sees. Nobody knows where the meeting point
is, or how many robots there are. Success: every correct robot (not crashed, stuck or lying)
within ``radius`` of the correct robots' centre (by default, a disc that holds the team at
HRVO's safety distance: 0.6 m for 10 robots, 0.85 m for 20), zero collisions.

    dream run examples/rendezvous.py -n 20 --json out.json
    dream run examples/rendezvous.py --swarm -n 1000 --backend fast --fault loss=0.3 --fault crash=0.1@50
    dream run examples/rendezvous.py --param radio_range=0.6 --video rendezvous.gif
"""

from __future__ import annotations

import math

import numpy as np

from dream import Experiment, initial_poses, param
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.swarm import Avoid, Movement, Radio, SwarmRobot, View


class MeetingRobot(SwarmRobot):
    """Agrees on a meeting point with the robots it hears, and heads for it.

    Each robot proposes a meeting point (at first, where it stands), and at every decision takes
    the mean of its own proposal and those it hears: an average consensus, so the proposals of
    a connected team converge to one point. Heading for the mean of the neighbours' *positions*
    instead stalls large teams: a robot amid others has its own position as that mean, so nothing
    presses the crowd together (1,000 robots stopped at 1.24 times the meeting radius)."""

    period = 5
    threaded = True  # decide reads its view alone: blocks of a swarm decide on several threads
    movement = Movement(range=0.5)
    memory = {"meet_x": math.nan, "meet_y": math.nan}

    def __init__(self, gain: float, safety: float, radio_range: float) -> None:
        self.gain = gain
        self.avoid = Avoid(safety=safety)
        self.radio = Radio(range=radio_range, fields=("x", "y"))

    def start(self, ids: np.ndarray) -> np.ndarray:
        return 10 + ids % 5  # the robots start a few steps apart, as they would in a lab

    def decide(self, view: View) -> np.ndarray:
        here = view.pose[:, :2]
        own = np.column_stack((view.memory["meet_x"], view.memory["meet_y"]))
        own = np.where(np.isnan(own), here, own)  # the first proposal: where the robot stands
        heard = view.heard
        meet = (heard.sum(["x", "y"]) + own) / (heard.count + 1)[:, None]
        view.memory["meet_x"], view.memory["meet_y"] = meet[:, 0], meet[:, 1]
        view.send(x=meet[:, 0], y=meet[:, 1])
        wished = self.gain * (meet - here)
        speed = np.hypot(wished[:, 0], wished[:, 1])
        fast = speed > self.spec.v_max
        wished[fast] *= (self.spec.v_max / speed[fast])[:, None]
        return wished


class Rendezvous(Experiment):
    name = "rendezvous"
    default_n = 10
    success = "every correct robot within `radius` of the correct robots' centre, zero collisions"
    radius: float = param(
        0.0, "the team has met when every robot is this close to its centre (m; 0: met_radius(n))", ge=0
    )
    radio_range: float = param(1.0, "how far a robot hears the others (m)", gt=0)
    gain: float = param(0.5, "proportional gain towards the meeting point (1/s)", gt=0)
    safety: float = param(0.2, "HRVO safety distance between robot centres (m)", gt=0)

    def met_radius(self, n: int) -> float:
        """The default ``radius``: 1.8 times that of the smallest disc holding n robots ``safety``
        apart (hexagonal packing). HRVO without a time horizon keeps robots out of each other's
        safety disc along their whole way, so a crowd settles looser than the densest packing:
        1,000 robots settled at 1.7 times it."""
        return 1.8 * self.safety / 2 * math.sqrt(n / 0.9069)

    def arena_for(self, n: int) -> ArenaSpec:
        """The Robotarium up to 40 robots; beyond, the Robotarium's shape with twice the start
        grid's points per robot (so that the team starts about as dense at any size)."""
        if n <= 40:
            return ROBOTARIUM
        scale = math.sqrt(2 * n / 84)  # 84: the Robotarium's start grid points, 0.2 m apart
        return ArenaSpec.centred(ROBOTARIUM.width * scale, ROBOTARIUM.height * scale)

    def steps(self, n: int) -> int:
        return 3000 + 2 * n

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """rps's random grid points, the robots numbered across the grid: no robot's role depends
        on its id, and near ids for near robots keep a million robots' arrays in cache."""
        return initial_poses(n, rng, self.arena, space_order=True)

    def swarm_robot(self, n: int) -> MeetingRobot:
        return MeetingRobot(self.gain, self.safety, self.radio_range)

    def check(self, n: int, backend: str) -> None:
        if self.radius == 0.0:
            self.radius = self.met_radius(n)

    def correct_positions(self, poses: np.ndarray) -> np.ndarray:
        """The correct robots' positions ``(2, k)`` (no copy of a team without faults)."""
        correct = self.correct
        return poses[:2] if correct.all() else poses[:2, correct]

    def spread(self, poses: np.ndarray) -> float:
        """The largest distance of a correct robot from the correct robots' centre (m)."""
        team = self.correct_positions(poses)
        squares = (team - team.mean(axis=1, keepdims=True)) ** 2
        return math.sqrt((squares[0] + squares[1]).max())  # one root, of the largest: a measure taken every step

    def done(self, step: int, poses: np.ndarray) -> bool:
        return self.spread(poses) <= self.radius

    def potential(self, poses: np.ndarray) -> np.ndarray:
        """For learners (:mod:`dream.rl`): each robot's distance to the correct robots' centre, negated
        (m; a learner's reward is its gain over a step)."""
        return -np.hypot(*(poses[:2] - self.correct_positions(poses).mean(axis=1, keepdims=True)))

    def measures(self) -> dict[str, float]:
        return {"spread": self.spread(self.sim.poses)}
