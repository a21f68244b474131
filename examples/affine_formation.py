"""Affine formation manoeuvres, written as a DREAM script in the original explicit-loop style.

Three leaders hold a triangle (standing a little to the right while they gather the others);
four followers come from the corners and take their places by the stress control law on radio
positions; then two pairs of bars sweep across and the leaders compress, then flatten, the
formation to pass, each shape change at a steady pace (``Leader.head_for``). Run headless:

    python examples/affine_formation.py
"""

import argparse

import numpy as np

from dream import *  # the original names: Odometry_sensor, Movement_sensor, create_timer, ...
from dream import GraphRadio, make_robotarium, reset_default_world
from dream.experiments.affine_formation import (
    GATHER,
    LEADERS,
    RECOVER,
    SAFETY,
    SHIFT,
    WEIGHTS,
    Follower,
    Leader,
    bars,
    corner_starts,
    formation,
    schedule,
)

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--steps", type=int, default=None)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
args = parser.parse_args()
N = 7
passes = schedule()
steps = args.steps or passes[-1][2] + 2 * RECOVER

world = reset_default_world(args.seed)
r = make_robotarium(N, args.backend, corner_starts(world.rng))
adjacency = (WEIGHTS != 0).astype(float)
robots = []
for i in range(N):
    rob = Leader(i, f"leader_{i}") if i < LEADERS else Follower(i, f"follower_{i}", safety=SAFETY)
    odo = Odometry_sensor(i, f"odom_{i}", rob.update_odom)
    rad = GraphRadio(i, f"radio_{i}", rob.update_radio, adjacency)
    timers = [{"delay": 2, "tag": "odom", "call": odo.update}]
    if i >= LEADERS:  # only followers look out for others
        mov = Movement_sensor(i, f"movement_{i}", rob.update_sensor, range=0.6)
        timers.append({"delay": 3, "tag": "movement", "call": mov.update})
    timers += [{"delay": 4, "tag": "radio", "call": rad.update}, {"delay": 4, "tag": "robot", "call": rob.update}]
    create_timer(i, 10 + i, timers)
    robots.append(rob)

dxu = np.zeros((2, N))
obstacles = []
for t in range(steps):
    if t in (0, GATHER):  # the leaders gather the followers a little to the right, then centre
        for leader in robots[:LEADERS]:
            leader.head_for(formation("nominal")[leader.robot_id] + (SHIFT * (t == 0), 0.0))
    for deform, enter, leave, shape, gap in passes:  # the leaders' planned manoeuvres
        if t in (deform, leave):
            for leader in robots[:LEADERS]:
                leader.head_for(formation(shape if t == deform else "nominal")[leader.robot_id])
        if t == enter:
            obstacles = bars(gap, r.arena.xmax + 0.15)
        if t == leave:
            obstacles = []
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    for bar in obstacles:
        bar.step(r.time_step)

r.call_at_scripts_end()
