"""Outcomes of the HRVO circle experiment, not just that it runs."""

from __future__ import annotations

import numpy as np
import pytest

from dream import rules
from dream.experiments import hrvo_circle


@pytest.mark.parametrize("seed", range(10))
def test_hrvo_circle_completes_three_circles_without_collision_on_rps(seed):
    result = hrvo_circle.run(n=10, seed=seed, backend="robotarium")
    assert result.backend == "robotarium"
    assert result.measures["circles_completed"] == 3
    assert result.completed_step is not None and result.completed_step < hrvo_circle.default_steps(10)
    assert result.steps == result.completed_step  # stops as soon as it is done
    assert result.collisions == 0
    assert result.boundary == 0


def test_hrvo_circle_fast_backend_follows_rps_trajectories():
    # Same algorithm, same semantics: identical poses until float rounding eventually tips a
    # discrete decision (the conversion's atan2 branch cut), which takes well over 500 steps.
    real = hrvo_circle.run(n=10, seed=3, backend="robotarium", steps=500, trace=True)
    fast = hrvo_circle.run(n=10, seed=3, backend="fast", steps=500, trace=True)
    assert real.trace.shape == fast.trace.shape == (501, 3, 10)
    np.testing.assert_allclose(fast.trace, real.trace, rtol=0, atol=1e-9)
    assert np.abs(real.trace[-1] - real.trace[0]).max() > 0.5  # the robots did move


def test_hrvo_circle_robots_wait_for_their_first_pose():
    # Robot i's timer starts after 20 + i % 10 steps: until then it has no pose and must not move
    # (only the heading's re-wrapping may change its last bit).
    result = hrvo_circle.run(n=10, seed=1, backend="fast", steps=60, trace=True)
    for i in range(10):
        still = result.trace[: 22 + i, :, i]
        np.testing.assert_allclose(still, np.repeat(result.trace[:1, :, i], 22 + i, axis=0), rtol=0, atol=1e-12)
        assert np.abs(result.trace[23 + i, :, i] - result.trace[0, :, i]).max() > 1e-6
    assert np.abs(result.trace[-1] - result.trace[0]).max() > 0


def test_hrvo_circle_is_reproducible():
    first = hrvo_circle.run(n=6, seed=11, backend="fast", steps=400, trace=True)
    second = hrvo_circle.run(n=6, seed=11, backend="fast", steps=400, trace=True)
    np.testing.assert_array_equal(first.trace, second.trace)


def test_hrvo_circle_goals_stay_apart_for_many_robots():
    for n in (10, 50, 200):
        goals = hrvo_circle.circle_goals(n)[:, 0]
        gaps = np.linalg.norm(goals - np.roll(goals, 1, axis=0), axis=1)
        assert gaps.min() >= hrvo_circle.GOAL_SPACING - 1e-12
        arena = hrvo_circle.circle_arena(n)
        assert np.all(np.abs(goals[:, 0]) < arena.xmax) and np.all(np.abs(goals[:, 1]) < arena.ymax)


def test_hrvo_circle_scales_beyond_ten_robots_on_fast():
    # The original state vector was hard-coded for 10 robots and crashed beyond.
    result = hrvo_circle.run(n=24, seed=0, backend="fast", steps=300)
    assert result.n == 24 and result.backend == "fast"
    assert result.collisions == 0


def test_hrvo_circle_thousand_robots_on_fast_do_not_collide():
    result = hrvo_circle.run(n=1000, seed=0, backend="fast", steps=200)
    assert result.n == 1000 and result.steps == 200
    assert result.collisions == 0 and result.boundary == 0


@pytest.mark.parametrize("seed", range(3))
def test_hrvo_circle_swarm_mode_completes_three_circles(seed):
    result = hrvo_circle.run(n=10, seed=seed, backend="fast", swarm=True)
    assert result.swarm and result.experiment == "hrvo-circle"
    assert result.measures["circles_completed"] == 3
    assert result.completed_step is not None and result.collisions == 0 and result.boundary == 0


def test_hrvo_circle_swarm_mode_runs_large_swarms_without_collision():
    result = hrvo_circle.run(n=3000, seed=0, steps=60, backend="fast", swarm=True)
    assert result.n == 3000 and result.steps == 60
    assert result.collisions == 0


def test_hrvo_circle_full_ring_on_rps_does_not_collide():
    # rps's arena cannot grow: as many robots as its ring holds with the 5 cm tolerance, goals on
    # the ellipse filling it (the packed ring beyond: test_hrvo_circle_packed.py).
    n = hrvo_circle.circle_capacity(packed=False)
    result = hrvo_circle.run(n=n, seed=0, backend="robotarium", steps=600)
    assert result.backend == "robotarium" and result.n == n
    assert result.measures["circle_radius"] == hrvo_circle.ROBOTARIUM.width / 2 - hrvo_circle.EDGE
    assert result.collisions == 0 and result.boundary == 0


def test_hrvo_circle_robot_moves_on_when_a_robot_is_already_ahead():
    # A robot taken for crashed while out of radio reach lets the others go ahead; the robots it
    # left behind must not wait for states equal to theirs (N = 100 seeds 3, 5, 7-9 waited for good).
    # Messages: (id, state, left, right, released, heartbeats).
    beats = np.array([0, 1, 1])
    robot = hrvo_circle.CircleRobot(0, "robot_0", np.zeros((3, 2)), 3)
    robot.state, robot.change_state = 2, False  # it reached its second goal
    robot.update_radio([(1, 3, 0, 0, 2, beats), (2, 2, 0, 0, 1, beats)])  # robot 1 reached its third
    assert robot.change_state and robot.released == 2  # heads for its third goal
    robot = hrvo_circle.CircleRobot(0, "robot_0", np.zeros((3, 2)), 3)
    robot.state, robot.change_state = 2, False
    robot.update_radio([(1, 1, 0, 0, 1, beats), (2, 2, 0, 0, 1, beats)])  # robot 1 is behind
    assert not robot.change_state and (robot.left, robot.right) == (1, 0)  # it knows robots 2 and 0


def _stalled_robot(position, detections):
    """A robot of a 100-robot ring at ``position`` whose goal lies across the ring, stalled."""
    layout = hrvo_circle.circle_layout(100)
    goals = np.array([[-5.67, 2.10], [5.67, -2.10], [-5.67, 2.10]])
    robot = hrvo_circle.CircleRobot(0, "robot_0", goals, 100, semi_axes=layout.semi_axes, safety=layout.safety)
    robot.update_odom([*position, 0.0])
    robot.update_sensor(detections)
    for _ in range(hrvo_circle.STALL + 1):  # the first sets how close it has come
        robot.squeeze(np.asarray(position, dtype=float))
    return robot, layout


def test_circle_robot_stalled_outside_the_ring_squeezes_through_it():
    # Traced at N = 100 under latency: a robot pushed outside the ring of parked robots (0.34 m
    # apart, safety radius 0.24 m) slid along it for 7,000 steps. It now takes the least safety
    # radius until no robot it sees is within the ring's.
    near = np.array([[0.17, 2.0, 0.0, 0.0], [0.17, -2.0, 0.0, 0.0]])  # two parked robots beside it
    a, b = hrvo_circle.circle_layout(100).semi_axes
    assert rules.outside_ring([a + 0.2, 0.0], (a, b)) and not rules.outside_ring([a - 0.2, 0.0], (a, b))
    robot, layout = _stalled_robot([a + 0.2, 0.0], near)
    assert robot.safety == hrvo_circle.PACKED_SAFETY < layout.safety
    robot.update_sensor(near)
    robot.closest = 100.0  # progress: it keeps the least radius while those robots are within the ring's
    robot.squeeze(np.array([a + 0.1, 0.0]))
    assert robot.stalled == 0 and robot.safety == hrvo_circle.PACKED_SAFETY
    robot.update_sensor(np.array([[0.5, 2.0, 0.0, 0.0]]))
    robot.squeeze(np.array([a - 0.1, 0.0]))
    assert robot.safety == layout.safety
    inside, _ = _stalled_robot([a - 0.5, 0.0], near)  # stalled inside the ring: a crowd, not a wall
    assert inside.safety == layout.safety


def test_circle_robot_stalled_beside_a_robot_standing_on_its_goal_takes_the_goal():
    # Traced at N = 100 under a crash: robot 80 stayed 0.39 m from its last goal, walled off by the
    # crashed robot 0.19 m off the goal and a finished one beside it.
    goal = np.array([-5.67, 2.10])
    here = goal + (0.39, 0.0)
    still = np.array([[0.20, 0.0, 0.0, 0.0]])  # a robot standing 0.19 m from the goal, towards it
    robot, layout = _stalled_robot(here, still)
    assert robot.goal_taken(here)
    robot.stalled = 0
    assert not robot.goal_taken(here)  # not stalled: 0.39 m is beyond the safety radius plus the tolerance


def test_circle_robot_counts_stalls_only_while_it_travels_to_one_goal():
    a, _ = hrvo_circle.circle_layout(100).semi_axes
    robot, _ = _stalled_robot([a + 0.2, 0.0], np.zeros((0, 4)))
    assert robot.stalled == hrvo_circle.STALL
    robot.state, robot.change_state = 1, False  # arrived: waiting on a goal is not a stall
    robot.squeeze(np.array([a + 0.2, 0.0]))
    assert robot.stalled == 0 and robot.safety == robot.ring_safety  # nobody near: the ring's radius
    robot.stalled, robot.closest = 7, 1.0
    robot.released = 1
    robot.update_radio([])  # every robot has reached its first goal: on to the next, counting over
    assert robot.change_state and (robot.stalled, robot.closest) == (0, np.inf)


def test_squeeze_keeps_the_colliders_of_the_rules_apart():
    from dream.backends import rules_named

    assert hrvo_circle.squeeze_radius(rules_named("rps0")) == hrvo_circle.PACKED_SAFETY
    rps2 = rules_named("rps2")  # colliders 0.135 m wide, 0.025 m ahead: facing robots touch at 0.185 m
    assert hrvo_circle.squeeze_radius(rps2) > rps2.diameter + 2 * rps2.collider_offset
