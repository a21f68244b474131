"""Radios: how robots talk. Each robot publishes on its world's message board and downloads
the messages of the robots it can hear (by range, or over a communication graph).

Beyond the original: ``loss`` drops each received message with that probability (seeded), and
``latency`` delays a published message by that many steps of the world's clock. The
defaults (no loss, no latency) behave as the original.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from dream._checks import RobotCallback, as_array, check_nonnegative, check_robot_id
from dream.world import current_world

Callback = Callable[[list[Any]], Any]


class Radio:
    """Base radio of robot ``robot_id``: publishes on the board of the world it was created in."""

    def __init__(self, robot_id: int, tag: str = "Radio", *, loss: float = 0.0, latency: int = 0) -> None:
        self.robot_id = robot_id
        self.tag = tag
        self.pos_x = 0.0
        self.pos_y = 0.0
        self.rot_w = 0.0
        if not 0.0 <= loss <= 1.0:
            raise ValueError(f"`loss` is a probability in [0, 1], got {loss}")
        if isinstance(latency, bool) or not isinstance(latency, (int, np.integer)) or latency < 0:
            raise ValueError(f"`latency` must be a whole number of steps >= 0, got {latency!r}")
        self.loss = float(loss)
        self.latency = int(latency)
        self.world = current_world()

    def send_data(self, data: Any) -> None:
        """Publish ``data`` under this robot's id (a copy: later changes to ``data`` stay private)."""
        self.world.publish(self.robot_id, data, self.latency)

    def update(self, x: Any) -> None:
        """Take the attached robot's pose from the pose array ``x`` ``(3, n)``."""
        poses = self.world.checked_poses(x)
        check_robot_id(self.robot_id, poses.shape[1], "x")
        self.pos_x, self.pos_y, self.rot_w = poses[:, self.robot_id].tolist()
        self._poses = poses

    callback: Callback = RobotCallback()  # type: ignore[assignment]

    def _exchange(self, callback: Callback, senders: np.ndarray) -> None:
        data = callback(self.world.receive(np.asarray(senders).tolist(), self.loss, self.robot_id))
        if data is not None:
            self.send_data(data)


class RangeRadio(Radio):
    """Downloads the messages of the robots within ``range`` (m, inclusive).

    On :meth:`update` the radio calls ``callback(messages)`` with the visible messages of the
    robots in range, by increasing id (never its own), and publishes what the callback returns
    (nothing when it returns ``None``).
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callback,
        range: float = 1.0,  # noqa: A002 (original name)
        *,
        loss: float = 0.0,
        latency: int = 0,
    ) -> None:
        super().__init__(robot_id, tag, loss=loss, latency=latency)
        self.callback = callback
        self.range = check_nonnegative(range, "range")

    def update(self, x: Any) -> None:
        """Exchange messages with the robots in range, given the poses ``x`` ``(3, n)``."""
        super().update(x)
        senders, _ = self.world.neighbours_of(self._poses, self.robot_id, self.range)
        self._exchange(self.callback, senders)


class GraphRadio(Radio):
    """Downloads the messages of the robots linked to this one in ``adjacency``.

    ``adjacency`` is an ``(n, n)`` matrix; robot j is heard when ``adjacency[robot_id, j] > 0``
    and j != robot_id. Messages come by increasing id; what the callback returns is published.
    """

    def __init__(
        self,
        robot_id: int,
        tag: str,
        callback: Callback,
        adjacency: Any,
        *,
        loss: float = 0.0,
        latency: int = 0,
    ) -> None:
        super().__init__(robot_id, tag, loss=loss, latency=latency)
        self.callback = callback
        matrix = as_array(adjacency, "adjacency", (None, None))
        if matrix.shape[0] != matrix.shape[1]:
            raise ValueError(f"`adjacency` must be square (n, n), got {matrix.shape}")
        check_robot_id(robot_id, matrix.shape[0], "adjacency")
        links = np.flatnonzero(matrix[robot_id] > 0)
        self.adjacency = matrix
        self.links = links[links != robot_id]

    def update(self, x: Any = None) -> None:
        """Exchange messages with the linked robots (``x``, if given, updates the radio's pose)."""
        if x is not None:
            super().update(x)
        self._exchange(self.callback, self.links)
