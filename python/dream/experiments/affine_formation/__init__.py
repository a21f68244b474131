"""Affine formation manoeuvres (thesis 3.4): followers track what three leaders do, by stress.

Seven robots per formation: leaders 0-2 know the planned shapes, followers 3-6 only what their
formation tells them by radio, and obey ``p_i' = -k sum_j w_ij (p_i - p_j)`` through HRVO. The
leaders compress, then flatten, the formation to pass two pairs of sweeping bars. The robots are
one :class:`~dream.experiments.affine_formation.robot.FormationRobot`, run robot by robot or as
a swarm with the same poses, under every fault. The story, the failures traced and the rules
that answer them: ``docs/experiments/affine-formation.md``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream.experiments.affine_formation.plan import (
    ENTRY,
    GAPS,
    LEADERS,
    MORPH,
    NOMINAL,
    RECOVER,
    SHAPES,
    TOLERANCE,
    WEIGHTS,
    affine_image,
    bars,
    clearing_shift,
    corner_starts,
    follower_positions,
    follower_targets,
    formation,
    schedule,
    shape_plan,
    stress_matrix,
    tile_centres,
    tiled_arena,
)
from dream.experiments.affine_formation.robot import (
    MEMBERS,
    SILENCE,
    STRIKES,
    FormationRobot,
    leader_goals,
)
from dream.experiments.spec import Experiment
from dream.frames import Frame
from dream.obstacles import Fleet
from dream.specs import GRITSBOT, ROBOTARIUM, ArenaSpec

NAME = "affine-formation"

__all__ = [
    "GAPS", "LEADERS", "MORPH", "NOMINAL", "SHAPES", "SILENCE", "STRIKES", "TOLERANCE", "WEIGHTS",
    "AffineFormation", "FormationRobot", "affine_image", "bars", "clearing_shift", "corner_starts",
    "follower_targets", "formation", "run", "schedule", "stress_matrix", "tile_centres", "tiled_arena",
]  # fmt: skip


class AffineFormation(Experiment):
    """The affine-formation experiment (see the module docs).

    ``n`` is 7 (the thesis's formation) or a multiple of 7: then each group of seven has its
    own Robotarium-sized tile of a larger arena, its own bars and the same manoeuvres.
    """

    name = NAME
    default_n = 7
    success = (
        "follower error below 0.05 m before the first bars, no robot touching a bar, zero violations, "
        "through both passes and back to the nominal shape; under faults, the correct robots hold the "
        "formation of the survivors (a crashed leader counts at its planned place), no correct robot "
        "touches a bar, and a crashed robot is an obstacle where it stopped (collisions with it count)"
    )

    def check(self, n: int, backend: str) -> None:
        if n % MEMBERS:
            raise ValueError(
                "the affine formation has 7 robots (3 leaders, 4 followers) per group: "
                f"n must be a multiple of 7, got n={n}"
            )

    def arena_for(self, n: int) -> ArenaSpec:
        return tiled_arena(n // MEMBERS)

    def swarm_robot(self, n: int) -> FormationRobot:
        self.centres = tile_centres(n // MEMBERS)
        self.leader = np.arange(n) % MEMBERS < LEADERS
        self.passes = schedule()
        self.orders = {int(step): k for k, step in enumerate(shape_plan()[0])}  #: plan step of each order
        self.bars = Fleet()
        self.contacts, self.settled_error, self.deformed_error = 0, math.nan, 0.0
        self.poses: np.ndarray | None = None  #: the last step's poses, whose error is the end's
        return FormationRobot(n, self.centres)

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return corner_starts(rng, self.centres)

    def steps(self, n: int) -> int:
        """Until 30 s after the last bars have left."""
        return self.passes[-1][2] + 2 * RECOVER

    def before_step(self, step: int) -> None:
        """The operator's orders to the leaders (the plan's shapes, on the world's time), and the bars."""
        assert self.engine is not None
        if step in self.orders and "order" in self.engine.memory:  # a learner (dream.rl) takes none
            self.engine.memory["order"][self.leader] = self.orders[step]
        for _, enter, leave, _, gap in self.passes:
            if step == enter:
                self.bars = Fleet(
                    [bar for centre in self.centres for bar in bars(gap, ROBOTARIUM.xmax + ENTRY, centre)]
                )
            if step == leave:
                self.bars = Fleet()

    def after_step(self, step: int, poses: np.ndarray) -> None:
        # The error is found only at the steps a measure reads it: the last step's when asked
        # (each step makes new poses, so keeping them costs no copy).
        self.bars.step(self.sim.time_step)
        self.poses = poses
        if step == self.passes[0][0]:
            self.settled_error = self.error(poses)
        if len(self.bars):
            self.deformed_error = max(self.deformed_error, self.error(poses))
            self.contacts += bool(self.bars.touching(poses[:2, self.correct].T, GRITSBOT.radius).any())

    def error(self, poses: np.ndarray | None) -> float:
        """The correct followers' largest distance (m) to their affine targets at ``poses`` (NaN
        before the first step)."""
        if poses is None:
            return math.nan
        errors = np.linalg.norm(poses[:2, ~self.leader].T - follower_positions(self.anchors(poses)), axis=1)
        return float(errors[self.correct[~self.leader]].max(initial=0.0))

    def anchors(self, poses: np.ndarray) -> np.ndarray:
        """The leaders' positions ``(n, 2)`` (rows of followers unused) that the survivors' formation
        is the affine image of: where the leaders are, and for a crashed leader (or a stuck one, which
        takes itself for crashed) its place in the plan (where a moving leader of its formation aims
        it now)."""
        anchors = poses[:2].T.copy()
        state = self.world.fault_state
        if state is None or not (halted := state.crashed | state.stuck)[self.leader].any():
            return anchors
        assert self.engine is not None
        robot, memory = self.engine.robot, self.engine.memory
        assert isinstance(robot, FormationRobot)
        first = np.arange(0, self.n, MEMBERS)
        for i in range(LEADERS):  # a later leader's aims over an earlier one's
            ids = first + i
            alive = ~halted[ids]
            aims = robot.aims(ids[alive], {key: memory[key][ids[alive]] for key in ("start", "goals", "decisions")})
            for m in range(LEADERS):
                stopped = halted[first[alive] + m]
                anchors[first[alive][stopped] + m] = aims[stopped, m]
        return anchors

    def done(self, step: int, poses: np.ndarray) -> bool:
        return step >= self.steps(self.n) and self.contacts == 0 and self.settled_error < TOLERANCE

    def measures(self) -> dict[str, Any]:
        """The correct followers' error to their affine target just before the first bars set off
        and at the end (m, largest over the formations), the iterations in which a correct robot
        touched a bar, and the largest error while bars are on the arena."""
        return {
            "error_before_bars": self.settled_error,
            "error_end": self.error(self.poses),
            "error_while_deformed": self.deformed_error,
            "bar_contacts": self.contacts,
        }

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        assert self.engine is not None
        leaders = np.flatnonzero(self.leader)
        goals = np.zeros((self.n, 2))
        goals[leaders] = leader_goals({"goals": self.engine.memory["goals"][leaders]}, leaders, self.centres)
        goals[~self.leader] = follower_positions(self.anchors(poses))
        links = np.argwhere(np.triu(WEIGHTS) != 0)
        return Frame(
            step,
            self.arena,
            poses,
            goals=goals,
            velocities=self.engine.dxi.copy(),
            links=(links[None] + MEMBERS * np.arange(self.n // MEMBERS)[:, None, None]).reshape(-1, 2),
            obstacles=[bar.polygon for bar in self.bars.obstacles],
            obstacle_moving=[True] * len(self.bars),
            roles=np.where(self.leader, "leader", "follower"),
            title=f"{NAME}: follower error {self.error(poses):.3f} m, bar contacts {self.contacts}",
        )
