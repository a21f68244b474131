"""Robots keep to the arena of the simulator they run on, and say so when they cannot."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from dream import RobotHRVO, World, make_robotarium
from dream.specs import ROBOTARIUM, ArenaSpec

LARGE = ArenaSpec.centred(20.0, 12.0)


def _far_robot(**kwargs):
    robot = RobotHRVO(0, **kwargs)
    robot.update_odom([7.0, 4.0, 0.0])  # outside the Robotarium, inside LARGE
    return robot


def test_robot_takes_the_arena_of_its_simulator():
    with World(0):
        robot = _far_robot()
        assert robot.arena == ROBOTARIUM  # no simulator yet
        make_robotarium(3, "fast", arena=LARGE)
        assert robot.arena == LARGE and robot.bound_x == [-10 + 0.055, 10 - 0.055]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            chosen = robot.HRVO(np.zeros((0, 4)), [0.1, 0.0])
    np.testing.assert_allclose(chosen, [0.1, 0.0])


def test_robot_outside_a_given_arena_warns_once_with_the_way_out():
    with World(0):
        make_robotarium(3, "fast", arena=LARGE)
        robot = _far_robot(arena=ROBOTARIUM)
        with pytest.warns(UserWarning, match=r"robot 0 is at \(7.00, 4.00\), outside its arena .* arena=sim.arena"):
            assert not robot.HRVO(np.zeros((0, 4)), [0.1, 0.0]).any()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            robot.HRVO(np.zeros((0, 4)), [0.1, 0.0])  # once is enough
