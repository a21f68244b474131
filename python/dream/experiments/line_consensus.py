"""Line consensus (thesis 3.2): robots agree, over a communication graph, on a line.

Each robot knows only the positions its graph neighbours send by radio and heads for
``x_i = mean_j (x_j + (id_j - id_i) d)``, ``y_i = mean_j y_j`` through HRVO; where the graph is
connected, the team converges to a horizontal line ordered by id, d apart. One :class:`LineRobot`,
written on arrays, runs robot by robot and as one swarm (``swarm=True``) with the same poses at
every step; with ``resilient`` = F it filters what it hears by W-MSR. How larger teams travel
beside the line and settle on it: docs/experiments/line-consensus.md.
Success: y spread and spacing error below 0.02 m, zero collisions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from dream import rules, timers
from dream._checks import Bounds
from dream._csr import offsets_of
from dream.experiments.spec import Experiment, param
from dream.frames import Frame
from dream.robot import SIDESTEP_UPDATES
from dream.specs import GRITSBOT, ROBOTARIUM, RPS, ArenaSpec
from dream.swarm import Avoid, Movement, Radio, SwarmRobot, View

NAME = "line-consensus"
SPACING = 0.3  #: distance between neighbours on the line (m)
TOLERANCE = 0.02  #: largest y spread and spacing error of a converged line (m)
GAIN = 1.0  #: proportional gain towards the consensus target (1/s)
LANE = 0.35  #: distance of the passing lanes from the line (m): more than HRVO's safety radius
FINE = 0.03  #: below this desired speed (m/s) a robot moves without HRVO (see :func:`dream.rules.settles`)
CLEARANCE = 0.2  #: settling without HRVO only with no robot this close (m): contact is at 0.11
CRUISE = 0.8 * GRITSBOT.v_max  #: top speed of a robot (m/s): the unicycle conversion's gain 0.8 times v_max
START_SPACING = 0.4  #: grid of the large teams' starting strip (m)
START_SHARE = 6  #: grid points per robot in the starting strip: about one robot per square metre
SAFETY = 0.24  #: HRVO's combined safety radius (m): the RobotHRVO default
SENSING = 1.0  #: range of the movement sensor (m)
START_DELAY = 10  #: start-up delay of robot i: this plus i % 3 steps
CONTROL_GAP = 4  #: steps between two decisions of a robot

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


def graph_links(n: int, rng: np.random.Generator, reach: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The communication graph as its links ``(receivers, senders)`` ``(m,)``, both directions,
    by receiver then sender id: the thesis's graph for six robots; otherwise a ring that links
    each robot to the ``reach`` next ids on either side, plus ``n`` random chords.

    The random chords make an expander: the consensus rate (the second eigenvalue of the
    random-walk Laplacian, about 0.13-0.17 for n = 100-1000) does not shrink with n, while a
    ring with local chords only has diameter ~n/k and a rate ~1/n^2. The mean degree is 4 with
    ``reach`` 1. W-MSR with F liars needs more (:func:`resilient_reach`).
    """
    if n == 6:
        receivers, senders = np.nonzero(THESIS_GRAPH)
        return receivers.astype(np.int64), senders.astype(np.int64)
    ring = np.arange(n)
    # Each chord joins two distinct robots, every ordered pair alike: the second is drawn from the
    # n - 1 others (one draw for all the chords; a draw a chord took 17 s at a million robots).
    ends = rng.integers(n, size=n)
    others = rng.integers(max(n - 1, 1), size=n)
    others += others >= ends
    a = np.concatenate((np.tile(ring, reach), ends))
    b = np.concatenate(((ring + np.arange(1, reach + 1)[:, None]).ravel() % n, others))
    links = np.sort(np.concatenate((a * n + b, b * n + a)))  # np.unique's hash took 3.3 s at a million
    links = links[np.concatenate(([True], links[1:] != links[:-1]))]
    receivers, senders = np.divmod(links, n)
    apart = receivers != senders
    return receivers[apart], senders[apart]


def resilient_reach(trimmed: int) -> int:
    """How many ids on either side the ring of :func:`graph_links` links for W-MSR that trims
    ``trimmed`` values on each side: 2F + 1.

    W-MSR converges with F liars on a (2F + 1)-robust graph (LeBlanc et al., 2013), whose every
    robot has at least 2F + 1 neighbours. With one link on either side, 12-19 robots of 100 hear
    only their two ring neighbours; when those lie on either side of its own value, the filter
    drops both and the robot stands still, and the line never formed (0 of 10 seeds at N = 100).
    A ring that links the 2F + 1 next ids on either side is (2F + 1)-robust: a run of consecutive
    ids always has an end robot with 2F + 1 neighbours beyond it.
    """
    return 2 * max(trimmed, 0) + 1


def graph(n: int, rng: np.random.Generator, reach: int = 1) -> np.ndarray:
    """The adjacency matrix ``(n, n)`` of :func:`graph_links`."""
    adjacency = np.zeros((n, n))
    adjacency[graph_links(n, rng, reach)] = 1.0
    return adjacency


def start_grid(n: int, spacing: float = SPACING) -> tuple[int, int]:
    """``(columns, rows)`` of the starting strip of a large team: columns ``START_SPACING`` apart
    over 1.25 times the line's length, rows enough for ``START_SHARE`` grid points per robot."""
    columns = math.floor(1.25 * (n - 1) * spacing / START_SPACING) + 1
    return columns, math.ceil(START_SHARE * n / columns)


def line_arena(n: int, spacing: float = SPACING) -> ArenaSpec:
    """The Robotarium while the line fits in its central 2 m; else a strip with room for the line
    (and for its centre settling off the start's) around the starting strip, 1 m to spare."""
    length = (n - 1) * spacing
    if length <= 2.0:
        return ROBOTARIUM
    rows = start_grid(n, spacing)[1]
    return ArenaSpec.centred(1.25 * length + 2.0, max(ROBOTARIUM.height, rows * START_SPACING + 2.0))


def strip_poses(n: int, rng: np.random.Generator, arena: ArenaSpec, spacing: float = SPACING) -> np.ndarray:
    """Poses ``(3, n)`` of a large team: distinct random points of the :func:`start_grid` strip
    (``START_SPACING`` apart) at the centre of ``arena``, random headings."""
    columns, rows = start_grid(n, spacing)
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


class LineRobot(SwarmRobot):
    """A robot that moves to the consensus of its graph neighbours' positions (see the module docs).

    Every ``CONTROL_GAP`` steps it heads for its consensus target (:func:`dream.rules.line_goal`,
    :func:`dream.rules.toward`); at the first decision of every ``radio_gap`` steps of its clock it
    also takes the mean place its neighbours' messages give it (:func:`dream.rules.line_places`,
    or their W-MSR mean with ``resilient`` > 0) and sends its position and row
    (:func:`dream.rules.sent_row`).

    ``lane`` (m) > 0 is the large team's robot: it travels beside the line, steps aside when HRVO
    blocks it and settles its last centimetres without HRVO. 0 is the thesis's robot, which heads
    straight for its target through HRVO.

    Robot objects with timers (before this robot was written on arrays) read their odometry every
    2 steps and their sensor every 3, and heard a message from a neighbour of lower id in the
    step it was sent; this robot reads both fresh at each decision and hears a message from the
    step after it was sent.
    """

    period = CONTROL_GAP
    threaded = True  # decide reads its view alone: blocks of a swarm decide on several threads
    movement = Movement(range=SENSING)
    memory = {"target_x": math.nan, "target_y": math.nan, "travelling": 0, "slot": -1}

    def __init__(
        self,
        graph: tuple[np.ndarray, np.ndarray],
        bounds: Bounds,
        spacing: float = SPACING,
        lane: float = 0.0,
        resilient: int = 0,
        radio_gap: int = 10,
    ) -> None:
        self.radio = Radio(graph=graph, fields=("x", "y"))  # robot i hears graph[1][graph[0][i]:graph[0][i + 1]]
        self.avoid = Avoid(safety=SAFETY, sidestep=SIDESTEP_UPDATES if lane > 0 else 0)
        self.bounds, self.spacing, self.lane = bounds, spacing, lane
        self.resilient, self.radio_gap = resilient, radio_gap

    def start(self, ids: np.ndarray) -> np.ndarray:
        """Staggered: a third of the team talks and decides at each of three neighbouring steps."""
        return timers.staggered(ids, START_DELAY, 3)

    def decide(self, view: View) -> np.ndarray:
        here, memory, heard = view.pose[:, :2], view.memory, view.heard
        target = np.column_stack((memory["target_x"], memory["target_y"]))
        travelling = memory["travelling"].astype(bool)
        # A radio exchange at the first decision of each `radio_gap` steps of the robot's clock.
        slot = np.floor((view.clock - self.start(view.ids)) / self.radio_gap).astype(np.int64)
        talking = slot > memory["slot"]
        if talking.any():
            places = rules.line_places(heard["sender"], view.ids[heard.owner], heard["x"], heard["y"], self.spacing)
            if self.resilient:  # W-MSR: ignore the extreme values a liar could send
                mean = np.column_stack([heard.wmsr_mean(places[:, c], here[:, c], self.resilient) for c in (0, 1)])
            else:
                mean = heard.mean(places)
            update = talking & (heard.count > 0)
            target[update] = mean[update]
            view.send(where=talking, x=here[:, 0], y=rules.sent_row(here[:, 1], target[:, 1], travelling))
            memory["slot"] = np.where(talking, slot, memory["slot"])
        desired = np.zeros((len(view), 2))
        aiming = np.isfinite(target[:, 0])
        goals, travelling[aiming] = rules.line_goal(
            here[aiming], target[aiming], travelling[aiming], self.spacing, self.lane, self.bounds
        )
        desired[aiming] = rules.toward(here[aiming], goals, GAIN, self.spec.v_max)
        if self.lane > 0:
            nearest = view.seen.min("distance")
            view.direct(rules.settles(desired, np.where(np.isnan(nearest), math.inf, nearest), FINE, CLEARANCE))
        memory["target_x"], memory["target_y"], memory["travelling"] = target[:, 0], target[:, 1], travelling
        return desired


class LineConsensus(Experiment):
    """The line-consensus experiment (see the module docs): its robots are one :class:`LineRobot`."""

    name = NAME
    default_n = 6
    success = "y spread and spacing error below 0.02 m (the line has formed), zero violations"
    spacing: float = param(SPACING, "distance between neighbours on the line (m)", gt=0)
    radio_gap: int = param(10, "steps between radio exchanges", ge=1)
    resilient: int = param(
        0,
        "W-MSR: drop the F largest and F smallest neighbour values; beyond 6 robots the ring links 2F+1 ids a side",
        ge=0,
    )

    def check(self, n: int, backend: str) -> None:
        if n < 2:
            raise ValueError(f"{NAME} needs at least 2 robots to form a line (each talks to its neighbours), got n={n}")

    def arena_for(self, n: int) -> ArenaSpec:
        return line_arena(n, self.spacing)

    def initial_poses(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The thesis's random start in the Robotarium; the :func:`strip_poses` strip beyond."""
        if self.arena == ROBOTARIUM:
            return super().initial_poses(n, rng)
        return strip_poses(n, rng, self.arena, self.spacing)

    def steps(self, n: int) -> int:
        """3000 in the Robotarium; beyond, 3000 plus five times the time the robot farthest from
        its place needs at full speed (half the line plus half the starting strip away): N = 100
        took 7522-27,917 steps over seeds 0-9 against a cap of 34,487, N = 1000 65,444-119,393 over
        seeds 0-2 against 322,177 (robot objects with timers, before :class:`LineRobot`)."""
        if self.arena_for(n) == ROBOTARIUM:
            return 3000
        travel = (n - 1) * self.spacing / 2 + (start_grid(n, self.spacing)[0] - 1) * START_SPACING / 2
        return 3000 + math.ceil(5 * travel / (CRUISE * RPS.time_step))

    def swarm_robot(self, n: int) -> LineRobot:
        """The team on its graph (:func:`graph_links`, a wider ring for W-MSR: :func:`resilient_reach`)."""
        self.links = graph_links(n, self.world.rng, resilient_reach(self.resilient))
        lane = 0.0 if self.arena == ROBOTARIUM else LANE  # the thesis's robots in the Robotarium
        graph = (offsets_of(self.links[0], n), self.links[1])
        bounds = self.arena.shrunk(GRITSBOT.radius)
        return LineRobot(graph, bounds, self.spacing, lane, self.resilient, self.radio_gap)

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
        assert self.engine is not None
        memory = self.engine.memory
        receivers, senders = self.links
        upper = receivers < senders
        return Frame(
            step,
            self.arena,
            poses,
            goals=np.column_stack((memory["target_x"], memory["target_y"])),
            velocities=self.engine.dxi.copy(),
            links=np.column_stack((receivers[upper], senders[upper])),
            title=f"{NAME}: y spread {spread:.3f} m, spacing error {error:.3f} m",
        )
