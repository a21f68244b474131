"""The Robotarium backend: the Georgia Tech simulator ``rps``, driven headless.

Works with both generations of ``rps``: 0.0.0 (PyPI ``robotarium-python-simulator``, 2017) and
the lab's 2.x (2026). The simulator is built with keyword arguments; DREAM counts violations
itself with the rules of the generation found (:data:`dream.specs.RPS0` or
:data:`dream.specs.RPS2`), so its counts equal rps's own. rps always runs without its own
figure (0.0.0's figure fails on matplotlib >= 3.8); DREAM draws.

On 2.x, real-time throttling (on by default there) is off unless asked for. So is the start-up
phase from the chargers in this class (``skip_initialization=False`` runs it; the backend's poses
are then the ones rps reached at its end); :func:`dream.make_robotarium` and :func:`dream.run` run
it by default, as the lab's verifier does, from starts it reaches
(:func:`dream.backends.startup.reachable_starts`).
"""

from __future__ import annotations

import functools
import inspect
from typing import Any

import numpy as np

from dream._checks import FloatArray, as_array
from dream.backends.base import Backend
from dream.specs import ROBOTARIUM, RULES

#: rps refuses more robots than this.
MAX_ROBOTS = 50
#: rps 2.x's start-up phase took 546-5,337 steps to reach the built-ins' starts at their lab sizes
#: (experiment seeds 0-4; seed 0 in ``tests/data/rps21/lab_startup.json``); it loops forever when two
#: initial conditions are closer than its barrier certificate lets robots come: stop it with an error.
MAX_STARTUP_STEPS = 20_000


def rps_available() -> bool:
    """Whether the ``rps`` package can be imported."""
    try:
        import rps.robotarium  # noqa: F401
    except ImportError:
        return False
    return True


def rps_generation() -> str | None:
    """``"rps0"`` for rps 0.0.0, ``"rps2"`` for rps 2.x, ``None`` when rps is not installed.

    Told apart by their end-of-script report: 2.x renamed ``call_at_scripts_end()`` to
    ``debug()`` (the distribution's version number is not reliable for a source checkout).
    """
    try:
        from rps.robotarium import Robotarium as Simulator
    except ImportError:
        return None
    return "rps0" if hasattr(Simulator, "call_at_scripts_end") else "rps2"


def as_obstacles(obstacles: Any) -> FloatArray:
    """Line-segment obstacles as a float64 ``(m, 2, 2)`` array (``[k, 0]`` start, ``[k, 1]`` end).

    ``None`` gives ``(0, 2, 2)``; other shapes or non-finite values are a ``ValueError``.
    """
    if obstacles is None:
        return np.zeros((0, 2, 2))
    return as_array(obstacles, "obstacles", (None, 2, 2))


def _bounded(simulator: type) -> type:
    """rps 2.x's simulator class whose start-up phase raises after :data:`MAX_STARTUP_STEPS` steps."""

    class Bounded(simulator):  # type: ignore[misc, valid-type]
        def step(self) -> None:
            super().step()
            if getattr(self, "initializing", False) and self._iteration > MAX_STARTUP_STEPS:
                raise RuntimeError(
                    f"rps's start-up phase did not bring the robots to their initial conditions in "
                    f"{MAX_STARTUP_STEPS} steps (it never reaches two initial conditions closer than its "
                    "barrier certificate lets robots come): move them apart with "
                    "dream.backends.startup.reachable_starts, or pass skip_initialization=True"
                )

    return Bounded


class Robotarium(Backend):
    """The real Robotarium simulator behind DREAM's backend interface.

    Parameters
    ----------
    initial_conditions : (3, n) array_like
        Initial poses; at most 50 robots (rps's limit) in the Robotarium arena.
    sim_in_real_time : bool
        Passed to rps: with 2.x it makes every step wait for 0.033 s of wall time.
    skip_initialization : bool, optional
        rps 2.x only. ``False`` first drives the robots from the chargers to
        ``initial_conditions`` (2.x's own default, and what the lab's verifier does; it never
        reaches initial conditions closer than ~0.35 m apart: see
        :func:`dream.backends.startup.reachable_starts`). This class's default (``None``) starts at
        the initial conditions, as rps 0.0.0 does.
    obstacles : (m, 2, 2) array_like, optional
        rps 2.x only: line-segment walls that its distance sensors see.
    use_distance_sensors : bool
        rps 2.x only: simulate the infrared distance sensors (``self.rps.get_distances()``).
    """

    name = "robotarium"

    def __init__(
        self,
        initial_conditions: Any,
        *,
        sim_in_real_time: bool = False,
        skip_initialization: bool | None = None,
        obstacles: Any = None,
        use_distance_sensors: bool = False,
    ) -> None:
        generation = rps_generation()
        if generation is None:
            raise ImportError("the Robotarium backend needs the `rps` package (robotarium-python-simulator)")
        super().__init__(initial_conditions, ROBOTARIUM, RULES[generation])
        if self.number_of_robots > MAX_ROBOTS:
            raise ValueError(
                f"the Robotarium runs at most {MAX_ROBOTS} robots, got {self.number_of_robots}: use backend='fast'"
            )
        self.obstacles = as_obstacles(obstacles)
        from rps import robotarium

        options: dict[str, Any] = {
            "number_of_robots": self.number_of_robots,
            "show_figure": False,
            "sim_in_real_time": bool(sim_in_real_time),
            "initial_conditions": self._poses.copy(),
        }
        simulator = robotarium.Robotarium
        if generation == "rps2":
            simulator = _bounded(simulator)
            options["skip_initialization"] = skip_initialization is not False
            options["use_distance_sensors"] = bool(use_distance_sensors)
            options["obstacles"] = self.obstacles if len(self.obstacles) else None
        elif skip_initialization is not None or len(self.obstacles) or use_distance_sensors:
            raise ValueError(
                "rps 0.0.0 has no start-up phase, obstacles or distance sensors: "
                "`skip_initialization`, `obstacles` and `use_distance_sensors` need rps 2.x"
            )
        self.rps = simulator(**options)
        # rps 0.0.0's `_validate(errors={})` shares one dict between all instances, so counts
        # would leak from one simulation to the next; give this instance a dict of its own.
        validate = self.rps._validate
        parameter = inspect.signature(validate).parameters.get("errors")
        if parameter is not None and parameter.default is not inspect.Parameter.empty:
            self.rps._validate = functools.partial(validate, errors={})
        # After 2.x's start-up phase the robots are near, not at, the initial conditions.
        self._poses = self._rps_poses()

    def _rps_poses(self) -> FloatArray:
        # 0.0.0 keeps the poses in `poses`, 2.x in `_poses`; get_poses() would count as a call.
        poses = self.rps.poses if hasattr(self.rps, "poses") else self.rps._poses
        return np.array(poses, dtype=np.float64)

    def _advance(self) -> None:
        self.rps.get_poses()
        # rps thresholds the array it is given in place and keeps a reference: give it a copy.
        self.rps.set_velocities(np.arange(self.number_of_robots), self._requested.copy())
        self.rps.step()
        self._poses = self._rps_poses()
