"""Reinforcement learning on DREAM: robots as agents, each knowing only what its sensors and radio
told it, acting on its own clock, in the experiment's world with its faults.

- :func:`parallel_env`: a PettingZoo ``ParallelEnv``, one agent per robot (``robot_<id>``);
- :func:`batch_env`: the same world as a Gymnasium ``VectorEnv``, one row per robot, for
  large swarms and batch learners;
- :class:`LinearPolicy`: a NumPy policy (observation row to action) with a weights file, which
  ``dream export --policy`` ships to the lab.

See :mod:`dream.rl.team` for what a step does, the default rewards and the endings,
:mod:`dream.rl.observation` for what a robot observes and :mod:`dream.rl.learner` for which
experiments a learner can take the world of. Needs the ``rl`` extra (``pettingzoo``,
``gymnasium``).
"""

from dream.rl.batch import BatchEnv, batch_env
from dream.rl.parallel import DreamParallelEnv, parallel_env
from dream.rl.policy import LinearPolicy
from dream.rl.team import Team

__all__ = ["BatchEnv", "DreamParallelEnv", "LinearPolicy", "Team", "batch_env", "parallel_env"]
