"""Timers: when each part of a robot runs, in simulation steps.

A timer belongs to a robot. It stays off while ``current_time <= delay`` (start-up delay);
afterwards each entry ``{"delay": gap, "tag": tag, "call": callable}`` runs
``call(*param[tag])`` whenever ``gap`` steps have passed since it last ran (initially at 0).
``create_timer`` and ``update_timers`` (the current world's timers) live in :mod:`dream.world`;
this module imports nothing of DREAM. :func:`due` and :func:`last_due` are the closed form of the
same rule for a whole swarm's timers.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np


@dataclass
class _Entry:
    delay: float
    tag: str
    call: Callable[..., Any]
    ptime: float = 0  # time of the last activation


class Timer:
    """Activates a robot's callbacks at their own rates.

    Parameters
    ----------
    robot_id : int
        Robot the timer belongs to (used in error messages).
    timer_delay : float
        Start-up delay: nothing runs while ``current_time <= timer_delay``.
    list_of_timers : list of dict
        Entries with keys ``delay`` (steps between activations), ``tag`` (key into the params
        dict of :meth:`update`) and ``call`` (the callable).
    """

    def __init__(self, robot_id: int, timer_delay: float, list_of_timers: Sequence[Mapping[str, Any]]) -> None:
        self.robot_id = robot_id
        self.timer_delay = _steps(timer_delay, f"timer of robot {robot_id}: start-up delay")
        self.current_time: float = 0
        self.list_of_timers = [self._entry(i, spec) for i, spec in enumerate(list_of_timers)]

    def _entry(self, index: int, spec: Mapping[str, Any]) -> _Entry:
        where = f"timer of robot {self.robot_id}, entry {index}"
        if not isinstance(spec, Mapping):
            raise TypeError(f"{where}: must be a dict with keys 'delay', 'tag', 'call', got {type(spec).__name__}")
        missing = [key for key in ("delay", "tag", "call") if key not in spec]
        if missing:
            raise KeyError(f"{where}: missing key(s) {', '.join(map(repr, missing))}")
        if not callable(spec["call"]):
            raise TypeError(
                f"{where} (tag {spec['tag']!r}): 'call' must be callable, got {type(spec['call']).__name__}"
            )
        return _Entry(_steps(spec["delay"], f"{where} (tag {spec['tag']!r}): 'delay'"), spec["tag"], spec["call"])

    def update(self, current_time: float, param: Mapping[str, Sequence[Any]]) -> None:
        """Run every entry that is due at ``current_time`` with its arguments ``param[tag]``."""
        self.current_time = current_time
        if current_time <= self.timer_delay:
            return
        for entry in self.list_of_timers:
            if current_time - entry.ptime >= entry.delay:
                entry.ptime = current_time
                entry.call(*self._arguments(entry.tag, param))

    def _arguments(self, tag: str, param: Mapping[str, Sequence[Any]]) -> Sequence[Any]:
        if tag not in param:
            given = ", ".join(map(repr, param)) or "none"
            raise KeyError(
                f"timer of robot {self.robot_id}: tag {tag!r} is not in the params dict (tags given: {given})"
            )
        args = param[tag]
        if not isinstance(args, (tuple, list)):
            raise TypeError(
                f"timer of robot {self.robot_id}: params[{tag!r}] must be a tuple of arguments, "
                f"got {type(args).__name__} (one argument is written as {tag!r}: (x,))"
            )
        return args


def last_due(step: int, start_delay: Any, gap: int) -> np.ndarray:
    """The last step up to integer step ``step`` at which a :class:`Timer` entry of ``gap`` steps
    ran (-1 if none yet), for timers of start-up delays ``start_delay`` ``(n,)`` (integers) on an
    exact clock: the closed form of :meth:`Timer.update`'s rule, for swarm modes that keep
    per-robot rates without timer objects.

    The entry first runs at the first step after the start-up delay that is at least ``gap``
    steps after 0 (its initial last activation), then every ``gap`` steps (every step for 0).
    """
    first = np.maximum(np.asarray(start_delay) + 1, gap)
    every = max(gap, 1)
    return np.where(step >= first, first + (step - first) // every * every, -1)


def due(step: int, start_delay: Any, gap: int) -> np.ndarray:
    """Whether the entry runs at ``step`` (see :func:`last_due`): ``(n,)`` bool."""
    return last_due(step, start_delay, gap) == step


def staggered(ids: Any, first: int, spread: int) -> np.ndarray:
    """Start-up delays ``(n,)`` (steps) of robots ``ids`` ``(n,)``: ``first`` plus ``id % spread``, so
    that a share of the team decides at each of ``spread`` neighbouring steps (the built-in
    experiments' staggered start)."""
    return first + np.asarray(ids, dtype=np.int64) % spread


def _steps(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value) or value < 0:
        raise ValueError(f"{what} must be a finite number of steps >= 0, got {value!r}")
    return cast(float, value)  # an int stays an int: timers count whole steps exactly
