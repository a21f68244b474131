"""Outcomes of the affine-formation experiment, and the stress algebra behind it."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

import dream
from dream.experiments import affine_formation as af
from dream.experiments.affine_formation import plan


def test_nominal_configuration_is_in_stress_equilibrium():
    # The thesis's weights are rounded to 4 digits: equilibrium holds to that precision.
    assert_allclose(af.stress_matrix() @ af.NOMINAL, 0.0, atol=3e-4)
    assert_allclose(af.WEIGHTS, af.WEIGHTS.T)


def test_follower_targets_are_the_affine_image_of_the_nominal():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2, 2)), rng.normal(size=2)
    image = af.NOMINAL @ a.T + b
    assert_allclose(af.follower_targets(image[: af.LEADERS]), image[af.LEADERS :], atol=2e-2)
    # The followers' part of the stress matrix is positive definite: the control law converges.
    assert np.linalg.eigvalsh(af.stress_matrix()[af.LEADERS :, af.LEADERS :]).min() > 0


@pytest.mark.parametrize("shape", sorted(af.SHAPES))
def test_every_shape_keeps_robots_apart(shape):
    points = af.formation(shape)
    gaps = np.linalg.norm(points[:, None] - points[None], axis=2) + 10 * np.eye(len(points))
    assert gaps.min() >= 0.24


def test_collinear_shape_spaces_the_robots_evenly():
    # 0.375 m between neighbours on the line (leader 0 further): rps 2.1's colliders, which
    # touch at 0.185 m, stay apart while the followers catch up with the leaders.
    gaps = np.diff(np.sort(af.formation("collinear")[:, 0]))
    assert_allclose(gaps[:-1], 0.375)
    assert gaps[-1] > 0.375


def test_deformed_shapes_fit_their_gaps():
    diameter = 0.11
    for shape, gap in zip(("compressed", "collinear"), af.GAPS):
        assert np.ptp(af.formation(shape)[:, 1]) + diameter < gap
    assert np.ptp(af.formation("nominal")[:, 1]) + diameter > af.GAPS[0]  # so it must deform


@pytest.mark.parametrize("seed", range(2))
def test_affine_formation_converges_then_passes_both_gaps_without_contact(seed):
    result = dream.run("affine-formation", seed=seed, backend="robotarium")
    assert result.measures["error_before_bars"] < 0.05
    assert result.measures["bar_contacts"] == 0
    assert result.collisions == 0 and result.boundary == 0
    assert result.completed_step is not None
    assert result.measures["error_end"] < 0.05  # back in the nominal shape


@pytest.mark.parametrize("seed", [0, 1])
def test_affine_formation_succeeds_under_rps2_rules(seed):
    """rps 2.1's colliders sit 0.025 m ahead of the centres: robots facing each other touch at
    0.185 m, not 0.11 m. Seed 0 had 252 collision pair-iterations and a tangled follower, seed 1
    28, before the leaders gathered off-centre, changed shapes at a steady pace and spaced the
    collinear line evenly."""
    result = dream.run("affine-formation", seed=seed, backend="fast", rules="rps2")
    assert result.rules == "rps2"
    assert result.success, result.summary()
    assert result.collisions == 0 and result.boundary == 0 and result.actuator == 0
    assert result.measures["error_before_bars"] < af.TOLERANCE
    assert result.measures["bar_contacts"] == 0


def test_leaders_change_places_at_a_steady_pace():
    robot = af.FormationRobot(7, np.zeros((1, 2)))
    ids = np.array([0])
    start = robot.aims(
        ids, {"start": np.full((1, 3, 2), np.nan), "goals": np.full((1, 3, 2), np.nan), "decisions": [0]}
    )
    places = af.formation("compressed") + (0.2, 0.0)  # the planned formation, leaders first
    memory = {"start": start, "goals": places[None, : af.LEADERS], "decisions": np.zeros(1, dtype=np.int64)}
    aims = []
    for decisions in range(af.MORPH + 6):
        memory["decisions"] = np.array([decisions])
        aims.append(robot.aims(ids, memory)[0])
    assert_allclose(aims[0], af.formation("nominal")[: af.LEADERS])  # from the nominal places
    steps = np.diff(np.array(aims)[: af.MORPH + 1], axis=0)
    assert_allclose(steps, np.broadcast_to(steps[0], steps.shape), atol=1e-12)  # straight lines, steady...
    assert_allclose(aims[-1], places[: af.LEADERS])  # ...that end at the new places


def test_the_leaders_plan_its_shapes_in_order():
    steps, shapes, offsets = plan.shape_plan()
    passes = af.schedule()
    assert steps.tolist() == [0, plan.GATHER] + [step for p in passes for step in (p[0], p[2])]
    assert shapes == ["nominal", "nominal", "compressed", "nominal", "collinear", "nominal"]
    assert offsets[0].tolist() == [plan.SHIFT, 0.0] and not offsets[1:].any()  # right while they gather


def test_affine_formation_has_seven_robots():
    with pytest.raises(ValueError, match="7 robots"):
        dream.run("affine-formation", n=8)


@pytest.fixture(scope="module")
def two_formations():
    """Two tiled formations robot by robot (Fast, seed 0), shared by the tests that need the run."""
    return dream.run("affine-formation", n=14, seed=0, backend="fast", trace=True)


def test_affine_formation_tiles_several_formations(two_formations):
    result = two_formations
    assert result.measures["error_before_bars"] < 0.05
    assert result.measures["bar_contacts"] == 0 and result.collisions == 0
    assert result.completed_step is not None


def test_affine_formation_swarm_mode_moves_as_the_robots_do(two_formations):
    # One FormationRobot, run robot by robot and as one swarm: the same poses at every step,
    # bit for bit, whole runs long.
    swarm = dream.run("affine-formation", n=14, seed=0, backend="fast", trace=True, swarm=True)
    assert two_formations.success and swarm.success and swarm.swarm
    assert swarm.collisions == 0 and swarm.boundary == 0 and swarm.actuator == 0
    assert swarm.completed_step == two_formations.completed_step
    assert np.array_equal(swarm.trace, two_formations.trace)
    assert swarm.measures == two_formations.measures


#: One of each fault kind (docs/faults.md), some together: each reaches the robots' own radios,
#: sensors, clocks and wheels, robot by robot as in the swarm.
FAULTS = {
    "crash": dream.Faults(crash=0.15, crash_at=100),
    "stuck": dream.Faults(stuck=0.15, stuck_at=100),
    "actuator noise": dream.Faults(actuator_noise=0.01),
    "byzantine": dream.Faults(byzantine=2, lie="random"),
    "loss, burst": dream.Faults(loss=0.3, burst=(0.1, 0.5)),
    "distance loss, latency, jitter": dream.Faults(distance_loss=0.2, latency=5, jitter=2),
    "sensor noise, dropout": dream.Faults(sensor_noise=0.005, sensor_dropout=0.1),
    "drift, clock jitter": dream.Faults(drift=0.02, clock_jitter=2),
}


@pytest.fixture(scope="module")
def unfaulted():
    """The poses of the fault tests' run without faults."""
    return dream.run("affine-formation", n=14, seed=1, backend="fast", steps=500, trace=True, swarm=True).trace


@pytest.mark.parametrize("case", FAULTS)
def test_affine_formation_is_the_same_both_ways_under_each_fault(case, unfaulted):
    robots, swarm = (
        dream.run(
            "affine-formation", n=14, seed=1, backend="fast", steps=500, trace=True, faults=FAULTS[case], swarm=way
        )
        for way in (False, True)
    )
    assert np.array_equal(swarm.trace, robots.trace) and swarm.faults == robots.faults
    assert swarm.collisions == robots.collisions == 0
    assert not np.array_equal(swarm.trace, unfaulted)  # the fault reached the robots


def test_affine_formation_thousand_robots_on_fast_do_not_collide():
    result = dream.run(
        "affine-formation", n=1001, seed=0, backend="fast", steps=100, swarm=True
    )  # robot by robot: the same run
    assert result.n == 1001 and result.collisions == 0 and result.boundary == 0


def test_affine_formation_tiles_are_robotarium_sized():
    centres = af.tile_centres(5)
    arena = af.tiled_arena(5)
    assert len(centres) == 5
    assert np.all(np.abs(centres[:, 0]) + 1.6 <= arena.xmax + 1e-9)
    assert np.all(np.abs(centres[:, 1]) + 1.0 <= arena.ymax + 1e-9)
    gaps = np.linalg.norm(centres[:, None] - centres[None], axis=2) + 10 * np.eye(5)
    assert gaps.min() >= 2.0 - 1e-9


def test_affine_formation_swarm_mode_frames_come_from_its_arrays():
    frames: dict[bool, list] = {False: [], True: []}
    for swarm in frames:
        dream.run("affine-formation", n=14, seed=0, backend="fast", steps=40, swarm=swarm, record=frames[swarm].append)
    robots, swarm = frames[False][-1], frames[True][-1]
    assert np.isfinite(swarm.goals).all() and np.any(swarm.velocities != 0)
    np.testing.assert_array_equal(swarm.goals, robots.goals)
    np.testing.assert_array_equal(swarm.velocities, robots.velocities)
    np.testing.assert_array_equal(swarm.links, robots.links)
    assert len(swarm.links) == 2 * np.count_nonzero(np.triu(af.WEIGHTS))
