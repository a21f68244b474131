"""Robot by robot: the view of every robot deciding now, cut into one view per robot, and their
decisions put back together.

The engine perceives for all the deciding robots at once, as for the swarm, and carries out
their wishes at once, with the same kernels: each kernel's rows are independent of one another,
so one call over k rows gives the bits of k calls over one (the both-ways tests compare whole
runs). Only :meth:`~dream.swarm.robot.SwarmRobot.decide` runs once per robot, on its own row: a
decision sees no other robot's view. Messages sent now are heard from the next step on either
way, so the order the robots decide in changes nothing.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from typing import Any

import numpy as np

from dream.swarm.neighbourhood import Deferred, Neighbourhood
from dream.swarm.robot import Avoid, View


def cut(whole: View) -> list[View]:
    """One view per row of ``whole`` (in its order), each a robot's own: slices of ``whole``'s
    arrays (read-only where ``whole``'s are), its own memory rows, nothing said or chosen yet."""
    k = len(whole)
    seen, heard = _rows(whole.seen, k), _rows(whole.heard, k)
    obstacles: Sequence[Neighbourhood | None] = [None] * k if whole.obstacles is None else _rows(whole.obstacles, k)
    ids, clock, pose, memory, command = whole.ids, whole.clock, whole.pose, whole.memory, whole.command
    return [
        View(
            ids[r : r + 1],
            clock[r : r + 1],
            pose[r : r + 1],
            seen[r],
            heard[r],
            {key: values[r : r + 1] for key, values in memory.items()},
            obstacles[r],
            None if command is None else command[r : r + 1],
            board_cells=whole.board_cells,
        )
        for r in range(k)
    ]


def _rows(hood: Neighbourhood, k: int) -> list[Neighbourhood]:
    """``hood``'s rows, each a neighbourhood of one row. An inbox found on first use (found then,
    for all the rows) and a neighbourhood without entries (a sensor the robot lacks, say) are cut
    when a robot first reads its row: most decisions never read them."""
    if isinstance(hood, Deferred) or not hood.offsets[-1]:
        return [Deferred(partial(_row_of, hood, r)) for r in range(k)]
    bounds = hood.offsets.tolist()
    return [_row(hood, start, end) for start, end in zip(bounds[:-1], bounds[1:])]


def _row_of(hood: Neighbourhood, r: int) -> Neighbourhood:
    return _row(hood, int(hood.offsets[r]), int(hood.offsets[r + 1]))


def _row(hood: Neighbourhood, start: int, end: int) -> Neighbourhood:
    """Entries ``start:end`` of ``hood`` as a neighbourhood of one row, read-only as ``hood`` (its
    slices are, as views of read-only arrays)."""
    offsets = np.array([0, end - start])
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
    whole: View, settled: Sequence[tuple[Any, Any, Any, Any, Any]], avoid: Avoid | None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, Neighbourhood]:
    """The checked decisions of the pieces of :func:`cut` (``settled``: each one's wished
    velocities, rows driven direct, safety radii and detections heeded, None where it chose
    nothing) as ``whole``'s: the wishes, the rows driven direct, the safety radii (the Avoid's
    where a robot kept them) and the detections heeded (all of a robot's where it chose none)."""
    wished, straight, safety, heeded, _ = zip(*settled)
    seen = whole.seen
    if any(h is not None for h in heeded):
        counts = np.diff(seen.offsets).tolist()
        seen = seen.where(
            np.concatenate([np.ones(c, dtype=bool) if h is None else h for h, c in zip(heeded, counts, strict=True)])
        )
    default = np.full(1, 0.0 if avoid is None else float(avoid.safety))
    return np.concatenate(wished), _joined(straight, np.zeros(1, dtype=bool)), _joined(safety, default), seen


def _joined(parts: Sequence[np.ndarray | None], missing: np.ndarray) -> np.ndarray | None:
    if all(part is None for part in parts):
        return None
    return np.concatenate([missing if part is None else part for part in parts])
