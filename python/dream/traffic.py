"""Each robot's radio traffic so far: messages sent, heard and lost, counted where they happen.

The world counts for robot objects (:meth:`dream.World.publish`, :meth:`dream.World.receive`),
the engine for a :class:`~dream.swarm.SwarmRobot`'s swarm (:mod:`dream.swarm.engine`); the
trajectory log (:mod:`dream.trajectory_log`) reads them. A message is heard each time it is
delivered to a robot's inbox (a board message read at two decisions counts twice), and lost
when the radio's or the world's losses keep it from an inbox it would have reached.
"""

from __future__ import annotations

import numpy as np


class Traffic:
    """Counts of ``n`` robots, each an ``(n,)`` int64 array, from 0 at the run's start.

    Attributes
    ----------
    sent, heard, lost : (n,) int64 ndarray
    """

    def __init__(self, n: int) -> None:
        self.sent = np.zeros(n, dtype=np.int64)
        self.heard = np.zeros(n, dtype=np.int64)
        self.lost = np.zeros(n, dtype=np.int64)

    def received(
        self, rows: np.ndarray, offsets: np.ndarray, through: np.ndarray | None = None, lost: np.ndarray | None = None
    ) -> None:
        """Count the messages of inboxes given in CSR form: robot ``rows[i]`` was offered the
        messages ``offsets[i]:offsets[i + 1]``, of which ``through`` ``(m,)`` bool got through
        (``None``: all did, and ``lost`` ``(k,)``, where given, counts those lost before: the
        losses drawn where the messages were found)."""
        offered = np.diff(offsets)
        if through is None:
            np.add.at(self.heard, rows, offered)
            if lost is not None:
                np.add.at(self.lost, rows, lost)
            return
        passed = np.concatenate(([0], np.cumsum(through)))
        got = passed[offsets[1:]] - passed[offsets[:-1]]
        np.add.at(self.heard, rows, got)
        np.add.at(self.lost, rows, offered - got)
