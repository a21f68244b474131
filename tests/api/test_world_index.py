"""The world's per-step neighbour index answers exactly as the stateless per-robot query."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import kernels
from dream.obstacles import Obstacle, sensed


@pytest.mark.parametrize("n", [1, 2, 40])
@pytest.mark.parametrize("fov", [2 * np.pi, np.pi / 2, 0.0])
def test_world_neighbours_of_matches_the_kernel(world, rng, n, fov):
    poses = np.vstack((rng.uniform(-1, 1, (2, n)), rng.uniform(-np.pi, np.pi, n)))
    poses[:, -1] = poses[:, 0]  # a co-located pair
    for i in range(n):
        got = world.neighbours_of(poses, i, 0.6, heading=poses[2, i], direction=0.3, fov=fov)
        want = kernels.neighbours_of(poses[:2].T, i, 0.6, heading=poses[2, i], direction=0.3, fov=fov)
        assert_array_equal(got[0], want[0])
        assert_array_equal(got[1], want[1])


def test_world_neighbours_of_notices_poses_changed_in_place(world):
    # rps hands out the same pose array every step, moved in place.
    poses = np.array([[0.0, 0.5, 3.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert_array_equal(world.neighbours_of(poses, 0, 1.0)[0], [1])
    poses[0, 2] = 0.2
    assert_array_equal(world.neighbours_of(poses, 0, 1.0)[0], [1, 2])


def test_world_neighbours_of_keeps_one_index_per_radius(world):
    poses = np.array([[0.0, 0.5, 0.9], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert_array_equal(world.neighbours_of(poses, 0, 0.6)[0], [1])
    assert_array_equal(world.neighbours_of(poses, 0, 1.0)[0], [1, 2])
    assert_array_equal(world.neighbours_of(poses, 0, 0.6)[0], [1])


def test_world_obstacles_near_matches_one_robots_reading_and_follows_the_obstacles(world, rng):
    # One whole-swarm reading per pose array and obstacle layout: each row as the robot's own,
    # to the bit; an obstacle moved (or poses moved in place) gives a fresh reading.
    obstacles = [Obstacle((0.3, 0.2), (0.4, 0.2), angle=0.4), Obstacle((-0.6, -0.3), (0.2, 0.5), velocity=(0.1, 0))]
    poses = np.vstack((rng.uniform(-1, 1, (2, 60)), np.zeros(60)))
    for _ in range(3):
        for i in range(60):
            want = sensed(obstacles, [poses[0, i], poses[1, i]], 0.5)[0]
            assert_array_equal(world.obstacles_near(poses, i, obstacles, 0.5), want)
        assert np.isfinite(world.obstacles_near(poses, 0, obstacles, 5.0)).all()  # one reading per range
        obstacles[1].step(1.0)
        poses[:2] += 0.05


def test_world_obstacles_near_keeps_one_reading_per_range(world):
    # Robots standing still while obstacles move: the reading is replaced, not kept beside the old.
    obstacle = Obstacle((0.0, 0.0), (0.2, 0.2), velocity=(0.1, 0.0))
    poses = np.array([[0.5, -0.5], [0.0, 0.0], [0.0, 0.0]])
    for _ in range(20):
        world.obstacles_near(poses, 0, [obstacle], 1.0)
        obstacle.step(0.1)
    assert len(world._readings) == 1
