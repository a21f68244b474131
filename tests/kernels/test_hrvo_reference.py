"""HRVO (SPEC 5.1): the NumPy reference and :func:`dream.kernels.hrvo` against hand-worked cases
and an independent re-evaluation of the velocity-obstacle geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from dream import _reference, kernels
from dream._reference import candidate_grid, hrvo

SAFETY = 0.24
V_MAX = 0.2
NONE = (np.zeros(0), np.zeros(0), np.zeros((0, 2)))  # no neighbours: directions, distances, velocities


def hrvo_velocity(velocity, preferred, angles, distances, others, **kwargs):
    """The reference with neighbour directions given as angles, as the hand-worked cases are."""
    units = np.column_stack((np.cos(angles), np.sin(angles))) if len(angles) else np.zeros((0, 2))
    return _reference.hrvo_velocity(velocity, preferred, units, distances, others, **kwargs)


# -- an independent reading of SPEC 5.1 -------------------------------------------------------------
def _unit(angle):
    return np.array([math.cos(angle), math.sin(angle)])


def _line_distance(point, apex, direction):
    """Euclidean distance from ``point`` to the line through ``apex`` along unit ``direction``."""
    w = point - apex
    return float(np.linalg.norm(w - (w @ direction) * direction))


def hrvo_depths(v, own, direction, distance, other, safety=SAFETY):
    """How deep ``v`` lies inside neighbour B's HRVO (> 0: strictly inside, forbidden), for each
    reading of the rule that SPEC 5.1 allows.

    Edges at angle(u) +- asin(r / max(d, r)); the RVO (apex (v_A + v_B) / 2) edge on the side
    v_A is closer to, the VO (apex v_B) edge on the other. When v_A is (nearly) equally close to
    both edges, which always happens for d <= r (phi = pi/2: both edges on one line), rounding
    decides: every variant is returned.
    """
    phi = math.asin(safety / max(distance, safety))
    left, right = _unit(direction + phi), _unit(direction - phi)
    rvo, vo = (own + other) / 2, other
    to_left, to_right = _line_distance(own, rvo, left), _line_distance(own, rvo, right)
    if abs(to_left - to_right) <= 1e-9:
        apexes = [(vo, vo), (rvo, vo), (vo, rvo)]
    else:
        apexes = [(rvo, vo) if to_left < to_right else (vo, rvo)]

    def depth(left_apex, right_apex):
        right_of_left = (v - left_apex) @ np.array([left[1], -left[0]])  # > 0: right of the left edge
        left_of_right = (v - right_apex) @ np.array([-right[1], right[0]])  # > 0: left of the right edge
        return min(right_of_left, left_of_right)

    return [depth(*pair) for pair in apexes]


def hrvo_depth(v, own, direction, distance, other, safety=SAFETY):
    """The depth when the HRVO is unambiguous."""
    depths = hrvo_depths(v, own, direction, distance, other, safety)
    assert len(depths) == 1
    return depths[0]


def surely_allowed(v, own, directions, distances, others, safety=SAFETY):
    """Outside every neighbour's HRVO by a margin, whichever reading."""
    return all(max(hrvo_depths(v, own, a, d, o, safety)) < -1e-12 for a, d, o in zip(directions, distances, others))


def possibly_allowed(v, own, directions, distances, others, safety=SAFETY):
    """Not strictly inside any neighbour's HRVO (up to rounding) for at least one reading."""
    return all(min(hrvo_depths(v, own, a, d, o, safety)) <= 1e-12 for a, d, o in zip(directions, distances, others))


def max_depth(v, own, directions, distances, others, safety=SAFETY):
    return max(
        (min(hrvo_depths(v, own, a, d, o, safety)) for a, d, o in zip(directions, distances, others)), default=-np.inf
    )


def original_sampling(v_max, n_angles=20, n_speeds=10):
    """The prototype's 201 samples (with duplicates), written out with loops."""
    samples = [(0.0, 0.0)]
    for k in range(n_angles):
        angle = 2 * math.pi * k / (n_angles - 1) if n_angles > 1 else 0.0
        for j in range(n_speeds):
            speed = v_max * j / (n_speeds - 1) if n_speeds > 1 else 0.0
            samples.append((speed * math.cos(angle), speed * math.sin(angle)))
    return np.array(samples)


def brute_neighbours(positions, radius):
    n = len(positions)
    rows = [[j for j in range(n) if j != i and np.linalg.norm(positions[j] - positions[i]) <= radius] for i in range(n)]
    indptr = np.concatenate(([0], np.cumsum([len(r) for r in rows]))).astype(np.int64)
    indices = np.array([j for r in rows for j in r], dtype=np.int64)
    return indptr, indices


def geometry_of(positions, i, js):
    offsets = positions[js] - positions[i]
    return np.arctan2(offsets[:, 1], offsets[:, 0]), np.hypot(offsets[:, 0], offsets[:, 1])


def clamp(v, v_max=V_MAX):
    norm = float(np.hypot(*v))
    return v * (v_max / norm) if norm > v_max else v


def check_choice(
    chosen, own, preferred, directions, distances, others, *, position=None, bounds=None, include_preferred=True
):
    """Assert SPEC 5.1's result rules for one robot, re-evaluating every candidate independently."""
    assert np.hypot(*chosen) <= V_MAX + 1e-12

    def inside(c):
        if bounds is None:
            return True
        x, y = position + c
        return bounds[0] < x < bounds[1] and bounds[2] < y < bounds[3]

    candidates = candidate_grid(V_MAX)
    if include_preferred:
        candidates = np.vstack((clamp(preferred), candidates))
    clearly_allowed = [c for c in candidates if surely_allowed(c, own, directions, distances, others) and inside(c)]
    if not clearly_allowed and np.array_equal(chosen, [0.0, 0.0]):
        return  # every candidate is (at least borderline) excluded: the zero fallback
    # The choice qualifies (a candidate forbidden by nobody, inside the bounds) ...
    assert any(np.array_equal(chosen, c) for c in candidates)
    assert possibly_allowed(chosen, own, directions, distances, others)
    assert inside(chosen)
    # ... and no clearly allowed candidate is strictly closer to the preferred velocity.
    best = float(np.sum((chosen - preferred) ** 2))
    assert all(np.sum((c - preferred) ** 2) >= best - 1e-12 for c in clearly_allowed)


# -- candidate_grid -------------------------------------------------------------------------------
def test_candidate_grid_default_has_the_172_distinct_samples_of_the_original():
    grid = candidate_grid(0.2)
    assert grid.shape == (172, 2)
    assert_array_equal(grid[0], [0.0, 0.0])
    gaps = np.linalg.norm(grid[:, None] - grid[None], axis=2) + np.eye(172)
    assert gaps.min() > 1e-6  # all distinct, not merely different in the last bit
    assert np.linalg.norm(grid, axis=1).max() <= 0.2 + 1e-12
    original = original_sampling(0.2)
    assert len(original) == 201
    # the same set as the prototype's samples
    distance_to_grid = np.linalg.norm(original[:, None] - grid[None], axis=2).min(axis=1)
    distance_to_original = np.linalg.norm(grid[:, None] - original[None], axis=2).min(axis=1)
    assert distance_to_grid.max() < 1e-12 and distance_to_original.max() < 1e-12


@pytest.mark.parametrize(
    ("v_max", "n_angles", "n_speeds", "rows"),
    [
        (1.0, 5, 3, 1 + 4 * 2),  # angles 0, pi/2, pi, 3pi/2 (2pi repeats 0); speeds 0.5, 1
        (0.2, 20, 10, 1 + 19 * 9),
        (0.5, 2, 2, 1 + 1 * 1),  # angles 0 and 2pi: a single direction
        (0.3, 13, 4, 1 + 12 * 3),
    ],
)
def test_candidate_grid_respects_counts(v_max, n_angles, n_speeds, rows):
    grid = candidate_grid(v_max, n_angles, n_speeds)
    assert grid.shape == (rows, 2)
    assert_array_equal(grid[0], [0.0, 0.0])
    norms = np.linalg.norm(grid, axis=1)
    assert norms.max() == pytest.approx(v_max, abs=1e-12)
    # speeds are the non-zero levels of linspace(0, v_max, n_speeds)
    levels = np.linspace(0, v_max, n_speeds)[1:]
    assert np.abs(norms[1:, None] - levels[None]).min(axis=1).max() < 1e-12
    assert len(np.unique(np.round(grid, 12), axis=0)) == rows


def test_candidate_grid_five_by_three_by_hand():
    expected = [(0, 0), (0.5, 0), (1, 0), (0, 0.5), (0, 1), (-0.5, 0), (-1, 0), (0, -0.5), (0, -1)]
    assert_allclose(candidate_grid(1.0, 5, 3), expected, atol=1e-12)


# -- no neighbours --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("preferred", "expected"),
    [
        ((0.1, -0.05), (0.1, -0.05)),  # free and slow enough: exactly the preferred velocity
        ((0.3, 0.4), (0.12, 0.16)),  # |v| = 0.5 clamped to 0.2 along the same direction
        ((0.0, 0.0), (0.0, 0.0)),
        ((0.0, -3.0), (0.0, -0.2)),
    ],
)
def test_hrvo_velocity_without_neighbours_returns_clamped_preferred(preferred, expected):
    got = hrvo_velocity(np.array([0.05, 0.05]), np.array(preferred), *NONE)
    assert_allclose(got, expected, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    ("preferred", "expected"),
    [
        ((0.2, 0.0), (0.2, 0.0)),  # on the grid
        ((0.3, 0.001), (0.2, 0.0)),
        ((0.0, 0.0), (0.0, 0.0)),
        ((0.012, 0.0), (0.2 / 9, 0.0)),  # the smallest non-zero speed is 0.2/9 = 0.0222...
        ((0.011, 0.0), (0.0, 0.0)),  # ... and 0.011 is nearer to zero than to it
    ],
)
def test_hrvo_velocity_without_preferred_picks_nearest_grid_candidate(preferred, expected):
    pref = np.array(preferred)
    got = hrvo_velocity(np.zeros(2), pref, *NONE, include_preferred=False)
    assert_allclose(got, expected, rtol=1e-12, atol=1e-15)
    grid = candidate_grid(V_MAX)
    nearest = grid[np.argmin(np.sum((grid - pref) ** 2, axis=1))]
    assert_array_equal(got, nearest)


def test_hrvo_velocity_ties_go_to_the_first_candidate():
    candidates = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0]])
    kwargs = dict(v_max=2.0, include_preferred=False)
    assert_array_equal(hrvo_velocity(np.zeros(2), np.zeros(2), *NONE, candidates=candidates, **kwargs), [1.0, 0.0])
    assert_array_equal(
        hrvo_velocity(np.zeros(2), np.zeros(2), *NONE, candidates=candidates[::-1], **kwargs), [0.0, 1.0]
    )


# -- one neighbour --------------------------------------------------------------------------------
def test_hrvo_velocity_head_on_pair_both_avoid():
    # A at (-0.5, 0) and B at (0.5, 0) drive at each other at full speed.
    positions = np.array([[-0.5, 0.0], [0.5, 0.0]])
    velocities = np.array([[0.2, 0.0], [-0.2, 0.0]])
    chosen = hrvo(positions, velocities, velocities.copy())
    for i, j in ((0, 1), (1, 0)):
        direction = math.atan2(*(positions[j] - positions[i])[::-1])
        # the preferred velocity (straight at the other) is forbidden, so it is not chosen
        # (v_A lies on the cone's bisector: a tie, whichever reading of it)
        assert min(hrvo_depths(velocities[i], velocities[i], direction, 1.0, velocities[j])) > 0
        assert not np.allclose(chosen[i], velocities[i])
        assert possibly_allowed(chosen[i], velocities[i], [direction], [1.0], [velocities[j]])
        towards = _unit(direction)
        assert chosen[i] @ towards > 0  # it still makes progress
    # they sidestep to opposite sides (each to its own left or each to its right): they pass
    assert chosen[0, 1] * chosen[1, 1] < 0
    assert abs(chosen[0, 1] - chosen[1, 1]) > 0.05


def vo_depth(v, direction, distance, other, safety=SAFETY):
    """Depth of ``v`` inside B's plain VO (apex v_B, half-angle asin(r / max(d, r)))."""
    phi = math.asin(safety / max(distance, safety))
    left, right = _unit(direction + phi), _unit(direction - phi)
    w = v - other
    return min(w @ np.array([left[1], -left[0]]), w @ np.array([-right[1], right[0]]))


@pytest.mark.parametrize("distance", [1.0, 0.2])
def test_hrvo_velocity_tie_uses_both_vo_edges(distance):
    # v_A - v_B along u puts v_A on the RVO's bisector: equally close to both edges, so both
    # edges are the VO's ("as the original", reference docstring); for d < r (phi = pi/2, both
    # edges on one line) every v_A is such a tie. The result must then be the nearest candidate
    # outside the plain VO (or zero if there is none) in every orientation of the same
    # situation: rounding must not break the tie.
    wrong = []
    for turn in [k * math.pi / 8 for k in range(16)]:
        u = _unit(turn)
        own, other = 0.2 * u, -0.2 * u
        got = hrvo_velocity(own, own.copy(), np.array([turn]), np.array([distance]), other[None, :])
        candidates = np.vstack((own, candidate_grid(V_MAX)))
        allowed = [c for c in candidates if vo_depth(c, turn, distance, other) <= 0]
        expected = min(allowed, key=lambda c: float(np.sum((c - own) ** 2))) if allowed else np.zeros(2)
        if not np.allclose(got, expected, rtol=0, atol=1e-12):
            wrong.append(round(math.degrees(turn), 1))
    assert not wrong, f"not the both-VO choice for headings (degrees) {wrong}"


def _simulate(positions, goals, steps, dt=0.033):
    velocities = np.zeros_like(positions)
    closest = np.inf
    for _ in range(steps):
        offsets = goals - positions
        lengths = np.linalg.norm(offsets, axis=1, keepdims=True)
        preferred = offsets / np.maximum(lengths, 1e-12) * np.minimum(V_MAX, lengths)
        velocities = kernels.hrvo(positions, velocities, preferred)
        positions = positions + dt * velocities
        gaps = np.linalg.norm(positions[:, None] - positions[None], axis=2) + 10 * np.eye(len(positions))
        closest = min(closest, gaps.min())
    return positions, closest


@pytest.mark.parametrize("n", [2, 5])
def test_hrvo_robots_swapping_places_never_collide(n):
    # Robots on a circle of radius 0.6 each head for the antipodal point: without avoidance they
    # would all meet in the centre.
    angles = 2 * np.pi * np.arange(n) / n
    start = 0.6 * np.column_stack((np.cos(angles), np.sin(angles)))
    end, closest = _simulate(start, -start, steps=450)
    assert closest > 0.11  # no collision by rps's criterion
    assert_allclose(end, -start, atol=0.01)


def test_hrvo_velocity_neighbour_closer_than_safety_forbids_approaching():
    # d < r: phi = pi/2, the cone is the half-plane of velocities with a component towards B.
    rng = np.random.default_rng(5)
    for _ in range(200):
        direction, distance = rng.uniform(-np.pi, np.pi), rng.uniform(0.0, SAFETY)
        preferred = rng.uniform(-0.3, 0.3, 2)
        got = hrvo_velocity(np.zeros(2), preferred, np.array([direction]), np.array([distance]), np.zeros((1, 2)))
        assert got @ _unit(direction) <= 1e-12
        if preferred @ _unit(direction) < -1e-9:
            assert_allclose(got, clamp(preferred), atol=1e-15)  # moving away is free


def test_hrvo_velocity_neighbour_closer_than_safety_straight_ahead_gives_zero():
    # Preferred straight at B: every candidate with v_x > 0 is forbidden and, of the others,
    # zero is the closest to (0.2, 0) (|c - p|^2 = |c|^2 - 0.4 c_x + 0.04 >= 0.04).
    got = hrvo_velocity(np.zeros(2), np.array([0.2, 0.0]), np.array([0.0]), np.array([0.1]), np.zeros((1, 2)))
    assert_array_equal(got, [0.0, 0.0])


def test_hrvo_velocity_surrounded_robot_stops():
    # Eight neighbours 0.15 away all around, each coming at the robot: every candidate, zero
    # included, is inside some HRVO.
    directions = 2 * np.pi * np.arange(8) / 8
    distances = np.full(8, 0.15)
    others = -0.1 * np.column_stack((np.cos(directions), np.sin(directions)))
    for preferred in ([0.2, 0.0], [0.0, -0.1], [0.05, 0.05]):
        got = hrvo_velocity(np.zeros(2), np.array(preferred), directions, distances, others)
        assert_array_equal(got, [0.0, 0.0])
    assert all(max_depth(c, np.zeros(2), directions, distances, others) > 1e-12 for c in candidate_grid(V_MAX))
    # with candidates that exclude zero, the fallback is still the zero velocity
    ring = candidate_grid(V_MAX)[1:]
    got = hrvo_velocity(
        np.zeros(2), np.array([0.2, 0.0]), directions, distances, others, candidates=ring, include_preferred=False
    )
    assert_array_equal(got, [0.0, 0.0])


def test_hrvo_velocity_keeps_clear_of_the_right_wall():
    # At x = 1.5 with xmax = 1.6, preferring (0.2, 0): only v_x < 0.1 keeps x + v_x inside. The
    # nearest such candidate is on the x axis at speed 4 * 0.2 / 9 (the next level, 0.111, is out).
    bounds = (-1.6, 1.6, -1.0, 1.0)
    got = hrvo_velocity(np.zeros(2), np.array([0.2, 0.0]), *NONE, position=np.array([1.5, 0.0]), bounds=bounds)
    assert_allclose(got, [0.8 / 9, 0.0], rtol=1e-12, atol=1e-15)


def test_hrvo_velocity_boundary_is_strict():
    # 1.5 + 0.125 lands exactly on xmax = 1.625: not strictly inside, so the next candidate wins.
    candidates = np.array([[0.125, 0.0], [0.0625, 0.0]])
    got = hrvo_velocity(
        np.zeros(2),
        np.array([0.125, 0.0]),
        *NONE,
        position=np.array([1.5, 0.0]),
        bounds=(-1.625, 1.625, -1.0, 1.0),
        candidates=candidates,
        include_preferred=False,
    )
    assert_array_equal(got, [0.0625, 0.0])


def test_hrvo_velocity_bounds_require_a_position():
    with pytest.raises(ValueError, match="position"):
        hrvo_velocity(np.zeros(2), np.zeros(2), *NONE, bounds=(-1.0, 1.0, -1.0, 1.0))


def test_hrvo_near_walls_stays_strictly_inside(rng):
    bounds = (-1.6, 1.6, -1.0, 1.0)
    n = 60
    positions = np.column_stack((rng.uniform(-1.59, 1.59, n), rng.uniform(-0.99, 0.99, n)))
    positions[:10, 0] = 1.6 - rng.uniform(0.0, 0.05, 10)  # hugging the right wall
    preferred = rng.uniform(-0.3, 0.3, (n, 2))
    preferred[:10] = [0.2, 0.0]
    got = kernels.hrvo(positions, np.zeros((n, 2)), preferred, radius=0.0, bounds=bounds)
    ahead = positions + got
    assert np.all(
        (bounds[0] < ahead[:, 0]) & (ahead[:, 0] < bounds[1]) & (bounds[2] < ahead[:, 1]) & (ahead[:, 1] < bounds[3])
    )
    assert np.all(got[:10, 0] < 1.6 - positions[:10, 0])


# -- random swarms: rules of the result, re-evaluated independently ---------------------------------
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("include_preferred", [True, False])
def test_hrvo_choice_is_allowed_and_optimal_on_random_swarms(seed, include_preferred):
    rng = np.random.default_rng(seed)
    n = 12
    positions = rng.uniform(-0.8, 0.8, (n, 2))
    velocities = rng.uniform(-0.15, 0.15, (n, 2))
    preferred = rng.uniform(-0.35, 0.35, (n, 2))
    bounds = (-1.0, 1.0, -1.0, 1.0) if seed % 2 else None
    chosen = kernels.hrvo(
        positions, velocities, preferred, radius=0.9, bounds=bounds, include_preferred=include_preferred
    )
    assert chosen.shape == (n, 2)
    indptr, indices = brute_neighbours(positions, 0.9)
    for i in range(n):
        js = indices[indptr[i] : indptr[i + 1]]
        directions, distances = geometry_of(positions, i, js)
        check_choice(
            chosen[i],
            velocities[i],
            preferred[i],
            directions,
            distances,
            velocities[js],
            position=positions[i],
            bounds=bounds,
            include_preferred=include_preferred,
        )


@pytest.mark.parametrize("n", [0, 1, 2, 40])
def test_hrvo_batch_equals_per_robot_calls(rng, n):
    positions = rng.uniform(-1.0, 1.0, (n, 2))
    velocities = rng.uniform(-0.2, 0.2, (n, 2))
    preferred = rng.uniform(-0.3, 0.3, (n, 2))
    bounds = (-1.2, 1.2, -1.2, 1.2)
    indptr, indices = brute_neighbours(positions, 0.6)
    for batch in (
        kernels.hrvo(positions, velocities, preferred, (indptr, indices), bounds=bounds, safety=0.2),
        hrvo(positions, velocities, preferred, indptr, indices, bounds=bounds, safety=0.2),
    ):
        assert batch.shape == (n, 2)
        for i in range(n):
            js = indices[indptr[i] : indptr[i + 1]]
            directions, distances = geometry_of(positions, i, js)
            one = hrvo_velocity(
                velocities[i],
                preferred[i],
                directions,
                distances,
                velocities[js],
                safety=0.2,
                position=positions[i],
                bounds=bounds,
            )
            assert_allclose(batch[i], one, rtol=0, atol=1e-12)


@pytest.mark.parametrize("radius", [0.0, 0.3, 0.8, 5.0])
def test_hrvo_without_neighbour_lists_uses_every_robot_within_radius(rng, radius):
    n = 30
    positions = rng.uniform(-1.0, 1.0, (n, 2))
    velocities = rng.uniform(-0.2, 0.2, (n, 2))
    preferred = rng.uniform(-0.3, 0.3, (n, 2))
    implicit = kernels.hrvo(positions, velocities, preferred, radius=radius)
    explicit = kernels.hrvo(positions, velocities, preferred, brute_neighbours(positions, radius), radius=123.0)
    assert_allclose(implicit, explicit, rtol=0, atol=1e-12)


def test_hrvo_ignores_robots_beyond_radius():
    positions = np.array([[-0.5, 0.0], [0.5, 0.0]])
    velocities = np.array([[0.2, 0.0], [-0.2, 0.0]])
    assert_allclose(kernels.hrvo(positions, velocities, velocities, radius=0.9), velocities, atol=1e-15)
    assert not np.allclose(kernels.hrvo(positions, velocities, velocities, radius=1.0), velocities)
    empty = (np.zeros(3, dtype=np.int64), np.zeros(0, dtype=np.int64))
    assert_allclose(kernels.hrvo(positions, velocities, velocities, empty, radius=5.0), velocities, atol=1e-15)


def test_hrvo_norms_never_exceed_v_max(rng):
    n = 80
    positions = rng.uniform(-1.5, 1.5, (n, 2))
    preferred = rng.uniform(-2.0, 2.0, (n, 2))
    for v_max in (0.05, 0.2, 1.0):
        got = kernels.hrvo(positions, rng.uniform(-v_max, v_max, (n, 2)), preferred, v_max=v_max, radius=0.5)
        assert np.linalg.norm(got, axis=1).max() <= v_max + 1e-12


def test_hrvo_custom_grid_counts_are_used():
    # With 5 angles, 3 speeds and v_max = 1 the candidates are 0 and the axes at 0.5 and 1. For a
    # preferred (0.7, 0.6) the squared distances are (0.5, 0): 0.40, (1, 0): 0.45, (0, 0.5): 0.50,
    # (0, 1): 0.65, 0: 0.85, the negative axes more: the answer is (0.5, 0).
    got = kernels.hrvo(
        np.zeros((1, 2)),
        np.zeros((1, 2)),
        np.array([[0.7, 0.6]]),
        v_max=1.0,
        n_angles=5,
        n_speeds=3,
        include_preferred=False,
    )
    assert_allclose(got, [[0.5, 0.0]], atol=1e-12)


# -- input errors of the public batch call ----------------------------------------------------------
GOOD = dict(positions=np.zeros((3, 2)), velocities=np.zeros((3, 2)), preferred=np.zeros((3, 2)))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (dict(positions=np.zeros((3, 3))), r"`positions` must have shape \(n, 2\), got \(3, 3\)"),
        (dict(positions=np.zeros(6)), r"`positions`"),
        (dict(velocities=np.zeros((4, 2))), r"`velocities` must have shape \(3, 2\), got \(4, 2\)"),
        (dict(preferred=np.zeros((3, 1))), r"`preferred` must have shape \(3, 2\)"),
        (dict(positions=np.array([[0.0, 0.0], [np.nan, 1.0], [2.0, 2.0]])), r"`positions`.*non-finite"),
        (dict(velocities=np.array([[0.0, 0.0], [0.0, np.inf], [0.0, 0.0]])), r"`velocities`.*non-finite"),
        (dict(preferred=np.full((3, 2), -np.inf)), r"`preferred`.*non-finite"),
        (dict(radius=-0.1), r"`radius`"),
        (dict(radius=np.nan), r"`radius`"),
        (dict(safety=-1.0), r"`safety`"),
        (dict(v_max=-0.2), r"`v_max`"),
        (dict(n_angles=0), r"`n_angles`"),
        (dict(n_speeds=0), r"`n_speeds`"),
        (dict(neighbours=(np.array([0, 1, 2]), np.array([1, 0]))), r"`neighbours`.*indptr"),  # n + 1 = 4 expected
        (dict(neighbours=(np.array([0, 1, 2, 3, 3]), np.array([1, 0, 0]))), r"`neighbours`.*indptr"),
        (dict(neighbours=(np.array([1, 1, 2, 3]), np.array([1, 0, 0]))), r"`neighbours`.*indptr"),
        (dict(neighbours=(np.array([0, 2, 1, 3]), np.array([1, 2, 0]))), r"`neighbours`.*indptr"),
        (dict(neighbours=(np.array([0, 1, 2, 4]), np.array([1, 0, 0]))), r"`neighbours`.*indptr"),
        (dict(neighbours=(np.array([0, 1, 2, 3]), np.array([1, 0, 3]))), r"`neighbours`.*indices"),
        (dict(neighbours=(np.array([0, 1, 2, 3]), np.array([1, -1, 0]))), r"`neighbours`.*indices"),
    ],
)
def test_hrvo_rejects_bad_input(change, message):
    kwargs = {**GOOD, **change}
    with pytest.raises(ValueError, match=message):
        kernels.hrvo(**kwargs)


def test_hrvo_accepts_empty_swarm_and_valid_csr():
    assert kernels.hrvo(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2))).shape == (0, 2)
    got = kernels.hrvo(**GOOD, neighbours=(np.array([0, 1, 2, 3]), np.array([1, 0, 0])))
    assert_array_equal(got, np.zeros((3, 2)))
    assert _reference.hrvo is hrvo


def test_preferred_velocities_are_bounded_row_by_row_whatever_the_others():
    """The bound on huge preferred velocities (kept from overflowing the ranking) scales only the
    rows beyond :data:`PREFERRED_LIMIT`, each as alone, and leaves the array as it is when no
    coordinate comes near it (the shortcut must agree with the norm's verdict at its edge)."""
    from dream.kernels._hrvo import PREFERRED_LIMIT, _bounded

    edge = PREFERRED_LIMIT / 2
    modest = np.array([[edge, -edge], [-edge, 0.0], [0.1, 0.2]])
    assert _bounded(modest) is modest  # within: the same array, not a copy
    rows = np.array([[PREFERRED_LIMIT, 1.0], [0.8e6, -0.7e6], [3e300, -4e300], [np.nextafter(edge, 1e9), 0.0]])
    got = _bounded(rows)
    for row, bounded in zip(rows, got, strict=True):
        norm = math.hypot(*row)
        want = row * (PREFERRED_LIMIT / norm) if norm > PREFERRED_LIMIT else row
        assert_array_equal(bounded, want)
        assert_array_equal(_bounded(row[None, :])[0], want)  # alone or among others
