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


def test_a_sensor_or_radio_reporting_to_another_robot_is_refused_at_once():
    from dream import EncoderSensor, GraphRadio, MovementSensor, OdometrySensor, RangeRadio

    with World(0):
        robot = RobotHRVO(4)
        OdometrySensor(4, "odom_4", robot.update_odom)  # its own id: fine
        makers = [
            lambda: OdometrySensor(2, "odom_2", robot.update_odom),
            lambda: MovementSensor(2, "movement_2", robot.update_sensor),
            lambda: EncoderSensor(2, "enc_2", robot.update_odom),
            lambda: RangeRadio(2, "radio_2", robot.update_odom),
            lambda: GraphRadio(2, "radio_2", robot.update_odom, np.ones((5, 5))),
        ]
        for make in makers:
            with pytest.raises(ValueError, match=r"has robot id 2 but reports to robot 4's update_\w+: give a robot"):
                make()


def test_a_robot_id_beyond_the_simulator_is_named_with_the_ids_it_has():
    from dream import OdometrySensor, World

    with World(0):
        sim = make_robotarium(3, "fast", seed=0)
        robot = RobotHRVO(5)
        sensor = OdometrySensor(5, "odom_5", robot.update_odom)
        with pytest.raises(IndexError, match=r"robot id 5 is out of range for x of 3 robots \(ids 0 to 2\): a robot"):
            sensor.update(sim.get_poses())
