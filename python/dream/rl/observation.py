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
message gives and the robot's odometry (of equal distances, the first detection or message the
robot got comes first): all of it is what the robot knows, nothing the world alone knows. The
``k`` nearest of each robot are picked in one pass over its entries, in Rust
(:func:`dream.kernels.segment_nearest` with ``k``; for messages,
:func:`dream.kernels.segment_nearest_to`, which reads their positions where they lie).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from dream import kernels
from dream.swarm import View

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
        m, k, at = len(view), self.k, self.slices
        out = np.zeros((m, self.size), dtype=np.float32)
        pose = view.pose
        out[:, at["pose"]] = np.column_stack((pose[:, :2], np.cos(pose[:, 2]), np.sin(pose[:, 2])))
        if goals is not None:
            out[:, at["goal"]] = np.take(goals, view.ids, axis=0) - pose[:, :2]
        if not k:
            return out
        seen = view.seen
        entries = kernels.segment_nearest(seen["distance"], seen.offsets, k)
        self._fill(out, "seen", entries, [seen.pick(c, entries) for c in SEEN])
        heard = view.heard
        if "x" in heard.names and heard.offsets[-1]:
            # Ranked in Rust by each message's squared distance from the robot's odometry, the
            # fields read on the board in place, and only the k picked taken less the odometry.
            entries = heard.nearest_to(["x", "y"], pose[:, :2], k)
            here = [pose[:, 0, None], pose[:, 1, None]]
            self._fill(out, "heard", entries, [heard.pick(c, entries) - at for c, at in zip("xy", here)])
        return out

    def _fill(self, out: np.ndarray, part: str, entries: np.ndarray, values: list[np.ndarray]) -> None:
        """Write ``values`` (each ``(m, k)``, picked at ``entries``; -1: an empty slot, left zero)
        into the slots of ``part`` of the rows ``out``, and the slots' mask."""
        m, k = entries.shape
        filled = entries >= 0
        slots = np.zeros((m, k, len(values)), dtype=np.float32)
        for c, value in enumerate(values):
            slots[..., c] = np.where(filled, value, 0.0)
        out[:, self.slices[part]] = slots.reshape(m, -1)
        out[:, self.slices[f"{part}_mask"]] = filled
