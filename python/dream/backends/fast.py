"""The Fast backend: DREAM's own simulator with exactly the Robotarium's semantics.

Same velocity thresholding, same forward-Euler unicycle update and angle wrapping, same
validation criteria as rps, but any number of robots, any arena, an O(n) collision check and no
drawing. Given the same initial poses and commands it reproduces rps's poses (to 1e-9). It
follows rps 0.0.0's rules by default and rps 2.1's with ``spec=dream.specs.RPS2``, optionally
with 2.1's start-up phase from the chargers (:mod:`dream.backends.startup`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dream import kernels
from dream.backends.base import Backend
from dream.backends.robotarium import as_obstacles
from dream.backends.startup import StartUp
from dream.backends.startup import start_up as drive_from_chargers
from dream.specs import ROBOTARIUM, RPS, RULES, ArenaSpec, SimulatorSpec


class Fast(Backend):
    """Embedded unicycle simulator for any number of robots (see module docs).

    Parameters
    ----------
    initial_conditions : (3, n) array_like
    arena : ArenaSpec
    spec : SimulatorSpec
        The rules to follow: :data:`dream.specs.RPS0` (default) or :data:`dream.specs.RPS2`.
    rules : {"rps0", "rps2"}, optional
        The same by name (:data:`dream.specs.RULES`); give ``spec`` or ``rules``, not both.
    obstacles : (m, 2, 2) array_like, optional
        Line-segment walls (``[k, 0]`` start, ``[k, 1]`` end), as rps 2.1 takes them; the robots'
        distance sensors see them (:class:`dream.DistanceSensor`), the dynamics do not.
    start_up : bool
        Drive the robots from the chargers to ``initial_conditions`` first, as rps 2.1 does
        unless told to skip it; validation is off meanwhile. :attr:`startup` tells how it went.
    rng : numpy.random.Generator, optional
        Draws the charger slots and detours of the start-up phase; default: a fresh generator.
    """

    name = "fast"

    def __init__(
        self,
        initial_conditions: Any,
        arena: ArenaSpec = ROBOTARIUM,
        spec: SimulatorSpec = RPS,
        *,
        rules: str | None = None,
        obstacles: Any = None,
        start_up: bool = False,
        rng: np.random.Generator | None = None,
    ) -> None:
        if rules is not None:
            if rules not in RULES:
                raise ValueError(f"unknown rules {rules!r}: choose one of {', '.join(RULES)}")
            if spec != RPS and spec != RULES[rules]:
                raise ValueError(f"`spec` and `rules={rules!r}` disagree: give one of them")
            spec = RULES[rules]
        super().__init__(initial_conditions, arena, spec)
        self.obstacles = as_obstacles(obstacles)
        self.startup: StartUp | None = None
        if start_up:
            generator = np.random.default_rng() if rng is None else rng
            self.startup = drive_from_chargers(self._poses, generator, arena, spec)
            self._poses = self.startup.poses.copy()

    def _advance(self) -> None:
        self._poses = kernels.unicycle_step(self._poses, self.velocities, self.time_step)
