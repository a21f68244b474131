"""The PettingZoo form: one agent per robot, ``robot_<id>``, over a :class:`~dream.rl.team.Team`."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from dream.experiments import Experiment
from dream.rl.team import Team


class DreamParallelEnv(ParallelEnv):
    """A PettingZoo ``ParallelEnv`` of one DREAM world (made by :func:`dream.rl.parallel_env`).

    Observations are dicts of the parts in :mod:`dream.rl.observation`; an action is a ``(2,)``
    float32 array in ``[-1, 1]`` (see :class:`~dream.rl.team.Team`). Each agent's ``info`` says
    whether its action will count at the next step (``"acts"``: its timer fires then); the others
    hold their last command. A crashed robot leaves :attr:`agents`.
    """

    metadata = {"name": "dream_v0", "render_modes": ["rgb_array"], "is_parallelizable": True, "render_fps": 30}

    def __init__(
        self,
        experiment: type[Experiment] | str,
        n: int | None = None,
        *,
        seed: int = 0,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.team = Team(experiment, n, **options)
        self.render_mode = render_mode
        self.possible_agents = [f"robot_{i}" for i in range(self.team.n)]
        self.agents: list[str] = []
        self._observation = self.team.layout.dict_space()
        self._action = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self._seeds = np.random.default_rng(seed)
        self._renderer: Any = None

    def observation_space(self, agent: str) -> spaces.Space:
        return self._observation

    def action_space(self, agent: str) -> spaces.Space:
        return self._action

    def reset(self, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        """A new episode, from ``seed`` or (without one) the next seed of the generator that the
        constructor's ``seed`` (or the last ``reset(seed)``) started."""
        if seed is not None:
            self._seeds = np.random.default_rng(seed)
            for number, space in enumerate((self._observation, self._action)):
                space.seed(seed + number)
        else:
            seed = int(self._seeds.integers(2**31))
        obs = self.team.reset(seed)
        self.agents = self.possible_agents[:]
        return self._observations(obs), self._infos()

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Step the world once with ``actions`` (those of agents whose timers do not fire are held,
        as are missing ones: an acting agent without an action wishes to stand still)."""
        team = self.team
        unknown = set(actions) - set(self.agents)
        if unknown:
            raise ValueError(f"actions for agents that are not live: {sorted(unknown)}")
        array = np.zeros((team.n, 2))
        for agent, action in actions.items():
            array[int(agent[6:])] = np.asarray(action, dtype=np.float64).reshape(2)
        live = self.agents
        obs, rewards, terminated, truncated = team.step(array)
        ids = [int(agent[6:]) for agent in live]
        out = (
            self._observations(obs, live),
            {agent: float(rewards[i]) for agent, i in zip(live, ids)},
            {agent: bool(terminated[i]) for agent, i in zip(live, ids)},
            {agent: bool(truncated[i]) for agent, i in zip(live, ids)},
            self._infos(live),
        )
        self.agents = [agent for agent, i in zip(live, ids) if not (terminated[i] or truncated[i])]
        return out

    def _observations(self, obs: np.ndarray, agents: list[str] | None = None) -> dict[str, Any]:
        agents = self.agents if agents is None else agents
        return {agent: self.team.layout.as_dict(obs[int(agent[6:])]) for agent in agents}

    def _infos(self, agents: list[str] | None = None) -> dict[str, dict[str, Any]]:
        agents = self.agents if agents is None else agents
        return {agent: {"acts": bool(self.team.acting[int(agent[6:])])} for agent in agents}

    def render(self) -> np.ndarray | None:
        """The world now, ``(H, W, 3)`` uint8, drawn by :class:`dream.viz.Renderer`."""
        if self.render_mode is None:
            return None
        from dream.viz import Renderer  # matplotlib only for those who draw

        team = self.team
        if self._renderer is None:
            self._renderer = Renderer(team.exp.arena, size=(640, 400))
        self._renderer.draw(team.stepper.frame(team.t, team.sim.poses))
        return self._renderer.to_rgb()

    def close(self) -> None:
        self._renderer = None

    def state(self) -> np.ndarray:
        """The world's true poses ``(3, n)`` (for centralised critics; no robot knows them)."""
        return self.team.sim.poses


def parallel_env(experiment: type[Experiment] | str, n: int | None = None, **options: Any) -> DreamParallelEnv:
    """A PettingZoo ``ParallelEnv`` in which each robot of ``experiment`` is an agent.

    Parameters
    ----------
    experiment : str or Experiment subclass
        A built-in's name (``"hrvo-circle"``, ``"line-consensus"``), a ``.py`` file that defines
        one experiment (``"examples/rendezvous.py"``) or a class; see :mod:`dream.rl.learner`.
    n : int, optional
        Number of robots.
    **options
        ``seed`` (of the episodes' seeds, default 0), ``render_mode`` (``"rgb_array"``), and
        :class:`~dream.rl.team.Team`'s: ``k``, ``action``, ``avoid``, ``faults``, ``max_steps``,
        ``rules`` and the experiment's parameters.

    Examples
    --------
    >>> env = parallel_env("hrvo-circle", n=4, max_steps=20)
    >>> obs, infos = env.reset(seed=1)
    >>> sorted(obs["robot_0"])
    ['goal', 'heard', 'heard_mask', 'pose', 'seen', 'seen_mask']
    >>> obs, rewards, terminated, truncated, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
    """
    return DreamParallelEnv(experiment, n, **options)
