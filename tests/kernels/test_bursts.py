"""Loss bursts on radio links (``bursts``): the Rust kernel against its NumPy reference step after
step, links sorted as the engine's inboxes list them or in any order, and its bad input named."""

from __future__ import annotations

import numpy as np
import pytest

from dream import _core, _reference


@pytest.mark.parametrize("order", ["sorted", "shuffled"])
def test_the_kernel_keeps_the_references_bursts(rng, order):
    lossy = np.zeros(0, dtype=np.int64)
    for _ in range(30):
        links = rng.integers(-50, 4000, int(rng.integers(0, 3000)))  # duplicates: a link heard twice
        links = np.sort(links) if order == "sorted" else links
        draws = rng.random(len(links))
        mine, theirs = _core.bursts(lossy, links, draws, 0.2, 0.35), _reference.bursts(lossy, links, draws, 0.2, 0.35)
        assert np.array_equal(mine[0], theirs[0]) and np.array_equal(mine[1], theirs[1])
        assert mine[0].dtype == bool and mine[1].dtype == np.int64 and (np.diff(mine[1]) > 0).all()
        lossy = mine[1]
    assert 0 < len(lossy) < 4050


def test_many_links_are_looked_up_in_pieces_alike(rng):
    """Enough links for the lookup to go in pieces on every core."""
    lossy = np.unique(rng.integers(0, 10**7, 200_000))
    links = np.sort(rng.integers(0, 10**7, 300_000))
    draws = rng.random(len(links))
    mine, theirs = _core.bursts(lossy, links, draws, 0.1, 0.3), _reference.bursts(lossy, links, draws, 0.1, 0.3)
    assert np.array_equal(mine[0], theirs[0]) and np.array_equal(mine[1], theirs[1])
    assert mine[0][np.isin(links, lossy)].mean() > 0.6  # most links in a burst stay in one


def test_a_link_stays_in_its_burst_until_a_message_ends_it():
    lossy = np.array([5, 9])
    now, after = _core.bursts(lossy, np.array([9, 9, 7]), np.array([0.9, 0.1, 0.05]), 0.1, 0.5)
    assert now.tolist() == [True, False, True] and after.tolist() == [5, 7]  # 9 ended on its second message


@pytest.mark.parametrize("implementation", [_core.bursts, _reference.bursts], ids=["rust", "numpy"])
@pytest.mark.parametrize(
    ("lossy", "links", "draws", "enter", "message"),
    [
        ([1, 3, 2], [], [], 0.1, "`lossy` is not strictly increasing at index 2"),
        ([], [1], [], 0.1, r"`draws` must have shape \(1,\), got \[0\]"),
        ([], [], [], 1.5, "`enter` must be finite and a probability in"),
    ],
)
def test_bad_input_is_named(implementation, lossy, links, draws, enter, message):
    with pytest.raises(ValueError, match=message):
        implementation(np.array(lossy, dtype=np.int64), np.array(links, dtype=np.int64), np.array(draws), enter, 0.2)
    with pytest.raises(ValueError, match="`lossy` must be a NumPy array of int64"):
        implementation(np.array(lossy, dtype=np.int32), np.array(links, dtype=np.int64), np.array(draws), enter, 0.2)
    extremes = np.array(
        [np.iinfo(np.int64).min, np.iinfo(np.int64).max]
    )  # increasing, though their difference overflows
    assert implementation(extremes, extremes[1:], np.array([0.9]), 0.1, 0.2)[1].tolist() == extremes.tolist()
