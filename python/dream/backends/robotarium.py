"""The Robotarium backend: the Georgia Tech simulator ``rps``, driven headless.

Works with ``rps`` 0.0.0 (PyPI ``robotarium-python-simulator``) and the lab's rps 2.x: the
simulator is built with keyword arguments and only the API common to both is used. rps always
runs without its own figure (rps 0.0.0's figure fails on matplotlib >= 3.8); DREAM draws.
"""

from __future__ import annotations

import functools
import inspect
from typing import Any

import numpy as np

from dream.backends.base import Backend
from dream.specs import ROBOTARIUM, RPS

#: rps refuses more robots than this.
MAX_ROBOTS = 50


def rps_available() -> bool:
    """Whether the ``rps`` package can be imported."""
    try:
        import rps.robotarium  # noqa: F401
    except ImportError:
        return False
    return True


class Robotarium(Backend):
    """The real Robotarium simulator behind DREAM's backend interface.

    Parameters
    ----------
    initial_conditions : (3, n) array_like
        Initial poses; at most 50 robots (rps's limit) in the Robotarium arena.
    sim_in_real_time : bool
        Passed to rps (it only matters when rps draws, which DREAM never asks for).
    """

    name = "robotarium"

    def __init__(self, initial_conditions: Any, *, sim_in_real_time: bool = False) -> None:
        super().__init__(initial_conditions, ROBOTARIUM, RPS)
        if self.number_of_robots > MAX_ROBOTS:
            raise ValueError(
                f"the Robotarium runs at most {MAX_ROBOTS} robots, got {self.number_of_robots}: use backend='fast'"
            )
        from rps import robotarium

        self.rps = robotarium.Robotarium(
            number_of_robots=self.number_of_robots,
            show_figure=False,
            sim_in_real_time=sim_in_real_time,
            initial_conditions=self._poses.copy(),
        )
        # rps 0.0.0's `_validate(errors={})` shares one dict between all instances, so counts
        # would leak from one simulation to the next; give this instance a dict of its own.
        validate = self.rps._validate
        if "errors" in inspect.signature(validate).parameters:
            self.rps._validate = functools.partial(validate, errors={})

    def _advance(self) -> None:
        self.rps.get_poses()
        # rps thresholds the array it is given in place and keeps a reference: give it a copy.
        self.rps.set_velocities(np.arange(self.number_of_robots), self.velocities.copy())
        self.rps.step()
        self._poses = np.array(self.rps.poses, dtype=np.float64)
