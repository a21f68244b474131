"""The threads a swarm step's NumPy work runs on, beside the Rust kernels' pool: as many as it has.

NumPy gives the interpreter lock back while a ufunc works through an array, so an array cut into
pieces is worked through by several cores at once, to the same bits (each value's arithmetic is
its own). The engine's decisions in blocks have a pool of their own (:mod:`dream.swarm.engine`):
a decision that draws numbers may wait on this one, and never waits on its own.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from functools import cache


def threads() -> int:
    """The threads to work on: as many as the Rust kernels' pool has (``RAYON_NUM_THREADS``,
    where it is a whole number above 0, else the cores this process may run on)."""
    asked = os.environ.get("RAYON_NUM_THREADS", "")
    if asked.isdigit() and int(asked) > 0:
        return int(asked)
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


#: Items a thread works through at least: fewer are not worth waking a thread for (65,536 values'
#: logarithm and cosine take about a millisecond).
LEAST_PIECE = 65_536


def spread(work: Callable[[slice], None], size: int, least: int | None = None) -> None:
    """``work(piece)`` for the slices that cut ``range(size)`` into one piece a thread, each of at
    least ``least`` items (default :data:`LEAST_PIECE`; one piece, on the calling thread, where
    there are fewer): the calling thread works through the first piece while the pool's threads
    work through the others."""
    least = LEAST_PIECE if least is None else least
    pieces = max(1, min(threads(), size // max(least, 1)))
    bounds = [size * k // pieces for k in range(pieces + 1)]
    others = [_pool().submit(work, slice(a, b)) for a, b in zip(bounds[1:-1], bounds[2:])]
    work(slice(bounds[0], bounds[1]))
    for piece in others:
        piece.result()


@cache
def _pool() -> ThreadPoolExecutor:
    return ThreadPoolExecutor(threads(), thread_name_prefix="dream-spread")


# A forked child (multiprocessing's default on Linux) has none of its parent's threads: a new pool.
os.register_at_fork(after_in_child=_pool.cache_clear)
