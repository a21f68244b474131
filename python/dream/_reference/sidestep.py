"""Stepping aside on arrays: the rule of :func:`dream.rules.sidestep_preference` and
:func:`~dream.rules.sidestep_update` for many robots, and on the swarm engine's tables (the
definition of :mod:`dream._core`'s ``sidestep_ask`` and ``sidestep_mark``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream._checks import FloatArray


def preference(desired: Any, sidestep: Any, side: Any) -> tuple[FloatArray, Any]:
    """``(wanted, sidestep)``: ``desired`` ``(..., 2)``, turned by -90 degrees times ``side`` where
    ``sidestep`` is above zero; the counters one decision fewer."""
    desired = np.asarray(desired, dtype=np.float64)
    sidestep = np.asarray(sidestep)
    right = np.stack((desired[..., 1], -desired[..., 0]), axis=-1)
    aside = (sidestep > 0)[..., None]
    wanted = np.where(aside, np.asarray(side, dtype=np.float64)[..., None] * right, desired)
    return wanted, np.maximum(sidestep - 1, 0)


def update(chosen: Any, desired: Any, sidestep: Any, side: Any, updates: int) -> tuple[Any, Any]:
    """``(sidestep, side)`` after HRVO chose ``chosen`` ``(..., 2)``: a robot stopped though it
    wished to move (a NaN component counts as moving, as in ``numpy.any``) steps aside for
    ``updates`` decisions, to its right, or to the other side if its counter was running."""
    chosen, desired = np.asarray(chosen), np.asarray(desired)
    stopped = (chosen[..., 0] == 0) & (chosen[..., 1] == 0)
    blocked = stopped & ((desired[..., 0] != 0) | (desired[..., 1] != 0))
    sidestep = np.asarray(sidestep)
    side = np.asarray(side, dtype=np.float64)
    new_side = np.where(blocked, np.where(sidestep > 0, -side, 1.0), side)
    return np.where(blocked, updates, sidestep), new_side


def sidestep_ask(
    want: FloatArray, rows: np.ndarray, counters: np.ndarray, sides: FloatArray, steer: np.ndarray | None = None
) -> FloatArray:
    """What robots ``rows`` ask HRVO for, ``want`` ``(k, 2)`` by :func:`preference`; their
    ``counters`` ``(n,)`` counted down in place. With ``steer`` ``(k,)``, only the rows it flags
    (the others ask for ``want``)."""
    asked = np.array(want, dtype=np.float64)
    at = slice(None) if steer is None else np.flatnonzero(steer)
    asked[at], counters[rows[at]] = preference(asked[at], counters[rows[at]], sides[rows[at]])
    return asked


def sidestep_mark(
    chosen: FloatArray,
    want: FloatArray,
    rows: np.ndarray,
    counters: np.ndarray,
    sides: FloatArray,
    updates: int,
    steer: np.ndarray | None = None,
) -> None:
    """:func:`update` of robots ``rows``' ``counters`` and ``sides`` ``(n,)``, in place; with ``steer``
    ``(k,)``, of the rows it flags."""
    at = slice(None) if steer is None else np.flatnonzero(steer)
    ids = rows[at]
    counters[ids], sides[ids] = update(chosen[at], want[at], counters[ids], sides[ids], updates)
