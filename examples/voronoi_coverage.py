"""Voronoi coverage (thesis 3.3), written as a DREAM script in the original explicit-loop style.

Fifteen robots leave the bottom-right corner and spread over the arena, around two static and
two moving obstacles. Each knows its own pose (odometry), the positions the robots within 2 m
send (range radio) and the closest points of the obstacles within 1 m (obstacle sensor). It
moves to the centroid of its Voronoi cell: a disc of 1 m clipped by the arena, by the bisectors
with the robots it hears and by virtual agents that keep its body off the obstacles. No HRVO:
the cells keep the robots apart. Success: the coverage cost stays below a fifth of its start
for 10 s, with no collision and no contact with a static obstacle.

    python examples/voronoi_coverage.py --static --video coverage.mp4
"""

import argparse

import numpy as np

from dream import *  # the original names: Odometry_sensor, Radio_range, create_timer, ...
from dream import ObstacleSensor, kernels, make_robotarium, reset_default_world
from dream.experiments.voronoi_coverage import COVERED, HOLD_STEPS, corner_poses, coverage_cost, thesis_obstacles
from dream.frames import Frame
from dream.obstacles import touching
from dream.specs import GRITSBOT
from dream.viz import Recorder

CELL_RADIUS = 1.0  # a cell is at most this disc (m); the obstacle sensor reaches as far, the radio twice
ARRIVAL = 0.05  # a robot this close to its centroid stays where it is (m)


class CoverageRobot(Robot):
    """Moves to the centroid of the part of the arena that is closer to it than to anyone it hears."""

    def __init__(self, robot_id, tag, arena):
        super().__init__(robot_id, tag)
        self.arena = arena
        self.others = np.zeros((0, 2))  # positions heard by radio
        self.obstacle_points = np.zeros((0, 2))  # closest points of the obstacles sensed
        self.cell = np.zeros((0, 2))  # its last cell, for drawing

    def update_radio(self, messages):
        self.others = np.array(messages).reshape(-1, 2)
        return (self.pos_x, self.pos_y) if self.has_pose else None

    def update_obstacles(self, closest_points):
        self.obstacle_points = closest_points

    def update(self, dxu):
        self.dxi = np.zeros(2)
        if self.has_pose:
            here = np.array([self.pos_x, self.pos_y])
            # An obstacle acts as a robot mirrored beyond it: the bisector keeps the body 2 cm off it.
            mirrored = kernels.obstacle_agents(here, self.obstacle_points, robot_radius=self.spec.radius, margin=0.02)
            centroid, _, self.cell = kernels.voronoi_cell(
                here, self.others, radius=CELL_RADIUS, bounds=self.arena.bounds, virtual=mirrored
            )
            way = centroid - here
            if np.hypot(*way) >= ARRIVAL:
                self.dxi = way * min(1.0, self.v_max / np.hypot(*way))  # gain 1/s, at most v_max
        self.command(dxu)


parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("-n", type=int, default=15)
parser.add_argument("--steps", type=int, default=1500)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--backend", default="auto")
parser.add_argument("--static", action="store_true", help="no moving obstacles")
Recorder.add_arguments(parser)  # --video PATH, --show, --every K
args = parser.parse_args()
recorder = Recorder.from_args(args, parser)  # None unless --video or --show
N = args.n

world = reset_default_world(args.seed)  # seeds the obstacles' directions and the headings
obstacles = thesis_obstacles(world.rng, moving=not args.static)
r = make_robotarium(N, args.backend, corner_poses(N, world.rng))
robots = []
for i in range(N):
    rob = CoverageRobot(i, f"robot_{i}", r.arena)
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
    robots.append(rob)

dxu = np.zeros((2, N))
start = cost = coverage_cost(r.poses[:2], r.arena, obstacles)
held, contacts = 0, 0  # steps the cost has stayed below COVERED of its start; steps touching a static obstacle
for t in range(args.steps):
    x = r.get_poses()
    update_timers(t, {"odom": (x,), "obstacles": (x,), "radio": (x,), "robot": (dxu,)})
    r.set_velocities(np.arange(N), dxu)
    r.step()
    for obstacle in obstacles:
        obstacle.step(r.time_step, r.arena)
    contacts += bool(touching([o for o in obstacles if not o.moving], r.poses[:2].T, GRITSBOT.radius).any())
    if t % 30 == 0:  # the cost takes a while to compute: once a second
        cost = coverage_cost(r.poses[:2], r.arena, obstacles)
    held = held + 1 if cost < COVERED * start else 0
    if recorder is not None:
        title, cells = f"coverage cost {cost / start:.0%} of its start", [rob.cell for rob in robots]
        shapes, moving = [o.polygon for o in obstacles], [o.moving for o in obstacles]
        recorder(Frame(t + 1, r.arena, r.poses, obstacles=shapes, obstacle_moving=moving, cells=cells, title=title))
    if held >= HOLD_STEPS:
        break

r.call_at_scripts_end()
collisions = r.violations.collision
outcome = "success" if held >= HOLD_STEPS and collisions == 0 and contacts == 0 else "failure"
print(
    f"{outcome}: coverage cost {cost / start:.0%} of its start, below {COVERED:.0%} for the last {held} of "
    f"{r.iterations} steps, {collisions} collisions, {contacts} static-obstacle contacts"
)
if recorder is not None:
    recorder.close()
    recorder.hold()  # with --show: until the window is closed
