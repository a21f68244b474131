"""Outcomes of the line-consensus experiment."""

from __future__ import annotations

import numpy as np
import pytest

import dream
from dream import rules
from dream.experiments import line_consensus as lc


@pytest.mark.parametrize("seed", range(5))
def test_line_consensus_forms_the_line_without_collision_on_rps(seed):
    result = dream.run("line-consensus", n=6, seed=seed, backend="robotarium")
    assert result.completed_step is not None
    assert result.measures["y_spread"] < lc.TOLERANCE
    assert result.measures["spacing_error"] < lc.TOLERANCE
    assert result.collisions == 0 and result.boundary == 0


def test_line_consensus_orders_robots_by_id_along_x():
    result = dream.run("line-consensus", n=6, seed=2, backend="fast", trace=True)
    x = result.trace[-1, 0]
    np.testing.assert_allclose(x[:-1] - x[1:], lc.SPACING, atol=lc.TOLERANCE)


@pytest.mark.parametrize(("n", "seed"), [(6, 0), (10, 1)])
def test_line_consensus_is_the_same_robot_by_robot_and_as_a_swarm(n, seed):
    # One LineRobot, run robot by robot and as one swarm: the same poses at every step, bit for
    # bit, whole runs long. Six robots: the thesis's (Robotarium arena, plain HRVO); ten: the
    # large team's code paths (lanes, stepping aside, settling without HRVO).
    robots = dream.run("line-consensus", n=n, seed=seed, backend="fast", trace=True)
    swarm = dream.run("line-consensus", n=n, seed=seed, backend="fast", swarm=True, trace=True)
    assert robots.success and swarm.success and swarm.swarm
    assert swarm.completed_step == robots.completed_step
    assert np.array_equal(swarm.trace, robots.trace)


FAULTS = {
    "loss, latency, crash": (dream.Faults(loss=0.3, latency=5, jitter=2, crash=0.1, crash_at=100), {}),
    "liars, W-MSR": (dream.Faults(byzantine=1, lie="random", sensor_noise=0.005, drift=0.02), {"resilient": 1}),
}


@pytest.mark.parametrize("case", FAULTS)
def test_line_consensus_is_the_same_both_ways_under_faults(case):
    faults, params = FAULTS[case]
    robots, swarm = (
        dream.run(
            "line-consensus", n=12, seed=2, backend="fast", steps=400, trace=True, swarm=way, faults=faults, **params
        )
        for way in (False, True)
    )
    assert np.array_equal(swarm.trace, robots.trace) and robots.faults == swarm.faults
    assert robots.faults["messages_lost"] > 0 if "loss" in case else robots.faults["events"]


def test_line_consensus_frames_come_from_its_robots():
    frames = []
    dream.run("line-consensus", n=10, seed=0, backend="fast", swarm=True, steps=40, record=frames.append)
    last = frames[-1]
    assert last.goals.shape == (10, 2) and np.isfinite(last.goals).all()
    assert last.velocities.shape == (10, 2) and np.any(last.velocities != 0)
    assert len(last.links) == len(lc.graph_links(10, np.random.default_rng(0))[0]) // 2


def test_line_consensus_uses_the_thesis_graph_for_six_robots():
    adjacency = lc.graph(6, np.random.default_rng(0))
    np.testing.assert_array_equal(adjacency, lc.THESIS_GRAPH)
    np.testing.assert_array_equal(adjacency, adjacency.T)


@pytest.mark.parametrize("n", [3, 12, 40])
def test_line_consensus_graph_for_other_sizes_is_connected_and_symmetric(n):
    adjacency = lc.graph(n, np.random.default_rng(n))
    np.testing.assert_array_equal(adjacency, adjacency.T)
    assert np.all(np.diag(adjacency) == 0)
    reached, frontier = {0}, [0]
    while frontier:
        i = frontier.pop()
        for j in np.flatnonzero(adjacency[i]):
            if j not in reached:
                reached.add(int(j))
                frontier.append(int(j))
    assert len(reached) == n


def test_line_errors_measure_spread_and_spacing():
    poses = np.array([[0.6, 0.3, 0.0], [0.01, -0.01, 0.0], [0.0, 0.0, 0.0]])
    spread, error = lc.line_errors(poses)
    assert spread == pytest.approx(0.02)
    assert error == pytest.approx(0.0, abs=1e-12)
    poses[0, 0] = 0.65
    assert lc.line_errors(poses)[1] == pytest.approx(0.05)


def test_line_consensus_scales_on_the_fast_backend():
    result = dream.run("line-consensus", n=12, seed=1, backend="fast")
    assert result.backend == "fast" and result.n == 12
    assert result.completed_step is not None and result.collisions == 0


def test_line_consensus_thousand_robots_on_fast_do_not_collide():
    result = dream.run(
        "line-consensus", n=1000, seed=0, backend="fast", steps=150, swarm=True
    )  # robot by robot: the same run
    assert result.n == 1000 and result.collisions == 0


@pytest.mark.parametrize("n", [8, 100, 1000])
def test_large_teams_start_scattered_over_a_strip_as_long_as_the_line(n):
    arena = lc.line_arena(n)
    poses = lc.strip_poses(n, np.random.default_rng(n), arena)
    length = (n - 1) * lc.SPACING
    # Scattered along the whole line (not a central block), at least START_SPACING apart,
    # inside the arena with a metre to spare.
    assert np.ptp(poses[0]) > 0.9 * length
    gaps = np.hypot(*(poses[:2, :, None] - poses[:2, None, :]))
    assert gaps[~np.eye(n, dtype=bool)].min() >= lc.START_SPACING - 1e-9
    assert poses[0].min() >= arena.xmin + 1 and poses[0].max() <= arena.xmax - 1
    assert poses[1].min() >= arena.ymin + 1 and poses[1].max() <= arena.ymax - 1


def test_line_goals_stay_within_the_bounds():
    bounds = (-2.0, 2.0, -1.0, 1.0)
    # A place beyond the left edge (travelling, in its lane) and one beyond the top (settling).
    goals, travelling = rules.line_goal(
        [[0.0, 0.0], [1.0, 0.9]], [[-3.0, 0.0], [1.0, 1.5]], [False, False], 0.3, 0.35, bounds
    )
    np.testing.assert_array_equal(travelling, [True, False])
    np.testing.assert_allclose(goals, [[-2.0, -0.35], [1.0, 1.0]])
