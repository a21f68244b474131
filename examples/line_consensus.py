"""Line consensus, written as a DREAM script in the original explicit-loop style.

Six robots talk over the thesis's communication graph (GraphRadio) and agree on a line,
0.3 m apart, avoiding each other with HRVO. Run headless:

    python examples/line_consensus.py --steps 2000
"""

import argparse

import numpy as np

from dream import *  # the original names: Odometry_sensor, Movement_sensor, create_timer, ...
from dream import GraphRadio, make_robotarium, reset_default_world
from dream.experiments.line_consensus import TOLERANCE, LineRobot, graph, line_arena, line_errors

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-n", type=int, default=6)
parser.add_argument("--steps", type=int, default=2000)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
args = parser.parse_args()
N = args.n

world = reset_default_world(args.seed)  # seeds sensor noise, radio loss and the graph
r = make_robotarium(N, args.backend, arena=line_arena(N), seed=args.seed)
adjacency = graph(N, world.rng)

for i in range(N):
    rob = LineRobot(i, f"robot_{i}", arena=r.arena)
    odo = Odometry_sensor(i, f"odom_{i}", rob.update_odom)
    mov = Movement_sensor(i, f"movement_{i}", rob.update_sensor)
    rad = GraphRadio(i, f"radio_{i}", rob.update_radio, adjacency)
    create_timer(
        i,
        10 + i % 3,
        [
            {"delay": 2, "tag": "odom", "call": odo.update},
            {"delay": 3, "tag": "movement", "call": mov.update},
            {"delay": 10, "tag": "radio", "call": rad.update},
            {"delay": 4, "tag": "robot", "call": rob.update},
        ],
    )

dxu = np.zeros((2, N))
for t in range(args.steps):
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    spread, error = line_errors(r.poses)
    if max(spread, error) < TOLERANCE:
        print(f"line formed at step {t + 1}: y spread {spread:.3f} m, spacing error {error:.3f} m")
        break

r.call_at_scripts_end()
