"""Outcomes of the HRVO circle experiment, not just that it runs."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream import rules
from dream.experiments import hrvo_circle


@pytest.mark.parametrize("seed", range(10))
def test_hrvo_circle_completes_three_circles_without_collision_on_rps(seed):
    result = dream.run("hrvo-circle", n=10, seed=seed, backend="robotarium")
    assert result.backend == "robotarium"
    assert result.measures["circles_completed"] == 3
    assert result.completed_step is not None and result.completed_step < hrvo_circle.default_steps(10)
    assert result.steps == result.completed_step  # stops as soon as it is done
    assert result.collisions == 0
    assert result.boundary == 0


def test_hrvo_circle_fast_backend_follows_rps_trajectories():
    # Same algorithm, same semantics: identical poses until float rounding eventually tips a
    # discrete decision (the conversion's atan2 branch cut), which takes well over 500 steps.
    real = dream.run("hrvo-circle", n=10, seed=3, backend="robotarium", steps=500, trace=True)
    fast = dream.run("hrvo-circle", n=10, seed=3, backend="fast", steps=500, trace=True)
    assert real.trace.shape == fast.trace.shape == (501, 3, 10)
    np.testing.assert_allclose(fast.trace, real.trace, rtol=0, atol=1e-9)
    assert np.abs(real.trace[-1] - real.trace[0]).max() > 0.5  # the robots did move


def test_hrvo_circle_robots_wait_for_their_first_pose():
    # Robot i's timer starts after 20 + i % 10 steps: until then it has no pose and must not move
    # (only the heading's re-wrapping may change its last bit).
    result = dream.run("hrvo-circle", n=10, seed=1, backend="fast", steps=60, trace=True)
    for i in range(10):
        still = result.trace[: 22 + i, :, i]
        np.testing.assert_allclose(still, np.repeat(result.trace[:1, :, i], 22 + i, axis=0), rtol=0, atol=1e-12)
        assert np.abs(result.trace[23 + i, :, i] - result.trace[0, :, i]).max() > 1e-6
    assert np.abs(result.trace[-1] - result.trace[0]).max() > 0


def test_hrvo_circle_is_reproducible():
    first = dream.run("hrvo-circle", n=6, seed=11, backend="fast", steps=400, trace=True)
    second = dream.run("hrvo-circle", n=6, seed=11, backend="fast", steps=400, trace=True)
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
    result = dream.run("hrvo-circle", n=24, seed=0, backend="fast", steps=300)
    assert result.n == 24 and result.backend == "fast"
    assert result.collisions == 0


def test_hrvo_circle_thousand_robots_on_fast_do_not_collide():
    result = dream.run(
        "hrvo-circle", n=1000, seed=0, backend="fast", steps=200, swarm=True
    )  # robot by robot: the same run
    assert result.n == 1000 and result.steps == 200
    assert result.collisions == 0 and result.boundary == 0


@pytest.mark.parametrize("seed", range(3))
def test_hrvo_circle_swarm_mode_completes_three_circles(seed):
    result = dream.run("hrvo-circle", n=10, seed=seed, backend="fast", swarm=True)
    assert result.swarm and result.experiment == "hrvo-circle"
    assert result.measures["circles_completed"] == 3
    assert result.completed_step is not None and result.collisions == 0 and result.boundary == 0


def test_hrvo_circle_swarm_mode_runs_large_swarms_without_collision():
    result = dream.run("hrvo-circle", n=3000, seed=0, steps=60, backend="fast", swarm=True)
    assert result.n == 3000 and result.steps == 60
    assert result.collisions == 0


@pytest.mark.parametrize(
    "faults",
    [None, dream.Faults(loss=0.3, latency=5, jitter=2, crash=0.2, crash_at=300, sensor_noise=0.002, drift=0.02)],
    ids=["no fault", "loss, latency, crash, noise, drift"],
)
def test_hrvo_circle_is_the_same_robot_by_robot_and_as_a_swarm(faults):
    # One CircleRobot, run robot by robot and as one swarm: the same poses at every step, bit for
    # bit (without faults the whole run, three circles long).
    steps = None if faults is None else 1500
    robots, swarm = (
        dream.run("hrvo-circle", n=10, seed=1, backend="fast", steps=steps, trace=True, swarm=way, faults=faults)
        for way in (False, True)
    )
    assert swarm.swarm and not robots.swarm and robots.faults == swarm.faults
    assert np.array_equal(swarm.trace, robots.trace)
    if faults is None:
        assert robots.success and swarm.completed_step == robots.completed_step
    else:
        assert robots.faults["messages_lost"] > 0 and len(robots.faults["events"]) == 2


def test_hrvo_circle_is_the_same_both_ways_under_every_fault_kind():
    every = dream.Faults.every_kind()
    robots, swarm = (
        dream.run("hrvo-circle", n=20, seed=1, backend="fast", steps=500, trace=True, swarm=way, faults=every)
        for way in (False, True)
    )
    assert np.array_equal(swarm.trace, robots.trace) and robots.faults == swarm.faults
    assert robots.faults["messages_lost"] > 0 and robots.faults["readings_dropped"] > 0
    assert robots.collisions == swarm.collisions == 0


def test_hrvo_circle_full_ring_on_rps_does_not_collide():
    # rps's arena cannot grow: as many robots as its ring holds with the 5 cm tolerance, goals on
    # the ellipse filling it (the packed ring beyond: test_hrvo_circle_packed.py).
    n = hrvo_circle.circle_capacity(packed=False)
    result = dream.run("hrvo-circle", n=n, seed=0, backend="robotarium", steps=600)
    assert result.backend == "robotarium" and result.n == n
    assert result.measures["circle_radius"] == hrvo_circle.ROBOTARIUM.width / 2 - hrvo_circle.EDGE
    assert result.collisions == 0 and result.boundary == 0


def _view(robot, memory, clock=20.0, pose=(0.0, 0.0, 0.0), heard=(), seen=()):
    """Robot 0's view: its ``memory`` (one value per field), the messages ``heard`` (sender and
    :data:`hrvo_circle.MESSAGE`'s fields each) and the detections ``seen`` (rows
    ``[distance, bearing, dx, dy, vx, vy]``)."""
    heard = np.asarray(heard, dtype=np.int64).reshape(-1, 1 + len(hrvo_circle.MESSAGE))
    seen = np.asarray(seen, dtype=np.float64).reshape(-1, 6)
    inbox = dream.swarm.Neighbourhood(
        np.array([0, len(heard)]),
        {"sender": heard[:, 0], **{key: heard[:, 1 + k] for k, key in enumerate(hrvo_circle.MESSAGE)}},
    )
    names = ("distance", "bearing", "dx", "dy", "vx", "vy")
    detections = dream.swarm.Neighbourhood(np.array([0, len(seen)]), {key: seen[:, k] for k, key in enumerate(names)})
    full = {key: np.atleast_1d(np.asarray(memory.get(key, value))) for key, value in robot.memory.items()}
    return dream.swarm.View(np.array([0]), np.array([clock]), np.array([pose]), detections, inbox, full)


def _robot(n):
    return hrvo_circle.CircleRobot(hrvo_circle.circle_layout(n), hrvo_circle.PACKED_SAFETY, 30, hrvo_circle.SENSING)


def test_hrvo_circle_robot_moves_on_when_a_robot_is_already_ahead():
    # A robot taken for crashed while out of radio reach lets the others go ahead; the robots it
    # left behind must not wait for states equal to theirs (N = 100 seeds 3, 5, 7-9 waited for good).
    # Messages: sender, then state, left, right, released, the two robots watched and their ages, suspects.
    robot = _robot(3)
    mine = {"state": 2, "unreached": 0, "heading": 1}  # it reached its second goal
    view = _view(robot, mine, heard=[(1, 3, 0, 0, 2, -1, 0, -1, 0, 0), (2, 2, 0, 0, 1, -1, 0, -1, 0, 0)])
    robot.decide(view)  # robot 1 reached its third goal
    assert view.memory["unreached"][0] == 1 and view.memory["heading"][0] == 2 and view.memory["released"][0] == 2
    view = _view(robot, mine, heard=[(1, 1, 0, 0, 1, -1, 0, -1, 0, 0), (2, 2, 0, 0, 1, -1, 0, -1, 0, 0)])
    robot.decide(view)  # robot 1 is behind
    assert view.memory["unreached"][0] == 0 and (view.memory["left"][0], view.memory["right"][0]) == (1, 0)


def test_a_silent_robot_is_taken_for_crashed_after_the_silence():
    # Robot 0 and robot 1 have reached their first goals; robot 2 never says a word. Robot 0 watches
    # it beyond both ends of its arc and takes it for crashed after SILENCE rounds, not before.
    robot = _robot(3)
    for relay, crashed in (((-1, 0), True), ((2, 0), False)):  # robot 1 hears robot 2 in the second case
        memory = {"state": 1, "unreached": 0}
        for round_ in range(1, hrvo_circle.SILENCE + 2):
            heard = [(1, 1, 0, 0, 0, -1, 0, *relay, 0)]
            view = _view(robot, memory, clock=20.0 + 30 * round_, heard=heard)
            robot.decide(view)
            memory = {key: values[0] for key, values in view.memory.items()}
            if round_ <= hrvo_circle.SILENCE or not crashed:
                assert memory["suspects"] == 0 and memory["unreached"] == 0 and memory["released"] == 0
        if crashed:  # its arc grew over robot 2: robot 0 moves on
            assert memory["suspects"] == 1 and memory["unreached"] == 1 and memory["released"] == 1
            assert memory["left"] + memory["right"] + 1 == 3


def test_circle_robot_stalled_outside_the_ring_squeezes_through_it():
    # Traced at N = 100 under latency: a robot pushed outside the ring of parked robots (0.34 m
    # apart, safety radius 0.24 m) slid along it for 7,000 steps. It now takes the least safety
    # radius until no robot it sees is within the ring's.
    a, b = hrvo_circle.circle_layout(100).semi_axes
    safety = hrvo_circle.circle_layout(100).safety
    assert rules.outside_ring([a + 0.2, 0.0], (a, b)) and not rules.outside_ring([a - 0.2, 0.0], (a, b))
    stall = hrvo_circle.STALL
    assert rules.squeezes(False, stall, stall, True, 0.17, safety)  # stalled outside: squeezes
    assert not rules.squeezes(False, stall - 1, stall, True, 0.17, safety)  # not yet stalled
    assert rules.squeezes(True, 0, stall, True, 0.17, safety)  # progress: keeps squeezing while robots are near
    assert not rules.squeezes(True, 0, stall, False, 0.5, safety)  # none within the ring's radius: back to it
    assert not rules.squeezes(True, 0, stall, False, np.nan, safety)  # none seen at all
    assert not rules.squeezes(False, stall, stall, False, 0.17, safety)  # stalled inside: a crowd, not a wall
    robot = _robot(100)
    near = [(0.17, 0.0, 0.17, 0.0, 0.0, 0.0)]
    memory = {"stalled": stall, "closest": 0.0}  # it has come no closer for STALL decisions
    view = _view(robot, memory, pose=(a + 0.2, 0.0, 0.0), seen=near)
    robot.decide(view)
    assert view.memory["squeezing"][0] == 1 and view.safety[0] == hrvo_circle.PACKED_SAFETY < safety


def test_circle_robot_stalled_beside_a_robot_standing_on_its_goal_takes_the_goal():
    # Traced at N = 100 under a crash: robot 80 stayed 0.39 m from its last goal, walled off by the
    # crashed robot 0.19 m off the goal and a finished one beside it.
    layout = hrvo_circle.circle_layout(100)
    goal = np.array([[-5.67, 2.10]])
    here = goal + (0.39, 0.0)
    still = np.array([[-0.20, 0.0]])  # a robot standing 0.19 m from the goal, towards it
    offsets, stands = np.array([0, 1]), np.array([True])
    stalled_reach = 2 * layout.safety + layout.arrival
    assert rules.goal_taken(here, goal, offsets, still, stands, [stalled_reach], layout.safety)[0]
    # not stalled: 0.39 m is beyond the safety radius plus the tolerance
    assert not rules.goal_taken(here, goal, offsets, still, stands, [layout.safety + layout.arrival], layout.safety)[0]
    assert not rules.goal_taken(here, goal, offsets, still, [False], [stalled_reach], layout.safety)[0]  # it moves


def test_circle_robot_counts_stalls_only_while_it_travels_to_one_goal():
    closest, stalled = rules.stall(1.0, 1.0, 7, True, hrvo_circle.PROGRESS)
    assert (closest, stalled) == (1.0, 8)  # no closer: one more decision stalled
    closest, stalled = rules.stall(0.85, 1.0, 7, True, hrvo_circle.PROGRESS)
    assert (closest, stalled) == (0.85, 0)  # progress
    assert rules.stall(1.0, 1.0, 7, False, hrvo_circle.PROGRESS)[1] == 0  # arrived: waiting on a goal is not a stall
    robot = _robot(100)
    memory = {"state": 1, "unreached": 0, "released": 1, "stalled": 7, "closest": 1.0}
    view = _view(robot, memory)
    robot.decide(view)  # every robot has reached its first goal: on to the next, counting over
    assert view.memory["unreached"][0] == 1 and view.memory["stalled"][0] == 0


def test_squeeze_keeps_the_colliders_of_the_rules_apart():
    from dream.backends import rules_named

    assert hrvo_circle.squeeze_radius(rules_named("rps0")) == hrvo_circle.PACKED_SAFETY
    rps2 = rules_named("rps2")  # colliders 0.135 m wide, 0.025 m ahead: facing robots touch at 0.185 m
    assert hrvo_circle.squeeze_radius(rps2) > rps2.diameter + 2 * rps2.collider_offset
