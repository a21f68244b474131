"""One run's part that is DREAM's, around a loop that makes the simulator's calls:
:class:`Stepper`, shared by :func:`dream.run`, an exported bundle's ``main.py`` and the learning
environments."""

from __future__ import annotations

from typing import Any

import numpy as np

from dream.backends.base import Backend
from dream.experiments.result import ExperimentResult
from dream.experiments.spec import Experiment
from dream.faults import Faults, FaultState
from dream.frames import Frame, fault_status, measures_title
from dream.specs import GRITSBOT, RPS, SimulatorSpec
from dream.swarm import Engine
from dream.traffic import Traffic
from dream.world import World


class Stepper:
    """DREAM's part of one run, around a loop that makes the Robotarium's calls itself.

    :func:`run` and the ``main.py`` of an exported bundle (:mod:`dream.export`) both drive their
    simulator through this, so the experiment sees the same sequence of hooks in either::

        stepper = Stepper(exp, n, world, rules)  # the experiment builds its robots
        sim = ...                             # a simulator started at stepper.initial_conditions
        stepper.attach(sim, faults)
        for t in range(cap):
            x = sim.get_poses()
            sim.set_velocities(ids, stepper.decide(t, x))
            sim.step()
            if stepper.after(t + 1, sim.poses):
                break
        result = stepper.result(done_at, wall_time)

    Parameters
    ----------
    exp : Experiment
        A fresh instance, already :meth:`~Experiment.check`-ed for ``n``.
    n : int
        Number of robots.
    world : World
        The run's world (current while the run steps); its generator draws the initial poses.
    rules : SimulatorSpec
        The rules of the simulator the run will have (the experiment may size its safety
        distances by them).
    swarm : bool
        Swarm mode: the experiment's :meth:`~Experiment.build_swarm` instead of its
        :meth:`~Experiment.build`, and its :meth:`~Experiment.swarm_step` instead of the timers.
    startup : bool
        The simulator is rps 2.x and drives the robots from the chargers first (its start-up
        phase): start from the experiment's :meth:`~Experiment.reachable_poses`.

    Raises
    ------
    ValueError
        ``swarm`` for an experiment without a swarm mode.
    """

    def __init__(
        self,
        exp: Experiment,
        n: int,
        world: World,
        rules: SimulatorSpec = RPS,
        swarm: bool = False,
        startup: bool = False,
    ) -> None:
        if swarm and not exp.has_swarm_mode:
            raise ValueError(
                f"{exp.label()} has no swarm mode (swarm=True, --swarm): run it robot by robot, or write its "
                "robots as a dream.swarm.SwarmRobot returned by swarm_robot(n) (see docs/swarm-robots.md)"
            )
        exp.n, exp.world, exp.rules, exp.arena, exp.swarm = n, world, rules, exp.arena_for(n), bool(swarm)
        team = exp.swarm_robot(n)
        if team is not None:
            exp.engine = Engine(team, n, world.seed or 0, exp.arena, one_by_one=not swarm)
        elif swarm:
            exp.build_swarm(n)
        else:
            exp.build(n)
        self.exp, self.world, self.swarm = exp, world, bool(swarm)
        #: ``(3, n)`` poses the experiment starts from (m, m, rad).
        self.requested = exp.initial_poses(n, world.rng)
        #: ``(3, n)`` poses the simulator starts from: :attr:`requested`, or with ``startup`` (the
        #: simulator is rps 2.x and runs its start-up phase first) :meth:`~Experiment.reachable_poses`.
        self.initial_conditions = exp.reachable_poses(self.requested) if startup else self.requested
        self.state: FaultState | None = None
        self.held = 0  # steps in a row that the experiment has been done
        self._limits = GRITSBOT

    def attach(self, sim: Backend, faults: Faults | None = None) -> None:
        """Give the experiment its simulator and command array, the world the simulator's arena
        and limits (which its robots keep to), and draw the run's faults."""
        exp = self.exp
        self.world.keep_to(sim.arena, sim.spec)
        exp.sim, exp.dxu = sim, np.zeros((2, exp.n))
        self.state = self.world.inject(faults, exp.n)
        self._limits = GRITSBOT.within(sim.spec)
        if exp.engine is not None:
            exp.engine.attach(sim.spec)
        elif not self.swarm:  # robot objects: the world counts their messages
            self.world.traffic = Traffic(exp.n)

    def decide(self, step: int, x: np.ndarray) -> np.ndarray:
        """The commands ``(2, n)`` ``[v; w]`` (m/s, rad/s) of step ``step`` (0-based).

        ``x`` ``(3, n)`` holds the poses that this step's ``get_poses()`` returned. Runs the
        experiment's :meth:`~Experiment.before_step`, then every robot's timers (sensors, radios,
        controllers, which write ``exp.dxu``), or in swarm mode its
        :meth:`~Experiment.swarm_step` (whose commands become ``exp.dxu``); faulty wheels then
        change what is carried out.
        """
        exp = self.exp
        self.begin(step, x)
        if exp.engine is not None:
            exp.dxu = exp.engine.step(step, x, exp.dxu, self.state)
        elif self.swarm:
            exp.dxu = self._commands(exp.swarm_step(step, x))
        return self.carried_out()

    def begin(self, step: int, x: np.ndarray) -> None:
        """What comes before the swarm decides at step ``step``: the experiment's
        :meth:`~Experiment.before_step` and the world's timers (robot objects' decisions; in
        swarm mode, the world's clock and the robots' faults)."""
        self.exp.before_step(step)
        self.world.update_timers(step, self.exp.timer_params(x, self.exp.dxu))

    def carried_out(self) -> np.ndarray:
        """The commands ``(2, n)`` the wheels carry out of ``exp.dxu``: a crashed robot's none,
        faulty wheels' changed (:meth:`dream.faults.FaultState.actuate`)."""
        exp = self.exp
        if self.state is None:
            return exp.dxu
        exp.dxu[:, self.state.crashed] = 0.0  # a crashed robot commands nothing: sensors see it stand
        return self.state.actuate(exp.dxu, self._limits)

    def _commands(self, dxu: Any) -> np.ndarray:
        """A swarm step's commands, checked: ``(2, n)`` float64."""
        out, n = np.asarray(dxu, dtype=np.float64), self.exp.n
        if out.shape != (2, n):
            raise ValueError(
                f"{self.exp.label()}.swarm_step returned commands of shape {out.shape}, expected (2, n) = (2, {n})"
            )
        return out

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        """The experiment's frame of this step, with the simulated time, who is faulty and, when the
        experiment gives no title, its name and measures (:func:`~dream.frames.measures_title`)."""
        frame = self.exp.frame(step, poses)
        if not frame.title:
            frame.title = measures_title(self.exp.label(), self.exp.measures())
        frame.time = step * self.exp.sim.time_step if frame.time is None else frame.time
        if self.state is not None and frame.status is None:  # who has crashed, is stuck or lies
            frame.status = fault_status(self.state.crashed, self.state.stuck, self.state.byzantine)
        return frame

    def after(self, step: int, poses: np.ndarray) -> bool:
        """After the simulator's step (``step`` steps run, ``poses`` ``(3, n)``): the experiment's
        :meth:`~Experiment.after_step`, then whether it is :meth:`~Experiment.done` and has been
        for its :attr:`~Experiment.hold_steps` steps before."""
        self.exp.after_step(step, poses)
        self.held = self.held + 1 if self.exp.done(step, poses) else 0
        return self.held > self.exp.hold_steps

    def result(self, done_at: int | None, wall: float, trace: np.ndarray | None = None) -> ExperimentResult:
        """The run's metrics: the simulator's counts, the experiment's measures and the faults."""
        exp = self.exp
        result = ExperimentResult.from_backend(
            exp.label(), self.world.seed or 0, exp.sim, done_at, wall, exp.measures(), trace, exp.params
        )
        result.faults = {} if self.state is None else self.state.summary()
        result.swarm = self.swarm
        return result
