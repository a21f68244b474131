"""The Rust kernels of :mod:`dream._core` against their NumPy reference :mod:`dream._reference`
(SPEC 5): the same results on seeded random inputs and hypothesis edge cases, the same
memory-layout independence, determinism under rayon, and the error mapping of the bindings
(bad input is a ``ValueError`` naming the argument, never a ``PanicException``)."""

from __future__ import annotations

import functools
import math
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from dream import _core, _reference, kernels
from dream._reference.obstacles import GAP, closest_point
from dream.errors import GeometryError

SAFETY = 0.24
V_MAX = 0.2
ARENA = (-1.6, 1.6, -1.0, 1.0)
ARENA_AREA = (ARENA[1] - ARENA[0]) * (ARENA[3] - ARENA[2])
TAU = 2 * math.pi
EXACT_TOL = dict(atol=1e-12, rtol=0)


def test_kernels_dispatch_follows_the_environment():
    # The "kernels" comparisons below are Rust vs NumPy in the normal run; the CI's second run
    # (DREAM_PURE_PYTHON=1) checks that the fallback is really the reference. The `_core` calls
    # compare Rust with NumPy in both runs.
    pure = os.environ.get("DREAM_PURE_PYTHON", "") not in ("", "0")
    assert kernels.IMPLEMENTATION == ("numpy" if pure else "rust")


# -- helpers --------------------------------------------------------------------------------------
def assert_csr_equal(got, want):
    """Neighbour CSR triples: identical structure, identical distances (both use sqrt(dx^2 + dy^2))."""
    (indptr, indices, distances), (r_indptr, r_indices, r_distances) = got, want
    assert indptr.dtype == indices.dtype == np.int64 and distances.dtype == np.float64
    assert_array_equal(indptr, r_indptr)
    assert_array_equal(indices, r_indices)
    assert_array_equal(distances, r_distances)


def core_neighbours(p, radius, headings=None, direction=0.0, fov=TAU, max_neighbours=None, rows=None):
    return _core.neighbours(p, radius, headings, direction, fov, max_neighbours, rows)


def ref_neighbours(p, radius, headings=None, direction=0.0, fov=TAU, max_neighbours=None, rows=None):
    return _reference.neighbours(
        p, radius, headings=headings, direction=direction, fov=fov, max_neighbours=max_neighbours, rows=rows
    )


HRVO_DEFAULTS = dict(
    radius=1.0, safety=SAFETY, v_max=V_MAX, bounds=None, n_angles=20, n_speeds=10, include_preferred=True
)


def hrvo_of(module, p, v, pref, csr=None, **kw):
    """``module.hrvo`` (``dream._core``'s or the reference's: same arguments) with keywords as
    :func:`dream.kernels.hrvo` takes them (the grid built from n_angles, n_speeds)."""
    kw = {**HRVO_DEFAULTS, **kw}
    grid = _reference.candidate_grid(kw["v_max"], kw.pop("n_angles"), kw.pop("n_speeds"))
    indptr, indices = (None, None) if csr is None else csr
    return module.hrvo(p, v, pref, indptr, indices, candidates=grid, **kw)


core_hrvo = functools.partial(hrvo_of, _core)
ref_hrvo = functools.partial(hrvo_of, _reference)


def assert_hrvo_matches(p, v, pref, csr=None, **kw):
    got = core_hrvo(p, v, pref, csr, **kw)
    assert got.shape == (len(p), 2) and got.dtype == np.float64
    assert_array_equal(got, ref_hrvo(p, v, pref, csr, **kw))
    return got


def swarm(rng, n, spread=1.5):
    """Positions, previous velocities and preferred velocities (some faster than V_MAX)."""
    return rng.uniform(-spread, spread, (n, 2)), rng.uniform(-V_MAX, V_MAX, (n, 2)), rng.uniform(-0.4, 0.4, (n, 2))


def cells_of(module, p, radius, bounds=ARENA, virtual=None, resolution=64):
    """``module.voronoi_cells`` (``dream._core``'s or the reference's: same arguments), ``virtual`` a CSR pair."""
    vi, vp = (None, None) if virtual is None else virtual
    return module.voronoi_cells(
        p, radius=radius, bounds=bounds, virtual_indptr=vi, virtual_points=vp, resolution=resolution
    )


core_cells = functools.partial(cells_of, _core)
ref_cells = functools.partial(cells_of, _reference)


def assert_cells_match(got, want):
    (centroids, areas, vertices, offsets), (r_centroids, r_areas, r_vertices, r_offsets) = got, want
    assert offsets.dtype == np.int64
    assert_array_equal(offsets, r_offsets)
    assert vertices.shape == r_vertices.shape
    assert_allclose(centroids, r_centroids, **EXACT_TOL)
    assert_allclose(areas, r_areas, **EXACT_TOL)
    assert_allclose(vertices, r_vertices, **EXACT_TOL)


def virtual_around(rng, p, most=3):
    """CSR ``(indptr, points)`` of 0..most virtual agents per robot, 0.05 to 0.6 m away, and each agent's robot."""
    counts = rng.integers(0, most + 1, len(p))
    indptr = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    owners = np.repeat(np.arange(len(p)), counts)
    angle, distance = rng.uniform(-np.pi, np.pi, len(owners)), rng.uniform(0.05, 0.6, len(owners))
    points = p[owners] + distance[:, None] * np.column_stack((np.cos(angle), np.sin(angle)))
    return indptr, points.reshape(-1, 2), owners


def layouts(array):
    """The same values as a C array, a Fortran array, a strided view and a reversed view."""
    wide = np.zeros((array.shape[0], 2 * array.shape[1]))
    wide[:, ::2] = array
    reversed_twice = np.ascontiguousarray(array[::-1])[::-1]
    views = [np.ascontiguousarray(array), np.asfortranarray(array), wide[:, ::2], reversed_twice]
    assert all(np.array_equal(view, array) for view in views)
    assert not any(view.flags.c_contiguous for view in views[1:])
    return views


LAYOUT_IDS = ["C", "F", "strided", "negative-stride"]


# -- 1. neighbours --------------------------------------------------------------------------------
VIEWS = [None, (0.0, math.pi / 3), (1.2, math.pi), (0.0, TAU), (1.2, TAU)]


@pytest.mark.parametrize("n", [0, 1, 2, 50, 2000, 3000])  # >= 2048 rows run on rayon
@pytest.mark.parametrize("radius", [0.0, 0.3, 2.0])
@pytest.mark.parametrize(
    "view", VIEWS, ids=["all-round", "fov60-dir0", "fov180-dir1.2", "fov360-dir0", "fov360-dir1.2"]
)
def test_neighbours_matches_reference_on_random_swarms(rng, n, radius, view):
    spread = 1.0 if n < 100 else 6.0  # a few neighbours at radius 0.3, hundreds at 2.0
    p = rng.uniform(-spread, spread, (n, 2))
    if radius == 0.0 and n > 1:
        p[n // 2 :: 7] = p[: len(p[n // 2 :: 7])]  # coincident robots, so radius 0 finds something
    kw = {} if view is None else dict(headings=rng.uniform(-10.0, 10.0, n), direction=view[0], fov=view[1])
    got = core_neighbours(p, radius, **kw)
    assert_csr_equal(got, ref_neighbours(p, radius, **kw))
    if n >= 50 and radius > 0:
        assert len(got[1]) > 0  # the comparison is not vacuous


@pytest.mark.parametrize(("offset", "scale"), [(0.0, 1e-155), (0.0, 1e-120), (1e8, 1.0), (0.0, 1e150), (-3e9, 1e3)])
def test_far_from_matches_reference_at_extreme_scales(rng, offset, scale):
    # Tiny distances (squares below 1e-300: hypot decides alone), squares that overflow, and
    # points far from the origin (the box margin against rounding), with others placed at the
    # distance and a hair either side of it.
    rows, distance = 30, 0.08 * scale
    seen_counts, heard_counts = rng.integers(1, 6, rows), rng.integers(1, 12, rows)
    points = offset + scale * rng.uniform(-1.0, 1.0, (seen_counts.sum(), 2))
    others = offset + scale * rng.uniform(-1.0, 1.0, (heard_counts.sum(), 2))
    firsts = np.concatenate(([0], np.cumsum(heard_counts)))[:-1]
    owners = np.repeat(np.arange(rows), seen_counts)
    for k, row in enumerate(owners[: 3 * rows : 3]):
        step = distance * (1.0, 1 + 1e-15, 1 - 1e-15, 1 + 1e-9)[k % 4]
        others[firsts[row]] = points[3 * k] + (step, 0.0)
    offsets = [np.concatenate(([0], np.cumsum(c))) for c in (seen_counts, heard_counts)]
    got = _core.far_from(points, others, distance, *offsets)
    assert_array_equal(got, _reference.far_from(points, others, distance, *offsets))
    assert_array_equal(_core.far_from(points, others, distance), _reference.far_from(points, others, distance))
    if scale == 1e150:  # squares overflow: every pair is far apart or decided by hypot
        wide = _core.far_from(points, others, 3.0 * scale)
        assert_array_equal(wide, _reference.far_from(points, others, 3.0 * scale))


@pytest.mark.parametrize("n", [1, 50, 3000])
@pytest.mark.parametrize("share", [0.0, 0.2, 1.0])
@pytest.mark.parametrize("with_view", [False, True])
def test_neighbours_of_some_rows_match_reference(rng, n, share, with_view):
    # The rows of the robots that read this step: theirs as in the full query, the others empty.
    p = rng.uniform(-4.0, 4.0, (n, 2))
    rows = rng.random(n) < share
    kw = dict(headings=rng.uniform(-np.pi, np.pi, n), direction=0.3, fov=2.0) if with_view else {}
    got = core_neighbours(p, 0.8, rows=rows, **kw)
    assert_csr_equal(got, ref_neighbours(p, 0.8, rows=rows, **kw))
    full = core_neighbours(p, 0.8, **kw)
    counts = np.diff(got[0])
    assert np.all(counts[~rows] == 0)
    assert_array_equal(counts[rows], np.diff(full[0])[rows])
    if n == 3000 and share > 0:
        assert counts.sum() > 0  # the comparison is not vacuous


@pytest.mark.parametrize("rows", [1, 7, 2000])  # 2000 rows of ~300 others run on rayon
@pytest.mark.parametrize("distance", [0.0, 0.08, 0.5])
def test_far_from_matches_reference(rng, rows, distance):
    # Robots that each see a few and hear many: some heard positions close to those seen, some
    # at exactly the distance along an axis, the rest a crowd.
    seen_counts, heard_counts = rng.integers(0, 20, rows), rng.integers(0, 300 if rows > 1000 else 60, rows)
    points = rng.uniform(-3.0, 3.0, (seen_counts.sum(), 2))
    others = rng.uniform(-3.0, 3.0, (heard_counts.sum(), 2))
    owners = np.repeat(np.arange(rows), seen_counts)
    firsts = np.concatenate(([0], np.cumsum(heard_counts)))[:-1]
    for k in range(len(points))[::3]:
        row = owners[k]
        if heard_counts[row]:
            others[firsts[row]] = points[k] + (distance if k % 2 else rng.normal(scale=0.03), 0.0)
    offsets = [np.concatenate(([0], np.cumsum(c))) for c in (seen_counts, heard_counts)]
    got = _core.far_from(points, others, distance, *offsets)
    assert_array_equal(got, _reference.far_from(points, others, distance, *offsets))
    if len(points) > 30:
        assert 0 < got.sum() < len(got)  # both answers occur: the comparison is not vacuous
    if rows < 100:  # one row: every point against every other
        assert_array_equal(_core.far_from(points, others, distance), _reference.far_from(points, others, distance))


@pytest.mark.parametrize("n", [2, 50, 3000])
@pytest.mark.parametrize("radius", [0.3, 2.0])
@pytest.mark.parametrize("max_neighbours", [None, 0, 1, 5])
@pytest.mark.parametrize("with_view", [False, True])
def test_neighbours_max_neighbours_matches_reference(rng, n, radius, max_neighbours, with_view):
    p = rng.uniform(-1.0 if n < 100 else 6.0, 1.0 if n < 100 else 6.0, (n, 2))
    # Robots on a 0.25 lattice too: many equal distances, so the index tie-break matters.
    p[: n // 2] = np.round(p[: n // 2] * 4) / 4
    kw = dict(headings=rng.uniform(-np.pi, np.pi, n), direction=1.2, fov=math.pi) if with_view else {}
    got = core_neighbours(p, radius, max_neighbours=max_neighbours, **kw)
    assert_csr_equal(got, ref_neighbours(p, radius, max_neighbours=max_neighbours, **kw))
    if max_neighbours is not None:
        assert np.all(np.diff(got[0]) <= max_neighbours)


# Coordinates that make coincident robots, pairs exactly at range (0.25, 0.5 and 0.75 are
# exact) and points a hair off a cell border (-1e-18 next to 0 and the radius itself).
EDGE_COORDINATES = st.sampled_from([0.0, 1e-18, -1e-18, 0.25, -0.25, 0.3, -0.3, 0.5, -0.5, 0.75, 0.11, -0.11, 1.0])


@st.composite
def edge_swarms(draw):
    base = draw(st.lists(st.tuples(EDGE_COORDINATES, EDGE_COORDINATES), min_size=1, max_size=14))
    copies = draw(st.lists(st.integers(0, len(base) - 1), max_size=5))  # duplicated points
    return np.array(base + [base[k] for k in copies], dtype=float)


@given(
    p=edge_swarms(),
    radius=st.sampled_from([0.0, 0.11, 0.25, 0.3, 0.5, 1.0]),
    headings=st.none() | st.floats(-7.0, 7.0),
    fov=st.sampled_from([0.0, math.pi / 3, math.pi, TAU]),
    max_neighbours=st.none() | st.integers(0, 4),
)
@settings(max_examples=60, deadline=None)
def test_neighbours_property_edge_cases_match_reference(p, radius, headings, fov, max_neighbours):
    h = None if headings is None else np.full(len(p), headings) + np.arange(len(p))
    kw = dict(headings=h, direction=0.4, fov=fov, max_neighbours=max_neighbours)
    assert_csr_equal(core_neighbours(p, radius, **kw), ref_neighbours(p, radius, **kw))


@given(
    clusters=st.lists(st.tuples(st.integers(-3, 3), st.integers(-3, 3)), min_size=1, max_size=6),
    offsets=st.lists(st.tuples(EDGE_COORDINATES, EDGE_COORDINATES), min_size=1, max_size=20),
    scale=st.sampled_from([1e9, 3e9, 1e12]),
    radius=st.sampled_from([0.0, 0.25, 0.5, 1.0]),
)
@settings(max_examples=50, deadline=None)
def test_neighbours_property_huge_spread_matches_reference(clusters, offsets, scale, radius):
    # Clusters 1e9+ m apart: the occupied box has too many cells for a dense table (sparse path).
    centres = scale * np.array(clusters, dtype=float)
    p = np.array([centres[k % len(centres)] + offsets[k] for k in range(len(offsets))])
    assert_csr_equal(core_neighbours(p, radius), ref_neighbours(p, radius))


@pytest.mark.parametrize("radius", [0.11, 0.25, 0.3, 0.5])
@pytest.mark.parametrize("axis", [0, 1])
def test_neighbours_pair_at_exact_range_across_cell_borders_matches_reference(radius, axis):
    # y = -1e-18 and y = radius: the pair straddles two cell borders but is exactly in range.
    p = np.zeros((3, 2))
    p[0, axis], p[1, axis], p[2, axis] = -1e-18, radius, -radius - 1e-18
    got = core_neighbours(p, radius)
    assert_csr_equal(got, ref_neighbours(p, radius))
    assert 1 in got[1][got[0][0] : got[0][1]]


# -- 2. HRVO, batch ---------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [0, 1, 2, 30, 400])  # >= 256 robots run on rayon
@pytest.mark.parametrize("mode", ["csr", "radius"])
@pytest.mark.parametrize("bounds", [None, ARENA])
@pytest.mark.parametrize("include_preferred", [True, False])
def test_hrvo_matches_reference_on_random_swarms(rng, n, mode, bounds, include_preferred):
    p, v, pref = swarm(rng, n)
    radius = 0.6
    csr = _reference.neighbours(p, radius)[:2] if mode == "csr" else None
    assert_hrvo_matches(p, v, pref, csr, radius=radius, bounds=bounds, include_preferred=include_preferred)


def ring_swarm(rng, n, radius):
    """hrvo-circle's swarm spread thin: ``n`` robots on a ring ~0.34 m apart, hundreds of radii
    wide, so the grids keep a table per column (too many cells for a dense one)."""
    angle = np.linspace(0.0, TAU, n, endpoint=False)
    wide = 0.34 * n / TAU
    p = np.column_stack((wide * np.cos(angle), 0.6 * wide * np.sin(angle))) + rng.uniform(-0.05, 0.05, (n, 2))
    return p, rng.uniform(-V_MAX, V_MAX, (n, 2)), rng.uniform(-V_MAX, V_MAX, (n, 2))


@pytest.mark.parametrize("radius", [0.11, 1.0])
def test_kernels_match_reference_on_a_thin_ring(rng, radius):
    n = 3000
    p, v, pref = ring_swarm(rng, n, radius)
    assert_csr_equal(_core.neighbours(p, radius, None, 0.0, TAU, None, None), _reference.neighbours(p, radius))
    assert_hrvo_matches(p, v, pref, None, radius=radius)
    poses = np.vstack((p.T, rng.uniform(-3, 3, n)))
    commands = np.zeros((2, n))
    box = (-150.0, 150.0, -90.0, 90.0)  # some robots outside
    wheels = dict(diameter=radius, wheel_radius=0.016, base_length=0.105, max_wheel=12.5)
    expected = _reference.validate(poses, commands, box, **wheels)
    assert expected[0] > 0 and (radius < 0.34 or expected[1] > 0)
    got = _core.validate(poses, commands, box, **wheels)
    assert got[:3] == expected[:3]
    assert_array_equal(got[3], expected[3])


def test_hrvo_matches_reference_on_arbitrary_csr_with_self_loops_and_repeats(rng):
    # CSR rows need not be symmetric or within range; a robot may list itself (d = 0) or a
    # neighbour twice: both kernels must treat every row entry the same way.
    n = 60
    p, v, pref = swarm(rng, n)
    counts = rng.integers(0, 8, n)
    indptr = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    indices = rng.integers(0, n, indptr[-1]).astype(np.int64)
    rows = np.flatnonzero(counts >= 3)
    indices[indptr[rows]] = rows  # each such row lists its own robot first ...
    indices[indptr[rows] + 2] = indices[indptr[rows] + 1]  # ... and one neighbour twice
    for bounds in (None, ARENA):
        assert_hrvo_matches(p, v, pref, (indptr, indices), bounds=bounds)


@pytest.mark.parametrize(("n_angles", "n_speeds"), [(20, 10), (1, 1), (2, 2), (7, 3), (36, 5), (3, 40)])
@pytest.mark.parametrize("v_max", [0.0, 0.2, 1.5])
def test_hrvo_matches_reference_for_candidate_grids(rng, n_angles, n_speeds, v_max):
    p, v, pref = swarm(rng, 30, spread=1.0)
    kw = dict(radius=0.8, v_max=v_max, n_angles=n_angles, n_speeds=n_speeds)
    for include_preferred in (True, False):
        assert_hrvo_matches(p, v, pref, include_preferred=include_preferred, **kw)


def test_hrvo_matches_reference_when_every_preference_is_blocked(rng):
    # A standing crowd, each robot wanting to drive into its nearest neighbour: no preferred
    # velocity is free, so every robot searches the candidates (on rayon: n >= 256).
    n = 300
    p = rng.uniform(0.0, 9.0, (n, 2))
    indptr, indices, distances = _reference.neighbours(p, 2.0)
    pref = np.zeros((n, 2))
    for i in range(n):
        row = slice(indptr[i], indptr[i + 1])
        offset = p[indices[row][np.argmin(distances[row])]] - p[i]
        pref[i] = 0.2 * offset / np.hypot(offset[0], offset[1])
    got = assert_hrvo_matches(p, np.zeros((n, 2)), pref, radius=1.0)
    assert not np.any(np.all(got == pref, axis=1))


@pytest.mark.parametrize("safety", [0.1, 0.24])
@pytest.mark.parametrize("bounds", [None, (-1.0, 1.0, -1.0, 1.0)])
def test_hrvo_matches_reference_in_a_dense_crowd(rng, safety, bounds):
    # 150 robots in a 2 m square, many within the safety radius of others: most candidates
    # are forbidden and most robots get the zero fallback.
    p, v, pref = swarm(rng, 150, spread=1.0)
    got = assert_hrvo_matches(p, v, pref, radius=0.6, safety=safety, bounds=bounds)
    stopped = np.all(got == 0.0, axis=1)
    assert stopped.sum() >= 10 and (~stopped).sum() >= 1  # both outcomes are exercised


@pytest.mark.parametrize("n", [2, 3, 40, 300])
@pytest.mark.parametrize("mode", ["csr", "radius"])
def test_hrvo_matches_reference_with_coincident_robots(rng, n, mode):
    # Co-located robots: distance 0, direction atan2(0, 0) = 0, half-angle pi / 2.
    p, v, pref = swarm(rng, n, spread=1.0)
    p[1::2] = p[0::2][: len(p[1::2])]
    v[2::3] = v[0]  # equal velocities too: the RVO apex equals v_A, a tie
    csr = _reference.neighbours(p, 0.5)[:2] if mode == "csr" else None
    for bounds in (None, ARENA):
        assert_hrvo_matches(p, v, pref, csr, radius=0.5, bounds=bounds)


@given(
    cells=st.lists(st.tuples(*[st.integers(-4, 4)] * 2, *[st.integers(-2, 2)] * 2), min_size=1, max_size=12),
    preferred=st.tuples(st.integers(-4, 4), st.integers(-4, 4)),
    include_preferred=st.booleans(),
)
@settings(max_examples=50, deadline=None)
def test_hrvo_property_lattice_swarms_match_reference(cells, preferred, include_preferred):
    # Positions on a 0.1 lattice and velocities on a 0.1 lattice: exact ties of every kind
    # (equal distances to v_pref, v_A on a bisector, coincident robots, d == safety).
    a = np.array(cells, dtype=float)
    p, v = 0.12 * a[:, :2], 0.1 * a[:, 2:]
    pref = np.tile(0.05 * np.array(preferred, dtype=float), (len(a), 1))
    assert_hrvo_matches(p, v, pref, radius=0.5, include_preferred=include_preferred)


@pytest.mark.parametrize("n", [0, 1, 2, 30, 400])
@pytest.mark.parametrize("with_csr", [False, True])
def test_hrvo_public_kernel_matches_reference(rng, n, with_csr):
    p, v, pref = swarm(rng, n)
    csr = _reference.neighbours(p, 0.6)[:2] if with_csr else None
    kw = dict(radius=0.6, bounds=ARENA, n_angles=12, n_speeds=6)
    assert_array_equal(kernels.hrvo(p, v, pref, csr, **kw), ref_hrvo(p, v, pref, csr, **kw))


# -- 3. HRVO, per robot ---------------------------------------------------------------------------
def detections_of(rng, k):
    """Seed-format rows [distance, angle, vx, vy]: angle from the detected robot to this one."""
    distance = rng.uniform(0.0, 1.2, k)  # some closer than the safety radius
    distance[: k // 4] = SAFETY  # exactly at the safety radius: phi = pi / 2
    return np.column_stack((distance, rng.uniform(-np.pi, np.pi, k), rng.uniform(-V_MAX, V_MAX, (k, 2))))


@pytest.mark.parametrize("k", [0, 1, 9, 30])
@pytest.mark.parametrize("bounds", [None, ARENA])
@pytest.mark.parametrize("include_preferred", [True, False])
def test_hrvo_planner_velocity_matches_reference(rng, k, bounds, include_preferred):
    planner = kernels.HrvoPlanner(bounds=bounds, include_preferred=include_preferred, n_angles=16, n_speeds=7)
    changed = 0
    for _ in range(30):
        detections = detections_of(rng, k)
        velocity, preferred = rng.uniform(-V_MAX, V_MAX, 2), rng.uniform(-0.4, 0.4, 2)
        position = rng.uniform([-1.6, -1.0], [1.6, 1.0])
        got = planner.velocity(detections, velocity, preferred, position)
        want = _reference.hrvo_velocity(
            velocity,
            preferred,
            _reference.detection_directions(detections),
            detections[:, 0],
            detections[:, 2:4],
            safety=SAFETY,
            v_max=V_MAX,
            position=position,
            bounds=bounds,
            candidates=_reference.candidate_grid(V_MAX, 16, 7),
            include_preferred=include_preferred,
        )
        assert got.shape == (2,) and got.dtype == np.float64
        assert_array_equal(got, want)
        changed += not np.array_equal(got, preferred)
    assert changed > 0


def test_hrvo_planner_core_class_matches_batch_kernel(rng):
    # The per-robot planner and the batch kernel agree when given the same neighbourhood.
    n = 40
    p, v, pref = swarm(rng, n, spread=1.0)
    grid = _reference.candidate_grid(V_MAX, 20, 10)
    planner = _core.HrvoPlanner(grid, safety=SAFETY, v_max=V_MAX, bounds=ARENA, include_preferred=True)
    batch = core_hrvo(p, v, pref, radius=0.7, bounds=ARENA)
    indptr, indices, distances = _reference.neighbours(p, 0.7)
    for i in range(n):
        js = indices[indptr[i] : indptr[i + 1]]
        offset = p[i] - p[js]  # from the neighbour towards robot i
        detections = np.column_stack(
            (distances[indptr[i] : indptr[i + 1]], np.arctan2(offset[:, 1], offset[:, 0]), v[js])
        )
        got = planner.velocity(detections, v[i], pref[i], p[i])
        # the detection angle round trip (atan2 then + pi) may move an edge by an ulp
        assert_allclose(got, batch[i], atol=1e-12)


# -- 4. Voronoi cells -------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [0, 1, 2, 60, 300])  # >= 256 robots run on rayon
@pytest.mark.parametrize("resolution", [3, 8, 64])
@pytest.mark.parametrize("with_virtual", [False, True])
def test_voronoi_cells_match_reference(rng, n, resolution, with_virtual):
    # A box a little larger than the arena: some robots are outside it (empty cells).
    p = rng.uniform([-1.8, -1.2], [1.8, 1.2], (n, 2))
    virtual = virtual_around(rng, p)[:2] if with_virtual else None
    radius = 0.5 if n < 100 else 0.25
    got = core_cells(p, radius, virtual=virtual, resolution=resolution)
    assert_cells_match(got, ref_cells(p, radius, virtual=virtual, resolution=resolution))
    assert got[0].shape == (n, 2) and got[1].shape == (n,) and got[3].shape == (n + 1,)


@pytest.mark.parametrize("bounds", [ARENA, (0.0, 1.0, 0.0, 1.0), (-100.0, 100.0, -0.3, 0.3)])
@pytest.mark.parametrize("radius", [0.05, 0.4, 3.0])
def test_voronoi_cells_match_reference_for_arenas_and_radii(rng, bounds, radius):
    p = rng.uniform([-1.8, -1.2], [1.8, 1.2], (80, 2))
    kw = dict(bounds=bounds, resolution=16)
    assert_cells_match(core_cells(p, radius, **kw), ref_cells(p, radius, **kw))


def test_voronoi_cells_outside_the_arena_are_empty_in_both(rng):
    inside = rng.uniform([-1.5, -0.9], [1.5, 0.9], (20, 2))
    outside = np.array([[5.0, 0.0], [-1.61 - 0.5, 0.0], [0.0, 1.0 + 0.6], [3.0, -4.0]])
    p = np.vstack((inside, outside))
    got = core_cells(p, 0.5)
    assert_cells_match(got, ref_cells(p, 0.5))
    centroids, areas, _, offsets = got
    assert_array_equal(areas[20:], 0.0)
    assert_array_equal(centroids[20:], outside)
    assert_array_equal(np.diff(offsets)[20:], 0)
    assert np.all(areas[:20] > 0)


@pytest.mark.parametrize("n", [2, 5, 60, 300])
@pytest.mark.parametrize("with_virtual", [False, True])
def test_voronoi_cells_match_reference_with_coincident_robots(rng, n, with_virtual):
    # Co-located robots have no bisector (zero normal): neither clips the other's cell.
    p = rng.uniform([-1.5, -0.9], [1.5, 0.9], (n, 2))
    p[1::2] = p[0::2][: len(p[1::2])]
    virtual = None
    if with_virtual:
        indptr, points, owners = virtual_around(rng, p)
        points[:3] = p[owners[:3]]  # virtual agents on top of their robot: zero normal as well
        virtual = (indptr, points)
    got = core_cells(p, 0.4, virtual=virtual)
    assert_cells_match(got, ref_cells(p, 0.4, virtual=virtual))
    if not with_virtual:
        assert_array_equal(got[1][0], got[1][1])  # the pair shares one cell


@given(
    points=st.lists(st.tuples(st.integers(-8, 8), st.integers(-5, 5)), min_size=1, max_size=16),
    radius=st.sampled_from([0.1, 0.2, 0.25, 0.5, 1.0]),
    resolution=st.sampled_from([3, 4, 8, 64]),
)
@settings(max_examples=50, deadline=None)
def test_voronoi_cells_property_lattice_swarms_match_reference(points, radius, resolution):
    # Lattice robots put bisectors through disc vertices and arena walls: exact ties of sa <= 0.
    p = 0.2 * np.array(points, dtype=float)
    assert_cells_match(core_cells(p, radius, resolution=resolution), ref_cells(p, radius, resolution=resolution))


@pytest.mark.parametrize("n", [2, 60, 300])
@pytest.mark.parametrize(("radius", "resolution"), [(0.3, 8), (0.3, 64), (1.0, 3)])
def test_voronoi_cells_property_disjoint_cells_near_their_robots(rng, n, radius, resolution):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2))
    centroids, areas, vertices, offsets = core_cells(p, radius, resolution=resolution)
    # Cells of distinct robots do not overlap and stay in the arena.
    assert areas.sum() <= ARENA_AREA + 1e-9
    assert np.all(areas >= 0)
    near_indptr, near_indices, _ = _reference.neighbours(p, 2 * radius)
    for i in range(n):
        cell = vertices[offsets[i] : offsets[i + 1]]
        if len(cell) == 0:
            continue
        # the centroid is inside the cell's bounding box
        assert np.all(cell.min(axis=0) - 1e-12 <= centroids[i]) and np.all(centroids[i] <= cell.max(axis=0) + 1e-12)
        # each vertex is at least as close to robot i as to any other robot within 2 radius
        others = p[near_indices[near_indptr[i] : near_indptr[i + 1]]]
        own = np.hypot(*(cell - p[i]).T)
        assert np.all(own <= radius + 1e-12)
        if len(others):
            theirs = np.hypot(cell[:, None, 0] - others[None, :, 0], cell[:, None, 1] - others[None, :, 1])
            assert np.all(own[:, None] <= theirs + 1e-9)


@pytest.mark.parametrize(("n", "radius", "resolution"), [(60, 5.0, 8), (60, 1.0, 64), (300, 0.5, 64)])
def test_voronoi_cells_property_dense_swarm_covers_the_arena(rng, n, radius, resolution):
    # With discs that reach every point's nearest robot, the cells tile the arena.
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2))
    areas = core_cells(p, radius, resolution=resolution)[1]
    assert abs(areas.sum() - ARENA_AREA) <= 1e-6


def test_voronoi_cells_virtual_agents_from_obstacles_match_reference(rng):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (120, 2))
    virtual = kernels.virtual_agents(p, OBSTACLES, range=0.8, robot_radius=0.05, margin=0.02)
    assert len(virtual[1]) > 20
    got = core_cells(p, 0.4, virtual=virtual)
    assert_cells_match(got, ref_cells(p, 0.4, virtual=virtual))
    assert got[1].sum() < core_cells(p, 0.4)[1].sum()  # the obstacles took area away


# -- 5. virtual agents ------------------------------------------------------------------------------
RECTANGLES = [(0.3, 0.8, 0.2, 0.6), (-1.2, -0.6, -0.7, -0.5), (-0.1, 0.1, -0.9, -0.1)]
TRIANGLE = np.array([[-1.0, 0.3], [-0.4, 0.4], [-0.8, 0.9]])


def _rectangle(xmin, xmax, ymin, ymax, clockwise):
    ring = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    return ring[::-1] if clockwise else ring


_POLYGONS = [_rectangle(*box, clockwise=k % 2 == 1) for k, box in enumerate(RECTANGLES)] + [TRIANGLE]
OBSTACLES = (np.vstack(_POLYGONS), np.concatenate(([0], np.cumsum([len(q) for q in _POLYGONS]))).astype(np.int64))


def closest_points(p):
    """(k, 2) closest point of every obstacle to p, independently: clipping for the rectangles."""
    boxes = [np.clip(p, [x0, y0], [x1, y1]) for x0, x1, y0, y1 in RECTANGLES]
    inside_triangle = closest_point(TRIANGLE, p)
    return np.array(boxes + [p if inside_triangle is None else inside_triangle])  # inside: distance 0


@pytest.mark.parametrize("n", [0, 1, 2, 200])
@pytest.mark.parametrize("sensing", [0.3, 1.0, 5.0])
@pytest.mark.parametrize(("margin", "mirror"), [(0.0, False), (0.03, False), (0.03, True)])
def test_virtual_agents_match_reference(rng, n, sensing, margin, mirror):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2))
    got = kernels.virtual_agents(
        p, OBSTACLES, range=sensing, robot_radius=0.05, margin=margin, mirror_at_surface=mirror
    )
    offset = 0.0 if mirror else 0.05 + margin
    want = _reference.virtual_agents(p, *OBSTACLES, range=sensing, offset=offset)
    assert got[0].dtype == np.int64 and got[1].shape == (got[0][-1], 2)
    assert_array_equal(got[0], want[0])
    assert_allclose(got[1], want[1], atol=1e-9, rtol=0)  # parry's projection is iterative
    if n == 200:
        assert len(got[1]) > 0


def test_virtual_agents_robots_inside_an_obstacle_get_none(rng):
    # Centres and random interior points of every obstacle: no direction to mirror along.
    interior = [rng.uniform([x0, y0], [x1, y1], (5, 2)) for x0, x1, y0, y1 in RECTANGLES]
    interior.append(TRIANGLE.mean(axis=0) + 0.05 * rng.uniform(-1, 1, (5, 2)))
    p = np.vstack(interior)
    rust = kernels.virtual_agents(p, OBSTACLES, range=5.0)
    for agents in (rust, _reference.virtual_agents(p, *OBSTACLES, range=5.0, offset=0.05)):
        counts = np.diff(agents[0])
        # a robot inside one obstacle still senses the others (within 5 m all are in range)
        assert_array_equal(counts, len(_POLYGONS) - 1)


def test_virtual_agents_robots_beyond_range_get_none(rng):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (200, 2))
    sensing = 0.25
    indptr, _ = kernels.virtual_agents(p, OBSTACLES, range=sensing)
    for i in range(len(p)):
        distances = np.hypot(*(closest_points(p[i]) - p[i]).T)
        assert indptr[i + 1] - indptr[i] == np.sum((distances > 0) & (distances <= sensing)), f"robot {i}"
    assert 0 < indptr[-1] < len(p) * len(_POLYGONS)


@pytest.mark.parametrize(("robot_radius", "margin"), [(0.05, 0.0), (0.05, 0.03), (0.0, 0.0), (0.2, 0.1)])
def test_virtual_agents_bisector_lies_the_offset_before_the_surface(rng, robot_radius, margin):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (200, 2))
    indptr, agents = kernels.virtual_agents(p, OBSTACLES, range=1.0, robot_radius=robot_radius, margin=margin)
    offset = robot_radius + margin
    checked = 0
    for i in range(len(p)):
        c = closest_points(p[i])
        d = np.hypot(*(c - p[i]).T)
        sensed = (d > 0) & (d <= 1.0)
        mine = agents[indptr[i] : indptr[i + 1]]
        assert len(mine) == sensed.sum()
        for agent, surface, distance in zip(mine, c[sensed], d[sensed]):
            middle = (p[i] + agent) / 2
            to_c, to_m = surface - p[i], middle - p[i]
            # the bisector's foot is on the segment from p to its closest point...
            assert abs(to_c[0] * to_m[1] - to_c[1] * to_m[0]) <= 1e-9
            assert -1e-9 <= to_m @ to_c <= to_c @ to_c + 1e-9
            if distance - offset >= GAP:  # ...`offset` before the surface
                assert abs(np.hypot(*(surface - middle)) - offset) <= 1e-9
                checked += 1
            else:  # ...or, for a robot already closer, just ahead of it
                assert abs(np.hypot(*to_m) - GAP) <= 1e-9
    assert checked > 20


@pytest.mark.parametrize("which", ["farther-than-offset", "closer-than-offset"])
def test_virtual_agents_keep_voronoi_cells_the_offset_clear_of_obstacles(rng, which):
    # The purpose of SPEC 5.4: clipped by its virtual agents, a robot's cell stays at least
    # robot_radius + margin from every obstacle it senses (the obstacle is convex, so beyond
    # the supporting line through its closest point c), so the centroid never pulls the
    # robot's body into the obstacle.
    offset = 0.08
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (4000, 2))
    distances = np.array([np.hypot(*(closest_points(q) - q).T) for q in p])
    if which == "farther-than-offset":
        keep = np.all(distances > offset, axis=1)
    else:
        keep = np.any((distances > 0.005) & (distances < offset), axis=1)
    keep &= np.all(distances > 0.005, axis=1)  # not inside, nor touching, any obstacle
    p = p[keep][:60]
    assert len(p) == 60
    virtual = kernels.virtual_agents(p, OBSTACLES, range=0.5, robot_radius=0.05, margin=offset - 0.05)
    for cells in (
        kernels.voronoi_cells(p, radius=0.3, virtual=virtual, polygons=True),
        ref_cells(p, 0.3, virtual=virtual),
    ):
        vertices, offsets = cells[2], cells[3]
        for i in range(len(p)):
            c = closest_points(p[i])
            for surface, distance in zip(c, np.hypot(*(c - p[i]).T)):
                if distance > 0.5:
                    continue
                u = (surface - p[i]) / distance
                cell = vertices[offsets[i] : offsets[i + 1]]
                clearance = (surface - cell) @ u
                message = f"robot {i} at {distance:.3f} m: its cell reaches {clearance.min():.3f} m from the surface"
                # A robot already closer than the offset keeps its cell behind itself.
                assert np.all(clearance >= min(offset, distance - GAP) - 1e-9), message


def test_virtual_agents_mirror_at_surface_puts_the_bisector_on_the_obstacle(rng):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (200, 2))
    indptr, agents = kernels.virtual_agents(
        p, OBSTACLES, range=1.0, robot_radius=0.05, margin=0.1, mirror_at_surface=True
    )
    checked = 0
    for i in range(len(p)):
        c = closest_points(p[i])
        d = np.hypot(*(c - p[i]).T)
        sensed = c[(d > 0) & (d <= 1.0)]
        middles = (p[i] + agents[indptr[i] : indptr[i + 1]]) / 2
        assert_allclose(middles, sensed.reshape(-1, 2), atol=1e-9)
        checked += len(sensed)
    assert checked > 20


DEGENERATE = {
    "three collinear": np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
    "four collinear": np.array([[0.0, 0.0], [0.5, 0.0], [1.5, 0.0], [3.0, 0.0]]),
    "two points": np.array([[0.0, 0.0], [1.0, 0.5]]),
    "collinear with repeats": np.array([[0.0, 1.0], [0.0, 1.0], [0.0, 2.0], [0.0, 3.0]]),
}


@pytest.mark.parametrize("name", DEGENERATE)
@pytest.mark.parametrize("position", [0, 1, 2])
def test_virtual_agents_degenerate_obstacle_raises_geometry_error_in_both(name, position):
    # The degenerate obstacle first, in the middle or last among good ones.
    polygons = list(_POLYGONS[:2])
    polygons.insert(position, DEGENERATE[name])
    vertices = np.vstack(polygons)
    offsets = np.concatenate(([0], np.cumsum([len(q) for q in polygons]))).astype(np.int64)
    p = np.array([[1.0, 0.9], [-1.5, 0.0]])
    with pytest.raises(GeometryError, match=f"obstacle {position} is degenerate"):
        kernels.virtual_agents(p, (vertices, offsets))
    with pytest.raises(GeometryError, match=f"obstacle {position} is degenerate"):
        _core.virtual_agents(p, vertices, offsets, range=1.0, offset=0.05)
    with pytest.raises(GeometryError, match=f"obstacle {position} is degenerate"):
        _reference.virtual_agents(p, vertices, offsets, range=1.0, offset=0.05)
    assert issubclass(GeometryError, ValueError)


@pytest.mark.parametrize(
    ("vertices", "offsets"),
    [
        (np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), [0, 3, 3]),  # an obstacle with no vertex
        (np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 2.0]]), [0, 3, 4]),  # one vertex
        (np.array([[0.5, 0.5], [0.5, 0.5], [0.5, 0.5]]), [0, 3]),  # three times the same point
    ],
    ids=["empty", "single-vertex", "coincident-vertices"],
)
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the reference averages an empty obstacle
def test_virtual_agents_obstacle_without_extent_raises_geometry_error_not_panic(vertices, offsets):
    # The reference raises GeometryError for these; the Rust path must too (no PanicException).
    offsets = np.array(offsets, dtype=np.int64)
    p = np.array([[3.0, 3.0]])
    with pytest.raises(GeometryError, match="degenerate"):
        _reference.virtual_agents(p, vertices, offsets, range=1.0, offset=0.05)
    with pytest.raises(GeometryError, match="degenerate"):
        _core.virtual_agents(p, vertices, offsets, range=1.0, offset=0.05)
    with pytest.raises(GeometryError, match="degenerate"):
        kernels.virtual_agents(p, (vertices, offsets))


@pytest.mark.parametrize(
    "vertices",
    [
        np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 1e-6]]),  # a 1 m sliver, 1 um high: area 5e-7 m^2
        np.array([[0.0, 0.0], [1e-6, 0.0], [0.0, 1e-6]]),  # a 1 um right triangle: area 5e-13 m^2
    ],
    ids=["sliver", "tiny"],
)
def test_virtual_agents_rust_and_reference_agree_on_degenerate_obstacles(vertices):
    # Whether an obstacle "encloses no area" must not depend on the implementation.
    p = np.array([[0.5, -0.5]])
    offsets = np.array([0, 3], dtype=np.int64)

    def outcome(call):
        try:
            indptr, points = call()
        except GeometryError:
            return "GeometryError"
        return (indptr.tolist(), np.round(points, 9).tolist())

    rust = outcome(lambda: _core.virtual_agents(p, vertices, offsets, range=1.0, offset=0.05))
    reference = outcome(lambda: _reference.virtual_agents(p, vertices, offsets, range=1.0, offset=0.05))
    assert rust == reference


def test_virtual_agents_obstacle_is_the_convex_hull_of_its_vertices(rng):
    # kernels.virtual_agents documents obstacle k as the convex hull of its vertices: interior
    # points and any vertex order give the same agents as the hull itself, in both paths.
    hull = _rectangle(*RECTANGLES[0], clockwise=False)
    cloud = np.vstack((hull, [[0.55, 0.4], [0.35, 0.25], [0.75, 0.55]]))[rng.permutation(7)]
    p = np.array([[0.55, 1.0], [0.0, 0.4], [1.2, 0.3], [0.55, -0.2], [0.2, 0.1]])
    offsets = np.array([0, 7], dtype=np.int64)
    want = _reference.virtual_agents(p, hull, np.array([0, 4], dtype=np.int64), range=1.0, offset=0.05)
    rust = _core.virtual_agents(p, cloud, offsets, range=1.0, offset=0.05)
    assert_array_equal(rust[0], want[0])
    assert_allclose(rust[1], want[1], atol=1e-9)
    reference = _reference.virtual_agents(p, cloud, offsets, range=1.0, offset=0.05)
    assert_array_equal(reference[0], want[0])
    assert_allclose(reference[1], want[1], atol=1e-9)  # fails: the reference sorts the points by angle, no hull


# -- 6. error mapping of dream._core -------------------------------------------------------------------
P = np.zeros((3, 2))
P[:, 0] = [0.0, 0.5, 1.0]
GRID = _reference.candidate_grid(V_MAX, 20, 10)
CSR = (np.array([0, 1, 2, 2], dtype=np.int64), np.array([1, 0], dtype=np.int64))
HRVO_KW = dict(radius=1.0, safety=SAFETY, v_max=V_MAX, bounds=None, candidates=GRID, include_preferred=True)
PLANNER_KW = dict(safety=SAFETY, v_max=V_MAX, bounds=None, include_preferred=True)


def with_value(array, value, index=(1, 0)):
    out = np.array(array, dtype=float)
    out[index] = value
    return out


def call_neighbours(positions=P, radius=1.0, headings=None, direction=0.0, fov=TAU, max_neighbours=None, rows=None):
    return lambda: _core.neighbours(positions, radius, headings, direction, fov, max_neighbours, rows)


def call_hrvo(positions=P, velocities=P, preferred=P, indptr=None, indices=None, **kw):
    return lambda: _core.hrvo(positions, velocities, preferred, indptr, indices, **{**HRVO_KW, **kw})


def call_cells(positions=P, **kw):
    return lambda: _core.voronoi_cells(positions, **{**dict(radius=0.5, bounds=ARENA), **kw})


def call_agents(positions=P, vertices=OBSTACLES[0], offsets=OBSTACLES[1], range=1.0, offset=0.05):  # noqa: A002
    return lambda: _core.virtual_agents(positions, vertices, offsets, range=range, offset=offset)


def planner():
    return _core.HrvoPlanner(GRID, safety=SAFETY, v_max=V_MAX, bounds=ARENA, include_preferred=True)


def call_planner(detections=None, velocity=None, preferred=None, position=None):
    detections = np.zeros((1, 4)) + 0.5 if detections is None else detections
    velocity, preferred, position = (np.zeros(2) if v is None else v for v in (velocity, preferred, position))
    return lambda: planner().velocity(detections, velocity, preferred, position)


BAD_ARRAYS = {
    "(n, 3)": np.zeros((3, 3)),
    "1-D": np.zeros(6),
    "3-D": np.zeros((3, 2, 1)),
    "float32": P.astype(np.float32),
    "int64": P.astype(np.int64),
    "list": P.tolist(),
}
NON_FINITE = [np.nan, np.inf, -np.inf]


@pytest.mark.parametrize("bad", BAD_ARRAYS.values(), ids=BAD_ARRAYS.keys())
@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda bad: call_neighbours(positions=bad), "positions"),
        (lambda bad: call_hrvo(positions=bad), "positions"),
        (lambda bad: call_hrvo(velocities=bad), "velocities"),
        (lambda bad: call_hrvo(preferred=bad), "preferred"),
        (lambda bad: call_hrvo(candidates=bad), "candidates"),
        (lambda bad: call_cells(positions=bad), "positions"),
        (lambda bad: call_cells(virtual_indptr=np.array([0, 0, 0, 3]), virtual_points=bad), "virtual_points"),
        (lambda bad: call_agents(positions=bad), "positions"),
        (lambda bad: call_agents(vertices=bad), "vertices"),
    ],
)
def test_core_rejects_wrong_shape_or_dtype_naming_the_argument(make, name, bad):
    with pytest.raises(ValueError, match=f"`{name}`"):
        make(bad)()


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (call_neighbours(headings=np.zeros(2)), "headings"),
        (call_neighbours(headings=np.zeros((3, 1))), "headings"),
        (call_neighbours(headings=np.zeros(3, dtype=np.float32)), "headings"),
        (call_hrvo(indptr=np.array([0.0, 1.0, 2.0, 2.0]), indices=CSR[1]), "indptr"),
        (call_hrvo(indptr=CSR[0].astype(np.int32), indices=CSR[1]), "indptr"),
        (call_hrvo(indptr=CSR[0], indices=CSR[1].astype(np.float64)), "indices"),
        (call_hrvo(indptr=CSR[0][:, None], indices=CSR[1]), "indptr"),
        (call_cells(virtual_indptr=np.array([0.0, 0, 0, 0]), virtual_points=np.zeros((0, 2))), "virtual_indptr"),
        (call_agents(offsets=np.array([0.0, 4.0])), "offsets"),
        (call_neighbours(rows=np.ones(2, dtype=bool)), "rows"),
        (lambda: _core.far_from(P, P, 0.1, np.array([0, 3]), np.array([0, 1, 3])), "others_offsets"),
        (lambda: _core.far_from(P, P, 0.1, np.array([0, 2]), np.array([0, 3])), "points_offsets"),
        (lambda: _core.far_from(P, P, 0.1, np.array([0.0, 3.0])), "points_offsets"),
        (lambda: _core.far_from(P.T.copy(), P, 0.1), "points"),
        (call_neighbours(rows=np.ones(3)), "rows"),
        (call_planner(detections=np.zeros((2, 3))), "detections"),
        (call_planner(detections=np.zeros(4)), "detections"),
        (call_planner(velocity=np.zeros(3)), "velocity"),
        (call_planner(preferred=np.zeros((1, 2))), "preferred"),
        (call_planner(position=np.zeros(2, dtype=np.float32)), "position"),
        (lambda: _core.HrvoPlanner(GRID.T.copy(), **PLANNER_KW), "candidates"),
    ],
)
def test_core_rejects_bad_auxiliary_arrays_naming_the_argument(call, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        call()


@pytest.mark.parametrize("bad", NON_FINITE)
@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda bad: call_neighbours(positions=with_value(P, bad)), "positions"),
        (lambda bad: call_neighbours(headings=with_value(np.zeros(3), bad, 2)), "headings"),
        (lambda bad: lambda: _core.far_from(with_value(P, bad), P, 0.1), "points"),
        (lambda bad: lambda: _core.far_from(P, with_value(P, bad), 0.1), "others"),
        (lambda bad: call_hrvo(positions=with_value(P, bad)), "positions"),
        (lambda bad: call_hrvo(positions=with_value(P, bad), indptr=CSR[0], indices=CSR[1]), "positions"),
        (lambda bad: call_hrvo(velocities=with_value(P, bad, (2, 1))), "velocities"),
        (lambda bad: call_hrvo(preferred=with_value(P, bad)), "preferred"),
        (lambda bad: call_hrvo(candidates=with_value(GRID, bad, (5, 1))), "candidates"),
        (lambda bad: call_cells(positions=with_value(P, bad)), "positions"),
        (
            lambda bad: call_cells(virtual_indptr=np.array([0, 1, 1, 1]), virtual_points=np.array([[bad, 0.0]])),
            "virtual",
        ),
        (lambda bad: call_agents(positions=with_value(P, bad)), "positions"),
        (lambda bad: call_agents(vertices=with_value(OBSTACLES[0], bad, (4, 1))), "obstacle vertices"),
        (lambda bad: call_planner(detections=with_value(np.full((3, 4), 0.5), bad, (2, 3))), "detections"),
        (lambda bad: call_planner(velocity=with_value(np.zeros(2), bad, 0)), "velocity"),
        (lambda bad: call_planner(preferred=with_value(np.zeros(2), bad, 1)), "preferred"),
        (lambda bad: call_planner(position=with_value(np.zeros(2), bad, 0)), "position"),
    ],
)
def test_core_rejects_non_finite_values_naming_the_argument(make, name, bad):
    with pytest.raises(ValueError, match=f"`{name}`.*non-finite"):
        make(bad)()


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (call_neighbours(radius=-0.5), "radius"),
        (call_neighbours(radius=np.nan), "radius"),
        (call_neighbours(radius=np.inf), "radius"),
        (call_neighbours(headings=np.zeros(3), direction=np.nan), "direction"),
        (call_neighbours(headings=np.zeros(3), direction=np.inf), "direction"),
        (call_neighbours(headings=np.zeros(3), fov=-1.0), "fov"),
        (call_neighbours(headings=np.zeros(3), fov=np.nan), "fov"),
        (call_hrvo(radius=-1.0), "radius"),
        (call_hrvo(radius=np.nan), "radius"),
        (call_hrvo(safety=-0.1), "safety"),
        (call_hrvo(safety=np.inf), "safety"),
        (call_hrvo(v_max=-0.2), "v_max"),
        (call_hrvo(v_max=np.nan), "v_max"),
        (call_cells(radius=0.0), "radius"),
        (call_cells(radius=-1.0), "radius"),
        (call_cells(radius=np.inf), "radius"),
        (call_cells(resolution=2), "resolution"),
        (call_cells(resolution=0), "resolution"),
        (call_agents(range=-1.0), "range"),
        (lambda: _core.far_from(P, P, -0.1), "distance"),
        (lambda: _core.far_from(P, P, np.nan), "distance"),
        (call_agents(range=np.nan), "range"),
        (call_agents(offset=-0.05), "offset"),
        (lambda: _core.HrvoPlanner(GRID, safety=-1.0, v_max=V_MAX, bounds=None, include_preferred=True), "safety"),
        (lambda: _core.HrvoPlanner(GRID, safety=SAFETY, v_max=np.nan, bounds=None, include_preferred=True), "v_max"),
    ],
)
def test_core_rejects_invalid_parameters_naming_them(call, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        call()


@pytest.mark.parametrize(
    "call",
    [
        call_neighbours(max_neighbours=-1),  # pyo3 raises OverflowError for a negative usize
        call_cells(resolution=-1),
    ],
    ids=["neighbours-max_neighbours", "voronoi_cells-resolution"],
)
def test_core_rejects_negative_counts_with_value_error(call):
    # SPEC 5 / STYLE: invalid input is a ValueError; OverflowError is not one.
    with pytest.raises(ValueError):
        call()


def test_core_voronoi_cells_rejects_absurd_resolution_without_panic():
    # 2**62 vertices cannot be allocated: that is bad input (ValueError), not a PanicException.
    with pytest.raises(ValueError, match="resolution"):
        call_cells(resolution=2**62)()


BAD_BOUNDS = [
    (1.0, 1.0, -1.0, 1.0),
    (1.0, -1.0, -1.0, 1.0),
    (-1.0, 1.0, 2.0, 1.0),
    (-1.0, np.nan, -1.0, 1.0),
    (-np.inf, 1.0, -1.0, 1.0),
]


@pytest.mark.parametrize("bounds", BAD_BOUNDS)
@pytest.mark.parametrize(
    "make",
    [
        lambda b: call_hrvo(bounds=b),
        lambda b: call_cells(bounds=b),
        lambda b: lambda: _core.HrvoPlanner(GRID, safety=SAFETY, v_max=V_MAX, bounds=b, include_preferred=True),
    ],
    ids=["hrvo", "voronoi_cells", "HrvoPlanner"],
)
def test_core_rejects_invalid_bounds(make, bounds):
    with pytest.raises(ValueError, match="bounds must satisfy xmin < xmax"):
        make(bounds)()


@pytest.mark.parametrize(
    ("indptr", "indices", "reason"),
    [
        ([0, 1, 2], [1, 0], r"indptr has 3 entries, expected 4"),  # wrong length
        ([0, 1, 2, 2, 2], [1, 0], r"indptr has 5 entries"),
        ([0, 2, 1, 2], [1, 0], r"indptr decreases at row 1"),  # decreasing
        ([1, 1, 2, 2], [1, 0], r"indptr must run from 0 to len\(indices\) = 2"),  # does not start at 0
        ([0, 1, 2, 3], [1, 0], r"indptr must run from 0 to len\(indices\) = 2"),  # does not end at len(indices)
        ([0, 1, 2, 2], [1, 3], r"index 3 is not a robot id"),  # out of range
        ([0, 1, 2, 2], [-1, 0], r"index -1 is not a robot id"),  # negative index
    ],
)
def test_core_hrvo_rejects_invalid_csr(indptr, indices, reason):
    call = call_hrvo(indptr=np.array(indptr, dtype=np.int64), indices=np.array(indices, dtype=np.int64))
    with pytest.raises(ValueError, match=r"`neighbours` is not a valid CSR of 3 rows: " + reason):
        call()


@pytest.mark.parametrize(
    ("indptr", "points"),
    [
        ([0, 1, 1], np.zeros((1, 2))),  # wrong length
        ([0, 1, 0, 1], np.zeros((1, 2))),  # decreasing
        ([0, 1, 1, 2], np.zeros((1, 2))),  # past the end of points
        ([1, 1, 1, 1], np.zeros((1, 2))),  # not from 0
    ],
)
def test_core_voronoi_cells_rejects_invalid_virtual_csr(indptr, points):
    with pytest.raises(ValueError, match="virtual"):
        call_cells(virtual_indptr=np.array(indptr, dtype=np.int64), virtual_points=points)()


@pytest.mark.parametrize("offsets", [[0], [0, 4, 8, 12, 16], [0, 4, 2, 12, 15], [1, 4, 8, 12, 15], []])
def test_core_virtual_agents_rejects_invalid_offsets(offsets):
    with pytest.raises(ValueError, match="offsets"):
        call_agents(offsets=np.array(offsets, dtype=np.int64))()


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (call_hrvo(velocities=np.zeros((2, 2))), "velocities"),
        (call_hrvo(preferred=np.zeros((4, 2))), "preferred"),
        (call_neighbours(headings=np.zeros(4)), "headings"),
    ],
)
def test_core_rejects_mismatched_lengths(call, name):
    with pytest.raises(ValueError, match=f"`{name}`"):
        call()


# -- 6b. memory layouts -------------------------------------------------------------------------------
@pytest.mark.parametrize("layout", range(4), ids=LAYOUT_IDS)
def test_core_kernels_give_the_same_results_for_any_memory_layout(rng, layout):
    p, v, pref = swarm(rng, 80, spread=1.5)
    headings = rng.uniform(-np.pi, np.pi, 80)
    lp, lv, lpref, lgrid = (layouts(a)[layout] for a in (p, v, pref, GRID))
    lheadings = np.column_stack((headings, headings))[:, 0] if layout else headings  # 1-D strided
    # neighbours
    assert_csr_equal(core_neighbours(lp, 0.4), core_neighbours(p, 0.4))
    assert_csr_equal(core_neighbours(lp, 0.4, lheadings, 1.2, math.pi), core_neighbours(p, 0.4, headings, 1.2, math.pi))
    # hrvo, with strided int64 CSR arrays as well
    indptr, indices, _ = _reference.neighbours(p, 0.5)
    wide = np.zeros(2 * len(indices), dtype=np.int64)
    wide[::2] = indices
    strided_indices = wide[::2] if layout >= 2 else indices
    got = _core.hrvo(lp, lv, lpref, indptr, strided_indices, **{**HRVO_KW, "candidates": lgrid, "bounds": ARENA})
    assert_array_equal(got, core_hrvo(p, v, pref, (indptr, indices), bounds=ARENA))
    assert_array_equal(got, ref_hrvo(p, v, pref, (indptr, indices), bounds=ARENA))
    # voronoi cells, with virtual points in the same layout
    vi, vp, _ = virtual_around(rng, p)
    lvp = layouts(vp)[layout] if len(vp) else vp
    got_cells = core_cells(lp, 0.4, virtual=(vi, lvp))
    for a, b in zip(got_cells, core_cells(p, 0.4, virtual=(vi, vp))):
        assert_array_equal(a, b)
    # virtual agents
    verts = layouts(OBSTACLES[0])[layout]
    got_agents = _core.virtual_agents(lp, verts, OBSTACLES[1], range=1.0, offset=0.05)
    for a, b in zip(got_agents, _core.virtual_agents(p, *OBSTACLES, range=1.0, offset=0.05)):
        assert_array_equal(a, b)


# -- 7. determinism under rayon ---------------------------------------------------------------------
def test_hrvo_is_deterministic_across_calls(rng):
    p, v, pref = swarm(rng, 3000, spread=8.0)
    first = core_hrvo(p, v, pref, radius=0.6, bounds=(-8.0, 8.0, -8.0, 8.0))
    for _ in range(2):
        assert_array_equal(core_hrvo(p, v, pref, radius=0.6, bounds=(-8.0, 8.0, -8.0, 8.0)), first)
    # and on a sample of robots it is the reference's answer
    sample = np.arange(0, 3000, 97)
    csr = _reference.neighbours(p, 0.6)[:2]
    assert_array_equal(core_hrvo(p, v, pref, csr, bounds=(-8.0, 8.0, -8.0, 8.0))[sample], first[sample])


def test_neighbours_is_deterministic_across_calls(rng):
    p = rng.uniform(-10.0, 10.0, (5000, 2))
    headings = rng.uniform(-np.pi, np.pi, 5000)
    for kw in (dict(), dict(headings=headings, direction=0.3, fov=2.0, max_neighbours=4)):
        first = core_neighbours(p, 0.5, **kw)
        assert len(first[1]) > 1000
        for _ in range(2):
            assert_csr_equal(core_neighbours(p, 0.5, **kw), first)
    assert_csr_equal(core_neighbours(p, 0.5), ref_neighbours(p, 0.5))


@pytest.mark.parametrize("shift", [0.0, 0.5, 1024.0])
def test_voronoi_cells_break_distance_ties_in_the_given_order_as_the_reference(rng, shift):
    # Points on a lattice around each robot, all coordinates dyadic so that the squared distances
    # tie exactly: rings of 4 or 8 equal distances (12 at 3-4-5), over more than the 32 agents
    # sorted at a time, in a shuffled order.
    k = np.arange(-6, 7)
    lattice = np.column_stack([g.ravel() for g in np.meshgrid(k, k)]).astype(float) / 16
    lattice = lattice[np.any(lattice != 0.0, axis=1)]
    p = shift + rng.integers(-32, 32, (3, 2)) / 64
    points = np.vstack([centre + rng.permutation(lattice) for centre in p])
    indptr = np.arange(4) * len(lattice)
    bounds = (shift - 1.6, shift + 1.6, shift - 1.0, shift + 1.0)
    kw = dict(radius=1.0, bounds=bounds, virtual_indptr=indptr, virtual_points=points, neighbours=False)
    for a, b in zip(_core.voronoi_cells(p, **kw), _reference.voronoi_cells(p, **kw), strict=True):
        assert_array_equal(a, b)


def test_voronoi_cells_are_deterministic_across_calls(rng):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (2000, 2))
    first = core_cells(p, 0.1)
    for a, b in zip(core_cells(p, 0.1), first):
        assert_array_equal(a, b)


@pytest.mark.parametrize(("offset", "scale"), [(0.0, 1.0), (1e6, 1.0), (-3e9, 1.0), (0.0, 1e-40), (2e-39, 1e-40)])
def test_voronoi_cells_each_clipped_by_its_own_points_match_reference_bit_for_bit(rng, offset, scale):
    # Robots that each heard a crowd (up to 300 points, most too far to cut the cell, which the
    # kernel skips), far from the origin or tiny: cells equal the reference's to the bit.
    n = 40
    p = offset + scale * rng.uniform(-1.5, 1.5, (n, 2))
    counts = rng.integers(0, 300, n)
    indptr = np.concatenate(([0], np.cumsum(counts)))
    points = np.repeat(p, counts, axis=0) + scale * rng.uniform(-1.0, 1.0, (indptr[-1], 2))
    bounds = tuple(offset + scale * np.array([-1.6, 1.6, -1.0, 1.0]))
    kw = dict(radius=scale, bounds=bounds, virtual_indptr=indptr, virtual_points=points, neighbours=False)
    got, want = _core.voronoi_cells(p, **kw), _reference.voronoi_cells(p, **kw)
    for a, b in zip(got, want, strict=True):
        assert_array_equal(a, b)
    # Alone means alone: the robots (1.5 m apart at most, within 2 radius) would clip each other.
    assert not np.array_equal(got[0], _core.voronoi_cells(p, **{**kw, "neighbours": True})[0])
