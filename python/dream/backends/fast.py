"""The Fast backend: DREAM's own simulator with exactly the Robotarium's semantics.

Same velocity thresholding, same forward-Euler unicycle update and angle wrapping, same
validation criteria as rps, but any number of robots, any arena, an O(n) collision check and no
drawing. Given the same initial poses and commands it reproduces rps's poses (to 1e-9).
"""

from __future__ import annotations

from typing import Any

from dream import kernels
from dream.backends.base import Backend
from dream.specs import ROBOTARIUM, RPS, ArenaSpec, SimulatorSpec


class Fast(Backend):
    """Embedded unicycle simulator for any number of robots (see module docs)."""

    name = "fast"

    def __init__(self, initial_conditions: Any, arena: ArenaSpec = ROBOTARIUM, sim: SimulatorSpec = RPS) -> None:
        super().__init__(initial_conditions, arena, sim)

    def _advance(self) -> None:
        self._poses = kernels.unicycle_step(self._poses, self.velocities, self.time_step)
