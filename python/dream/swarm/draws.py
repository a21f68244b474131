"""Counter-based random draws: each number is a hash of (seed, stream, step, keys).

A robot's noise, a message's loss or a liar's value depends only on who, when and what, never on
the order in which the engine asks: one robot at a time or the whole swarm at once draw the same
numbers. The hash is SplitMix64's finaliser, applied once per key.
"""

from __future__ import annotations

from typing import Any

import numpy as np

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)

#: Streams: one per kind of draw, so that two kinds never share a number.
LOSS, BURST, DETECTION_NOISE, ODOMETRY_NOISE, DROPOUT, CLOCK_JITTER, LATENCY_JITTER, LIE, OBSTACLE_NOISE = range(9)


def _mix(z: np.ndarray) -> np.ndarray:
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def _hash(seed: int, stream: int, step: int, keys: tuple[Any, ...]) -> np.ndarray:
    shape = np.broadcast_shapes(*(np.shape(k) for k in keys)) if keys else ()
    h = np.full(shape, np.uint64(seed % 2**64), dtype=np.uint64).reshape(-1)
    for key in (stream, step, *keys):
        word = np.broadcast_to(np.asarray(key, dtype=np.int64), shape).reshape(-1).view(np.uint64)
        h = _mix(h ^ (word * _GOLDEN))
    return h.reshape(shape)


def uniform(seed: int, stream: int, step: int, *keys: Any) -> np.ndarray:
    """Uniform draws in [0, 1), one per element of the broadcast ``keys`` (integer arrays)."""
    return (_hash(seed, stream, step, keys) >> np.uint64(11)).astype(np.float64) * 2.0**-53


def normal(seed: int, stream: int, step: int, *keys: Any) -> np.ndarray:
    """Standard normal draws (Box-Muller of two uniforms keyed apart by a last key of 0 and 1)."""
    u = uniform(seed, stream, step, *keys, 0)
    v = uniform(seed, stream, step, *keys, 1)
    return np.sqrt(-2.0 * np.log1p(-u)) * np.cos(2.0 * np.pi * v)


def integers(low: int, high: int, seed: int, stream: int, step: int, *keys: Any) -> np.ndarray:
    """Integers uniform in ``[low, high]``."""
    return low + np.floor(uniform(seed, stream, step, *keys) * (high - low + 1)).astype(np.int64)
