"""One learning world as arrays: the experiment's world, a :class:`~dream.rl.learner.Learner` per
robot, and a policy's actions in, observations, rewards and endings out, one row per robot.

Both environments (:func:`dream.rl.parallel_env`, :func:`dream.rl.batch_env`) are views of a
:class:`Team`. One :meth:`Team.step` is one step of the world (one Robotarium iteration):

1. the robots whose timers fire this step (``acting``, from the observation before) act: their
   actions become wishes that go through the engine (HRVO if asked, the unicycle conversion,
   the actuator limits, the motion guard) and each sends its odometry position on the radio;
   **the other robots hold their last command**, whatever action they were given;
2. faulty wheels, then the simulator, move the robots;
3. the rewards and endings are taken (below); the world moves on to the next step (its faults,
   who crashes), and the robots whose timers fire then read their sensors and radio: their
   rows of the observation are new; the others' rows stay what those robots knew when they last
   decided.

Rewards (one per robot, :data:`SUCCESS`, :data:`COLLISION`, :data:`OUTSIDE`), unless the
experiment says otherwise:

- the change of the experiment's ``potential(poses)`` hook ``(n,)`` (higher is better) over the
  step; an experiment with goals and no potential has minus each robot's distance to its goal;
- ``- COLLISION`` for a robot whose collider is within a diameter of another's, ``- OUTSIDE`` for
  a robot outside the arena (the simulator's own criteria);
- ``+ SUCCESS`` for every correct robot at the step the experiment is done.

Endings: everyone terminates when the experiment is done (its success, held for its
``hold_steps``); a robot that crashes terminates then (it leaves the agents); everyone is
truncated at the step cap (the experiment's ``steps(n)``, or ``max_steps``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dream import kernels
from dream.backends import make_robotarium, rules_named
from dream.experiments import Experiment
from dream.experiments.stepper import Stepper
from dream.faults import Faults
from dream.rl.learner import goals_of, learning_class
from dream.rl.observation import Layout
from dream.swarm import Avoid
from dream.world import World

SUCCESS = 10.0  #: reward of every correct robot at the step the experiment is done
COLLISION = 1.0  #: penalty of a robot in a collision, per step
OUTSIDE = 1.0  #: penalty of a robot outside the arena, per step
ACTIONS = ("velocity", "unicycle")


class Team:
    """One learning world (see the module docs).

    Parameters
    ----------
    experiment : Experiment subclass or str
        A built-in's name, a ``.py`` file or a class (see :func:`dream.rl.learner.learning_class`).
    n : int, optional
        Number of robots (default: the experiment's ``default_n``).
    k : int
        Detections and messages each observation holds (the nearest ones).
    action : {"velocity", "unicycle"}
        An action ``(2,)`` in ``[-1, 1]`` is a wished velocity (times the robot's top speed, world
        frame), or a unicycle command ``[v, w]`` (times the top linear and angular speeds).
    avoid : bool or Avoid
        The HRVO safety layer on wished velocities (``True``: :class:`~dream.swarm.Avoid`'s
        defaults); not with unicycle actions.
    faults : Faults, optional
        What goes wrong (:mod:`dream.faults`).
    max_steps : int, optional
        The step cap (default: the experiment's).
    rules : {"rps0", "rps2"}, optional
        The rps generation the simulator follows (see :func:`dream.run`).
    **params
        The experiment's parameters.
    """

    def __init__(
        self,
        experiment: type[Experiment] | str,
        n: int | None = None,
        *,
        k: int = 4,
        action: str = "velocity",
        avoid: bool | Avoid = False,
        faults: Faults | None = None,
        max_steps: int | None = None,
        rules: str | None = None,
        **params: Any,
    ) -> None:
        self.cls = learning_class(experiment)
        self.params = params
        self.n = self.cls.default_n if n is None else _whole(n, "n", 1)
        if action not in ACTIONS:
            raise ValueError(f"action must be one of {', '.join(ACTIONS)}, got {action!r}")
        if avoid is True:
            avoid = Avoid()
        if avoid is not False and not isinstance(avoid, Avoid):
            raise ValueError(f"avoid must be True, False or a dream.swarm.Avoid, got {avoid!r}")
        if avoid and action == "unicycle":
            raise ValueError("avoid (HRVO) works on wished velocities: use action='velocity' with it")
        self.action, self.avoid = action, avoid or None
        if faults is not None and not isinstance(faults, Faults):
            raise ValueError(f"faults must be a dream.Faults, such as Faults(loss=0.3), got {faults!r}")
        self.faults, self.rules = faults, rules_named(rules)
        self.max_steps = None if max_steps is None else _whole(max_steps, "max_steps", 1)
        self.exp = self._experiment()
        self.goals = goals_of(self.exp, self.n)
        self.layout = Layout(k, self.goals is not None)
        self.seed = 0
        self.t = 0

    def _experiment(self) -> Experiment:
        exp = self.cls(**self.params)
        exp.avoid = self.avoid  # type: ignore[attr-defined]  # the learning class's
        exp.steps_cap = self.max_steps
        exp.check(self.n, "fast")
        return exp

    # -- the episode ------------------------------------------------------------------------
    def reset(self, seed: int) -> np.ndarray:
        """Start a new episode from ``seed``: the observations ``(n, size)``."""
        self.seed = _whole(seed, "seed", 0)
        self.exp = exp = self._experiment()
        self.world = World(self.seed)
        with self.world:
            self.stepper = Stepper(exp, self.n, self.world, self.rules, swarm=True)
            self.sim = make_robotarium(
                self.n, "fast", self.stepper.initial_conditions, arena=exp.arena, rules=self.rules.rules
            )
            self.stepper.attach(self.sim, self.faults)
        assert exp.engine is not None  # the learning class's swarm_robot always gives one
        self.engine = exp.engine
        self.goals = goals_of(exp, self.n)
        self.cap = exp.steps(self.n) if self.max_steps is None else self.max_steps
        self.t = 0
        self.obs = np.zeros((self.n, self.layout.size), dtype=np.float32)
        self.gone = np.zeros(self.n, dtype=bool)  #: crashed robots: no longer agents
        self.ended = False
        self.potential = self._potential(self.sim.poses)
        self._perceive()
        return self.obs

    @property
    def crashed(self) -> np.ndarray:
        """``(n,)`` bool: the robots that have crashed."""
        state = self.stepper.state
        return np.zeros(self.n, dtype=bool) if state is None else state.crashed

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Carry out ``actions`` ``(n, 2)`` in ``[-1, 1]`` (only the ``acting`` robots'); returns the
        observations ``(n, size)``, rewards ``(n,)``, terminations and truncations ``(n,)`` bool."""
        if self.ended:
            raise RuntimeError("the episode has ended: reset() before stepping again")
        actions = np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0)
        if actions.shape != (self.n, 2) or not np.isfinite(actions).all():
            raise ValueError(f"actions must be finite, of shape (n, 2) = ({self.n}, 2), got shape {actions.shape}")
        exp, engine, spec = self.exp, self.engine, self.engine.robot.spec
        wishes = []
        for view in self.views:
            view.send(x=view.pose[:, 0], y=view.pose[:, 1])
            wishes.append(actions[view.ids] * (spec.v_max if self.action == "velocity" else 0.0))
        with self.world:
            exp.dxu = engine.act(self.t, self.views, wishes, exp.dxu, self.stepper.state)
            if self.action == "unicycle":
                rows = np.flatnonzero(self.acting)
                top = engine.limits
                exp.dxu[:, rows] = kernels.actuator_limit(actions[rows].T * [[top.v_max], [top.w_max]], top)
            self.sim.set_velocities(np.arange(self.n), self.stepper.carried_out())
            self.sim.step()
            poses = self.sim.poses
            done = self.stepper.after(self.t + 1, poses)
        self.t += 1
        colliding = np.zeros(self.n, dtype=bool)
        colliding[self.sim.in_collision] = True  # the robots of the pairs the simulator counted
        rewards = self._rewards(poses, done, colliding)
        terminated = np.full(self.n, done) | self.gone
        truncated = np.full(self.n, self.t >= self.cap)
        self.ended = done or self.t >= self.cap
        if not self.ended:
            self._perceive()
        now = self.crashed & ~self.gone
        terminated |= now  # a robot that has crashed this step ends here
        rewards[self.gone] = 0.0
        self.gone |= now
        return self.obs, rewards, terminated, truncated

    def _perceive(self) -> None:
        """Move the world to step ``t`` (its faults) and read the due robots' sensors and radio."""
        with self.world:
            self.x = x = self.sim.get_poses()
            self.stepper.begin(self.t, x)
            self.views = self.engine.perceive(self.t, x, self.exp.dxu, self.stepper.state)
        self.acting = np.zeros(self.n, dtype=bool)  #: the robots whose actions count this step
        for view in self.views:
            self.obs[view.ids] = self.layout.rows(view, self.goals)
            self.acting[view.ids] = True

    # -- rewards ------------------------------------------------------------------------------
    def _potential(self, poses: np.ndarray) -> np.ndarray:
        hook = getattr(self.exp, "potential", None)
        if hook is not None:
            value = np.broadcast_to(np.asarray(hook(poses), dtype=np.float64), (self.n,))
            if not np.isfinite(value).all():
                raise ValueError(f"{self.exp.label()}.potential(poses) must be finite")
            return value.copy()
        if self.goals is not None:
            return -np.hypot(*(poses[:2] - self.goals.T))
        return np.zeros(self.n)

    def _rewards(self, poses: np.ndarray, done: bool, colliding: np.ndarray) -> np.ndarray:
        potential = self._potential(poses)
        rewards = potential - self.potential
        self.potential = potential
        rewards -= COLLISION * colliding + OUTSIDE * self._outside(self.x)
        if done:
            rewards += SUCCESS * self.exp.correct
        return rewards

    def _outside(self, poses: np.ndarray) -> np.ndarray:
        xmin, xmax, ymin, ymax = self.exp.arena.bounds
        return (poses[0] < xmin) | (poses[0] > xmax) | (poses[1] < ymin) | (poses[1] > ymax)


def _whole(value: Any, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise ValueError(f"{name} must be a whole number >= {least}, got {value!r}")
    return int(value)
