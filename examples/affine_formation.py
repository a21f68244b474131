"""Affine formation manoeuvres (thesis 3.4), written as a DREAM script in the original explicit-loop style.

Three leaders hold a triangle and alone know the plan; four followers come from the corners and
obey the stress control law p_i' = -k sum_j w_ij (p_i - p_j) on the positions their weighted
neighbours send (GraphRadio), through HRVO (movement sensor). So the followers settle at the
affine image of the nominal shape that the leaders span, and follow when the leaders compress,
then flatten, the formation to pass two pairs of sweeping bars. Success: follower error below
0.05 m before the first pass, no robot touching a bar, zero collisions.

    python examples/affine_formation.py --video formation.mp4 --every 2
"""

import argparse

import numpy as np

from dream import *  # the original names: Odometry_sensor, Movement_sensor, create_timer, ...
from dream import GraphRadio, make_robotarium, reset_default_world
from dream.experiments.affine_formation import WEIGHTS, bars, corner_starts, follower_targets, formation, schedule
from dream.frames import Frame
from dream.obstacles import touching
from dream.specs import GRITSBOT
from dream.viz import Recorder

LEADERS = 3  # robots 0-2 lead, 3-6 follow
STRESS_GAIN = 8.0  # the followers' gain k (1/s)
SAFETY = 0.15  # the followers' HRVO safety radius (m): robots in the formation are 0.3 m apart


class Leader(Robot):
    """Goes to its place in the shape the plan asks for; the followers are not its concern."""

    def __init__(self, robot_id, tag):
        super().__init__(robot_id, tag)
        self.goal = formation("nominal")[robot_id]

    def update_radio(self, messages):
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update(self, dxu):
        way = 1.5 * (self.goal - (self.pos_x, self.pos_y))  # gain 1.5/s, at most v_max
        self.dxi = way * min(1.0, self.v_max / max(np.hypot(*way), 1e-9)) if self.has_pose else np.zeros(2)
        self.command(dxu)


class Follower(Robot_hrvo):
    """Moves down the formation's stress: towards the weighted pull of the neighbours it hears."""

    def __init__(self, robot_id, tag, **kwargs):
        super().__init__(robot_id, tag, **kwargs)
        self.weights = WEIGHTS[robot_id]  # w_ij, nonzero for its radio neighbours
        self.heard = {}  # id -> last position heard

    def update_radio(self, messages):
        self.heard.update({j: np.array([x, y]) for j, x, y in messages})
        return (self.robot_id, self.pos_x, self.pos_y) if self.has_pose else None

    def update(self, dxu):
        wanted = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            wanted = -STRESS_GAIN * sum((self.weights[j] * (here - p) for j, p in self.heard.items()), np.zeros(2))
            wanted *= min(1.0, self.v_max / max(np.hypot(*wanted), 1e-9))
        # HRVO forbids even the slowest approach to a neighbour inside its cones, and a place in
        # the formation may lie towards a neighbour 0.3 m away: the last centimetres go without it.
        self.dxi = wanted if np.hypot(*wanted) < 0.03 else self.HRVO(self.detections, wanted)
        self.command(dxu)


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--steps", type=int, default=None)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
Recorder.add_arguments(parser)  # --video PATH, --show, --every K
args = parser.parse_args()
recorder = Recorder.from_args(args, parser)  # None unless --video or --show
N = 7
passes = schedule()  # (deform, enter, leave, shape, gap) steps of the two bar passes
steps = args.steps or passes[-1][2] + 900  # until 30 s after the last bars have left

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
obstacles, contacts, settled = [], 0, np.nan
for t in range(steps):
    for deform, enter, leave, shape, gap in passes:  # the leaders' plan
        if t in (deform, leave):
            for leader in robots[:LEADERS]:
                leader.goal = formation(shape if t == deform else "nominal")[leader.robot_id]
        obstacles = bars(gap, r.arena.xmax + 0.15) if t == enter else [] if t == leave else obstacles
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "movement": (x, dxu), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    for bar in obstacles:
        bar.step(r.time_step)
    p = r.poses[:2].T
    targets = follower_targets(p[:LEADERS])  # where the leaders' triangle puts the followers
    error = np.hypot(*(p[LEADERS:] - targets).T).max()
    settled = error if t == passes[0][0] else settled  # as the leaders set off for the first pass
    contacts += bool(touching(obstacles, p, GRITSBOT.radius).any())
    if recorder is not None:
        goals = np.vstack([[rob.goal for rob in robots[:LEADERS]], targets])
        polygons = [bar.polygon for bar in obstacles]
        recorder(Frame(t + 1, r.arena, r.poses, goals=goals, obstacles=polygons, title=f"follower error {error:.3f} m"))

r.call_at_scripts_end()
collisions = r.violations.collision
outcome = "success" if settled < 0.05 and contacts == 0 and collisions == 0 else "failure"
print(f"{outcome}: follower error {settled:.3f} m before the bars, {contacts} bar contacts, {collisions} collisions")
if recorder is not None:
    recorder.close()
    recorder.hold()  # with --show: until the window is closed
