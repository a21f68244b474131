"""hrvo-circle beyond the thesis's ten robots: completion, refusal, and the shared rules."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import dream
from dream import rules
from dream.experiments import hrvo_circle

DATA = Path(__file__).parent / "data"


def assert_clean_completion(result):
    assert result.measures["circles_completed"] == hrvo_circle.CIRCLES
    assert result.completed_step is not None and result.steps == result.completed_step
    assert result.collisions == 0 and result.boundary == 0 and result.actuator == 0


@pytest.mark.parametrize("seed", range(3))
def test_hrvo_circle_twenty_robots_complete_on_rps(seed):
    result = dream.run("hrvo-circle", n=20, seed=seed, backend="robotarium", swarm=True)  # robot by robot: the same run
    assert result.backend == "robotarium"
    assert_clean_completion(result)


@pytest.mark.skipif(os.environ.get("DREAM_PURE_PYTHON") == "1", reason="the largest case: too slow with NumPy HRVO")
def test_hrvo_circle_hundred_robots_complete_on_fast():
    result = dream.run("hrvo-circle", n=100, seed=0, backend="fast", swarm=True)  # robot by robot: the same run
    assert result.backend == "fast"
    assert_clean_completion(result)


@pytest.fixture(scope="module")
def swarm_of_40():
    return dream.run("hrvo-circle", n=40, seed=0, backend="fast", swarm=True, trace=True)


def test_hrvo_circle_swarm_mode_completes_a_large_swarm(swarm_of_40):
    assert swarm_of_40.swarm and swarm_of_40.n == 40
    assert_clean_completion(swarm_of_40)


def test_hrvo_circle_swarm_keeps_its_pinned_trajectories(swarm_of_40):
    # Poses of the CircleRobot swarm, pinned when it replaced the hand-written swarm mode (which
    # finished n=40 seed 0 at step 6046): every 500 steps of n=40 (seed 0, done at step 5852) and
    # every 150 steps of n=200 (seed 1, 300 steps).
    expected = np.load(DATA / "hrvo_circle_swarm.npz")
    assert swarm_of_40.completed_step == expected["n40_seed0_done"] == 5852
    np.testing.assert_allclose(swarm_of_40.trace[::500], expected["n40_seed0"], rtol=0, atol=1e-9)
    wide = dream.run("hrvo-circle", n=200, seed=1, steps=300, backend="fast", swarm=True, trace=True)
    assert (wide.completed_step, wide.collisions, wide.boundary, wide.actuator) == (None, 0, 0, 0)
    np.testing.assert_allclose(wide.trace[::150], expected["n200_seed1_steps300"], rtol=0, atol=1e-9)


def test_hrvo_circle_swarm_mode_frames_and_measures_come_from_its_arrays():
    frames = []
    result = dream.run("hrvo-circle", n=12, seed=2, steps=40, backend="fast", swarm=True, record=frames.append)
    assert len(frames) == 40 and result.measures["circles_completed"] == 0
    last = frames[-1]
    assert last.goals.shape == last.velocities.shape == (12, 2)
    np.testing.assert_array_equal(last.goals, hrvo_circle.circle_goals(12)[:, 0])  # no robot has arrived yet
    assert np.abs(last.velocities).max() > 0  # the robots move
    assert last.title.startswith("hrvo-circle: circles 0/3")


def test_hrvo_circle_refuses_a_radio_gap_below_one_step():
    with pytest.raises(ValueError, match="parameter .radio_gap. of hrvo-circle must be >= 1, got 0"):
        dream.run("hrvo-circle", n=4, backend="fast", swarm=True, radio_gap=0)


def test_hrvo_circle_refuses_more_robots_than_the_robotarium_ring_holds():
    most = hrvo_circle.circle_capacity()
    assert most >= 50  # rps's own limit is 50 robots: every size it simulates has a ring
    assert hrvo_circle.circle_layout(most, grow=False).safety >= hrvo_circle.PACKED_SAFETY  # the limit is accepted
    with pytest.raises(ValueError, match=rf"n={most + 1} robots do not fit .* at most {most} robots"):
        dream.run("hrvo-circle", n=most + 1, backend="robotarium")
    assert hrvo_circle.circle_layout(most + 1, grow=True).arena.width > 3.2  # Fast grows instead
    with pytest.raises(ValueError, match="`n` must be an integer >= 0"):
        hrvo_circle.circle_layout(-1)


@pytest.mark.parametrize(("n", "grow"), [(10, False), (20, False), (30, False), (120, True)])
def test_hrvo_circle_layout_keeps_goals_reachable(n, grow):
    layout = hrvo_circle.circle_layout(n, grow)
    goals = layout.goals
    gaps = np.hypot(*(goals - np.roll(goals, 1, axis=0)).T)
    assert gaps.min() == pytest.approx(layout.spacing)
    assert hrvo_circle.MIN_SAFETY <= layout.safety <= min(hrvo_circle.SAFETY, layout.spacing - 2 * hrvo_circle.ARRIVAL)
    a, b = layout.semi_axes
    np.testing.assert_allclose((goals[:, 0] / a) ** 2 + (goals[:, 1] / b) ** 2, 1.0, atol=1e-9)
    xmin, xmax, ymin, ymax = layout.arena.shrunk(hrvo_circle.EDGE * 0.99)
    assert np.all((goals[:, 0] > xmin) & (goals[:, 0] < xmax) & (goals[:, 1] > ymin) & (goals[:, 1] < ymax))
    if n % 2 == 0:  # antipodes are other robots' goals: the point set is centrally symmetric
        np.testing.assert_allclose(np.roll(goals, n // 2, axis=0), -goals, atol=1e-6)


def test_roundabout_keeps_the_centre_on_the_left():
    semi_axes = (1.5, 0.9)
    start = np.array([[1.5, 0.0], [-1.5, 0.0], [0.0, 0.9], [1.2, 0.0]])
    goal = np.array([[-1.5, 0.0], [1.5, 0.0], [0.0, -0.9], [1.5, 0.0]])
    aim = rules.roundabout_aim(start, goal, semi_axes, 0.5)
    way = aim - start
    cross = start[:, 0] * way[:, 1] - start[:, 1] * way[:, 0]  # > 0: counter-clockwise about the centre
    assert np.all(cross[:3] > 0)
    np.testing.assert_array_equal(aim[3], goal[3])  # a clear way goes straight
    np.testing.assert_array_equal(rules.roundabout_aim(start, goal, semi_axes, 0.0), goal)  # no island


def test_rules_decide_the_same_for_one_robot_and_for_the_swarm(rng):
    n = 40
    positions = rng.uniform(-1.5, 1.5, (n, 2))
    goals = rng.uniform(-1.5, 1.5, (n, 2))
    goals[:3] = positions[:3]  # some robots at their goal
    unreached = rng.random(n) < 0.5
    sidestep = rng.integers(0, 3, n)
    side = rng.choice([-1.0, 1.0], n)
    chosen = np.where((rng.random(n) < 0.5)[:, None], 0.0, rng.normal(size=(n, 2)))

    arrived, reached = rules.arrival(positions, goals, unreached, 0.05)
    aim = rules.roundabout_aim(positions, goals, (1.5, 0.9), 0.5)
    desired = rules.preferred_velocity(positions, aim, goals, 0.2, 1.0)
    wanted, counter = rules.sidestep_preference(desired, sidestep, side)
    after, new_side = rules.sidestep_update(chosen, desired, counter, side, 10)
    for i in range(n):
        one_arrived, one_reached = rules.arrival(positions[i], goals[i], unreached[i], 0.05)
        assert (one_arrived, one_reached) == (arrived[i], reached[i])
        one_aim = rules.roundabout_aim(positions[i], goals[i], (1.5, 0.9), 0.5)
        np.testing.assert_allclose(one_aim, aim[i], rtol=0, atol=1e-15)
        one_desired = rules.preferred_velocity(positions[i], one_aim, goals[i], 0.2, 1.0)
        np.testing.assert_allclose(one_desired, desired[i], rtol=0, atol=1e-15)
        one_wanted, one_counter = rules.sidestep_preference(one_desired, sidestep[i], side[i])
        np.testing.assert_allclose(one_wanted, wanted[i], rtol=0, atol=1e-15)
        one_after, one_side = rules.sidestep_update(chosen[i], one_desired, one_counter, side[i], 10)
        assert (one_counter, one_after, one_side) == (counter[i], after[i], new_side[i])
    speed = np.hypot(*desired.T)
    assert np.all(speed <= 0.2 + 1e-12) and np.all(speed[:3] == 0)
    assert np.all(after[~chosen.any(axis=1) & desired.any(axis=1)] == 10)  # blocked robots step aside
