"""hrvo-circle on the Robotarium's packed ring (31-51 robots): layout, docking rules, refusals, success."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream import rules
from dream.experiments import hrvo_circle
from dream.specs import RPS2

SEMI_AXES = (1.52, 0.92)


def test_packed_ring_starts_where_the_five_centimetre_tolerance_stops():
    most = hrvo_circle.circle_capacity(packed=False)
    assert not hrvo_circle.circle_layout(most, grow=False).packed
    for n in (most + 1, 40, 50, hrvo_circle.circle_capacity()):
        layout = hrvo_circle.circle_layout(n, grow=False)
        assert layout.packed and layout.arrival == hrvo_circle.PACKED_ARRIVAL
        # robots anywhere within the tolerance of neighbouring goals keep the safety radius
        assert hrvo_circle.PACKED_SAFETY <= layout.safety <= layout.spacing - 2 * layout.arrival + 1e-12
        assert layout.safety <= hrvo_circle.PACKED_SAFETY_CAP
        assert layout.safety >= dream.specs.GRITSBOT.diameter + 0.01  # rps 0.0.0 collides at 0.11 m
    assert not hrvo_circle.circle_layout(200, grow=True).packed  # a growing arena never packs


def test_packed_ring_docks_lie_inside_their_goals():
    goals = hrvo_circle.circle_goals(50, grow=False)[:, 0]
    targets, band = rules.dock(goals * 0.5, goals, SEMI_AXES, 0.3, 0.05, 0.15)  # from well inside
    assert not band.any()
    np.testing.assert_allclose(np.hypot(*(goals - targets).T), 0.3, atol=1e-12)
    a, b = SEMI_AXES
    assert np.all(np.hypot(targets[:, 0] / a, targets[:, 1] / b) < 1.0)
    normal = goals / np.array(SEMI_AXES) ** 2
    way = goals - targets
    np.testing.assert_allclose(way[:, 0] * normal[:, 1] - way[:, 1] * normal[:, 0], 0.0, atol=1e-12)  # along the normal


def test_dock_sends_a_robot_to_its_goal_only_through_its_corridor():
    goal = np.array([0.0, 0.92])  # top of the ring: the inward normal points down, dock at y = 0.62
    for y in (0.63, 0.75, 0.9):
        target, band = rules.dock(np.array([0.02, y]), goal, SEMI_AXES, 0.3, 0.05, 0.15)
        np.testing.assert_array_equal(target, goal)  # in the corridor, 2 cm off its axis
    target, band = rules.dock(np.array([0.3, 0.88]), goal, SEMI_AXES, 0.3, 0.05, 0.15)
    assert band  # beside its goal in the ring's band: back in first, ahead counter-clockwise
    a, b = SEMI_AXES
    assert np.hypot(target[0] / a, target[1] / b) < np.hypot(0.3 / a, 0.88 / b)
    assert np.arctan2(target[1] / b, target[0] / a) == pytest.approx(np.arctan2(0.88 / b, 0.3 / a) + 0.15)
    target, band = rules.dock(np.array([0.5, 0.0]), goal, SEMI_AXES, 0.3, 0.05, 0.15)
    assert not band
    np.testing.assert_allclose(target, [0.0, 0.62], atol=1e-12)  # from inside: to the dock
    positions = np.array([[0.02, 0.75], [0.3, 0.88], [0.5, 0.0]])
    rows, bands = rules.dock(positions, np.tile(goal, (3, 1)), SEMI_AXES, 0.3, 0.05, 0.15)
    np.testing.assert_array_equal(bands, [True, True, False])  # one row each, as for one robot
    np.testing.assert_array_equal(rows[0], goal)


def test_clear_way_measures_the_segment_to_the_goal():
    position, goal = np.array([0.0, 0.0]), np.array([0.02, 0.0])
    assert rules.clear_way(position, goal, np.zeros((0, 2)), 0.12)
    assert rules.clear_way(position, goal, [[0.01, 0.13], [0.15, 0.0]], 0.12)  # beside, and beyond the goal
    assert not rules.clear_way(position, goal, [[0.01, 0.11]], 0.12)
    assert not rules.clear_way(position, goal, [[0.13, 0.0]], 0.12)  # 0.11 past the goal


def test_packed_ring_robots_start_inside_it():
    exp = hrvo_circle.HrvoCircle()
    exp.check(50, "robotarium")
    exp.arena = exp.arena_for(50)
    poses = exp.initial_poses(50, np.random.default_rng(3))
    a, b = exp.layout.semi_axes
    assert np.all(np.hypot(poses[0] / a, poses[1] / b) <= hrvo_circle.START_INSIDE)
    gaps = np.hypot(*(poses[:2, :, None] - poses[:2, None, :]))
    assert gaps[~np.eye(50, dtype=bool)].min() >= 0.2 - 1e-12  # rps's grid


def test_packed_ring_is_refused_where_it_cannot_succeed():
    refusal = r"only rps 0.0.0's rules leave room for: rps2's colliders .* at most 30 robots"
    with pytest.raises(ValueError, match=refusal):
        _packed_under(RPS2)  # the lab's rps 2.1, installed, is the only way there: Fast grows the ring
    with pytest.raises(ValueError, match="at most 51 robots fit"):
        hrvo_circle.circle_layout(52, grow=False)


def _packed_under(rules_spec):
    """Build the 40-robot packed ring as a run under ``rules_spec`` would."""
    exp = hrvo_circle.HrvoCircle()
    exp.check(40, "robotarium")
    exp.n, exp.rules, exp.arena = 40, rules_spec, exp.arena_for(40)
    exp.swarm_robot(40)


def test_packed_ring_is_the_same_robot_by_robot_and_as_a_swarm():
    # Its docks, inward side-steps, parking and clear final approach run both ways alike (the
    # hand-written swarm mode refused the packed ring).
    robots, swarm = (
        dream.run("hrvo-circle", n=40, seed=1, backend="robotarium", steps=400, trace=True, swarm=way)
        for way in (False, True)
    )
    assert np.array_equal(swarm.trace, robots.trace) and swarm.swarm
    assert np.abs(robots.trace[-1] - robots.trace[0]).max() > 0.5 and robots.collisions == 0


def test_a_robot_that_changes_its_safety_radius_plans_with_the_new_one():
    beside = np.array([[0.3, -3 * np.pi / 4, 0.0, 0.0]])  # a standing robot 0.3 m away at 45 degrees

    def choice(robot):
        robot.update_odom([0.0, 0.0, 0.0])
        robot.dxi = np.zeros(2)
        return robot.HRVO(beside, [0.2, 0.0])

    robot = dream.RobotHRVO(0, "r", safety=0.28)
    wide = choice(robot)
    robot.safety = 0.15
    narrow = choice(robot)
    np.testing.assert_array_equal(narrow, choice(dream.RobotHRVO(1, "r", safety=0.15)))
    assert np.hypot(*(narrow - [0.2, 0.0])) < np.hypot(*(wide - [0.2, 0.0]))  # a narrower cone, closer to +x


@pytest.mark.parametrize("seed", [0])
def test_fifty_robots_complete_three_circles_on_rps(seed):
    result = dream.run("hrvo-circle", n=50, seed=seed, backend="robotarium")
    assert result.backend == "robotarium" and result.n == 50
    assert result.measures["circles_completed"] == hrvo_circle.CIRCLES
    assert result.completed_step is not None and result.completed_step == result.steps
    assert (result.collisions, result.boundary, result.actuator) == (0, 0, 0)
