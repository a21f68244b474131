"""What a learner observes: its odometry, its goal, its movement sensor's detections and its radio
inbox, the last two padded to the ``k`` nearest with a mask, as one flat float32 row per robot.

A row is the concatenation of these parts (:class:`Layout` gives each one's place):

=============  ==========  ====================================================================
part           shape       what
=============  ==========  ====================================================================
``pose``       ``(4,)``    odometry ``x, y`` (m), ``cos theta, sin theta``; zeros until read
``goal``       ``(2,)``    the goal less the odometry position (m); only if the experiment has goals
``seen``       ``(k, 4)``  the ``k`` nearest detections: the other's ``dx, dy`` (m), ``vx, vy`` (m/s)
``seen_mask``  ``(k,)``    1 where a detection fills the slot
``heard``      ``(k, 2)``  the ``k`` nearest messages: the sender's position less the robot's (m)
``heard_mask`` ``(k,)``    1 where a message fills the slot
=============  ==========  ====================================================================

Nearest means by detected distance, and for messages by the distance between the position a
message gives and the robot's odometry: all of it is what the robot knows, nothing the world
alone knows.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from dream.swarm import Neighbourhood, View

if TYPE_CHECKING:
    from gymnasium import spaces

SEEN = ("dx", "dy", "vx", "vy")  #: the detection columns a learner observes


class Layout:
    """Where each part of an observation row lies (see the module docs).

    Parameters
    ----------
    k : int
        Slots for detections and for messages.
    goals : bool
        Whether rows carry a goal.
    """

    def __init__(self, k: int, goals: bool) -> None:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 0:
            raise ValueError(f"k (detections and messages observed) must be a whole number >= 0, got {k!r}")
        self.k = int(k)
        shapes: dict[str, tuple[int, ...]] = {"pose": (4,), **({"goal": (2,)} if goals else {})}
        shapes |= {"seen": (k, len(SEEN)), "seen_mask": (k,), "heard": (k, 2), "heard_mask": (k,)}
        self.shapes = shapes
        self.slices: dict[str, slice] = {}
        start = 0
        for name, shape in shapes.items():
            size = int(np.prod(shape))
            self.slices[name] = slice(start, start + size)
            start += size
        self.size = start  #: the length of a row

    def flat_space(self) -> spaces.Box:
        """The space of one row."""
        from gymnasium import spaces  # here: a lab bundle's policy observes without gymnasium

        return spaces.Box(-np.inf, np.inf, (self.size,), np.float32)

    def dict_space(self) -> spaces.Dict:
        """The space of one row as named parts (masks as :class:`~gymnasium.spaces.MultiBinary`)."""
        from gymnasium import spaces

        parts: dict[str, spaces.Space] = {}
        for name, shape in self.shapes.items():
            parts[name] = (
                spaces.MultiBinary(shape) if name.endswith("mask") else spaces.Box(-np.inf, np.inf, shape, np.float32)
            )
        parts["pose"] = spaces.Box(
            np.array([-np.inf, -np.inf, -1, -1], np.float32), np.array([np.inf, np.inf, 1, 1], np.float32)
        )
        return spaces.Dict(parts)

    def as_dict(self, row: np.ndarray) -> dict[str, np.ndarray]:
        """One row's parts (copies), masks as int8."""
        return {
            name: (row[part].astype(np.int8) if name.endswith("mask") else row[part].copy()).reshape(self.shapes[name])
            for name, part in self.slices.items()
        }

    def rows(self, view: View, goals: np.ndarray | None) -> np.ndarray:
        """The observation rows ``(m, size)`` of the robots of ``view``; ``goals`` ``(n, 2)``."""
        m, k = len(view), self.k
        out = np.zeros((m, self.size), dtype=np.float32)
        pose = view.pose
        out[:, self.slices["pose"]] = np.column_stack((pose[:, :2], np.cos(pose[:, 2]), np.sin(pose[:, 2])))
        if goals is not None:
            out[:, self.slices["goal"]] = goals[view.ids] - pose[:, :2]
        seen = view.seen
        found, mask = padded(seen, np.column_stack([seen[name] for name in SEEN]), seen["distance"], k)
        out[:, self.slices["seen"]] = found.reshape(m, -1)
        out[:, self.slices["seen_mask"]] = mask
        heard = view.heard
        if "x" in heard.names:
            here = pose[heard.owner, :2]
            offsets = np.column_stack((heard["x"], heard["y"])) - here
            found, mask = padded(heard, offsets, np.hypot(offsets[:, 0], offsets[:, 1]), k)
            out[:, self.slices["heard"]] = found.reshape(m, -1)
            out[:, self.slices["heard_mask"]] = mask
        return out


def padded(rows: Neighbourhood, values: np.ndarray, key: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Each row's ``k`` entries of smallest ``key`` (in that order; ties: the first entry), padded
    with zeros: ``(m, k, c)`` values of ``values`` ``(e, c)`` and the ``(m, k)`` mask of filled
    slots. Picks the nearest ``k`` times over (:meth:`Neighbourhood.nearest`, rows in parallel in
    Rust): for a few slots, cheaper than sorting every row."""
    m, c = len(rows), values.shape[1]
    out, mask = np.zeros((m, k, c)), np.zeros((m, k))
    left = np.array(key, dtype=np.float64)
    for slot in range(min(k, int(rows.count.max(initial=0)))):
        best = rows.nearest(left)
        found = np.flatnonzero(best >= 0)
        out[found, slot] = values[best[found]]
        mask[found, slot] = 1.0
        left[best[found]] = np.nan  # taken: the next pass skips it
    return out, mask
