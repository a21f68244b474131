"""Start poses: distinct grid points, drawn without a table of the whole arena's grid."""

from __future__ import annotations

import numpy as np
import pytest

from dream import ArenaSpec, initial_poses


def test_initial_poses_in_a_vast_arena_cost_only_the_robots():
    # 2,000 km square: 7.3e13 grid points, which a table of them (as before) could never hold.
    arena = ArenaSpec.centred(2e6, 2e6)
    poses = initial_poses(1000, np.random.default_rng(0), arena)
    assert poses.shape == (3, 1000)
    xy = np.round(poses[:2] / 0.2).astype(np.int64)
    assert len(np.unique(xy, axis=1).T) == 1000  # distinct grid points
    assert np.all(np.abs(poses[0]) <= 2e6 * 2.5 / 3.2 / 2) and np.all(np.abs(poses[1]) <= 2e6 * 1.5 / 2.0 / 2)
    assert np.abs(poses[:2]).max() > 1e5  # spread over the arena, not packed in a corner


def test_initial_poses_still_refuse_more_robots_than_grid_points():
    # The Robotarium's central 2.5 x 1.5 m holds a 12 x 7 grid of 0.2 m.
    with pytest.raises(ValueError, match="85 robots do not fit 0.2 m apart in the central 2.50 x 1.50 m"):
        initial_poses(85, np.random.default_rng(0))
    poses = initial_poses(84, np.random.default_rng(0))
    assert len(np.unique(np.round(poses[:2] / 0.1).astype(int), axis=1).T) == 84  # every grid point


@pytest.mark.parametrize("where", [None, lambda x, y: np.hypot(x, y) <= 20.0], ids=["grid", "disc"])
def test_initial_poses_in_space_order_number_the_same_points_across_the_grid(where):
    """With ``space_order`` the robots go column by column across the grid (x, then y, increasing),
    so that robots near each other get near ids: the same poses as drawn (rps's order, the
    default), each point with its heading, only numbered otherwise."""
    arena = ArenaSpec.centred(64.0, 40.0)
    drawn = initial_poses(5000, np.random.default_rng(3), arena, where=where)
    ordered = initial_poses(5000, np.random.default_rng(3), arena, where=where, space_order=True)
    x, y = np.round(ordered[:2] / 0.2).astype(np.int64)
    assert np.all((np.diff(x) > 0) | ((np.diff(x) == 0) & (np.diff(y) > 0)))
    assert not np.all(np.diff(np.round(drawn[0] / 0.2)) >= 0)  # as drawn: anywhere
    assert np.array_equal(drawn[:, np.lexsort((drawn[1], drawn[0]))], ordered)
