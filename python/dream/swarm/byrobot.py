"""Robot by robot, or block by block: the view of every robot deciding now, cut into one view
per robot (or per block of rows), and their decisions put back together.

The engine perceives for all the deciding robots at once, as for the swarm, and carries out
their wishes at once, with the same kernels: each kernel's rows are independent of one another,
so one call over k rows gives the bits of k calls over one (the both-ways tests compare whole
runs). Only :meth:`~dream.swarm.robot.SwarmRobot.decide` runs once per piece, on its own rows: a
decision sees no other robot's view. Messages sent now are heard from the next step on either
way, so the order the pieces are decided in changes nothing, and blocks of a swarm can be
decided on several threads at once (:attr:`~dream.swarm.robot.SwarmRobot.threaded`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from typing import Any

import numpy as np

from dream.swarm.neighbourhood import Deferred, Neighbourhood
from dream.swarm.robot import Avoid, View


def cut(whole: View, bounds: Sequence[int] | None = None) -> list[View]:
    """One view per row of ``whole`` (in its order), each a robot's own, or one per block of rows
    ``bounds[i]:bounds[i + 1]`` (``bounds`` increasing from 0 to ``len(whole)``): slices of
    ``whole``'s arrays (read-only where ``whole``'s are), its own memory rows, nothing said or
    chosen yet."""
    bounds = range(len(whole) + 1) if bounds is None else bounds
    pieces = list(zip(bounds[:-1], bounds[1:]))
    seen, heard = _rows(whole.seen, bounds), _rows(whole.heard, bounds)
    obstacles: Sequence[Neighbourhood | None] = (
        [None] * len(pieces) if whole.obstacles is None else _rows(whole.obstacles, bounds)
    )
    ids, clock, pose, memory, command = whole.ids, whole.clock, whole.pose, whole.memory, whole.command
    return [
        View(
            ids[a:b],
            clock[a:b],
            pose[a:b],
            seen[i],
            heard[i],
            {key: values[a:b] for key, values in memory.items()},
            obstacles[i],
            None if command is None else command[a:b],
            board_cells=whole.board_cells,
        )
        for i, (a, b) in enumerate(pieces)
    ]


def blocks(k: int, threads: int, least: int) -> list[int] | None:
    """The bounds of up to ``threads`` blocks of nearly equal size, each of at least ``least`` of
    ``k`` rows; None where fewer than two such blocks fit."""
    count = min(threads, k // max(least, 1))
    if count < 2:
        return None
    return [k * i // count for i in range(count + 1)]


def _rows(hood: Neighbourhood, bounds: Sequence[int]) -> list[Neighbourhood]:
    """``hood``'s blocks of rows ``bounds[i]:bounds[i + 1]``, each a neighbourhood of its own. An
    inbox found on first use (found then, for all the rows) and a neighbourhood without entries (a
    sensor the robot lacks, say) are cut when a block first reads it: most decisions never read
    them."""
    if isinstance(hood, Deferred) or not hood.offsets[-1]:
        summed = hood._summed if isinstance(hood, Deferred) else None
        return [
            Deferred(partial(_block_of, hood, a, b), None if summed is None else summed.rows(a, b))
            for a, b in zip(bounds[:-1], bounds[1:])
        ]
    starts = hood.offsets[np.asarray(bounds)].tolist()
    return [
        _block(hood, a, b, start, end) for a, b, start, end in zip(bounds[:-1], bounds[1:], starts[:-1], starts[1:])
    ]


def _block_of(hood: Neighbourhood, a: int, b: int) -> Neighbourhood:
    return _block(hood, a, b, int(hood.offsets[a]), int(hood.offsets[b]))


def _block(hood: Neighbourhood, a: int, b: int, start: int, end: int) -> Neighbourhood:
    """Rows ``a:b`` of ``hood``, entries ``start:end``, as a neighbourhood of their own, read-only
    as ``hood`` (its slices are, as views of read-only arrays)."""
    offsets = np.array([0, end - start]) if b == a + 1 else hood.offsets[a : b + 1] - start
    offsets.flags.writeable = not hood.read_only
    part = Neighbourhood(
        offsets,
        {name: values[start:end] for name, values in hood.columns.items()},
        None if hood.index is None else (hood.index[start:end], hood.sources),
        hood.derived,
    )
    part.read_only = hood.read_only
    return part


def merged(
    whole: View, settled: Sequence[tuple[Any, Any, Any, Any, Any]], avoid: Avoid | None, bounds: Sequence[int]
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, Neighbourhood]:
    """The checked decisions of the pieces of :func:`cut` (``settled``: each one's wished
    velocities, rows driven direct, safety radii and detections heeded, None where it chose
    nothing; ``bounds``: their rows) as ``whole``'s: the wishes, the rows driven direct, the safety
    radii (the Avoid's where a piece kept them) and the detections heeded (all of a piece's where
    it chose none)."""
    wished, straight, safety, heeded, _ = zip(*settled)
    seen = whole.seen
    if any(h is not None for h in heeded):
        counts = np.diff(seen.offsets[np.asarray(bounds)]).tolist()
        seen = seen.where(
            np.concatenate([np.ones(c, dtype=bool) if h is None else h for h, c in zip(heeded, counts, strict=True)])
        )
    sizes = np.diff(np.asarray(bounds)).tolist()
    default = 0.0 if avoid is None else float(avoid.safety)
    return np.concatenate(wished), _joined(straight, False, sizes), _joined(safety, default, sizes), seen


def _joined(parts: Sequence[np.ndarray | None], missing: Any, sizes: Sequence[int]) -> np.ndarray | None:
    """The pieces' ``parts`` end to end, ``missing`` in each row of a piece that gave none."""
    if all(part is None for part in parts):
        return None
    return np.concatenate([np.full(size, missing) if part is None else part for part, size in zip(parts, sizes)])
