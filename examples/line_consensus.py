"""Line consensus (thesis 3.2), written as a DREAM script in the original explicit-loop style.

Six robots agree on a horizontal line, ordered by id and 0.3 m apart, with no leader and no
shared map. Each hears only its neighbours in the thesis's communication graph (GraphRadio),
which send their positions; it heads for the consensus of what it hears, through HRVO
(movement sensor) so as not to run into the robots crossing its way. Success: y spread and
spacing error below 0.02 m, zero collisions.

    python examples/line_consensus.py
    python examples/line_consensus.py --show
"""

import argparse

import numpy as np

from dream import *  # the original names: Odometry_sensor, Movement_sensor, create_timer, ...
from dream import GraphRadio, make_robotarium, reset_default_world
from dream.experiments.line_consensus import TOLERANCE, graph, line_arena, line_errors
from dream.frames import Frame
from dream.viz import Recorder

SPACING = 0.3  # distance between neighbours on the line (m)


class LineRobot(Robot_hrvo):
    """Heads for the line its graph neighbours' positions imply, at speed proportional to the way left."""

    def __init__(self, robot_id, tag, **kwargs):
        super().__init__(robot_id, tag, **kwargs)
        self.target = None  # where the consensus puts it, once it has heard anyone

    def update_radio(self, messages):
        if messages:
            # Neighbour j at x_j puts robot i at x_j + (j - i) * SPACING; the line's y is everyone's mean.
            ids, xs, ys = np.array(messages).T
            self.target = np.array([np.mean(xs + (ids - self.robot_id) * SPACING), np.mean(ys)])
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update(self, dxu):
        wanted = np.zeros(2)
        if self.has_pose and self.target is not None:
            wanted = self.target - (self.pos_x, self.pos_y)  # gain 1/s
            wanted *= min(1.0, self.v_max / max(np.hypot(*wanted), 1e-9))  # at most v_max
        self.HRVO(self.detections, wanted)
        self.command(dxu)


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-n", type=int, default=6)
parser.add_argument("--steps", type=int, default=2000)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
Recorder.add_arguments(parser)  # --video PATH, --show, --every K
args = parser.parse_args()
recorder = Recorder.from_args(args, parser)  # None unless --video or --show
N = args.n

world = reset_default_world(args.seed)  # seeds sensor noise, radio loss and the graph
r = make_robotarium(N, args.backend, arena=line_arena(N), seed=args.seed)
adjacency = graph(N, world.rng)  # the thesis's graph for six robots
robots = []
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
    robots.append(rob)

dxu = np.zeros((2, N))
for t in range(args.steps):
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    spread, error = line_errors(r.poses, SPACING)
    if recorder is not None:
        targets = np.array([np.full(2, np.nan) if rob.target is None else rob.target for rob in robots])
        title = f"y spread {spread:.3f} m, spacing error {error:.3f} m"
        recorder(Frame(t + 1, r.arena, r.poses, goals=targets, links=np.argwhere(np.triu(adjacency)), title=title))
    if max(spread, error) < TOLERANCE:
        break

r.call_at_scripts_end()
collisions = r.violations.collision
outcome = "success" if max(spread, error) < TOLERANCE and collisions == 0 else "failure"
print(
    f"{outcome}: y spread {spread:.3f} m, spacing error {error:.3f} m at step {r.iterations}, {collisions} collisions"
)
if recorder is not None:
    recorder.close()
    recorder.hold()  # with --show: until the window is closed
