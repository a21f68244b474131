"""Line consensus, Voronoi coverage and the affine formation succeed at N = 100 on the Fast backend.

Each test asserts the experiment's own success (``result.success``: its done() criterion reached
with zero collisions, boundary and actuator violations) and the measures behind it. With the
NumPy reference kernels (``DREAM_PURE_PYTHON=1``) every robot's HRVO and Voronoi cell runs in
NumPy, several times slower, so those runs use the smaller sizes of ``PURE`` (still beyond the
Robotarium's arena, so the large-team code paths run).
"""

from __future__ import annotations

import dream
from dream import kernels
from dream.experiments import affine_formation as af
from dream.experiments import line_consensus as lc
from dream.experiments import voronoi_coverage as vc

RUST = kernels.IMPLEMENTATION == "rust"
#: experiment -> size in pure-NumPy mode (affine: a multiple of 7, here two formations)
PURE = {"line": 20, "coverage": 40, "affine": 14}


def size(experiment: str, rust: int) -> int:
    return rust if RUST else PURE[experiment]


def test_line_consensus_forms_the_line_at_scale():
    # Swarm mode: the per-robot mode's trajectories (test_line_consensus), several times faster.
    n = size("line", 100)
    result = dream.run("line-consensus", n=n, seed=0, backend="fast", swarm=True)
    assert result.success, result.summary()
    assert result.measures["y_spread"] < lc.TOLERANCE
    assert result.measures["spacing_error"] < lc.TOLERANCE
    assert result.completed_step < lc.LineConsensus().steps(n)


def test_voronoi_coverage_with_moving_obstacles_covers_at_scale():
    result = dream.run("voronoi-coverage", n=size("coverage", 100), seed=0, backend="fast")
    assert result.success, result.summary()
    assert result.measures["static_contacts"] == 0
    assert result.measures["cost_end"] < vc.COVERED * result.measures["cost_start"]
    assert result.measures["cost_end"] < vc.SPREAD * result.measures["cost_ideal"]


def test_voronoi_coverage_without_moving_obstacles_comes_to_rest_at_scale():
    result = dream.run("voronoi-coverage", n=size("coverage", 100), seed=0, backend="fast", moving_obstacles=False)
    assert result.success, result.summary()
    assert result.measures["static_contacts"] == 0
    assert result.measures["moving_at_end"] == 0
    assert result.measures["cost_end"] < vc.COVERED * result.measures["cost_start"]
    assert result.measures["cost_end"] < vc.SPREAD * result.measures["cost_ideal"]


def test_affine_formation_converges_and_passes_the_bars_at_scale():
    """98 robots: 14 formations of seven (the experiment's unit), each on its own tile. Swarm
    mode: the per-robot mode's trajectories (test_affine_formation), several times faster."""
    result = dream.run("affine-formation", n=size("affine", 98), seed=0, backend="fast", swarm=True)
    assert result.success, result.summary()
    assert result.measures["error_before_bars"] < af.TOLERANCE
    assert result.measures["bar_contacts"] == 0
