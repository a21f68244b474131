"""What every simulator backend shares: the Robotarium call protocol and DREAM's bookkeeping."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from dream import kernels
from dream._checks import FloatArray, as_poses
from dream.kernels._dispatch import kernel_input
from dream.specs import ROBOTARIUM, RPS, ArenaSpec, SimulatorSpec


class Backend(ABC):
    """A simulator with the Robotarium interface, plus what DREAM needs.

    The protocol is the Robotarium's: each iteration calls :meth:`get_poses` once, then
    :meth:`set_velocities`, then :meth:`step`. Before each step the backend counts violations
    by the criteria of the rps generation ``spec`` follows (robots outside the arena, colliders
    closer than a diameter, commands beyond the wheel limit) into :attr:`violations`. Scripts
    end with :meth:`call_at_scripts_end` (rps 0.0.0) or :meth:`debug` (rps 2.1): both print the
    same report, so a script written for either generation runs on every backend.

    Attributes
    ----------
    number_of_robots : int
    arena : ArenaSpec
    spec : SimulatorSpec
        Time step and the limits the simulator enforces.
    velocities : (2, n) ndarray
        The commands applied at the next step (after thresholding).
    iterations : int
        Steps taken.
    violations : dream.kernels.Violations
        Counts summed over all steps so far.
    in_collision : (m,) int64 ndarray
        The robots in a collision at the last step's count, ascending.
    """

    name = "backend"

    def __init__(self, initial_conditions: Any, arena: ArenaSpec = ROBOTARIUM, spec: SimulatorSpec = RPS) -> None:
        poses = as_poses(initial_conditions, "initial_conditions")
        self.number_of_robots = poses.shape[1]
        self.arena = arena
        self.spec = spec
        self.time_step = spec.time_step
        self.velocities = np.zeros((2, self.number_of_robots))
        self._requested = np.zeros((2, self.number_of_robots))
        self._ids: np.ndarray | None = None
        self.iterations = 0
        self.violations = kernels.Violations(0, 0, 0)
        self.in_collision = np.zeros(0, dtype=np.int64)
        self._poses = poses.copy()
        self._poses_taken = False
        self._figure: Any = None
        self._axes: Any = None

    @property
    def poses(self) -> FloatArray:
        """Current poses ``(3, n)``, read-only (does not count as :meth:`get_poses`). A step makes
        new poses and never writes into these, so they stay as they were: no copy (24 MB a step
        at a million robots) is needed to keep them."""
        poses = self._poses.view()
        poses.flags.writeable = False
        return poses

    def get_poses(self) -> FloatArray:
        """Poses ``(3, n)`` of all robots; once per :meth:`step`, as on the Robotarium."""
        if self._poses_taken:
            raise RuntimeError("get_poses() can only be called once per step(), as on the Robotarium")
        self._poses_taken = True
        return self._poses.copy()

    def set_velocities(self, ids: Any, velocities: Any) -> None:
        """Command robots ``ids`` with unicycle velocities ``(2, len(ids))`` ``[v; w]``.

        Commands beyond the simulator's limits are clipped as its rps generation clips them
        (:func:`dream.kernels.threshold_velocities`); robots not in ``ids`` keep their previous
        command.
        """
        index = np.atleast_1d(np.asarray(ids))
        if index.dtype.kind not in "iu" or index.ndim != 1:
            raise ValueError(f"`ids` must be a 1-D array of robot ids, got {np.asarray(ids)!r}")
        n = self.number_of_robots
        # Every robot in order (a swarm's step) is one comparison with 0..n-1, and the commands a
        # copy, 20 times faster than writing a million columns by index.
        every = len(index) == n and (n == 0 or (index[0] == 0 and np.array_equal(index, self._every())))
        if not every and len(index) and (index.min() < 0 or index.max() >= n):
            bad = index[(index < 0) | (index >= n)][0]
            raise IndexError(f"robot id {bad} is out of range for a simulation of {n} robots")
        # The kernel checks that every command is finite (on every core): nothing is kept of bad ones.
        commands = kernel_input(velocities, "velocities", (2, len(index)))
        # Kept as given: rps 2.1 checks the actuator limit on commands before clipping them. A new
        # array each time: a caller may hold the last one.
        if every:
            requested = np.array(commands, order="C")
        else:
            requested = self._requested.copy()
            requested[:, index] = commands
        self.velocities = kernels.threshold_velocities(requested, self.spec)
        self._requested = requested

    def _every(self) -> np.ndarray:
        """The ids of every robot in order, ``0..n-1`` (made once)."""
        if self._ids is None:
            self._ids = np.arange(self.number_of_robots)
        return self._ids

    def step(self) -> None:
        """Count this iteration's violations, then advance the simulation by one time step."""
        if not self._poses_taken:
            raise RuntimeError("call get_poses() before each step(), as on the Robotarium")
        checked = self._requested if self.spec.validates_requested else self.velocities
        found, self.in_collision = kernels.validate_each(self._poses, checked, self.arena, self.spec)
        self.violations = kernels.Violations(*(a + b for a, b in zip(self.violations, found)))
        self._advance()
        self.iterations += 1
        self._poses_taken = False

    @abstractmethod
    def _advance(self) -> None:
        """Move the robots by one time step with ``self.velocities``; update ``self._poses``."""

    def call_at_scripts_end(self) -> None:
        """Print the run's duration on the real Robotarium and its violation counts (rps 0.0.0's name)."""
        print(self.summary())

    def debug(self) -> None:
        """Print the same report as :meth:`call_at_scripts_end` (rps 2.1's name for it)."""
        print(self.summary())

    def summary(self) -> str:
        """Iterations, real-time duration and violation counts, in one paragraph."""
        b, c, a = self.violations
        seconds = math.ceil(self.iterations * self.time_step)
        lines = [f"{self.iterations} iterations on the {self.name} backend (~{seconds} s on the Robotarium)."]
        if b or c or a:
            outside = "iteration(s) with robots" if self.spec.boundary_per_iteration else "robot-iteration(s)"
            lines += [
                f"  {b} {outside} outside the boundaries",
                f"  {c} pair-iteration(s) where robots collided",
                f"  {a} iteration(s) where the actuator limits were exceeded",
            ]
        else:
            lines.append("  No errors: acceptance of the experiment on the Robotarium is likely.")
        return "\n".join(lines)

    # -- drawing, for seed-style scripts that add patches (``r.axes.add_patch(...)``) ---------
    @property
    def figure(self) -> Any:
        """A headless matplotlib figure of the arena, created on first use."""
        if self._figure is None:
            self._make_figure()
        return self._figure

    @property
    def axes(self) -> Any:
        """The axes of :attr:`figure`."""
        if self._axes is None:
            self._make_figure()
        return self._axes

    def _make_figure(self) -> None:
        from matplotlib.figure import Figure
        from matplotlib.patches import Rectangle

        self._figure = Figure()
        self._axes = self._figure.add_subplot()
        a = self.arena
        self._axes.add_patch(Rectangle((a.xmin, a.ymin), a.width, a.height, fill=False))
        self._axes.set_xlim(a.xmin - 0.1, a.xmax + 0.1)
        self._axes.set_ylim(a.ymin - 0.1, a.ymax + 0.1)
        self._axes.set_aspect("equal")
