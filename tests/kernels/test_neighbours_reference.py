"""Neighbour filtering (SPEC 5.2): :func:`dream.kernels.neighbours` and ``neighbours_of``
against a brute-force double loop, plus hand-placed edge cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from dream import _reference, kernels


def brute_force(positions, radius, headings=None, direction=0.0, fov=2 * math.pi, max_neighbours=None):
    """Rows of ``(j, distance)`` by a double loop with the math module."""
    rows = []
    for i, (xi, yi) in enumerate(positions):
        row = []
        for j, (xj, yj) in enumerate(positions):
            if j == i:
                continue
            distance = math.hypot(xj - xi, yj - yi)
            if distance > radius:
                continue
            if headings is not None and distance > 0:
                off = math.atan2(yj - yi, xj - xi) - (headings[i] + direction)
                off = math.atan2(math.sin(off), math.cos(off))  # into [-pi, pi]
                if abs(off) > fov / 2:
                    continue
            row.append((j, distance))
        if max_neighbours is not None:
            row = sorted(sorted(row, key=lambda jd: (jd[1], jd[0]))[:max_neighbours])
        rows.append(row)
    return rows


def check_csr(result, n):
    indptr, indices, distances = result
    assert indptr.dtype == np.int64 and indices.dtype == np.int64 and distances.dtype == np.float64
    assert indptr.shape == (n + 1,) and indptr[0] == 0 and np.all(np.diff(indptr) >= 0)
    assert indices.shape == distances.shape == (indptr[-1],)
    return indptr, indices, distances


def assert_rows(result, rows):
    indptr, indices, distances = check_csr(result, len(rows))
    for i, row in enumerate(rows):
        got = indices[indptr[i] : indptr[i + 1]]
        assert_array_equal(got, [j for j, _ in row], err_msg=f"robot {i}")
        assert_allclose(distances[indptr[i] : indptr[i + 1]], [d for _, d in row], rtol=1e-12, atol=1e-15)


# -- against the double loop ----------------------------------------------------------------------
@pytest.mark.parametrize("n", [0, 1, 2, 17, 300])
@pytest.mark.parametrize("radius", [0.0, 0.5, 3.0])
def test_neighbours_matches_brute_force(rng, n, radius):
    positions = rng.uniform(-5.0, 5.0, size=(n, 2))
    if n >= 17:
        positions[5] = positions[3]  # a co-located pair
    assert_rows(kernels.neighbours(positions, radius), brute_force(positions, radius))
    assert_rows(_reference.neighbours(positions, radius), brute_force(positions, radius))


@pytest.mark.parametrize("n", [1, 2, 17, 300])
@pytest.mark.parametrize(
    ("direction", "fov"), [(0.0, math.pi / 2), (math.pi / 3, math.pi), (-2.0, 0.3), (1.0, 2 * math.pi)]
)
def test_neighbours_field_of_view_matches_brute_force(rng, n, direction, fov):
    positions = rng.uniform(-2.0, 2.0, size=(n, 2))
    headings = rng.uniform(-math.pi, math.pi, n)
    expected = brute_force(positions, 1.5, headings, direction, fov)
    assert_rows(kernels.neighbours(positions, 1.5, headings=headings, direction=direction, fov=fov), expected)


@pytest.mark.parametrize("n", [2, 17, 300])
@pytest.mark.parametrize("k", [0, 1, 3, 10])
def test_neighbours_max_neighbours_matches_brute_force(rng, n, k):
    positions = rng.uniform(-1.0, 1.0, size=(n, 2))
    assert_rows(kernels.neighbours(positions, 0.8, max_neighbours=k), brute_force(positions, 0.8, max_neighbours=k))


@pytest.mark.parametrize("n", [1, 2, 17, 300])
def test_neighbours_of_matches_rows_of_neighbours(rng, n):
    positions = rng.uniform(-3.0, 3.0, size=(n, 2))
    headings = rng.uniform(-math.pi, math.pi, n)
    indptr, indices, distances = kernels.neighbours(positions, 1.0, headings=headings, direction=0.4, fov=2.0)
    for i in range(0, n, max(1, n // 20)):
        js, ds = kernels.neighbours_of(positions, i, 1.0, heading=headings[i], direction=0.4, fov=2.0)
        assert_array_equal(js, indices[indptr[i] : indptr[i + 1]])
        assert_array_equal(ds, distances[indptr[i] : indptr[i + 1]])
        assert js.dtype == np.int64


# -- hand-placed cases ----------------------------------------------------------------------------
def test_neighbours_excludes_self_but_keeps_co_located_robots():
    positions = np.array([[0.3, 0.3], [0.3, 0.3], [0.3, 0.3], [2.0, 2.0]])
    indptr, indices, distances = kernels.neighbours(positions, 0.1)
    assert_array_equal(indptr, [0, 2, 4, 6, 6])
    assert_array_equal(indices, [1, 2, 0, 2, 0, 1])
    assert_array_equal(distances, np.zeros(6))
    # radius 0: only robots exactly on top of each other
    assert_array_equal(kernels.neighbours(positions, 0.0)[1], [1, 2, 0, 2, 0, 1])
    js, ds = kernels.neighbours_of(positions, 1, 0.0)
    assert_array_equal(js, [0, 2])
    # co-located robots are seen whatever the heading and field of view
    js, _ = kernels.neighbours_of(positions, 0, 0.1, heading=1.0, fov=0.1)
    assert_array_equal(js, [1, 2])


@pytest.mark.parametrize(
    ("other", "radius", "seen"),
    [
        ((0.5, 0.0), 0.5, True),  # exactly at the radius: inclusive
        ((0.0, -0.5), 0.5, True),
        ((0.3, 0.4), 0.5, True),  # hypot(0.3, 0.4) == 0.5 in floating point too
        ((np.nextafter(0.5, 1.0), 0.0), 0.5, False),
        ((0.5, 0.0), np.nextafter(0.5, 0.0), False),
        ((0.0, 0.0), 0.0, True),
    ],
)
def test_neighbours_range_is_inclusive(other, radius, seen):
    positions = np.array([[0.0, 0.0], other])
    assert math.hypot(*other) == radius or not seen  # the construction is exact
    indptr, indices, distances = kernels.neighbours(positions, radius)
    assert_array_equal(indptr, [0, 1, 2] if seen else [0, 0, 0])
    if seen:
        assert_array_equal(indices, [1, 0])
        assert_array_equal(distances, [radius, radius])


@pytest.mark.parametrize("tiny", [1e-18, 1e-45])
@pytest.mark.parametrize("radius", [0.5, 0.11, 0.3])
def test_neighbours_range_is_inclusive_across_cell_boundaries(tiny, radius):
    # The computed distance is exactly the radius although the exact one is a hair more and the
    # two points fall two grid cells (of side radius) apart: a grid must still pair them.
    positions = np.array([[0.0, -tiny], [0.0, radius], [-tiny, 2.0], [radius, 2.0]])
    assert math.hypot(*(positions[1] - positions[0])) == radius
    indptr, indices, _ = kernels.neighbours(positions, radius)
    assert [list(indices[indptr[i] : indptr[i + 1]]) for i in range(4)] == [[1], [0], [3], [2]]


@pytest.mark.parametrize(
    ("degrees", "direction", "seen"),
    [
        (30, 0.0, True),
        (-30, 0.0, True),
        (60, 0.0, False),
        (-60, 0.0, False),
        (180, 0.0, False),  # behind
        (120, 0.0, False),
        (90, math.pi / 2, True),  # the sensor looks to the left
        (60, math.pi / 2, True),
        (0, math.pi / 2, False),
        (180, math.pi, True),  # a rear sensor
    ],
)
def test_neighbours_field_of_view_by_hand(degrees, direction, seen):
    # Robot 0 at the origin heading along +x, fov pi/2 (45 degrees either side of the sensor axis).
    angle = math.radians(degrees)
    positions = np.array([[0.0, 0.0], [math.cos(angle), math.sin(angle)]])
    headings = np.array([0.0, 0.0])
    indptr, indices, _ = kernels.neighbours(positions, 2.0, headings=headings, direction=direction, fov=math.pi / 2)
    assert list(indices[indptr[0] : indptr[1]]) == ([1] if seen else [])
    js, _ = kernels.neighbours_of(positions, 0, 2.0, heading=0.0, direction=direction, fov=math.pi / 2)
    assert list(js) == ([1] if seen else [])


def test_neighbours_field_of_view_follows_each_robots_heading():
    # Three robots on a line; the middle one looks left (-x), the outer ones look at it.
    positions = np.array([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]])
    headings = np.array([0.0, math.pi, math.pi])
    indptr, indices, _ = kernels.neighbours(positions, 5.0, headings=headings, fov=math.pi / 2)
    rows = [list(indices[indptr[i] : indptr[i + 1]]) for i in range(3)]
    assert rows == [[1, 2], [0], [0, 1]]


def test_neighbours_field_of_view_wraps_around_pi():
    # Heading just below pi, a robot just "above" -pi in angle: 0.2 rad apart, not 2 pi - 0.2.
    positions = np.array([[0.0, 0.0], [math.cos(-math.pi + 0.1), math.sin(-math.pi + 0.1)]])
    js, _ = kernels.neighbours_of(positions, 0, 2.0, heading=math.pi - 0.1, fov=0.5)
    assert list(js) == [1]


def test_neighbours_max_neighbours_keeps_nearest_with_ties_by_index():
    # Robot 0 at the origin; robots 1..5 at distances 0.4, 0.2, 0.2, 0.3, 0.2.
    positions = np.array([[0.0, 0.0], [0.4, 0.0], [0.0, 0.2], [-0.2, 0.0], [0.0, -0.3], [0.0, -0.2]])
    js, ds = kernels.neighbours_of(positions, 0, 1.0)
    assert list(js) == [1, 2, 3, 4, 5]
    indptr, indices, distances = kernels.neighbours(positions, 1.0, max_neighbours=2)
    assert list(indices[indptr[0] : indptr[1]]) == [2, 3]  # three at 0.2: the two lowest indices
    assert_allclose(distances[indptr[0] : indptr[1]], [0.2, 0.2])
    indptr, indices, _ = kernels.neighbours(positions, 1.0, max_neighbours=4)
    assert list(indices[indptr[0] : indptr[1]]) == [2, 3, 4, 5]  # sorted by index, 0.4 dropped
    indptr, indices, _ = kernels.neighbours(positions, 1.0, max_neighbours=0)
    assert_array_equal(indptr, np.zeros(7))
    indptr, _, _ = kernels.neighbours(positions, 1.0, max_neighbours=100)
    assert indptr[1] == 5


def test_neighbours_rows_are_sorted_by_index(rng):
    positions = rng.uniform(-1.0, 1.0, size=(200, 2))
    indptr, indices, _ = kernels.neighbours(positions, 0.4, max_neighbours=5)
    for i in range(200):
        row = indices[indptr[i] : indptr[i + 1]]
        assert np.all(np.diff(row) > 0)
        assert i not in row


def test_neighbours_empty_swarm():
    indptr, indices, distances = check_csr(kernels.neighbours(np.zeros((0, 2)), 1.0), 0)
    assert_array_equal(indptr, [0])
    assert len(indices) == len(distances) == 0


@given(
    points=st.lists(st.tuples(st.integers(-4, 4), st.integers(-4, 4)), min_size=0, max_size=25),
    radius=st.sampled_from([0.0, 0.25, 0.5, 1.0, 2.0]),
)
@settings(max_examples=60, deadline=None)
def test_neighbours_property_on_a_coarse_lattice(points, radius):
    # Multiples of 0.25 make coincident robots and distances exactly equal to the radius common.
    positions = 0.25 * np.array(points, dtype=float).reshape(-1, 2)
    assert_rows(kernels.neighbours(positions, radius), brute_force(positions, radius))
    indptr, indices, _ = kernels.neighbours(positions, radius)
    # symmetry without a field of view: j sees i exactly when i sees j
    pairs = {(i, int(j)) for i in range(len(positions)) for j in indices[indptr[i] : indptr[i + 1]]}
    assert pairs == {(j, i) for i, j in pairs}


# -- errors ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: kernels.neighbours(np.zeros((4, 3)), 1.0), r"`positions` must have shape \(n, 2\), got \(4, 3\)"),
        (lambda: kernels.neighbours(np.zeros(4), 1.0), r"`positions` must have shape \(n, 2\)"),
        (lambda: kernels.neighbours(np.array([[0.0, 0.0], [np.nan, 0.0]]), 1.0), r"`positions`.*non-finite"),
        (lambda: kernels.neighbours(np.array([[0.0, np.inf]]), 1.0), r"`positions`.*non-finite"),
        (lambda: kernels.neighbours(np.zeros((2, 2)), -0.5), r"`radius`"),
        (lambda: kernels.neighbours(np.zeros((2, 2)), np.nan), r"`radius`"),
        (lambda: kernels.neighbours(np.zeros((3, 2)), 1.0, headings=np.zeros(2)), r"`headings` must have shape \(3,\)"),
        (lambda: kernels.neighbours(np.zeros((3, 2)), 1.0, headings=np.zeros((3, 1))), r"`headings`"),
        (
            lambda: kernels.neighbours(np.zeros((3, 2)), 1.0, headings=np.array([0.0, np.nan, 0.0])),
            r"`headings`.*non-finite",
        ),
        (lambda: kernels.neighbours(np.zeros((3, 2)), 1.0, max_neighbours=-1), r"`max_neighbours`"),
        (lambda: kernels.neighbours(np.zeros((3, 2)), 1.0, rows=np.ones(2, bool)), r"`rows` must have shape \(3,\)"),
        (lambda: kernels.neighbours(np.zeros((3, 2)), 1.0, rows=np.ones(3)), r"`rows` must be a bool array"),
        (lambda: kernels.neighbours_of(np.zeros((3, 3)), 0, 1.0), r"`positions` must have shape \(n, 2\)"),
        (lambda: kernels.far_from(np.zeros((3, 3)), np.zeros((1, 2)), 0.1), r"`points` must have shape \(n, 2\)"),
        (lambda: kernels.far_from(np.zeros((3, 2)), [[np.nan, 0.0]], 0.1), r"`others`.*non-finite"),
        (lambda: kernels.far_from(np.zeros((3, 2)), np.zeros((1, 2)), -0.1), r"`distance`"),
        (
            lambda: kernels.far_from(np.zeros((3, 2)), np.zeros((1, 2)), 0.1, offsets=([0, 2], [0, 1])),
            r"`offsets` \[0\] \(of the points\) must be offsets of shape \(rows \+ 1,\) rising from 0 to 3",
        ),
        (
            lambda: kernels.far_from(np.zeros((3, 2)), np.zeros((1, 2)), 0.1, offsets=([0, 1, 3], [0, 1])),
            r"`offsets` \[1\] \(of the others\) must be offsets of shape \(3,\)",
        ),
        (
            lambda: kernels.far_from(np.zeros((3, 2)), np.zeros((2, 2)), 0.1, offsets=([0, 1.5, 3], [0, 1, 2])),
            r"`offsets` \[0\] \(of the points\) must hold integer offsets",
        ),
        (
            lambda: kernels.far_from(np.zeros((3, 2)), np.zeros((1, 2)), 0.1, offsets=([0, 3],)),
            r"`offsets` must be a pair",
        ),
        (
            lambda: kernels.voronoi_cells(np.zeros((2, 2)), virtual=(np.array([0.0, 1.0, 1.0]), np.zeros((1, 2)))),
            r"`virtual` indptr must hold integer offsets",
        ),
        (lambda: kernels.neighbours_of(np.zeros((3, 2)), 0, -1.0), r"`radius`"),
    ],
)
def test_neighbours_rejects_bad_input(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.parametrize("robot_id", [-1, 3, 10])
def test_neighbours_of_rejects_unknown_robot(robot_id):
    with pytest.raises(IndexError, match=f"robot id {robot_id}"):
        kernels.neighbours_of(np.zeros((3, 2)), robot_id, 1.0)
