"""Per-robot kernels answer exactly as the whole-swarm kernels do for that robot."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from dream import Obstacle, _reference, kernels
from dream.obstacles import as_csr

ARENA = (-1.6, 1.6, -1.0, 1.0)


@pytest.mark.parametrize("n", [1, 2, 25])
def test_voronoi_cell_matches_the_row_of_voronoi_cells(rng, n):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2))
    agents = rng.uniform(-1.0, 1.0, (n, 2))
    virtual = (np.arange(n + 1, dtype=np.int64), agents)
    swarm = kernels.voronoi_cells(p, radius=0.6, bounds=ARENA, virtual=virtual, polygons=True)
    for i in range(n):
        others = np.delete(p, i, axis=0)  # farther robots than 2 radius change nothing
        for centroid, area, vertices in (
            kernels.voronoi_cell(p[i], others, radius=0.6, bounds=ARENA, virtual=agents[i : i + 1]),
            _reference.voronoi_cell(p[i], others, agents[i : i + 1], radius=0.6, bounds=ARENA),
        ):
            assert_allclose(centroid, swarm.centroids[i], atol=1e-12)
            assert area == pytest.approx(swarm.areas[i], abs=1e-12)
            assert_allclose(vertices, swarm.vertices[swarm.offsets[i] : swarm.offsets[i + 1]], atol=1e-12)


def test_voronoi_cell_rejects_bad_input():
    with pytest.raises(ValueError, match="others"):
        kernels.voronoi_cell([0.0, 0.0], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="radius"):
        kernels.voronoi_cell([0.0, 0.0], np.zeros((0, 2)), radius=0.0)
    with pytest.raises(ValueError, match="position"):
        kernels.voronoi_cell([np.nan, 0.0], np.zeros((0, 2)))


@pytest.mark.parametrize("margin", [0.0, 0.05])
def test_obstacle_agents_match_virtual_agents_of_the_sensed_points(rng, margin):
    obstacles = [Obstacle((0.5, 0.2), (0.4, 0.3), angle=0.4), Obstacle((-0.8, -0.4), (0.2, 0.6))]
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (40, 2))
    indptr, agents = kernels.virtual_agents(p, as_csr(obstacles), range=0.7, margin=margin)
    for i, q in enumerate(p):
        sensed = [c for c in (o.closest_point(q) for o in obstacles) if c is not None and np.hypot(*(c - q)) <= 0.7]
        mine = kernels.obstacle_agents(q, np.array(sensed).reshape(-1, 2), margin=margin)
        assert_allclose(mine, agents[indptr[i] : indptr[i + 1]], atol=1e-9)


def test_obstacle_agents_of_nothing_sensed_is_empty():
    assert_array_equal(kernels.obstacle_agents([0.0, 0.0], np.zeros((0, 2))).shape, (0, 2))
