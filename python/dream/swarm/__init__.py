"""Robots written once, on arrays: the same class runs robot by robot and as a swarm of any size.

See :mod:`dream.swarm.robot` for how a robot is declared and :mod:`dream.swarm.engine` for
what the world does to it every step.
"""

from dream.swarm.engine import Engine
from dream.swarm.neighbourhood import Neighbourhood
from dream.swarm.robot import Avoid, Movement, Radio, SwarmRobot, View

__all__ = ["Avoid", "Engine", "Movement", "Neighbourhood", "Radio", "SwarmRobot", "View"]
