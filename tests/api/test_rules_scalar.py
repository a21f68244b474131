"""The rules' scalar path (one robot's ``(2,)`` vectors, or its ``(1, 2)`` row) rounds exactly as
their array path (a swarm's ``(n, 2)`` rows), so per-robot and swarm modes keep deciding alike."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import rules

N = 2000


@pytest.fixture
def scene(rng):
    """Positions, goals and velocities around a ring of semi-axes (1.5, 0.9), some coinciding."""
    positions = rng.uniform(-2.0, 2.0, (N, 2))
    goals = rng.uniform(-2.0, 2.0, (N, 2))
    goals[::7] = -positions[::7]  # straight through the centre
    goals[::11] = positions[::11]  # already there
    velocities = rng.uniform(-0.2, 0.2, (N, 2))
    velocities[::5] = 0.0
    return positions, goals, velocities


def test_roundabout_aim_scalar_path_matches_rows(scene):
    positions, goals, _ = scene
    for island in (0.0, 0.5):
        batch = rules.roundabout_aim(positions, goals, (1.5, 0.9), island)
        crossing = 0
        for i in range(N):
            one = rules.roundabout_aim(positions[i], goals[i], (1.5, 0.9), island)
            assert_array_equal(one, batch[i])
            row = rules.roundabout_aim(positions[i : i + 1], goals[i : i + 1], (1.5, 0.9), island)
            assert row.shape == (1, 2) and np.array_equal(row[0], one)
            crossing += not np.array_equal(one, goals[i] / (1.5, 0.9) * (1.5, 0.9))
        assert island == 0.0 or crossing > N // 10  # the island's branch is taken too


def test_preferred_velocity_scalar_path_matches_rows(scene):
    positions, goals, _ = scene
    aims = rules.roundabout_aim(positions, goals, (1.5, 0.9), 0.5)
    batch = rules.preferred_velocity(positions, aims, goals, 0.2, 1.0)
    for i in range(N):
        assert_array_equal(rules.preferred_velocity(positions[i], aims[i], goals[i], 0.2, 1.0), batch[i])
        row = rules.preferred_velocity(positions[i : i + 1], aims[i : i + 1], goals[i : i + 1], 0.2, 1.0)
        assert row.shape == (1, 2) and np.array_equal(row[0], batch[i])


def test_sidestep_rules_scalar_path_matches_rows(scene, rng):
    _, _, velocities = scene
    desired = np.roll(velocities, 1, axis=0)
    sidestep = rng.integers(0, 3, N)
    side = rng.choice([-1.0, 1.0], N)
    wanted, after = rules.sidestep_preference(desired, sidestep, side)
    counter, turned = rules.sidestep_update(velocities, desired, after, side, 10)
    for i in range(N):
        one_wanted, one_after = rules.sidestep_preference(desired[i], int(sidestep[i]), float(side[i]))
        assert_array_equal(one_wanted, wanted[i])
        assert int(one_after) == after[i]
        one_counter, one_side = rules.sidestep_update(velocities[i], desired[i], int(after[i]), float(side[i]), 10)
        assert (int(one_counter), float(one_side)) == (counter[i], turned[i])
    assert len(np.unique(counter)) > 2 and (turned != side).any()  # blocked robots step aside


def test_arrival_scalar_path_matches_rows(scene, rng):
    positions, goals, _ = scene
    goals = positions + rng.normal(0.0, 0.05, positions.shape)
    unreached = rng.random(N) < 0.5
    arrived, reached = rules.arrival(positions, goals, unreached, 0.05)
    for i in range(N):
        assert rules.arrival(positions[i], goals[i], bool(unreached[i]), 0.05) == (arrived[i], reached[i])
        row = rules.arrival(positions[i : i + 1], goals[i : i + 1], unreached[i : i + 1], 0.05)
        assert [(r.shape, r.dtype, r[0]) for r in row] == [((1,), bool, arrived[i]), ((1,), bool, reached[i])]
    assert arrived.any() and not arrived.all() and reached.any()


def test_ring_rules_take_one_robots_row_as_its_row_of_many(scene, rng):
    positions, goals, _ = scene
    distance, closest = rng.uniform(0.0, 2.0, N), rng.uniform(0.0, 2.0, N)
    closest[::9] = np.inf
    stalled, unreached = rng.integers(0, 30, N), rng.integers(0, 2, N)
    squeezing, outside, nearest = rng.integers(0, 2, N), rng.random(N) < 0.5, rng.uniform(0.0, 0.5, N)
    nearest[::4] = np.nan  # nobody seen
    many = rules.stall(distance, closest, stalled, unreached, 0.05)
    squeeze = rules.squeezes(squeezing, stalled, 20, outside, nearest, 0.24)
    beyond = rules.outside_ring(positions, (1.5, 0.9))
    for i in range(N):
        one = slice(i, i + 1)
        got = rules.stall(distance[one], closest[one], stalled[one], unreached[one], 0.05)
        assert [(g.shape, g.dtype, g[0]) for g in got] == [((1,), m.dtype, m[i]) for m in many]
        got = rules.squeezes(squeezing[one], stalled[one], 20, outside[one], nearest[one], 0.24)
        assert (got.shape, got.dtype, got[0]) == ((1,), squeeze.dtype, squeeze[i])
        got = rules.outside_ring(positions[one], (1.5, 0.9))
        assert (got.shape, got.dtype, got[0]) == ((1,), beyond.dtype, beyond[i])
    assert many[1].any() and (many[1] == 0).any() and squeeze.any() and not squeeze.all() and beyond.any()
