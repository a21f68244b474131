"""``heard_cells``, the cells of robots that know the others by radio: the Rust pass against its
NumPy reference (``neighbours``, ``far_from`` and ``voronoi_cells`` one after the other) to the
bit, against the one-robot kernel a robot calls for itself, and its errors."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from dream import _core, _reference, kernels
from dream._reference.draws import delivered

BOUNDS = (-2.0, 2.0, -1.5, 1.5)


def scene(rng, n, side, share=0.4, drift=0.05, unsaid=0.1):
    """Robots at ``positions`` whose last messages lie up to ``drift`` off, some silent, some
    having spoken again this round; a ``share`` of them hear, each seeing the robots within
    0.3 m (a few placed exactly ``same`` off a message) and sensing up to two virtual agents."""
    positions = rng.uniform(-side / 2, side / 2, (n, 2))
    said = positions + rng.uniform(-drift, drift, (n, 2))
    said[rng.random(n) < unsaid] = np.nan
    said_now = said.copy()
    again = rng.random(n) < 0.3
    said_now[again] = positions[again]
    hearers = np.flatnonzero(rng.random(n) < share)
    here = positions[hearers] + rng.normal(scale=0.01, size=(len(hearers), 2))
    seen, seen_counts, agents, agent_counts = [], [], [], []
    for i in hearers:
        near = np.flatnonzero(np.hypot(*(positions - positions[i]).T) < 0.3)
        near = near[near != i]
        points = positions[near] + rng.normal(scale=0.05, size=(len(near), 2))
        if len(near) and not np.isnan(said[near[0], 0]):
            points[0] = said[near[0]] + (0.08, 0.0)  # exactly `same` off a message heard
        seen.append(points)
        seen_counts.append(len(near))
        count = int(rng.integers(0, 3))
        agents.append(positions[i] + rng.uniform(-0.5, 0.5, (count, 2)))
        agent_counts.append(count)
    return dict(
        here=here,
        hearers=hearers.astype(np.int64),
        positions=positions,
        said=said,
        said_now=said_now,
        seen=csr(seen, seen_counts),
        virtual=csr(agents, agent_counts),
    )


def csr(parts, counts):
    """CSR ``(indptr, points)`` of rows ``parts`` of ``counts`` points each."""
    return np.concatenate(([0], np.cumsum(counts))).astype(np.int64), np.vstack([np.zeros((0, 2)), *parts])


def both(s, radius=1.0, range_=2.0, same=0.08, bounds=BOUNDS, resolution=32, loss=None, lost=None):
    """The Rust pass's and the reference's ``(centroids, areas, vertices, offsets)`` (through the
    radio's ``loss`` and without the links ``lost``, if any)."""
    args = (s["here"], s["hearers"], s["positions"], s["said"], s["said_now"])
    kw = dict(
        range=range_,
        seen_indptr=s["seen"][0],
        seen_points=s["seen"][1],
        same=same,
        virtual_indptr=s["virtual"][0],
        virtual_points=s["virtual"][1],
        radius=radius,
        bounds=bounds,
        resolution=resolution,
        loss=loss,
        lost=lost,
    )
    return _core.heard_cells(*args, **kw), _reference.heard_cells(*args, **kw)


@pytest.mark.parametrize(
    ("n", "side", "range_", "radius"),
    [
        (1, 1.0, 2.0, 1.0),
        (40, 3.0, 0.0, 1.0),  # nobody heard: cells clipped by sight and agents alone
        (120, 3.0, 2.0, 1.0),  # everyone hears everyone, the crowd of a packed start
        (150, 12.0, 1.0, 0.5),  # spread: the search widens round after round
        (700, 4.0, 2.0, 1.0),  # 280 hearers: rows on rayon
    ],
)
def test_heard_cells_match_the_reference_to_the_bit(rng, n, side, range_, radius):
    s = scene(rng, n, side)
    got, want = both(s, radius=radius, range_=range_, bounds=(-side / 2, side / 2, -side / 2, side / 2))
    for a, b in zip(got, want, strict=True):
        assert_array_equal(a, b)
    if n >= 120:
        areas = got[1]
        assert 0 < areas.min() < np.pi * radius**2 * 0.5  # crowded cells were clipped: not vacuous


def test_heard_cells_far_from_the_origin_and_with_late_messages(rng):
    # Far-flung robots (the grid's sparse table) and messages a metre off their robots.
    s = scene(rng, 200, 6.0, drift=1.0)
    s["positions"][:5] += 1e9
    got, want = both(s, bounds=(-4.0, 4.0, -4.0, 4.0))
    for a, b in zip(got, want, strict=True):
        assert_array_equal(a, b)


def test_a_hearers_cell_is_the_cell_it_computes_for_itself(rng):
    # What CoverageRobot.update computes from its radio's messages, its silent sightings and its agents.
    s = scene(rng, 150, 3.0)
    cells = kernels.heard_cells(
        s["here"], s["hearers"], s["positions"], s["said"], s["said_now"], range=2.0, seen=s["seen"], same=0.08,
        virtual=s["virtual"], radius=1.0, bounds=BOUNDS, polygons=True,
    )  # fmt: skip
    for r, i in enumerate(s["hearers"][:20]):
        near, _ = kernels.neighbours_of(s["positions"], int(i), 2.0)
        heard = np.where((near < i)[:, None], s["said_now"][near], s["said"][near])
        heard = heard[~np.isnan(heard[:, 0])]
        seen = s["seen"][1][s["seen"][0][r] : s["seen"][0][r + 1]]
        silent = seen[kernels.far_from(seen, heard, 0.08)]
        agents = s["virtual"][1][s["virtual"][0][r] : s["virtual"][0][r + 1]]
        centroid, area, polygon = kernels.voronoi_cell(
            s["here"][r], np.vstack((heard, silent)), virtual=agents, radius=1.0, bounds=BOUNDS
        )
        assert_array_equal(cells.centroids[r], centroid)
        assert cells.areas[r] == area
        assert_array_equal(cells.vertices[cells.offsets[r] : cells.offsets[r + 1]], polygon)


def test_heard_cells_defaults_and_empty_input(rng):
    s = scene(rng, 30, 3.0)
    plain = kernels.heard_cells(s["here"], s["hearers"], s["positions"], s["said"], range=1.0, bounds=BOUNDS)
    same_round = kernels.heard_cells(
        s["here"], s["hearers"], s["positions"], s["said"], s["said"], range=1.0, bounds=BOUNDS
    )
    assert_array_equal(plain.centroids, same_round.centroids)
    assert plain.vertices is None
    nobody = kernels.heard_cells(np.zeros((0, 2)), np.zeros(0, dtype=np.int64), s["positions"], s["said"], range=1.0)
    assert nobody.centroids.shape == (0, 2)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda s: s["said"].__setitem__((3, 0), np.nan) or s["said"].__setitem__((3, 1), 0.5),
            "`said` row 3 is half NaN",
        ),
        (lambda s: s["said_now"].__setitem__((2, 0), np.inf), "`said_now`"),
        (lambda s: s.__setitem__("hearers", s["hearers"][::-1].copy()), "strictly increasing"),
        (lambda s: s["hearers"].__setitem__(-1, 10**6), "strictly increasing"),
        (lambda s: s.__setitem__("hearers", s["hearers"].astype(float)), "robot indices"),
        (lambda s: s["positions"].__setitem__((0, 0), np.nan), "`positions`"),
        (lambda s: s.__setitem__("said", s["said"][:-1]), "`said` must have shape"),
        (lambda s: s.__setitem__("seen", (s["seen"][0][:-1], s["seen"][1])), "`seen` indptr"),
        (lambda s: s["here"].__setitem__((0, 1), 1e200), "`here`"),
    ],
)
def test_heard_cells_bad_input_names_the_argument(rng, change, message):
    s = scene(rng, 30, 3.0, unsaid=0.0)
    change(s)
    with pytest.raises(ValueError, match=message):
        kernels.heard_cells(
            s["here"], s["hearers"], s["positions"], s["said"], s["said_now"], range=1.0, seen=s["seen"],
            same=0.08, virtual=s["virtual"], bounds=BOUNDS,
        )  # fmt: skip


@pytest.mark.parametrize("bad", [dict(range=-1.0), dict(same=np.nan), dict(radius=0.0), dict(resolution=2)])
def test_heard_cells_bad_parameters_are_value_errors(rng, bad):
    s = scene(rng, 10, 3.0)
    kw = dict(range=1.0, same=0.08, radius=1.0, resolution=16) | bad
    with pytest.raises(ValueError, match=next(iter(bad))):
        kernels.heard_cells(s["here"], s["hearers"], s["positions"], s["said"], **kw)
    # The binding checks too: no panic reaches Python.
    with pytest.raises(ValueError):
        _core.heard_cells(
            s["here"], s["hearers"], s["positions"], s["said"], s["said"], seen_indptr=s["seen"][0],
            seen_points=s["seen"][1], virtual_indptr=s["virtual"][0], virtual_points=s["virtual"][1],
            bounds=BOUNDS, **kw,
        )  # fmt: skip


LOSSES = [(0.5, 0.0), (0.9, 0.4)]


@pytest.mark.parametrize(("keep", "per_metre"), LOSSES, ids=["flat", "fading"])
@pytest.mark.parametrize(
    ("n", "side", "range_", "radius"),
    [(1, 1.0, 2.0, 1.0), (120, 3.0, 2.0, 1.0), (150, 12.0, 1.0, 0.5), (700, 4.0, 2.0, 1.0)],
)
def test_heard_cells_lose_messages_as_the_reference_draws_them(rng, n, side, range_, radius, keep, per_metre):
    """Through a lossy radio the Rust pass is still the reference to the bit, and the loss is
    felt: with a good share of the messages lost, many cells change (a robot's cell grows where
    its message is lost, or is clipped by its sighting instead)."""
    s = scene(rng, n, side)
    bounds = (-side / 2, side / 2, -side / 2, side / 2)
    loss = kernels.Loss(int(rng.integers(2**64, dtype=np.uint64)), 3, 11, keep, per_metre)
    got, want = both(s, radius=radius, range_=range_, bounds=bounds, loss=loss)
    for a, b in zip(got, want, strict=True):
        assert_array_equal(a, b)
    lossless, _ = both(s, radius=radius, range_=range_, bounds=bounds)
    if n >= 120:
        assert (got[1] != lossless[1]).mean() > 0.3


@pytest.mark.parametrize(("keep", "per_metre"), LOSSES, ids=["flat", "fading"])
def test_a_lossy_hearers_cell_is_its_cell_without_the_messages_lost(rng, keep, per_metre):
    """Each hearer's cell through the loss is the cell it computes alone, without a loss, from
    messages of which those :func:`delivered` drops for it (hearer, sender, distance) were never
    said."""
    s = scene(rng, 150, 3.0)
    loss = kernels.Loss(2**64 - 5, -2, 40, keep, per_metre)
    kw = dict(range=2.0, same=0.08, radius=1.0, bounds=BOUNDS, polygons=True)
    args = (s["here"], s["hearers"], s["positions"], s["said"], s["said_now"])
    cells = kernels.heard_cells(*args, seen=s["seen"], virtual=s["virtual"], loss=loss, **kw)
    dropped = 0
    for r, i in enumerate(s["hearers"][:25]):
        near, distances = kernels.neighbours_of(s["positions"], int(i), 2.0)
        lost = near[~delivered(loss, np.full(len(near), i), near, distances)]
        dropped += len(lost)
        said, said_now = s["said"].copy(), s["said_now"].copy()
        said[lost] = said_now[lost] = np.nan
        seen = (
            np.array([0, s["seen"][0][r + 1] - s["seen"][0][r]]),
            s["seen"][1][s["seen"][0][r] : s["seen"][0][r + 1]],
        )
        virtual = (
            np.array([0, s["virtual"][0][r + 1] - s["virtual"][0][r]]),
            s["virtual"][1][s["virtual"][0][r] : s["virtual"][0][r + 1]],
        )
        alone = kernels.heard_cells(
            s["here"][r : r + 1], [i], s["positions"], said, said_now, seen=seen, virtual=virtual, **kw
        )
        assert_array_equal(cells.centroids[r], alone.centroids[0])
        assert cells.areas[r] == alone.areas[0]
        assert_array_equal(cells.vertices[cells.offsets[r] : cells.offsets[r + 1]], alone.vertices)
    assert dropped > 25  # messages were lost


def test_heard_cells_keep_all_or_lose_all_at_the_bounds(rng):
    """``keep=1`` with no fading is the lossless radio; ``keep=0`` is a radio on which nothing was
    said (on both paths)."""
    s = scene(rng, 150, 3.0)
    lossless, _ = both(s)
    unsaid = dict(s, said=np.full_like(s["said"], np.nan), said_now=np.full_like(s["said"], np.nan))
    deaf, _ = both(unsaid)
    assert not np.array_equal(lossless[1], deaf[1])
    for loss, expected in ((kernels.Loss(1, 2, 3, 1.0, 0.0), lossless), (kernels.Loss(1, 2, 3, 0.0, 0.0), deaf)):
        for cells in both(s, loss=loss):
            for a, b in zip(cells, expected, strict=True):
                assert_array_equal(a, b)


def test_heard_cells_at_tiny_and_huge_scales_match_the_reference(rng):
    # Squared distances that underflow (a message must not be lost between two rounds' boxes) and
    # a robot 3e18 m away (the search box's cell count overflows: no endless walk of empty cells).
    tiny = dict(positions=np.array([[0.0, 0.0], [1e-201, 0.0]]), here=np.array([[1e-170, 0.0]]))
    far = dict(positions=np.array([[3e18, 0.0], [0.0, 0.0]]), here=np.array([[0.5, 0.0]]))
    for scene_, hearer, range_ in ((tiny, 0, 1e-200), (far, 1, 1.0)):
        s = dict(scene_, hearers=np.array([hearer]), said=scene_["positions"] + 0.0, said_now=scene_["positions"] + 0.0)
        s["seen"] = s["virtual"] = (np.zeros(2, dtype=np.int64), np.zeros((0, 2)))
        got, want = both(s, range_=range_, same=0.0, resolution=8)
        for a, b in zip(got, want, strict=True):
            assert_array_equal(a, b)
    for scale in (1e-175, 1e-160):
        s = scene(rng, 60, 1.0)
        for key in ("here", "positions", "said", "said_now"):
            s[key] = s[key] * scale
        s["seen"] = (s["seen"][0], s["seen"][1] * scale)
        s["virtual"] = (s["virtual"][0], s["virtual"][1] * scale)
        got, want = both(s, radius=scale, range_=2 * scale, same=0.08 * scale, bounds=(-scale, scale, -scale, scale))
        for a, b in zip(got, want, strict=True):
            assert_array_equal(a, b)


def test_heard_cells_refuse_positions_beyond_reach():
    with pytest.raises(ValueError, match="`positions`"):
        kernels.heard_cells([[0.0, 0.0]], [0], [[0.0, 0.0], [1e308, 0.0]], [[0.0, 0.0], [0.0, 0.0]], range=1.0)


@pytest.mark.parametrize("loss", [None, kernels.Loss(3, 0, 9, 0.8, 0.0)], ids=["links alone", "with a loss"])
def test_heard_cells_without_the_links_lost_match_the_reference(rng, loss):
    # A burst's lost messages, found as the engine lists an inbox, come as links i * n + j: the
    # cells are those of the hearers without them (some links out of range, some not hearers').
    s = scene(rng, 200, 3.0)
    n = len(s["positions"])
    lost = np.flatnonzero(rng.random(n * n) < 0.3)
    got, want = both(s, loss=loss, lost=lost)
    for a, b in zip(got, want, strict=True):
        assert_array_equal(a, b)
    kept, _ = both(s, loss=loss)
    assert (got[1] != kept[1]).mean() > 0.3  # the links lost matter
    silent = both(s, loss=loss, lost=np.arange(n * n))[0]  # every link lost: nobody heard
    unsaid = dict(s, said=np.full_like(s["said"], np.nan), said_now=np.full_like(s["said"], np.nan))
    for a, b in zip(silent, both(unsaid)[0], strict=True):
        assert_array_equal(a, b)


@pytest.mark.parametrize(
    ("lost", "message"),
    [
        (np.array([4, 4]), "`lost` must be strictly increasing, but the link at index 1"),
        (np.array([1.5]), "`lost` must be a 1-D array"),
        (np.array([-5, 1]), r"`lost` links must lie in \[0, n\^2\) = \[0, 100\)"),
        (np.array([5, 2**63], dtype=np.uint64), r"`lost` links must lie in \[0, n\^2\)"),
    ],
)
def test_heard_cells_bad_lost_links_are_named(rng, lost, message):
    s = scene(rng, 10, 3.0)
    with pytest.raises(ValueError, match=message):
        kernels.heard_cells(s["here"], s["hearers"], s["positions"], s["said"], range=1.0, lost=lost)
