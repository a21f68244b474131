"""The world learns its simulator's arena and limits from whoever runs it, never from a backend."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import RobotHRVO, World, make_robotarium
from dream.backends import Fast, initial_poses, make_simulator
from dream.export import LabRun
from dream.specs import GRITSBOT, ROBOTARIUM, RPS2, ArenaSpec

LARGE = ArenaSpec.centred(20.0, 12.0)


def test_a_backend_made_directly_leaves_the_current_world_alone():
    with World(0) as world:
        robot = RobotHRVO(0)
        Fast(initial_poses(3, np.random.default_rng(0), LARGE), LARGE, RPS2)
        assert world.arena is None and world.limits is None
        assert robot.arena == ROBOTARIUM and robot.limits == GRITSBOT


def test_make_simulator_touches_no_world_and_keep_to_gives_the_robots_its_arena_and_limits():
    with World(0) as world:
        robot = RobotHRVO(0)
        sim = make_simulator(3, "fast", initial_poses(3, np.random.default_rng(0), LARGE), arena=LARGE, rules="rps2")
        assert world.arena is None and robot.arena == ROBOTARIUM
        world.keep_to(sim.arena, sim.spec)
        assert robot.arena == LARGE
        assert robot.limits == GRITSBOT.within(RPS2) != GRITSBOT  # rps 2.1's wider wheel base


def test_a_lab_run_gives_its_own_world_the_limits_even_when_another_world_is_current():
    own = World(3)
    with World(4) as other:
        lab = LabRun("hrvo-circle", 4, 3, {}, world=own)
    assert (own.arena, own.limits) == (lab.sim.arena, lab.sim.spec)
    assert other.limits is None


def test_make_robotarium_draws_its_poses_from_the_generator_it_is_given():
    drawn = make_robotarium(5, "fast", rng=np.random.default_rng(11)).get_poses()
    assert_array_equal(drawn, initial_poses(5, np.random.default_rng(11)))
    with pytest.raises(ValueError, match="not both"):
        make_robotarium(5, "fast", seed=1, rng=np.random.default_rng(1))
