"""Counter-based random draws (``draws``): the Rust kernel against its NumPy reference, to the bit,
both against a hash written out on Python integers, and ``dream.swarm.draws`` over broadcast keys."""

from __future__ import annotations

import numpy as np
import pytest

from dream import _core, _reference, kernels
from dream.kernels import _dispatch
from dream.swarm import draws

MASK = 2**64 - 1


def hashed_uniform(seed: int, words: list[int]) -> float:
    """The definition on Python integers: each word times the golden ratio XORed in, SplitMix64's
    finaliser applied; the 53 high bits over 2^53."""
    h = seed % 2**64
    for word in words:
        z = h ^ ((int(word) % 2**64) * 0x9E3779B97F4A7C15 & MASK)
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9 & MASK
        z = (z ^ (z >> 27)) * 0x94D049BB133111EB & MASK
        h = z ^ (z >> 31)
    return (h >> 11) / 2**53


def random_table(rng: np.random.Generator) -> tuple[list[np.ndarray], str, int, int]:
    rows, columns = int(rng.integers(0, 40)), int(rng.integers(0, 6))
    kinds = "".join(rng.choice(list("arc"), size=int(rng.integers(0, 5))))
    extremes = np.array([np.iinfo(np.int64).min, -1, 0, np.iinfo(np.int64).max])
    keys = []
    for kind in kinds:
        size = {"a": 1, "r": rows, "c": columns}[kind]
        words = rng.integers(-(2**40), 2**40, size)
        words[rng.random(size) < 0.2] = rng.choice(extremes)
        keys.append(words.astype(np.int64))
    return keys, kinds, rows, columns


@pytest.mark.parametrize("trial", range(40))
def test_the_kernel_draws_the_references_numbers_and_the_definitions(rng, trial):
    keys, kinds, rows, columns = random_table(rng)
    seed, stream, step = int(rng.integers(0, 2**63)) * 2 + 1, int(rng.integers(0, 9)), int(rng.integers(-5, 10**6))
    mine = _core.draws(seed, stream, step, keys, kinds, rows, columns)
    theirs = _reference.draws(seed, stream, step, keys, kinds, rows, columns)
    assert mine.shape == theirs.shape == (rows, columns)
    assert mine.tobytes() == theirs.tobytes()
    for r, j in zip(rng.integers(0, max(rows, 1), 5), rng.integers(0, max(columns, 1), 5), strict=True):
        if rows and columns:
            words = [int(key[0 if kind == "a" else r if kind == "r" else j]) for key, kind in zip(keys, kinds)]
            assert mine[r, j] == hashed_uniform(seed, [stream, step, *words])


def test_large_tables_are_drawn_on_every_core_alike(rng):
    rows = rng.integers(0, 10**6, 300_000)
    args = (12345, draws.DETECTION_NOISE, 77, [rows, np.arange(4)], "rc", len(rows), 4)
    assert _core.draws(*args).tobytes() == _reference.draws(*args).tobytes()


@pytest.mark.parametrize(
    ("keys", "kinds", "rows", "columns", "message"),
    [
        ([np.arange(3)], "", 3, 1, "`kinds` names 0 keys, but 1 are given"),
        ([np.arange(3)], "x", 3, 1, "each key is `a`, `r` or `c`"),
        ([np.arange(3)], "a", 3, 1, "a key of kind `a` holds one word, got 3"),
        ([np.arange(3)], "r", 2, 1, "has 3 values, expected 2"),
        ([np.arange(3)], "c", 1, 2, "has 3 values, expected 2"),
    ],
)
@pytest.mark.parametrize("implementation", [_core.draws, _reference.draws])
def test_bad_tables_are_named(implementation, keys, kinds, rows, columns, message):
    with pytest.raises(ValueError, match=message):
        implementation(1, 0, 0, keys, kinds, rows, columns)


@pytest.mark.parametrize("core", [_core, None], ids=["rust", "numpy"])
def test_broadcast_keys_draw_each_elements_own_numbers(core, rng):
    me, others = rng.integers(-3, 1000, 30), rng.integers(0, 1000, 30)
    full = rng.integers(0, 50, (30, 4))
    _dispatch._core, saved = core, _dispatch._core
    try:
        shapes = {
            "one": draws.uniform(9, draws.LOSS, 4),
            "rows": draws.uniform(9, draws.LOSS, 4, me, others),
            "rows and columns": draws.uniform(9, draws.LOSS, 4, me[:, None], np.arange(4)),
            "columns first": draws.uniform(9, draws.LOSS, 4, np.arange(4)[None, :], others[:, None]),
            "a full key": draws.uniform(9, draws.LOSS, 4, full, np.arange(4)),
            "three axes": draws.uniform(9, draws.LOSS, 4, me[:2, None, None], np.arange(3)[:, None], np.arange(4)),
        }
        normal = draws.normal(9, draws.DETECTION_NOISE, 4, me[:, None], np.arange(2))
        integers = draws.integers(-2, 2, 9, draws.CLOCK_JITTER, 4, me)
    finally:
        _dispatch._core = saved
    keys = {
        "one": [],
        "rows": [me, others],
        "rows and columns": [me[:, None], np.arange(4)],
        "columns first": [np.arange(4)[None, :], others[:, None]],
        "a full key": [full, np.arange(4)],
        "three axes": [me[:2, None, None], np.arange(3)[:, None], np.arange(4)],
    }
    for name, drawn in shapes.items():
        broadcast = np.broadcast_arrays(*keys[name]) if keys[name] else []
        shape = broadcast[0].shape if broadcast else ()
        assert drawn.shape == shape, name
        for index in np.ndindex(shape):
            assert drawn[index] == hashed_uniform(9, [draws.LOSS, 4, *(int(k[index]) for k in broadcast)]), name
    u = np.array([[hashed_uniform(9, [draws.DETECTION_NOISE, 4, m, j, 0]) for j in range(2)] for m in me])
    v = np.array([[hashed_uniform(9, [draws.DETECTION_NOISE, 4, m, j, 1]) for j in range(2)] for m in me])
    assert normal.tobytes() == (np.sqrt(-2.0 * np.log1p(-u)) * np.cos(2.0 * np.pi * v)).tobytes()
    assert integers.min() >= -2 and integers.max() <= 2
    expected = [-2 + int(hashed_uniform(9, [draws.CLOCK_JITTER, 4, m]) * 5) for m in me]
    assert integers.tolist() == expected


@pytest.mark.parametrize("core", [_core, None], ids=["rust", "numpy"])
@pytest.mark.parametrize("seed", [0, 2**63 + 5, 2**64 - 1, -1, -(2**70)])
def test_edge_shapes_and_seeds(core, seed):
    """Empty tables, a lone column, 0-d keys and seeds beyond int64 (taken modulo 2^64)."""
    _dispatch._core, saved = core, _dispatch._core
    try:
        empty = draws.uniform(seed, draws.LIE, 1, np.zeros((0, 1), dtype=np.int64), np.arange(3))
        column = draws.uniform(seed, draws.LIE, 1, np.arange(5)[:, None], np.zeros((1, 1), dtype=np.int64))
        scalar = draws.uniform(seed, draws.LIE, 1, np.int64(7), 3)
        nothing = draws.normal(seed, draws.LIE, 1)
    finally:
        _dispatch._core = saved
    assert empty.shape == (0, 3) and column.shape == (5, 1)
    assert column[:, 0].tolist() == [hashed_uniform(seed, [draws.LIE, 1, k, 0]) for k in range(5)]
    assert type(scalar) is np.float64 and scalar == hashed_uniform(seed, [draws.LIE, 1, 7, 3])
    assert type(nothing) is np.float64 and np.isfinite(nothing)


@pytest.mark.parametrize(
    ("loss", "message"),
    [
        ((1, 2, 3, 1.5, 0.0), r"`keep` must be within \[0, 1\], got 1.5"),
        ((1, 2, 3, np.nan, 0.0), r"`keep` must be within \[0, 1\], got nan"),
        ((1, 2, 3, 0.5, -1.0), "`per_metre` must be finite and >= 0, got -1"),
        ((1, 2, 3, 0.5, np.inf), "`per_metre` must be finite and >= 0, got inf"),
        ((1, 2, 3.0, 0.5, 0.0), "the loss's step must be an integer, got 3.0"),
    ],
)
def test_a_bad_radio_loss_is_named(loss, message):
    # Through both kernels that draw a radio's loss, and their bindings (in their own words: no
    # panic reaches Python).
    positions, here, hearers = np.zeros((3, 2)), np.zeros((1, 2)), np.array([0])
    radio = dict(radio_range=1.0, talking=np.ones(3, dtype=bool))
    empty = (np.zeros(2, dtype=np.int64), np.zeros((0, 2)))
    with pytest.raises(ValueError, match=message):
        kernels.perceive(positions, np.zeros(3), hearers, **radio, loss=kernels.Loss(*loss))
    with pytest.raises(ValueError, match=message):
        kernels.heard_cells(here, hearers, positions, positions, range=1.0, loss=kernels.Loss(*loss))
    if isinstance(loss[2], int):
        with pytest.raises(ValueError, match=message.split()[0]):
            _core.perceive(positions, np.zeros(3), hearers, **radio, loss=loss)
        with pytest.raises(ValueError, match=message.split()[0]):
            _core.heard_cells(
                here, hearers, positions, positions, positions, range=1.0, seen_indptr=empty[0],
                seen_points=empty[1], same=0.0, virtual_indptr=empty[0], virtual_points=empty[1], radius=1.0,
                bounds=(-1.0, 1.0, -1.0, 1.0), loss=loss,
            )  # fmt: skip
