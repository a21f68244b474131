"""Voronoi coverage, written as a DREAM script in the original explicit-loop style.

Fifteen robots leave the bottom-right corner and spread over the arena, each moving to the
centroid of its Voronoi cell, around two static and two moving obstacles. Run headless:

    python examples/voronoi_coverage.py --steps 1500
"""

import argparse

import numpy as np

from dream import *  # the original names: Odometry_sensor, Radio_range, create_timer, ...
from dream import ObstacleSensor, make_robotarium, reset_default_world
from dream.experiments.voronoi_coverage import CELL_RADIUS, CoverageRobot, corner_poses, thesis_obstacles

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-n", type=int, default=15)
parser.add_argument("--steps", type=int, default=1500)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
parser.add_argument("--static", action="store_true", help="no moving obstacles")
args = parser.parse_args()
N = args.n

world = reset_default_world(args.seed)  # seeds the obstacles' directions and the headings
obstacles = thesis_obstacles(world.rng, moving=not args.static)
r = make_robotarium(N, args.backend, corner_poses(N, world.rng))
for obstacle in obstacles:  # draw them for seed-style plotting (r.figure is headless)
    r.axes.fill(*obstacle.polygon.T, color="k")

for i in range(N):
    rob = CoverageRobot(i, f"robot_{i}", arena=r.arena)
    odo = Odometry_sensor(i, f"odom_{i}", rob.update_odom)
    obs = ObstacleSensor(i, f"obstacles_{i}", rob.update_obstacles, obstacles, range=CELL_RADIUS)
    rad = Radio_range(i, f"radio_{i}", rob.update_radio, range=2 * CELL_RADIUS)
    create_timer(
        i,
        10 + i % 5,
        [
            {"delay": 2, "tag": "odom", "call": odo.update},
            {"delay": 3, "tag": "obstacles", "call": obs.update},
            {"delay": 5, "tag": "radio", "call": rad.update},
            {"delay": 5, "tag": "robot", "call": rob.update},
        ],
    )

dxu = np.zeros((2, N))
for t in range(args.steps):
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "obstacles": (x,), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    for obstacle in obstacles:
        obstacle.step(r.time_step, r.arena)

r.call_at_scripts_end()
