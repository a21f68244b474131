"""HRVO circle, written as a DREAM script in the original explicit-loop style.

Ten robots with an odometry sensor, a movement sensor and a range radio each; timers decide
when each part runs; the loop feeds the simulator's poses to the timers and the robots'
commands back to the simulator. Run headless:

    python examples/hrvo_circle.py --steps 3000

On the Robotarium lab, replace `make_robotarium(...)` with
`rps.robotarium.Robotarium(number_of_robots=N, show_figure=True, sim_in_real_time=True)`.
"""

import argparse

import numpy as np

from dream import *  # the original names: Robot_hrvo, Movement_sensor, Radio_range, ...
from dream import make_robotarium
from dream.experiments.hrvo_circle import CIRCLES, CircleRobot, circle_arena, circle_goals

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-n", type=int, default=10)
parser.add_argument("--steps", type=int, default=3000)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
args = parser.parse_args()
N = args.n

r = make_robotarium(N, args.backend, arena=circle_arena(N), seed=args.seed)
goals = circle_goals(N)

robots = []
for i in range(N):
    rob = CircleRobot(i, f"robot_{i}", goals[i], N, arena=r.arena)
    odo = Odometry_sensor(i, f"odom_{i}", rob.update_odom)
    mov = Movement_sensor(i, f"movement_{i}", rob.update_sensor)
    rad = Radio_range(i, f"radio_{i}", rob.update_radio)
    # Sense first, then talk, then act: a robot never commands from an unknown pose.
    create_timer(
        i,
        20 + i % 10,
        [
            {"delay": 2 + i % 2, "tag": "odom", "call": odo.update},
            {"delay": 3 + i % 2, "tag": "movement", "call": mov.update},
            {"delay": 30, "tag": "radio", "call": rad.update},
            {"delay": 4 + i % 2, "tag": "robot", "call": rob.update},
        ],
    )
    robots.append(rob)

dxu = np.zeros((2, N))
for t in range(args.steps):
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    if all(rob.state >= CIRCLES for rob in robots):
        print(f"all {N} robots completed {CIRCLES} circles at step {t + 1}")
        break

r.call_at_scripts_end()
