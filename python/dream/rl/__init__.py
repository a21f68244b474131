"""Reinforcement learning on DREAM: robots as agents, each knowing only what its sensors and radio
told it, acting on its own clock, in the experiment's world with its faults.

- :func:`parallel_env`: a PettingZoo ``ParallelEnv``, one agent per robot (``robot_<id>``);
- :func:`batch_env`: the same world as a Gymnasium ``VectorEnv``, one row per robot, for
  large swarms and batch learners;
- :func:`team_env`: the whole team as one Gymnasium ``Env`` (one ``(n, 2)`` action), for
  single-agent code;
- :class:`LinearPolicy`: a NumPy policy (observation row to action) with a weights file, which
  ``dream export --policy`` ships to the lab;
- :class:`MlpPolicy`: a small torch network policy for gradient learners (needs torch).

See :mod:`dream.rl.team` for what a step does, the default rewards and the endings,
:mod:`dream.rl.observation` for what a robot observes and :mod:`dream.rl.learner` for which
experiments a learner can take the world of. The environments need the ``rl`` extra
(``pettingzoo``, ``gymnasium``; ``torch`` for :class:`MlpPolicy`), imported when first used: a lab
bundle runs a policy without them.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

#: Public names and the modules that hold them.
_HOMES = {
    "BatchEnv": "batch",
    "batch_env": "batch",
    "DreamParallelEnv": "parallel",
    "parallel_env": "parallel",
    "LinearPolicy": "policy",
    "MlpPolicy": "mlp",
    "Team": "team",
    "TeamEnv": "batch",
    "team_env": "batch",
}
__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module 'dream.rl' has no attribute {name!r}")
    return getattr(import_module(f"dream.rl.{_HOMES[name]}"), name)
