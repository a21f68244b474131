"""The vectorised obstacle queries (contains, distances, touching) against the per-point ones."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dream.obstacles import Fleet, Obstacle, touching


@pytest.mark.parametrize("angle", [0.0, 0.7])
def test_distances_and_contains_match_closest_point(angle):
    rng = np.random.default_rng(1)
    obstacle = Obstacle((0.3, -0.2), (0.5, 0.2), angle=angle)
    points = rng.uniform(-1.0, 1.0, size=(400, 2))
    distances = obstacle.distances(points)
    inside = obstacle.contains(points)
    assert inside.any() and (~inside).any()
    for point, distance, is_inside in zip(points, distances, inside):
        closest = obstacle.closest_point(point)
        assert is_inside == (closest is None)
        assert distance == pytest.approx(0.0 if closest is None else math.dist(closest, point), abs=1e-12)


def test_touching_is_strictly_closer_than_the_radius():
    # A turned bar; points straight out from the middle of its long side at known distances.
    obstacle = Obstacle((1.0, 1.0), (0.4, 0.2), angle=math.pi / 2)  # long side vertical, faces +x
    gaps = np.array([-0.05, 0.0, 0.04, 0.12, 0.3])
    positions = np.column_stack((1.0 + 0.1 + gaps, np.full(5, 1.0)))
    assert touching([obstacle], positions, 0.1).tolist() == [True, True, True, False, False]
    assert touching([], positions, 0.1).tolist() == [False] * 5
    assert touching([obstacle], np.zeros((0, 2)), 0.1).shape == (0,)


def test_touching_names_a_bad_positions_array():
    with pytest.raises(ValueError, match=r"`positions` must have shape \(n, 2\)"):
        touching([Obstacle((0.0, 0.0), (1.0, 1.0))], np.zeros((3, 3)), 0.1)


@pytest.mark.parametrize("column", [False, True])
def test_touching_matches_each_obstacles_distances(column):
    # Obstacles of very different sizes (a large one must not hide a small one), turned; robots
    # scattered or in one column (the axis the query sorts along changes).
    rng = np.random.default_rng(7)
    for _ in range(50):
        obstacles = [
            Obstacle(rng.uniform(-5, 5, 2), rng.uniform(0.05, 4.0, 2), angle=rng.uniform(-3, 3))
            for _ in range(rng.integers(1, 20))
        ]
        positions = rng.uniform(-6, 6, size=(300, 2))
        if column:
            positions[:, 0] = rng.uniform(-0.1, 0.1, 300)
        radius = rng.uniform(0.0, 0.5)
        expected = np.any([obstacle.distances(positions) < radius for obstacle in obstacles], axis=0)
        assert touching(obstacles, positions, radius).tolist() == expected.tolist()


def test_a_fleet_moves_and_touches_as_its_obstacles_do():
    # The affine experiment's bars as arrays: the same positions, to the bit, and the same contacts.
    rng = np.random.default_rng(4)
    obstacles = [
        Obstacle(rng.uniform(-2, 2, 2), rng.uniform(0.05, 0.5, 2), float(rng.uniform(-1, 1)), rng.uniform(-0.2, 0.2, 2))
        for _ in range(40)
    ]
    fleet = Fleet(obstacles)
    points = rng.uniform(-2.5, 2.5, (500, 2))
    for _ in range(25):
        for obstacle in obstacles:
            obstacle.step(0.033)
        fleet.step(0.033)
        np.testing.assert_array_equal(fleet.centres, [o.center for o in obstacles])
        np.testing.assert_array_equal(fleet.touching(points, 0.055), touching(obstacles, points, 0.055))
    assert touching(obstacles, points, 0.055).any()  # the comparison is not vacuous
    drawn = fleet.obstacles
    np.testing.assert_array_equal([o.polygon for o in drawn], [o.polygon for o in obstacles])
    assert len(Fleet()) == 0 and not Fleet().touching(points, 0.1).any()


def test_a_fleet_leaves_static_obstacles_alone():
    # Obstacle.step does not touch a static obstacle: not even the sign of a zero.
    fleet = Fleet([Obstacle((-0.0, 0.5), (0.2, 0.2)), Obstacle((0.0, 0.0), (0.2, 0.2), velocity=(0.1, 0.0))])
    fleet.step(0.5)
    assert math.copysign(1.0, fleet.centres[0, 0]) == -1.0
    np.testing.assert_array_equal(fleet.centres[1], [0.05, 0.0])
