"""Counter-based random draws: each number a hash of (seed, stream, step, keys) (see :mod:`dream.swarm.draws`).

The hash absorbs one 64-bit word at a time: the word times the golden ratio is XORed in and
SplitMix64's finaliser applied; a draw is the hash's 53 high bits over 2^53. The draws come as a
``(rows, columns)`` table whose keys are each one word for every draw (kind ``a``), one per row
(``r``) or one per column (``c``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from dream._checks import FloatArray

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


def _mix(z: np.ndarray) -> np.ndarray:
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def _absorb(h: np.ndarray, words: np.ndarray | int) -> np.ndarray:
    """``h`` with one more word absorbed (a negative word as its two's complement)."""
    return _mix(h ^ (np.asarray(words, dtype=np.int64).view(np.uint64) * _GOLDEN))


def draws(
    seed: int,
    stream: int,
    step: int,
    keys: Sequence[np.ndarray],
    kinds: str,
    rows: int,
    columns: int,
) -> FloatArray:
    """The ``(rows, columns)`` uniform draws in [0, 1) of ``stream`` at ``step``: ``keys`` are 1-D
    int64 arrays, of the kinds ``kinds`` names in turn."""
    if len(kinds) != len(keys):
        raise ValueError(f"`kinds` names {len(kinds)} keys, but {len(keys)} are given")
    h = _absorb(_absorb(np.full(rows * columns, np.uint64(seed), dtype=np.uint64), stream), step)
    for key, kind in zip(keys, kinds, strict=True):
        words = np.asarray(key, dtype=np.int64)
        if kind == "a":
            if words.size != 1:
                raise ValueError(f"a key of kind `a` holds one word, got {words.size}")
            h = _absorb(h, words.reshape(-1)[0])
        elif kind == "r":
            h = _absorb(h, np.repeat(_sized(words, rows, "row"), columns))
        elif kind == "c":
            h = _absorb(h, np.tile(_sized(words, columns, "column"), rows))
        else:
            raise ValueError(f"`kinds` holds {kind!r}: each key is `a`, `r` or `c`")
    return (h >> np.uint64(11)).astype(np.float64).reshape(rows, columns) * 2.0**-53


class Loss(NamedTuple):
    """A radio's losses at one step: robot i hears the message of robot j, ``distance`` (m) away,
    when the draw of (``stream``, ``step``, i, j) is below ``keep * max(1 - per_metre * distance,
    0)`` (the distance not read where ``per_metre`` is 0: a graph radio may not measure it)."""

    seed: int
    stream: int
    step: int
    keep: float
    per_metre: float


def delivered(
    loss: Loss,
    hearers: np.ndarray,
    senders: np.ndarray,
    distances: FloatArray,
    table: Callable[..., FloatArray] = draws,
) -> np.ndarray:
    """Which messages get through ``loss`` (``(m,)`` bool): message e from ``senders[e]`` to
    ``hearers[e]``, ``distances[e]`` apart, drawn by ``table`` (:func:`draws`, or the Rust
    kernel's twin of it)."""
    keep: float | FloatArray = loss.keep
    if loss.per_metre > 0:
        keep = loss.keep * np.maximum(1.0 - loss.per_metre * np.asarray(distances), 0.0)
    u = table(loss.seed % 2**64, loss.stream, loss.step, [hearers, senders], "rr", len(senders), 1)
    return np.asarray(u).reshape(-1) < keep


def _sized(words: np.ndarray, expected: int, kind: str) -> np.ndarray:
    if len(words) != expected:
        raise ValueError(f"`{kind} keys` has {len(words)} values, expected {expected}")
    return words
