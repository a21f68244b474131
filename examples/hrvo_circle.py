"""HRVO circle (thesis 3.1), written as a DREAM script in the original explicit-loop style.

Ten robots start at random poses. Each goes to its point on a circle of radius 0.85 m, then to
the opposite point, then back: three circles. A robot knows only its own pose (odometry), the
robots its movement sensor sees (HRVO keeps it off them) and, every 30 steps, the progress
vectors its range radio hears; it sets off for its next goal when it knows that every robot has
reached as many goals as itself. Success: three circles, zero collisions.

    python examples/hrvo_circle.py
    python examples/hrvo_circle.py --video circle.gif --every 3

On the Robotarium lab, replace `make_robotarium(...)` with
`rps.robotarium.Robotarium(number_of_robots=N, show_figure=True, sim_in_real_time=True)`.
"""

import argparse

import numpy as np

from dream import *  # the original names: Robot_hrvo, Movement_sensor, Radio_range, ...
from dream import make_robotarium
from dream.experiments.hrvo_circle import circle_arena, circle_goals
from dream.frames import Frame
from dream.viz import Recorder

ARRIVAL = 0.05  # a robot this close to its goal has reached it (m)


class CircleRobot(Robot_hrvo):
    """Visits its goals in turn; waits at each until it knows that everyone has got as far."""

    def __init__(self, robot_id, tag, goals, n, **kwargs):
        super().__init__(robot_id, tag, **kwargs)
        self.goals = goals  # (3, 2): its point on the circle, the opposite point, its point again
        self.heading = 0  # index of the goal it heads for
        self.state = 0  # goals reached so far
        self.known = np.zeros(n, dtype=int)  # the states of all robots, as far as it knows

    def update_radio(self, messages):
        # States only grow, so the largest value known or heard for each robot is its latest.
        self.known = np.max([self.known, *messages], axis=0)
        self.known[self.robot_id] = self.state
        arrived = self.state > self.heading  # it has reached the goal it headed for
        if arrived and self.state < len(self.goals) and (self.known >= self.state).all():
            self.heading = self.state  # everyone has got as far: on to the next goal
        return self.known

    def update(self, dxu):
        desired = np.zeros(2)
        if self.has_pose:
            offset = self.goals[self.heading] - (self.pos_x, self.pos_y)
            distance = np.hypot(*offset)
            if distance < ARRIVAL and self.state == self.heading:
                self.state += 1  # counted once per goal
            # Full speed, slowing down over the last 0.2 m so as to stop on the goal, not past it.
            desired = offset * min(self.v_max, distance) / max(distance, 1e-9)
        self.steer(self.detections, desired)  # HRVO; steps aside when it blocks the robot
        self.command(dxu)


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-n", type=int, default=10)
parser.add_argument("--steps", type=int, default=4000)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
Recorder.add_arguments(parser)  # --video PATH, --show, --every K
args = parser.parse_args()
recorder = Recorder.from_args(args, parser)  # None unless --video or --show
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
    circles = min(rob.state for rob in robots)
    if recorder is not None:
        heading_for = np.array([rob.goals[rob.heading] for rob in robots])
        velocities = np.array([rob.dxi for rob in robots])
        recorder(Frame(t + 1, r.arena, r.poses, goals=heading_for, velocities=velocities, title=f"circles {circles}"))
    if circles == 3:
        break

r.call_at_scripts_end()
collisions = r.violations.collision
outcome = "success" if circles == 3 and collisions == 0 else "failure"
print(f"{outcome}: {circles} circles in {r.iterations} steps, {collisions} collisions")
if recorder is not None:
    recorder.close()
    recorder.hold()  # with --show: until the window is closed
