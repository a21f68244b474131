"""Neighbourhood reductions and HRVO on a robot's own detections: the Rust kernels against their
NumPy reference on random ragged rows (empty rows, NaN entries, one row, many rows), and bad
input named in a ValueError."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from dream import _core, _reference, kernels
from dream._reference.draws import delivered
from dream.kernels import _dispatch
from dream.kernels._hrvo import _bounded, _grid

OPS = ("sum", "mean", "min", "max")


def ragged(rng, rows, width, nan=0.0):
    counts = rng.integers(0, 6, rows)
    counts[rng.random(rows) < 0.2] = 0  # empty rows
    offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    values = rng.normal(0, 3, (offsets[-1], width))
    values[rng.random(values.shape) < nan] = np.nan
    return values, offsets


@pytest.mark.parametrize("rows", [0, 1, 7, 5000])
@pytest.mark.parametrize("op", OPS)
def test_segment_reduce_matches_the_reference(rng, rows, op):
    for width, nan in ((1, 0.0), (3, 0.0), (2, 0.3)):
        values, offsets = ragged(rng, rows, width, nan)
        got = _core.segment_reduce(values, offsets, op)
        want = _reference.segment_reduce(values, offsets, op)
        assert got.shape == want.shape == (rows, width)
        assert_allclose(got, want, rtol=1e-12, atol=1e-12, equal_nan=True)


@pytest.mark.parametrize("rows", [0, 1, 7, 5000])
@pytest.mark.parametrize("op", OPS)
def test_segment_reduce_through_an_index_is_the_gathered_reduce(rng, rows, op):
    """Entry e taken from row index[e] of a per-robot array: bit for bit the reduce of the
    gathered copy, on both paths."""
    source = rng.normal(0, 3, (50, 2))
    source[rng.random(source.shape) < 0.1] = np.nan
    _, offsets = ragged(rng, rows, 1)
    index = rng.integers(0, len(source), offsets[-1])
    want = _reference.segment_reduce(source[index], offsets, op)
    assert_array_equal(_core.segment_reduce(source, offsets, op, index), want)
    assert_array_equal(_reference.segment_reduce(source, offsets, op, index), want)
    assert_array_equal(kernels.segment_reduce(source[:, 1], offsets, op, index), want[:, 1])


def test_segment_reduce_empty_rows_and_nan():
    values = np.array([1.0, np.nan, 3.0, 4.0])
    offsets = [0, 0, 3, 4]
    assert_array_equal(kernels.segment_reduce(values, offsets, "sum")[[0, 2]], [0.0, 4.0])
    assert math.isnan(kernels.segment_reduce(values, offsets, "sum")[1])  # the sum carries NaN
    assert_array_equal(kernels.segment_reduce(values, offsets, "min")[1:], [1.0, 4.0])  # extremes skip it
    assert_array_equal(kernels.segment_reduce(values, offsets, "max")[1:], [3.0, 4.0])
    assert np.isnan(kernels.segment_reduce(values, offsets, "mean")[0])  # nothing to average
    assert kernels.segment_reduce(values[:, None], offsets, "max").shape == (3, 1)


@pytest.mark.parametrize("rows", [0, 1, 9, 5000])
def test_segment_any_and_nearest_match_the_reference(rng, rows):
    values, offsets = ragged(rng, rows, 1, nan=0.2)
    keys = values[:, 0]
    flags = rng.random(len(keys)) < 0.2
    assert_array_equal(_core.segment_any(flags, offsets), _reference.segment_any(flags, offsets))
    nearest = _core.segment_nearest(keys, offsets)
    assert_array_equal(nearest, _reference.segment_nearest(keys, offsets))
    for r in range(rows):  # the smallest non-NaN key of its row, or -1
        row = keys[offsets[r] : offsets[r + 1]]
        if np.isnan(row).all():
            assert nearest[r] == -1
        else:
            assert offsets[r] <= nearest[r] < offsets[r + 1] and keys[nearest[r]] == np.nanmin(row)


def test_nearest_takes_the_first_of_equals():
    assert_array_equal(kernels.segment_nearest([2.0, 1.0, 1.0, np.inf], [0, 3, 4]), [1, 3])


@pytest.mark.parametrize("rows", [0, 1, 9, 5000])
@pytest.mark.parametrize("k", [0, 1, 3, 8])
def test_segment_nearest_k_matches_the_reference_and_a_stable_sort(rng, rows, k):
    counts = rng.integers(0, 20, rows)  # 5,000 rows: ~47,500 entries, picked on every core
    offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    keys = rng.integers(0, 5, offsets[-1]).astype(float)  # many ties: the first of equals comes first
    keys[rng.random(len(keys)) < 0.2] = np.nan
    got = _core.segment_nearest(keys, offsets, k)
    assert got.shape == (rows, k)
    assert_array_equal(got, _reference.segment_nearest(keys, offsets, k))
    for r in range(rows):
        row = keys[offsets[r] : offsets[r + 1]]
        kept = np.flatnonzero(~np.isnan(row))
        want = offsets[r] + kept[np.argsort(row[kept], kind="stable")][:k]
        assert_array_equal(got[r], np.concatenate((want, np.full(k - len(want), -1))))
    if k:
        assert_array_equal(got[:, 0], _core.segment_nearest(keys, offsets))  # its first slot: the nearest


@pytest.mark.parametrize("rows", [0, 1, 9, 5000])
@pytest.mark.parametrize("k", [0, 1, 4])
@pytest.mark.parametrize("board", [False, True])
def test_segment_nearest_to_matches_the_reference_and_the_keys(rng, rows, k, board):
    counts = rng.integers(0, 20, rows)
    offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    origins = rng.uniform(-3, 3, (rows, 2))
    # Points on a coarse lattice: equal distances are common, the first of equals comes first.
    points = rng.integers(-6, 7, (300 if board else offsets[-1], 2)) * 0.5
    points[rng.random(len(points)) < 0.1, 0] = np.nan
    index = rng.integers(0, len(points), offsets[-1]) if board else None
    got = _core.segment_nearest_to(points, offsets, origins, k, index)
    assert got.shape == (rows, k)
    assert_array_equal(got, _reference.segment_nearest_to(points, offsets, origins, k, index))
    at = points if index is None else points[index]
    d = at - np.repeat(origins, counts, axis=0)
    assert_array_equal(got, _core.segment_nearest(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1], offsets, k))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: kernels.segment_reduce([1.0, 2.0], [0, 3], "sum"), "`offsets` must be offsets"),
        (lambda: kernels.segment_reduce([1.0, 2.0], [0, 2, 1, 2], "sum"), "`offsets` must be offsets"),
        (lambda: kernels.segment_reduce([1.0], [0, 1], "median"), "`op` must be one of sum, mean, min, max"),
        (lambda: kernels.segment_any([True], [0.0, 1.0]), "integer offsets"),
        (lambda: kernels.segment_nearest(np.zeros((2, 2)), [0, 2]), "`keys` must have shape (k,)"),
        (lambda: kernels.segment_nearest([1.0, 2.0], [0, 2], -1), "`k` must be a whole number >= 0, got -1"),
        (lambda: kernels.segment_nearest([1.0, 2.0], [0, 2], 1.5), "`k` must be a whole number >= 0, got 1.5"),
        (lambda: _core.segment_reduce(np.zeros((2, 1)), np.array([0, 3]), "sum"), "not a valid CSR"),
        (
            lambda: kernels.segment_reduce([1.0, 2.0], [0, 1], "sum", [2]),
            "`index` holds 2, which is not a row of the 2",
        ),
        (lambda: kernels.segment_reduce([1.0, 2.0], [0, 1], "sum", [0.5]), "`index` must be integer rows"),
        (lambda: _core.segment_reduce(np.zeros((2, 1)), np.array([0, 1]), "sum", np.array([-1])), "`index` holds -1"),
        (lambda: _core.segment_reduce(np.zeros((2, 1)), np.array([0, 2]), "avg"), "`op` must be"),
        (lambda: kernels.segment_nearest_to(np.zeros((2, 3)), [0, 2], np.zeros((1, 2)), 1), "`points` must have"),
        (lambda: kernels.segment_nearest_to(np.zeros((2, 2)), [0, 2], np.zeros((2, 2)), 1), "`origins` must have"),
        (lambda: kernels.segment_nearest_to(np.zeros((2, 2)), [0, 1], np.zeros((1, 2)), 1, [2]), "`index` holds 2"),
        (lambda: kernels.segment_nearest_to(np.zeros((2, 2)), [0, 2], np.zeros((1, 2)), -1), "`k` must be"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        call()


def detections_scene(rng, rows):
    """Random robots deciding now, each with its own detections [distance, angle, vx, vy]."""
    counts = rng.integers(0, 8, rows)
    offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    k = offsets[-1]
    seen = np.column_stack(
        (rng.uniform(0, 0.8, k), rng.uniform(-np.pi, np.pi, k), rng.normal(0, 0.1, k), rng.normal(0, 0.1, k))
    )
    seen[rng.random(k) < 0.05, 0] = 0.0  # robots at the same spot
    positions = rng.uniform(-1.5, 1.5, (rows, 2))
    return rng.normal(0, 0.1, (rows, 2)), rng.normal(0, 0.3, (rows, 2)), positions, offsets, seen


@pytest.mark.parametrize("rows", [0, 1, 30, 5000])
def test_hrvo_rows_is_the_planner_row_by_row(rng, rows):
    velocities, preferred, positions, offsets, seen = detections_scene(rng, rows)
    options = dict(safety=0.24, v_max=0.2, bounds=(-1.6, 1.6, -1.0, 1.0), include_preferred=True)
    grid = _grid(0.2, 20, 10)
    got = _core.hrvo_rows(velocities, preferred, positions, offsets, seen, candidates=grid, **options)
    want = _reference.hrvo_rows(velocities, preferred, positions, offsets, seen, candidates=grid, **options)
    assert_allclose(got, want, atol=1e-12)
    columns = tuple(seen.T.copy())  # a neighbourhood's four columns, unstacked: the same answer
    assert_array_equal(
        _core.hrvo_rows(velocities, preferred, positions, offsets, columns, candidates=grid, **options), got
    )
    assert_array_equal(kernels.hrvo_rows(velocities, preferred, positions, offsets, columns, **options), got)
    # A movement sensor's neighbourhood: distances and offsets, the direction their quotient (no
    # trigonometry: the same bits on both paths), on both paths and in both forms.
    towards = seen[:, 1] + np.pi
    sensed = np.column_stack((seen[:, 0], seen[:, 0] * np.cos(towards), seen[:, 0] * np.sin(towards), seen[:, 2:]))
    want = _reference.hrvo_rows(
        velocities, preferred, positions, offsets, sensed, candidates=grid, relative=True, **options
    )
    for path in (_core, _reference):
        for form in (sensed, tuple(sensed.T.copy()), np.asfortranarray(sensed)):
            relative = path.hrvo_rows(
                velocities, preferred, positions, offsets, form, candidates=grid, relative=True, **options
            )
            assert_array_equal(relative, want)
    assert_array_equal(
        kernels.hrvo_rows(velocities, preferred, positions, offsets, sensed, relative=True, **options), want
    )
    # The same robots seen in both forms, their directions to an ulp (the polar form's at distance 0
    # along its angle, the offsets' along (1, 0): so the angle there too).
    polar = seen.copy()
    polar[seen[:, 0] == 0.0, 1] = -np.pi
    steered = _core.hrvo_rows(velocities, preferred, positions, offsets, polar, candidates=grid, **options)
    assert_allclose(want, steered, atol=1e-12)
    planner = _core.HrvoPlanner(grid, **options)
    for r in range(0, rows, max(rows // 40, 1)):  # exactly the per-robot planner's answer
        row = seen[offsets[r] : offsets[r + 1]]
        assert_array_equal(got[r], planner.velocity(row, velocities[r], preferred[r], positions[r]))


@pytest.mark.parametrize("rows", [1, 30, 5000])
def test_hrvo_rows_steers_only_the_rows_flagged(rng, rows):
    velocities, preferred, positions, offsets, seen = detections_scene(rng, rows)
    preferred[rng.random(rows) < 0.1] *= 1e7  # huge wishes: those not steered are kept as given
    steer = rng.random(rows) < 0.6
    options = dict(safety=0.24, v_max=0.2, bounds=(-1.6, 1.6, -1.0, 1.0), include_preferred=True)
    every = kernels.hrvo_rows(velocities, preferred, positions, offsets, seen, **options)
    grid = _grid(0.2, 20, 10)
    for path in (_core, _reference):
        flagged = path.hrvo_rows(
            velocities, _bounded(preferred), positions, offsets, seen, candidates=grid, steer=steer, **options
        )
        assert_array_equal(flagged[steer], every[steer])
    for core in (_core, None):
        _dispatch._core, saved = core, _dispatch._core
        try:
            got = kernels.hrvo_rows(velocities, preferred, positions, offsets, seen, steer=steer, **options)
        finally:
            _dispatch._core = saved
        assert_array_equal(got[steer], every[steer])
        assert_array_equal(got[~steer], preferred[~steer])
    with pytest.raises(ValueError, match="`steer`"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets, seen, steer=steer[1:], **options)
    with pytest.raises(ValueError, match="`steer`"):
        _core.hrvo_rows(velocities, preferred, positions, offsets, seen, candidates=grid, steer=steer[1:], **options)


def test_hrvo_rows_bad_input_is_named(rng):
    velocities, preferred, positions, offsets, seen = detections_scene(rng, 3)
    options = dict(safety=0.2, v_max=0.2, bounds=None, candidates=_grid(0.2, 20, 10), include_preferred=True)

    def core(detections, **more):
        return _core.hrvo_rows(velocities, preferred, positions, offsets, detections, **options, **more)

    with pytest.raises(ValueError, match="`offsets`"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets[:-1], seen)
    bad = seen.copy()
    bad[0, 0] = -0.1
    with pytest.raises(ValueError, match="detection distance"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets, bad)
    with pytest.raises(ValueError, match="detection distance"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets, tuple(bad.T))
    with pytest.raises(ValueError, match=r"columns must be \(distance, angle, vx, vy\), got 3"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets, tuple(bad.T[:3]))
    with pytest.raises(ValueError, match=r"columns must be \(distance, dx, dy, vx, vy\), got 4"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets, tuple(seen.T), relative=True)
    with pytest.raises(ValueError, match="columns must be"):
        core(tuple(seen.T), relative=True)
    sensed = np.column_stack((seen[:, :1], np.zeros((len(seen), 2)), seen[:, 2:]))
    sensed[0, 1] = np.nan
    with pytest.raises(ValueError, match="`detections` contains a non-finite value"):
        kernels.hrvo_rows(velocities, preferred, positions, offsets, sensed, relative=True)
    with pytest.raises(ValueError, match="columns must be"):
        core(tuple(bad.T[:3]))
    with pytest.raises(ValueError, match="detection distance"):
        core(bad)


def perceive_scene(rng, n):
    positions = rng.uniform(-2, 2, (n, 2))
    positions[1::7] = positions[::7][: len(positions[1::7])]  # some robots on the same spot
    return positions, rng.uniform(-np.pi, np.pi, n), rng.random(n) < 0.7


@pytest.mark.parametrize("n", [1, 2, 40, 3000])
@pytest.mark.parametrize("fov", [2 * np.pi, 1.5])
@pytest.mark.parametrize("everyone", [False, True], ids=["some talk", "all talk"])
def test_perceive_matches_the_reference(rng, n, fov, everyone):
    positions, headings, talking = perceive_scene(rng, n)
    talking |= everyone  # all talking over the longest range: the query's rows are what is heard
    rows = np.sort(rng.choice(n, size=max(n // 2, 1), replace=False))
    carried = [rng.normal(size=n), rng.normal(size=n)]  # the velocities a sensor reports, say
    options = dict(sight=(0.4, fov, 0.3), radio_range=0.7, talking=talking, carried=carried)
    got = _core.perceive(positions, headings, rows, **options)
    want = _reference.perceive(positions, headings, rows, **options)
    for mine, theirs in zip(got, want, strict=True):
        assert len(mine) == len(theirs)
        for k, (a, b) in enumerate(zip(mine, theirs)):
            if k == 3:  # bearings: Rust's atan2 and NumPy's, to an ulp
                assert_allclose(a, b, rtol=0, atol=1e-15)
            else:  # offsets, ids, distances, dx, dy, the carried values: the same arithmetic
                assert_array_equal(a, b)
    (offsets, seen, distances, bearings, dx, dy, vx, vy), (h_offsets, heard, h_distances, lost) = got
    assert lost.shape == (0,)  # no loss: nothing counted lost
    assert_array_equal(vx, carried[0][seen])  # each robot seen's own value
    assert_array_equal(vy, carried[1][seen])
    assert_allclose(np.hypot(dx, dy), distances, rtol=1e-15)
    assert_allclose(np.arctan2(dy, dx), bearings, rtol=0, atol=1e-15)
    assert (distances <= 0.4).all() and (h_distances <= 0.7).all() and talking[heard].all()
    assert len(offsets) == len(h_offsets) == len(rows) + 1


@pytest.mark.parametrize("fov", [2 * np.pi, 1.5])
@pytest.mark.parametrize("implementation", [_core, _reference], ids=["rust", "reference"])
def test_perceive_leaves_the_bearings_out_unless_asked(rng, fov, implementation):
    positions, headings, talking = perceive_scene(rng, 3000)
    rows = np.sort(rng.choice(3000, size=1500, replace=False))
    options = dict(sight=(0.4, fov, 0.3), radio_range=0.7, talking=talking, carried=[rng.normal(size=3000)])
    full = implementation.perceive(positions, headings, rows, **options)
    bare = implementation.perceive(positions, headings, rows, **options, bearings=False)
    assert len(full[0][3]) > 1000 and bare[0][3].shape == (0,)  # the field of view still decides who is seen
    for k, (a, b) in enumerate(zip(full[0], bare[0], strict=True)):
        if k != 3:
            assert_array_equal(a, b)
    for a, b in zip(full[1], bare[1], strict=True):
        assert_array_equal(a, b)


def test_perceive_carries_no_column_unless_asked(rng):
    positions, headings, talking = perceive_scene(rng, 50)
    seen, _ = kernels.perceive(positions, headings, np.arange(50), sight=(1.0, 2 * np.pi, 0.0))
    assert len(seen) == 6
    (*_, vx), _ = kernels.perceive(positions, headings, [], sight=(1.0, 2 * np.pi, 0.0), carried=[np.ones(50)])
    assert vx.shape == (0,) and vx.dtype == np.float64
    odd = np.arange(50.0)
    odd[7] = np.nan  # data, not geometry: carried as it is
    (_, ids, *_, values), _ = kernels.perceive(positions, headings, [7, 8], sight=(2.0, 2 * np.pi, 0.0), carried=[odd])
    assert_array_equal(values, odd[ids])
    assert np.isnan(values).any()


def test_a_perceived_row_does_not_depend_on_the_other_rows(rng):
    positions, headings, talking = perceive_scene(rng, 500)
    options = dict(sight=(0.5, 2.0, 0.0), radio_range=1.0, talking=talking)
    rows = np.arange(0, 500, 3)
    (offsets, seen, *_), (h_offsets, heard, *_) = kernels.perceive(positions, headings, rows, **options)
    for r in range(0, len(rows), 17):
        (o1, s1, *_), (h1, r1, *_) = kernels.perceive(positions, headings, rows[r : r + 1], **options)
        assert_array_equal(s1, seen[offsets[r] : offsets[r + 1]])
        assert_array_equal(r1, heard[h_offsets[r] : h_offsets[r + 1]])


@pytest.mark.parametrize("scale", [0.1, 1e154], ids=["lattice", "squares overflow"])
@pytest.mark.parametrize("kinds", ["sight and radio", "sight", "radio"])
@pytest.mark.parametrize("fov", [2 * np.pi, 1.5])
def test_perceive_counts_alike_at_the_ranges_edge(rng, scale, kinds, fov):
    """Robots on a lattice whose spacing is the ranges' unit: many pairs lie exactly at a range
    (the count's test of squares against the range's bound and the rows' test of roots must agree,
    on every row); past 1.3e154 m the squares overflow, and lengths come from hypot."""
    side = 12
    positions = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2) * scale
    positions[::5] = positions[1::5][: len(positions[::5])]  # some robots on the same spot
    n = len(positions)
    headings = rng.uniform(-np.pi, np.pi, n)
    options = {}
    if "sight" in kinds:
        options["sight"] = (2 * scale, fov, 0.3)
    if "radio" in kinds:
        options |= dict(radio_range=3 * scale, talking=rng.random(n) < 0.8)
    rows = np.arange(0, n, 2)
    got = _core.perceive(positions, headings, rows, **options)
    want = _reference.perceive(positions, headings, rows, **options)
    for mine, theirs in zip(got, want, strict=True):
        for k, (a, b) in enumerate(zip(mine, theirs, strict=True)):
            if k == 3:  # bearings: Rust's atan2 and NumPy's, to an ulp
                assert_allclose(a, b, rtol=0, atol=1e-15)
            else:
                assert_array_equal(a, b)
    (offsets, *_), (h_offsets, *_) = got
    assert offsets[-1] > 0 if "sight" in kinds else offsets[-1] == 0
    assert h_offsets[-1] > 0 if "radio" in kinds else h_offsets[-1] == 0


@pytest.mark.parametrize("n", [1, 40, 3000])
@pytest.mark.parametrize("scale", [1.0, 1e154], ids=["metres", "squares overflow"])
@pytest.mark.parametrize("fov", [1.5, 2 * np.pi, None], ids=["ahead", "all around", "no sensor"])
@pytest.mark.parametrize("columns", [1, 2, 3, 4, 5])
def test_perceive_sums_what_is_heard_as_the_reduction_of_its_rows(rng, n, scale, fov, columns):
    """A radio that sums (a decision reading only its inbox's sums): each row's sums are the
    reduction of the rows it would list, to the bit (NaN and huge values carried), as the
    reference's; the sensor's rows are untouched and the heard rows are left out. The rows are
    counted as they are summed, past the sensor's reach; up to four columns add up together."""
    positions, headings, talking = perceive_scene(rng, n)
    positions *= scale
    rows = np.sort(rng.choice(n, size=max(n // 2, 1), replace=False))
    values = [rng.normal(size=n), np.where(rng.random(n) < 0.05, np.nan, 1e300 * rng.normal(size=n))]
    values = (values + [rng.normal(size=n) for _ in range(columns)])[:columns]
    options = dict(radio_range=0.7 * scale, talking=talking)
    if fov is not None:
        options["sight"] = (0.4 * scale, fov, 0.3)
    listed = _core.perceive(positions, headings, rows, **options)
    got = _core.perceive(positions, headings, rows, **options, summed=values)
    want = _reference.perceive(positions, headings, rows, **options, summed=values)
    for a, b in zip(got[0], listed[0], strict=True):
        assert_array_equal(a, b)
    (offsets, ids, distances, lost, *sums), (listed_offsets, senders, *_) = got[1], listed[1]
    assert_array_equal(offsets, listed_offsets)
    assert ids.shape == distances.shape == lost.shape == (0,)
    reduced = kernels.segment_reduce(np.column_stack(values), offsets, "sum", senders)
    for column, (mine, theirs) in enumerate(zip(sums, want[1][4:], strict=True)):
        assert_array_equal(mine, reduced[:, column])  # NaN where a row heard one
        assert_array_equal(mine, theirs)
    if n == 3000:  # the cases arose: rows hearing several robots, a NaN summed
        assert offsets[-1] > len(rows) and (columns == 1 or np.isnan(sums[1]).any())
    nobody = _core.perceive(positions, headings, rows[:0], **options, summed=values)[1]
    assert_array_equal(nobody[0], [0])
    assert nobody[3].shape == (0,)  # no loss: nothing counted lost
    assert len(nobody[4:]) == columns and all(column.shape == (0,) for column in nobody[4:])


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (dict(rows=[5]), r"`rows` must be increasing robot ids in \[0, 3\)"),
        (dict(rows=[1, 0]), r"`rows` must be increasing robot ids"),
        (dict(rows=[1.0]), "integer robot ids"),
        (dict(rows=[0], sight=(-1.0, 1.0, 0.0)), "sensor range"),
        (dict(rows=[0], radio_range=1.0), "give both `radio_range` and `talking`"),
        (dict(rows=[0], radio_range=1.0, talking=[True]), "`talking` must"),
        (dict(rows=[0], carried=[np.zeros(2)]), r"`carried` must hold arrays of shape \(3,\)"),
        (dict(rows=[0], carried=[["a", "b", "c"]]), "`carried` must hold float arrays"),
        (dict(rows=[0], summed=[np.zeros(3)]), "`summed` and `loss` need a radio"),
        (dict(rows=[0], loss=kernels.Loss(1, 2, 3, 0.5, 0.0)), "`summed` and `loss` need a radio"),
        (
            dict(rows=[0], radio_range=1.0, talking=[True] * 3, summed=[np.zeros(4)]),
            r"`summed` must hold arrays of shape \(3,\)",
        ),
    ],
)
def test_perceive_bad_input_is_named(options, message):
    with pytest.raises(ValueError, match=message):
        kernels.perceive(np.zeros((3, 2)), np.zeros(3), **options)


def offsets_kept(offsets, through):
    """The offsets of the rows ``offsets`` once only the entries ``through`` (bool) are kept."""
    return np.concatenate(([0], np.cumsum(through)))[offsets].astype(np.int64)


@pytest.mark.parametrize("n", [1, 40, 2000])
@pytest.mark.parametrize("fov", [2 * np.pi, 1.5])
@pytest.mark.parametrize("per_metre", [0.0, 0.9], ids=["flat", "fading"])
@pytest.mark.parametrize("scale", [1.0, 1e154], ids=["metres", "squares overflow"])
def test_perceive_loses_messages_as_the_reference_draws_them(rng, n, fov, per_metre, scale):
    """A lossy radio, listed, counted (``summed=[]``) and summed (1-3 columns): the Rust kernel's
    every array as the reference's (``lost`` too), the sensor's rows untouched by the loss, and the
    rows heard those of the lossless radio that :func:`delivered` lets through (drawn by either
    draw table): ``lost`` the rest of what each row was offered (silent robots offer nothing)."""
    positions, headings, talking = perceive_scene(rng, n)
    positions *= scale
    rows = np.sort(rng.choice(n, size=max(n // 2, 1), replace=False))
    options = dict(
        sight=(0.4 * scale, fov, 0.3), radio_range=0.7 * scale, talking=talking, carried=[rng.normal(size=n)]
    )
    seed = int(rng.integers(2**64, dtype=np.uint64))  # all 64 bits of it
    loss = kernels.Loss(seed, 4, 17, 0.6, per_metre / scale)
    values = [rng.normal(size=n), np.where(rng.random(n) < 0.05, np.nan, rng.normal(size=n)), rng.normal(size=n)]
    lossless = _core.perceive(positions, headings, rows, **options)
    offered_offsets, senders, distances, none_lost = lossless[1]
    assert none_lost.shape == (0,) and talking[senders].all()
    hearers = np.repeat(rows, np.diff(offered_offsets))
    through = delivered(loss, hearers, senders, distances)
    assert_array_equal(through, delivered(loss, hearers, senders, distances, table=_core.draws))
    offsets = offsets_kept(offered_offsets, through)
    lost = np.diff(offered_offsets) - np.diff(offsets)
    for summed in (None, [], values[:1], values[:2], values):
        got = _core.perceive(positions, headings, rows, **options, summed=summed, loss=loss)
        want = _reference.perceive(positions, headings, rows, **options, summed=summed, loss=loss)
        for mine, theirs in zip(got, want, strict=True):
            assert len(mine) == len(theirs)
            for k, (a, b) in enumerate(zip(mine, theirs)):
                if k == 3 and mine is got[0]:  # bearings: Rust's atan2 and NumPy's, to an ulp
                    assert_allclose(a, b, rtol=0, atol=1e-15)
                else:
                    assert a.dtype == b.dtype
                    assert_array_equal(a, b)
        for a, b in zip(got[0], lossless[0], strict=True):  # the loss is the radio's alone
            assert_array_equal(a, b)
        heard = got[1]
        assert len(heard) == 4 + (0 if summed is None else len(summed))
        assert_array_equal(heard[0], offsets)  # counted or summed rows are the listed rows' counts
        assert heard[3].dtype == np.int64
        assert_array_equal(heard[3], lost)
        if summed is None:
            assert_array_equal(heard[1], senders[through])
            assert_array_equal(heard[2], distances[through])
        else:
            assert heard[1].shape == heard[2].shape == (0,)
            for column, sums in zip(summed, heard[4:], strict=True):
                assert_array_equal(
                    sums, _reference.segment_reduce(column[:, None], offsets, "sum", senders[through])[:, 0]
                )
    if n == 2000:  # not vacuous: some but not all lost, the more the farther when the loss fades
        assert 0 < lost.sum() < len(senders)
        assert (lost > 0).any() and (np.diff(offsets) > 0).any()
        near, far = distances < 0.25 * scale, distances > 0.5 * scale
        if per_metre:
            assert through[far].mean() < through[near].mean() - 0.2
        else:
            assert abs(through.mean() - 0.6) < 0.01 and abs(through[far].mean() - through[near].mean()) < 0.03


@pytest.mark.parametrize("implementation", [_core, _reference], ids=["rust", "reference"])
def test_perceive_keeps_all_or_loses_all_at_the_bounds(rng, implementation):
    """``keep=1`` with no fading loses nothing (the lossless rows, ``lost`` all zeros); ``keep=0``
    loses every message offered, and sums over nothing are +0.0."""
    n = 400
    positions, headings, talking = perceive_scene(rng, n)
    rows = np.sort(rng.choice(n, size=200, replace=False))
    options = dict(sight=(0.4, 1.5, 0.3), radio_range=0.7, talking=talking)
    offsets, senders, distances, _ = implementation.perceive(positions, headings, rows, **options)[1]
    assert len(senders) > 1000
    values = [rng.normal(size=n)]
    for summed in (None, [], values):
        kept = implementation.perceive(
            positions, headings, rows, **options, summed=summed, loss=kernels.Loss(9, 1, 2, 1.0, 0.0)
        )
        assert_array_equal(kept[1][0], offsets)
        assert_array_equal(kept[1][3], np.zeros(len(rows), dtype=np.int64))
        if summed is None:
            assert_array_equal(kept[1][1], senders)
            assert_array_equal(kept[1][2], distances)
        gone = implementation.perceive(
            positions, headings, rows, **options, summed=summed, loss=kernels.Loss(9, 1, 2, 0.0, 0.0)
        )
        assert_array_equal(gone[1][0], np.zeros(len(rows) + 1, dtype=np.int64))
        assert_array_equal(gone[1][3], np.diff(offsets))
        assert gone[1][1].shape == gone[1][2].shape == (0,)
        for sums in gone[1][4:]:
            assert_array_equal(sums, np.zeros(len(rows)))
            assert not np.signbit(sums).any()


def test_perceive_draws_the_loss_of_its_seed_stream_and_step(rng):
    """The same loss loses the same messages; another step, stream or seed others; a seed is read
    modulo 2^64 (-1 is 2^64 - 1)."""
    positions, headings, talking = perceive_scene(rng, 300)
    options = dict(radio_range=0.7, talking=talking)
    rows = np.arange(0, 300, 2)

    def heard(*loss):
        return kernels.perceive(positions, headings, rows, **options, loss=kernels.Loss(*loss))[1]

    first = heard(5, 1, 2, 0.5, 0.0)
    for a, b in zip(first, heard(5, 1, 2, 0.5, 0.0), strict=True):
        assert_array_equal(a, b)
    for other in (heard(5, 1, 3, 0.5, 0.0), heard(5, 2, 2, 0.5, 0.0), heard(6, 1, 2, 0.5, 0.0)):
        assert_array_equal(other[0][-1] + other[3].sum(), first[0][-1] + first[3].sum())  # as many offered
        assert not np.array_equal(other[1], first[1])
    for a, b in zip(heard(-1, 1, 2, 0.5, 0.0), heard(2**64 - 1, 1, 2, 0.5, 0.0), strict=True):
        assert_array_equal(a, b)


def random_graph(rng, n, most):
    """A communication graph over n robots: up to `most` links each, some to itself, some twice."""
    counts = rng.integers(0, most + 1, n)
    indptr = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    return indptr, rng.integers(0, n, indptr[-1]).astype(np.int64)


@pytest.mark.parametrize("n", [1, 5, 300, 20000])
def test_linked_matches_the_reference(rng, n):
    positions = rng.uniform(-50, 50, (n, 2))
    graph, talking = random_graph(rng, n, 8), rng.random(n) < 0.7
    rows = np.sort(rng.choice(n, size=max(n // 3, 1), replace=False))
    got = _core.linked(rows, *graph, talking, positions=positions)
    want = _reference.linked(rows, *graph, talking, positions=positions)
    for mine, theirs in zip(got, want, strict=True):
        assert_array_equal(mine, theirs)  # the same ids in the same order, the same hypot
    offsets, ids, distances = got
    assert len(offsets) == len(rows) + 1 and talking[ids].all()
    owner = np.repeat(rows, np.diff(offsets))
    assert (ids != owner).all()
    assert_array_equal(distances, np.hypot(*(positions[ids] - positions[owner]).T))
    unmeasured = kernels.linked(rows, graph, talking)  # no positions: no distances
    assert_array_equal(unmeasured[0], offsets)
    assert_array_equal(unmeasured[1], ids)
    assert np.isnan(unmeasured[2]).all() and len(unmeasured[2]) == len(ids)


def test_linked_reads_only_the_rows_asked_for():
    graph, talking = ([0, 1, 2, 2], [7, 0]), np.ones(3, dtype=bool)  # row 0 links robot 7, which is none
    positions = np.array([[0.0, 0.0], [3.0, 4.0], [1.0, 1.0]])
    offsets, ids, distances = kernels.linked([1, 2], graph, talking, positions=positions)
    assert_array_equal(offsets, [0, 1, 1])
    assert_array_equal(ids, [0])
    assert_array_equal(distances, [5.0])


@pytest.mark.parametrize(
    ("graph", "rows", "message"),
    [
        (([0, 1, 1, 1], [3]), [0], r"`graph` is not a valid CSR of 3 rows: row 0 links 3, which is not a robot id"),
        (([0, 1, 1, 1], [-1]), [0], "row 0 links -1, which is not a robot id"),
        (([0, 2, 1, 1], [0, 1]), [1], "row 1's links run from 2 to 1, not within the 2 indices"),
        (([0, 1, 1], [2]), [0], r"`graph` indptr must have shape \(4,\)"),
        (([0, 1, 1, 1], [0.5]), [0], "`graph` indices must be integers"),
        (([0, 1, 1, 1], [2]), [2, 1], "`rows` must be increasing robot ids"),
    ],
)
def test_linked_bad_input_is_named(graph, rows, message):
    with pytest.raises(ValueError, match=message):
        kernels.linked(rows, graph, np.ones(3, dtype=bool), positions=np.zeros((3, 2)))


# -- the motion guard ------------------------------------------------------------------------------
@pytest.mark.parametrize("rows", [0, 1, 30, 5000])
def test_motion_guard_matches_the_reference(rng, rows):
    counts = rng.integers(0, 6, rows)
    offsets = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    k = offsets[-1]
    speeds = rng.uniform(-0.2, 0.2, rows)
    speeds[rng.random(rows) < 0.1] = 0.0  # standing robots never stop
    headings = rng.uniform(-np.pi, np.pi, rows)
    dx, dy = rng.uniform(-0.3, 0.3, k), rng.uniform(-0.3, 0.3, k)
    got = _core.motion_guard(speeds, headings, offsets, dx, dy, near=0.12, horizon=0.25)
    want = _reference.motion_guard(speeds, headings, offsets, dx, dy, near=0.12, horizon=0.25)
    assert_array_equal(got, want)
    assert not got[speeds == 0].any()
    if rows == 5000:
        assert 0 < got.sum() < rows  # some stop, some drive on


def test_motion_guard_stops_short_of_a_robot_ahead_only():
    ahead = kernels.motion_guard([0.2, -0.2], [0.0, 0.0], [0, 1, 2], [0.1, 0.1], [0.0, 0.0], near=0.12, horizon=0.25)
    assert_array_equal(ahead, [True, False])  # the second backs away from it


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"dx": [np.nan]}, "`dx` contains a non-finite value"),
        ({"offsets": [0, 2]}, "`offsets` must be offsets"),
        ({"near": 0.0}, "`near` must be finite and > 0"),
        ({"headings": [0.0, 1.0]}, "`headings` must have shape (1,)"),
    ],
)
def test_motion_guard_bad_input_is_named(options, message):
    args = {
        "speeds": [0.1],
        "headings": [0.0],
        "offsets": [0, 1],
        "dx": [0.1],
        "dy": [0.0],
        "near": 0.1,
        "horizon": 0.2,
    }
    args.update(options)
    near, horizon = args.pop("near"), args.pop("horizon")
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        kernels.motion_guard(*args.values(), near=near, horizon=horizon)
