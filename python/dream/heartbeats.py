"""A heartbeat failure detector: which robots a robot takes for crashed, from its own radio rounds.

Each robot counts its radio rounds as its heartbeat and sends the highest heartbeat it knows
of every robot; receivers keep the element-wise maximum, so heartbeats spread like gossip and
a robot need not hear another directly. A robot heard from once whose heartbeat has not
risen for ``silence`` of this robot's own rounds is taken for crashed (its radio fell
silent). Rounds are local: no clock is shared. Used by affine-formation (survivors stop
listening to the crashed); hrvo-circle's barrier has a bounded one (:func:`dream.rules.watch_ends`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike


class Heartbeats:
    """What one robot knows of the heartbeats of ``n`` robots (itself is ``me``).

    Attributes
    ----------
    beats : (n,) int ndarray
        The latest heartbeat known of each robot (0: none yet); what the robot sends.
    news : (n,) int ndarray
        This robot's round in which each heartbeat last rose.
    rounds : int
        This robot's radio rounds so far: its own heartbeat.
    """

    def __init__(self, n: int, me: int, silence: int) -> None:
        self.me = me
        self.silence = silence
        self.beats = np.zeros(n, dtype=np.int64)
        self.news = np.zeros(n, dtype=np.int64)
        self.rounds = 0

    def round(self, heard: Sequence[ArrayLike]) -> None:
        """One radio round: merge the heartbeat vectors ``heard`` ``(n,)`` each (arrays or
        :meth:`sent` tuples), and beat."""
        self.rounds += 1
        if len(heard):
            latest = np.max(np.asarray(heard), axis=0)
            rose = latest > self.beats
            self.beats[rose], self.news[rose] = latest[rose], self.rounds
        self.beats[self.me], self.news[self.me] = self.rounds, self.rounds

    def sent(self) -> tuple[int, ...]:
        """The heartbeats to send, as plain integers (many times faster to copy than an array)."""
        return tuple(self.beats.tolist())

    @property
    def alive(self) -> np.ndarray:
        """``(n,)`` bool: robots not taken for crashed (never heard of, or heard of lately)."""
        return (self.beats == 0) | (self.rounds - self.news <= self.silence)
