"""Robots written once, on arrays: the same class runs robot by robot and as a swarm of any size.

See :mod:`dream.swarm.robot` for how a robot is declared and :mod:`dream.swarm.engine` for
what the world does to it every step.
"""

from dream.swarm.cells import known_cells
from dream.swarm.engine import Engine
from dream.swarm.neighbourhood import Neighbourhood
from dream.swarm.robot import Avoid, Guard, Movement, Obstacles, Radio, SwarmRobot, View
from dream.swarm.rows import put_all, put_rows, take_all, take_rows

__all__ = [
    "Avoid",
    "Engine",
    "Guard",
    "Movement",
    "Neighbourhood",
    "Obstacles",
    "Radio",
    "SwarmRobot",
    "View",
    "known_cells",
    "put_all",
    "put_rows",
    "take_all",
    "take_rows",
]
