"""The batch forms of one world of ``n`` robots: a Gymnasium ``VectorEnv`` of ``n`` rows, for large
swarms and batch learners (a policy evaluated on all rows at once, one robot a row), and a
Gymnasium ``Env`` of the whole team (one ``(n, 2)`` action, one reward), for single-agent code."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from dream.experiments import Experiment
from dream.rl.team import Team


class BatchEnv(VectorEnv):
    """One DREAM world as a ``VectorEnv``: row i is robot i (made by :func:`batch_env`).

    Observations are ``(n, size)`` float32 (the flat rows of :mod:`dream.rl.observation`),
    actions ``(n, 2)`` in ``[-1, 1]``; ``info["acts"]`` ``(n,)`` says whose actions count at the
    next step (the others hold their last command).

    The rows share one world, so they end together: when the experiment is done or the step
    cap is reached, every row is terminated or truncated and the next :meth:`step` resets the
    world (Gymnasium's next-step autoreset: that step's actions are ignored, its rewards are 0).
    A robot that crashes is terminated from then on, with reward 0, until the world resets:
    its row cannot start again on its own.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self, experiment: type[Experiment] | str, n: int | None = None, *, seed: int = 0, **options: Any
    ) -> None:
        self.team = Team(experiment, n, **options)
        self.num_envs = self.team.n
        self.single_observation_space = self.team.layout.flat_space()
        self.single_action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._seeds = np.random.default_rng(seed)
        self._ended = False

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """A new episode, from ``seed`` or the next seed of the constructor's generator."""
        if seed is not None:
            self._seeds = np.random.default_rng(seed)
            self.action_space.seed(seed)
        else:
            seed = int(self._seeds.integers(2**31))
        obs = self.team.reset(seed)
        self._ended = False
        return obs.copy(), {"acts": self.team.acting.copy()}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if self._ended:
            obs, info = self.reset()
            none = np.zeros(self.num_envs, dtype=bool)
            return obs, np.zeros(self.num_envs), none, none.copy(), info
        obs, rewards, terminated, truncated = self.team.step(actions)
        self._ended = self.team.ended
        return obs.copy(), rewards, terminated, truncated, {"acts": self.team.acting.copy()}


def batch_env(experiment: type[Experiment] | str, n: int | None = None, **options: Any) -> BatchEnv:
    """The world of :func:`dream.rl.parallel_env` as a Gymnasium ``VectorEnv`` of ``n`` rows (see
    :class:`BatchEnv`); the same options.

    Examples
    --------
    >>> env = batch_env("examples/rendezvous.py", n=8, max_steps=10)
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, env.single_action_space.shape
    ((8, 36), (2,))
    """
    return BatchEnv(experiment, n, **options)


class TeamEnv(gymnasium.Env):
    """One DREAM world as a single-agent Gymnasium ``Env`` (made by :func:`team_env`): the observation
    is every robot's row ``(n, size)``, the action every robot's ``(n, 2)``, the reward the robots'
    mean; it terminates when the experiment is done or every robot has crashed. Each robot still
    sees only its own row's worth and acts on its own clock: a policy that reads another robot's
    row is centralised, which no lab robot can run."""

    metadata = {"render_modes": []}

    def __init__(self, experiment: type[Experiment] | str, n: int | None = None, **options: Any) -> None:
        self.team = Team(experiment, n, **options)
        shape = (self.team.n, self.team.layout.size)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape, np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, (self.team.n, 2), np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)  # seeds self.np_random, which draws the world's seed
        obs = self.team.reset(int(self.np_random.integers(2**31)))
        return obs.copy(), {"acts": self.team.acting.copy()}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        live = ~self.team.gone  # the robots that had not crashed before this step
        obs, rewards, terminated, truncated = self.team.step(action)
        return (
            obs.copy(),
            float(rewards[live].mean()) if live.any() else 0.0,
            bool(terminated.all()),
            bool(truncated.all() and not terminated.all()),
            {"acts": self.team.acting.copy()},
        )


def team_env(experiment: type[Experiment] | str, n: int | None = None, **options: Any) -> TeamEnv:
    """The world of :func:`dream.rl.parallel_env` as one Gymnasium ``Env`` of the whole team (see
    :class:`TeamEnv`); the same options but ``seed`` (give it to ``reset``)."""
    return TeamEnv(experiment, n, **options)
