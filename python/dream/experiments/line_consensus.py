"""Line consensus (thesis 3.2): robots agree, over a communication graph, on a line.

Each robot knows only the positions its graph neighbours send by radio. It heads for
``x_i = mean_j (x_j + (id_j - id_i) d)`` and ``y_i = mean_j y_j`` over its neighbours j
(spacing d), through HRVO so that the robots crossing each other's way do not collide. Where
the graph is connected, the team converges to a horizontal line ordered by id, d apart.
Six robots use the thesis's adjacency matrix; more robots use a ring plus random chords.

Beyond the thesis's arena (more than seven robots, a line longer than 2 m) two things change.
The robots start scattered over a strip as long as the line (about one robot per square metre:
a block at the centre made every robot cross the crowd of those heading the other way, and 1000
robots jammed in it, 700 still there after 12,000 steps), and a robot whose
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

Swarm mode (``swarm=True``, :meth:`LineConsensus.swarm_step`) runs the same robots on arrays: the
same decision rules (:mod:`dream.rules`: the consensus update, the goal beside the line, settling,
stepping aside; the motion guard of :func:`dream.robot.stopping`), each robot at its own timer's
steps (:func:`dream.timers.due`), one HRVO call for the robots deciding in a step. It also keeps
what the per-robot timers imply within a step, where robots run one after the other by id: a
radio hears the message a neighbour of lower id sent in that very step, and a movement sensor
reads, besides the poses, the commands those neighbours have just decided. Each robot decides
from what its sensor read at its last reading (up to two steps old), with the velocities the
sensor estimates. The trajectories equal the per-robot mode's to rounding (the tests compare them
over whole runs); it has no W-MSR, since faults reach a swarm through its wheels only.

Success: y spread and spacing error below 0.02 m, zero collisions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from dream import rules, timers
from dream.experiments.sightings import Nearby, Sight, decide_in_order, last_detections
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
START_SPACING = 0.4  #: grid of the large teams' starting strip (m)
START_SHARE = 6  #: grid points per robot in the starting strip: about one robot per square metre
SAFETY = 0.24  #: HRVO's combined safety radius (m): the RobotHRVO default
SENSING = 1.0  #: range of the movement sensor (m)
START_DELAY = 10  #: start-up delay of robot i's timer: this plus i % 3 steps
ODOM_GAP, MOVEMENT_GAP, CONTROL_GAP = 2, 3, 4  #: steps between odometry readings, detections, decisions
SIDESTEP_UPDATES = 10  #: decisions a blocked robot steps aside for (see RobotHRVO.steer)

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
    chords = np.array([rng.choice(n, size=2, replace=False) for _ in range(n)], dtype=np.int64).reshape(-1, 2)
    a = np.concatenate((np.tile(ring, reach), chords[:, 0]))
    b = np.concatenate(((ring + np.arange(1, reach + 1)[:, None]).ravel() % n, chords[:, 1]))
    links = np.unique(np.concatenate((a * n + b, b * n + a)))
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


def start_delays(n: int) -> np.ndarray:
    """Start-up delays ``(n,)`` of the robots' timers (steps): staggered so that a third of the
    team talks and decides at each of three neighbouring steps."""
    return START_DELAY + np.arange(n) % 3


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


def settle_or_steer(
    robot: RobotHRVO,
    desired: np.ndarray,
    fine: float = FINE,
    clearance: float = CLEARANCE,
    sidestep_updates: int = SIDESTEP_UPDATES,
) -> None:
    """Set ``robot.dxi``: ``desired`` itself when slower than ``fine`` (m/s) with no detected robot
    closer than ``clearance`` (m) (:func:`dream.rules.settles`); else :meth:`RobotHRVO.steer`.

    A robot this slow is within centimetres of its place, and velocity obstacles (no time
    horizon) forbid every velocity towards a neighbour inside the cone, however slow: on a line
    0.3 m apart that is the very direction of the last centimetres, so HRVO would push the robot
    sideways, off the line, for ever. The clearance keeps HRVO in charge when two places still
    nearly coincide (the consensus not yet converged): without it two such robots creep into
    each other.
    """
    detections = np.asarray(robot.detections)
    nearest = float(detections[:, 0].min()) if detections.size else math.inf
    if rules.settles(desired, nearest, fine, clearance):
        robot.dxi = desired
    else:
        robot.steer(robot.detections, desired, sidestep_updates)


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
            senders, x, y = np.array(messages, dtype=np.float64).T
            places = rules.line_places(senders, self.robot_id, x, y, self.spacing)
            if self.resilient and self.has_pose:  # W-MSR: ignore the extreme values a liar could send
                xs = [*rules.wmsr_keep(places[:, 0], self.pos_x, self.resilient), self.pos_x]
                ys = [*rules.wmsr_keep(places[:, 1], self.pos_y, self.resilient), self.pos_y]
                self.target = np.array([np.mean(xs), np.mean(ys)])
            else:
                self.target = rules.consensus(places, np.zeros(len(places), dtype=np.int64), 1)[0]
        if not self.has_pose:
            return None
        target_y = math.nan if self.target is None else self.target[1]
        return (self.robot_id, self.pos_x, float(rules.sent_row(self.pos_y, target_y, self.travelling)))

    def goal(self, target: np.ndarray) -> np.ndarray:
        """Where the robot heads now for its consensus ``target`` ``(2,)`` (:func:`dream.rules.line_goal`:
        the target, or beside the line while its place is far along it)."""
        goal, travelling = rules.line_goal(
            (self.pos_x, self.pos_y), target, self.travelling, self.spacing, self.lane, self.bounds
        )
        self.travelling = bool(travelling)
        return goal

    def update(self, dxu: np.ndarray) -> None:
        desired = np.zeros(2)
        if self.has_pose and self.target is not None:
            desired = rules.toward((self.pos_x, self.pos_y), self.goal(self.target), GAIN, self.v_max)
        if self.lane > 0:
            settle_or_steer(self, desired, sidestep_updates=SIDESTEP_UPDATES)
        else:
            self.HRVO(self.detections, desired)
        self.command(dxu)


@dataclass
class LineSwarm:
    """Every robot's state in swarm mode, one row or column each (see :meth:`LineConsensus.swarm_step`).

    Attributes
    ----------
    delays : (n,) int ndarray
        Start-up delay of each robot's timer (steps), as in the per-robot mode.
    receivers, senders : (m,) int ndarrays
        The graph's links (:func:`graph_links`).
    pose : (3, n) ndarray
        Each robot's last odometry reading (NaN before the first).
    target : (n, 2) ndarray
        Consensus targets (m; NaN before the first message).
    travelling : (n,) bool ndarray
        Whether each robot travels beside the line (:func:`dream.rules.line_goal`).
    sent : (n, 2) ndarray
        The radio board: the ``(x, y)`` each robot sent last (NaN before it first spoke).
    dxi : (n, 2) ndarray
        The velocities chosen last (m/s).
    sidestep, side : (n,) ndarrays
        Decisions left stepping aside, and to which side (see :meth:`~dream.RobotHRVO.steer`).
    """

    delays: np.ndarray
    receivers: np.ndarray
    senders: np.ndarray
    pose: np.ndarray
    target: np.ndarray
    travelling: np.ndarray
    sent: np.ndarray
    dxi: np.ndarray
    sidestep: np.ndarray
    side: np.ndarray

    @classmethod
    def start(cls, n: int, links: tuple[np.ndarray, np.ndarray]) -> LineSwarm:
        """``n`` robots that know nothing yet, on the graph ``links`` ``(receivers, senders)``."""
        return cls(
            delays=start_delays(n),
            receivers=links[0],
            senders=links[1],
            pose=np.full((3, n), np.nan),
            target=np.full((n, 2), np.nan),
            travelling=np.zeros(n, dtype=bool),
            sent=np.full((n, 2), np.nan),
            dxi=np.zeros((n, 2)),
            sidestep=np.zeros(n, dtype=np.int64),
            side=np.ones(n),
        )


class LineConsensus(Experiment):
    """The line-consensus experiment (see the module docs).

    Swarm mode (``swarm=True``) keeps the per-robot mode's schedule and decision rules (see the
    module docs) with the team's state in a :class:`LineSwarm`.
    """

    name = NAME
    default_n = 6
    success = "y spread and spacing error below 0.02 m (the line has formed), zero violations"
    has_swarm_mode = True
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
        seeds 0-2 against 322,177."""
        if self.arena_for(n) == ROBOTARIUM:
            return 3000
        travel = (n - 1) * self.spacing / 2 + (start_grid(n, self.spacing)[0] - 1) * START_SPACING / 2
        return 3000 + math.ceil(5 * travel / (CRUISE * RPS.time_step))

    def build(self, n: int) -> None:
        self.adjacency = graph(n, self.world.rng, resilient_reach(self.resilient))
        lane, delays = self.lane(), start_delays(n)
        for i in range(n):
            robot = LineRobot(i, f"robot_{i}", self.spacing, lane, self.resilient, safety=SAFETY, arena=self.arena)
            odometry = OdometrySensor(i, f"odom_{i}", robot.update_odom)
            movement = MovementSensor(i, f"movement_{i}", robot.update_sensor, range=SENSING)
            radio = GraphRadio(i, f"radio_{i}", robot.update_radio, self.adjacency)
            create_timer(
                i,
                int(delays[i]),
                [
                    {"delay": ODOM_GAP, "tag": "odom", "call": odometry.update},
                    {"delay": MOVEMENT_GAP, "tag": "movement", "call": movement.update},
                    {"delay": self.radio_gap, "tag": "radio", "call": radio.update},
                    {"delay": CONTROL_GAP, "tag": "robot", "call": robot.update},
                ],
            )
            self.robots.append(robot)

    def lane(self) -> float:
        """The passing lanes' distance from the line (m): none in the Robotarium (the thesis's robots)."""
        return 0.0 if self.arena == ROBOTARIUM else LANE

    def build_swarm(self, n: int) -> None:
        if self.resilient:
            raise ValueError(
                "line-consensus's swarm mode has no W-MSR (resilient > 0): its radio carries no lies "
                "(faults reach a swarm through its wheels only); run it robot by robot"
            )
        self.team = LineSwarm.start(n, graph_links(n, self.world.rng))
        self.bounds = self.arena.shrunk(GRITSBOT.radius)
        self.sights: dict[int, Sight] = {}

    def swarm_step(self, step: int, x: np.ndarray) -> np.ndarray:
        """Every robot's part of step ``step``, at the per-robot mode's rates (:func:`dream.timers.due`
        of each robot's timer): odometry, a radio round (:meth:`_talk`), a decision (:meth:`_decide`);
        a robot that does not decide keeps its last command."""
        team = self.team
        if step == 0:  # no robot drives faster than its simulator lets it
            self.nearby = Nearby(SENSING, GRITSBOT.within(self.sim.spec).v_max, self.sim.time_step)
        # What the movement sensors of this step see: the poses, the commands before this step's
        # decisions, and who is in range (the last MOVEMENT_GAP steps are kept for later decisions).
        looking = np.flatnonzero(timers.due(step, team.delays, MOVEMENT_GAP))
        self.sights[step] = Sight(x, self.dxu.copy(), *self.nearby.rows(step, x, looking))
        self.sights.pop(step - MOVEMENT_GAP, None)
        reading = timers.due(step, team.delays, ODOM_GAP)
        team.pose[:, reading] = x[:, reading]
        talking = timers.due(step, team.delays, self.radio_gap)
        if talking.any():
            self._talk(talking)
        deciding = np.flatnonzero(timers.due(step, team.delays, CONTROL_GAP))
        commands = self.dxu.copy()
        if len(deciding):
            self._decide(step, deciding, commands)
        return commands

    def _talk(self, talking: np.ndarray) -> None:
        """One radio round of the ``talking`` robots ``(n,)`` bool: each takes the mean place of the
        messages on the board from its graph neighbours (:func:`dream.rules.consensus`), then sends
        its own. The per-robot mode's radios talk one after the other by id, so a neighbour of lower
        id talking in the same step has already replaced its message: its position now, and a row
        (:func:`dream.rules.sent_row`) that can depend on the target it has just taken. Those rows
        follow the ids, so repeating the round until they no longer change gives exactly the
        per-robot messages (twice for teams that do not travel)."""
        team, n = self.team, self.n
        links = talking[team.receivers]
        receivers, senders = team.receivers[links], team.senders[links]
        fresh = talking[senders] & (senders < receivers)
        board = team.sent[senders]
        heard = fresh | np.isfinite(board[:, 0])  # silent robots (none yet) send nothing
        receivers, senders, fresh, board = receivers[heard], senders[heard], fresh[heard], board[heard]
        x_sent = np.where(fresh, team.pose[0, senders], board[:, 0])
        rows = rules.sent_row(team.pose[1], team.target[:, 1], team.travelling)
        while True:
            places = rules.line_places(
                senders, receivers, x_sent, np.where(fresh, rows[senders], board[:, 1]), self.spacing
            )
            mean = rules.consensus(places, receivers, n)
            target = np.where((talking & np.isfinite(mean[:, 0]))[:, None], mean, team.target)
            settled, rows = rows, rules.sent_row(team.pose[1], target[:, 1], team.travelling)
            if np.array_equal(rows[talking], settled[talking], equal_nan=True):
                break
        team.target = target
        team.sent[talking] = np.column_stack((team.pose[0, talking], rows[talking]))

    def _decide(self, step: int, who: np.ndarray, commands: np.ndarray) -> None:
        """The decisions of robots ``who`` ``(k,)`` (ids, increasing), as :meth:`LineRobot.update`
        takes them: head for the goal (:func:`dream.rules.line_goal`, :func:`dream.rules.toward`),
        settle or steer, then write their limited and guarded commands into ``commands`` ``(2, n)``
        in the per-robot mode's order (:func:`~dream.experiments.sightings.decide_in_order`: one
        HRVO call for them all), each from what its movement sensor saw at its last reading
        (:func:`~dream.experiments.sightings.last_detections`).
        """
        team, lane = self.team, self.lane()
        own = team.pose[:2, who].T
        aiming = np.isfinite(team.target[who, 0])
        goals, team.travelling[who[aiming]] = rules.line_goal(
            own[aiming], team.target[who[aiming]], team.travelling[who[aiming]], self.spacing, lane, self.bounds
        )
        desired = np.zeros((len(who), 2))
        desired[aiming] = rules.toward(own[aiming], goals, GAIN, GRITSBOT.v_max)
        seen = last_detections(self.sights, team.delays[who], step, who, MOVEMENT_GAP)
        settle = np.zeros(len(who), dtype=bool)
        wanted, sidestep = desired, team.sidestep[who]
        if lane > 0:
            nearest = np.full(len(who), np.inf)
            np.minimum.at(nearest, seen.owners, seen.distances)
            settle = rules.settles(desired, nearest, FINE, CLEARANCE)
            wanted, sidestep = rules.sidestep_preference(desired, sidestep, team.side[who])
        chosen = decide_in_order(
            who,
            team.pose[:, who],
            team.dxi[who],
            desired,
            wanted,
            settle,
            seen,
            commands,
            safety=SAFETY,
            v_max=GRITSBOT.v_max,
            bounds=self.bounds,
            limits=GRITSBOT.within(self.sim.spec),
        )
        if lane > 0:
            sidestep, side = rules.sidestep_update(chosen, desired, sidestep, team.side[who], SIDESTEP_UPDATES)
            steered = who[~settle]
            team.sidestep[steered], team.side[steered] = sidestep[~settle], side[~settle]
        team.dxi[who] = np.where(settle[:, None], desired, chosen)

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
        if self.swarm:
            goals, velocities = self.team.target, self.team.dxi
            upper = self.team.receivers < self.team.senders
            links = np.column_stack((self.team.receivers[upper], self.team.senders[upper]))
        else:
            goals = np.array([np.full(2, np.nan) if r.target is None else r.target for r in self.robots])
            velocities = np.array([r.dxi for r in self.robots]).reshape(-1, 2)
            links = np.argwhere(np.triu(self.adjacency) > 0)
        return Frame(
            step,
            self.arena,
            poses,
            goals=goals.reshape(-1, 2),
            velocities=velocities,
            links=links,
            title=f"{NAME}: y spread {spread:.3f} m, spacing error {error:.3f} m",
        )


run = LineConsensus.run
