"""Line consensus (thesis 3.2): robots agree, over a communication graph, on a line.

Each robot knows only the positions its graph neighbours send by radio. It heads for
``x_i = mean_j (x_j + (id_j - id_i) d)`` and ``y_i = mean_j y_j`` over its neighbours j
(spacing d), through HRVO so that the robots crossing each other's way do not collide. Where
the graph is connected, the team converges to a horizontal line ordered by id, d apart.
Six robots use the thesis's adjacency matrix; more robots use a ring plus random chords.

Beyond the thesis's arena (more than seven robots, a line longer than 2 m) two things change.
The robots start in a block at the centre of a strip that the line fits, and a robot whose
place is far away along the line travels *beside* it: it keeps its own row, or, near the
line, a passing lane ``LANE`` above it (heading right) or below it (heading left), and only
joins the line once it is within a spacing of its place. Without this, the line forms in y
first and a robot that still has to pass others is stuck behind them on it; its neighbours'
targets then depend on the straggler, and the whole team converges at its pace (N = 20 took
over 4000 steps, N = 100 never got there). While travelling, a robot sends the y it heads for
rather than its own, so that its detour does not pull the others' line. These robots also step
aside when HRVO blocks them, and settle their last centimetres without HRVO, whose cones
otherwise forbid the very direction of a neighbour 0.3 m away on the line and keep the line
shaking sideways (see :func:`settle_or_steer`).

Success: y spread and spacing error below 0.02 m, zero collisions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream import rules
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.radios import GraphRadio
from dream.robot import RobotHRVO
from dream.sensors import MovementSensor, OdometrySensor
from dream.specs import GRITSBOT, ROBOTARIUM, RPS, ArenaSpec
from dream.world import create_timer

NAME = "line-consensus"
SPACING = 0.3  #: distance between neighbours on the line (m)
TOLERANCE = 0.02  #: largest y spread and spacing error of a converged line (m)
GAIN = 1.0  #: proportional gain towards the consensus target (1/s)
LANE = 0.35  #: distance of the passing lanes from the line (m): more than HRVO's safety radius
FINE = 0.03  #: below this desired speed (m/s) a robot moves without HRVO (see `settle_or_steer`)
CLEARANCE = 0.2  #: settling without HRVO only with no robot this close (m): contact is at 0.11
CRUISE = 0.8 * GRITSBOT.v_max  #: top speed of a robot (m/s): the unicycle conversion's gain 0.8 times v_max
START_SPACING = 0.4  #: grid of the large teams' starting block (m)

#: The thesis's communication graph for six robots.
THESIS_GRAPH = np.array(
    [
        [0, 1, 1, 0, 0, 0],
        [1, 0, 1, 0, 1, 0],
        [1, 1, 0, 1, 0, 0],
        [0, 0, 1, 0, 1, 1],
        [0, 1, 0, 1, 0, 1],
        [0, 0, 0, 1, 1, 0],
    ],
    dtype=np.float64,
)


def graph(n: int, rng: np.random.Generator) -> np.ndarray:
    """The thesis's graph for six robots; otherwise a ring plus ``n`` random chords.

    The random chords make an expander: the consensus rate (the second eigenvalue of the
    random-walk Laplacian, about 0.13-0.17 for n = 100-1000) does not shrink with n, while a
    ring with local chords only has diameter ~n/k and a rate ~1/n^2. The mean degree is 4.
    """
    if n == 6:
        return THESIS_GRAPH.copy()
    adjacency = np.zeros((n, n))
    for i in range(n):
        adjacency[i, (i + 1) % n] = adjacency[(i + 1) % n, i] = 1.0
    for _ in range(n):
        i, j = rng.choice(n, size=2, replace=False)
        adjacency[i, j] = adjacency[j, i] = 1.0
    np.fill_diagonal(adjacency, 0.0)
    return adjacency


def start_grid(n: int) -> tuple[int, int]:
    """``(columns, rows)`` of the starting block of a large team: 1.5 grid points per robot, 3:1."""
    points = math.ceil(1.5 * n)
    columns = math.ceil(math.sqrt(3 * points))
    return columns, math.ceil(points / columns)


def line_arena(n: int, spacing: float = SPACING) -> ArenaSpec:
    """The Robotarium while the line fits in its central 2 m; else a strip with room for the line
    (and for its centre settling off the block's) around the starting block."""
    length = (n - 1) * spacing
    if length <= 2.0:
        return ROBOTARIUM
    columns, rows = start_grid(n)
    width = max(1.25 * length, columns * START_SPACING) + 2.0
    return ArenaSpec.centred(width, max(ROBOTARIUM.height, rows * START_SPACING + 2.0))


def block_poses(n: int, rng: np.random.Generator, arena: ArenaSpec) -> np.ndarray:
    """Poses ``(3, n)`` of a large team: distinct random points of the :func:`start_grid` block
    (``START_SPACING`` apart) at the centre of ``arena``, random headings."""
    columns, rows = start_grid(n)
    cells = rng.choice(columns * rows, size=n, replace=False)
    cx, cy = (arena.xmin + arena.xmax) / 2, (arena.ymin + arena.ymax) / 2
    x = cx + (cells % columns - (columns - 1) / 2) * START_SPACING
    y = cy + (cells // columns - (rows - 1) / 2) * START_SPACING
    return np.vstack((x, y, rng.uniform(-math.pi, math.pi, n)))


def line_errors(poses: np.ndarray, spacing: float = SPACING, correct: np.ndarray | None = None) -> tuple[float, float]:
    """``(y spread, spacing error)`` of the team (of its ``correct`` robots, if given): robot i
    should be ``spacing`` right of robot i + 1, so ``(j - i) spacing`` right of robot j."""
    ids = np.arange(poses.shape[1]) if correct is None else np.flatnonzero(correct)
    x, y = poses[0, ids], poses[1, ids]
    gaps = x[:-1] - x[1:] - (ids[1:] - ids[:-1]) * spacing
    return float(np.ptp(y)) if len(y) else 0.0, float(np.abs(gaps).max()) if len(gaps) else 0.0


def settle_or_steer(robot: RobotHRVO, desired: np.ndarray, fine: float = FINE, clearance: float = CLEARANCE) -> None:
    """Set ``robot.dxi``: ``desired`` itself when slower than ``fine`` (m/s) with no detected robot
    closer than ``clearance`` (m); else :meth:`RobotHRVO.steer`.

    A robot this slow is within centimetres of its place, and velocity obstacles (no time
    horizon) forbid every velocity towards a neighbour inside the cone, however slow: on a line
    0.3 m apart that is the very direction of the last centimetres, so HRVO would push the robot
    sideways, off the line, for ever. The clearance keeps HRVO in charge when two places still
    nearly coincide (the consensus not yet converged): without it two such robots creep into
    each other.
    """
    detections = np.asarray(robot.detections)
    nearest = float(detections[:, 0].min()) if detections.size else math.inf
    if math.hypot(desired[0], desired[1]) < fine and nearest >= clearance:
        robot.dxi = desired
    else:
        robot.steer(robot.detections, desired)


class LineRobot(RobotHRVO):
    """A robot that moves to the consensus of its graph neighbours' positions.

    Callbacks: :meth:`update_odom`, :meth:`update_sensor`, :meth:`update_radio` (receives
    ``(id, x, y)`` messages, returns its own) and :meth:`update` (the controller).

    ``lane`` (m) > 0 is the large team's robot: it travels beside the line (see the module
    docs), steps aside when HRVO blocks it (:meth:`~RobotHRVO.steer`) and settles its last
    centimetres without HRVO (:func:`settle_or_steer`). 0 is the thesis's robot, which heads
    straight for its target through HRVO.
    """

    def __init__(
        self, robot_id: int, tag: str, spacing: float = SPACING, lane: float = 0.0, resilient: int = 0, **kwargs: Any
    ) -> None:
        super().__init__(robot_id, tag, **kwargs)
        self.spacing = spacing
        self.lane = lane
        self.resilient = resilient
        self.target: np.ndarray | None = None
        self.travelling = False

    def update_radio(self, messages: list[tuple[int, float, float]]) -> tuple[int, float, float] | None:
        if messages:
            xs = [x + (j - self.robot_id) * self.spacing for j, x, _ in messages]
            ys = [y for _, _, y in messages]
            if self.resilient and self.has_pose:  # W-MSR: ignore the extreme values a liar could send
                xs = [*rules.wmsr_keep(xs, self.pos_x, self.resilient), self.pos_x]
                ys = [*rules.wmsr_keep(ys, self.pos_y, self.resilient), self.pos_y]
            self.target = np.array([np.mean(xs), np.mean(ys)])
        if not self.has_pose:
            return None
        y = self.target[1] if self.travelling and self.target is not None else self.pos_y
        return (self.robot_id, self.pos_x, y)

    def goal(self, target: np.ndarray) -> np.ndarray:
        """Where the robot heads now, for its consensus ``target`` ``(2,)``: the target itself, or,
        while its place is more than two spacings away along x (until it is within one), the
        target's x in its own row, at least ``lane`` off the line (above it when heading right,
        below when heading left, if closer)."""
        dx = target[0] - self.pos_x
        if self.lane > 0 and abs(dx) > 2 * self.spacing:
            self.travelling = True
        elif abs(dx) < self.spacing:
            self.travelling = False
        if not self.travelling:
            return target
        off_line = self.pos_y - target[1]
        if abs(off_line) < self.lane:
            off_line = math.copysign(self.lane, dx)
        return np.array([target[0], target[1] + off_line])

    def update(self, dxu: np.ndarray) -> None:
        desired = np.zeros(2)
        if self.has_pose and self.target is not None:
            desired = GAIN * (self.goal(self.target) - (self.pos_x, self.pos_y))
            speed = math.hypot(desired[0], desired[1])
            if speed > self.v_max:
                desired *= self.v_max / speed
        if self.lane > 0:
            settle_or_steer(self, desired)
        else:
            self.HRVO(self.detections, desired)
        self.command(dxu)


class LineConsensus(Experiment):
    """The line-consensus experiment (see the module docs)."""

    name = NAME
    default_n = 6
    success = "y spread and spacing error below 0.02 m (the line has formed), zero violations"
    spacing: float = param(SPACING, "distance between neighbours on the line (m)")
    radio_gap: int = param(10, "steps between radio exchanges")
    resilient: int = param(0, "W-MSR: ignore this many of the largest and smallest neighbour values (liars tolerated)")

    def arena_for(self, n: int) -> ArenaSpec:
        return line_arena(n, self.spacing)

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The thesis's random start in the Robotarium; a :func:`block_poses` block beyond."""
        return super().initial_poses(n, rng) if self.arena == ROBOTARIUM else block_poses(n, rng, self.arena)

    def steps(self, n: int) -> int:
        """3000 in the Robotarium; beyond, 3000 plus five times the time the robot farthest from
        its place needs at full speed (half the line plus half the start block away): N = 100 took
        6576-10,656 steps over seeds 0-9 but seed 3 17,636 (a group that passed the others late),
        against a cap of 21,230."""
        if self.arena_for(n) == ROBOTARIUM:
            return 3000
        travel = (n - 1) * self.spacing / 2 + start_grid(n)[0] * START_SPACING / 2
        return 3000 + math.ceil(5 * travel / (CRUISE * RPS.time_step))

    def build(self, n: int) -> None:
        self.adjacency = graph(n, self.world.rng)
        lane = 0.0 if self.arena == ROBOTARIUM else LANE
        for i in range(n):
            robot = LineRobot(i, f"robot_{i}", self.spacing, lane, self.resilient, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor)
            radio = GraphRadio(i, f"radio_{i}", robot.update_radio, self.adjacency)
            create_timer(
                i,
                10 + i % 3,
                [
                    {"delay": 2, "tag": "odom", "call": odometry.update},
                    {"delay": 3, "tag": "movement", "call": movement.update},
                    {"delay": self.radio_gap, "tag": "radio", "call": radio.update},
                    {"delay": 4, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def done(self, step: int, poses: np.ndarray) -> bool:
        self.errors = line_errors(poses, self.spacing, self.correct)
        self.done_at = step if max(self.errors) < TOLERANCE else None
        return self.done_at is not None

    def measures(self) -> dict[str, Any]:
        """The final ``y_spread`` and ``spacing_error`` (m) and the convergence time (s)."""
        spread, error = line_errors(self.sim.poses, self.spacing, self.correct)
        time = None if self.done_at is None else self.done_at * self.sim.time_step
        return {"y_spread": spread, "spacing_error": error, "convergence_time_s": time}

    def frame(self, step: int, poses: np.ndarray) -> Frame:
        spread, error = line_errors(poses, self.spacing, self.correct)
        return Frame(
            step,
            self.arena,
            poses,
            goals=np.array([np.full(2, np.nan) if r.target is None else r.target for r in self.robots]),
            velocities=np.array([r.dxi for r in self.robots]).reshape(-1, 2),
            links=np.argwhere(np.triu(self.adjacency) > 0),
            title=f"{NAME}: y spread {spread:.3f} m, spacing error {error:.3f} m",
        )


run = LineConsensus.run
