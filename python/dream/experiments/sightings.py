"""Swarm modes' movement sensors and HRVO decisions, in the per-robot mode's order.

In the per-robot mode robots run their timers one after the other by id, so within a step a
robot's movement sensor sees the commands that robots of lower id have just decided. A swarm
mode that keeps each robot's timer schedule (:func:`dream.timers.due`) keeps this too: it takes
each robot's detections from its last reading (:func:`last_detections`) and lets the robots that
saw a command of this step decide again until none they see changes (:func:`decide_in_order`).
The readings themselves are :class:`Sight` (one step's, who is near whom from :class:`Nearby`)
and :class:`Detections` (some robots' last ones). Line-consensus and affine-formation share them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from dream import kernels, timers
from dream._csr import spans
from dream.kernels import Bounds
from dream.robot import GUARD_HORIZON, guard_distance, stopping
from dream.sensors import seen_velocity
from dream.specs import RobotSpec


class Nearby:
    """Who is within ``radius`` (m) of some robots, step after step (swarm mode), as
    :func:`dream.kernels.neighbours` answers (the same distances, ``sqrt(dx^2 + dy^2)``, and
    the same inclusive test), from one index of a larger radius rebuilt every ``every`` steps:
    robots at most ``speed`` (m/s) fast, ``dt`` (s) a step, cannot close the margin between."""

    def __init__(self, radius: float, speed: float, dt: float, every: int = 4) -> None:
        self.radius, self.every = radius, every
        self.reach = radius + 2 * speed * dt * every * 1.01
        self.built = -every
        self.index = (np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64))

    def rows(self, step: int, x: np.ndarray, who: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """CSR ``(indptr (n + 1,), indices, distances)`` of the robots within the radius of robots
        ``who`` ``(k,)`` (ids, increasing; other rows empty) at poses ``x`` ``(3, n)``."""
        if step - self.built >= self.every:
            self.index, self.built = kernels.neighbours(x[:2].T, self.reach)[:2], step
        indptr, indices = self.index
        starts, counts = indptr[who], np.diff(indptr)[who]
        owners = np.repeat(who, counts)
        others = indices[spans(starts, counts)]
        dx, dy = x[0, others] - x[0, owners], x[1, others] - x[1, owners]
        distances = np.sqrt(dx * dx + dy * dy)
        near = distances <= self.radius
        ptr = np.concatenate(([0], np.cumsum(np.bincount(owners[near], minlength=x.shape[1]))))
        return ptr, others[near], distances[near]


class Sight(NamedTuple):
    """What the movement sensors of one step see (swarm mode): the poses ``(3, n)``, every robot's
    command before the step's decisions ``(2, n)``, and who is within the sensors' range of the
    robots reading their sensor in that step (CSR, :class:`Nearby`)."""

    poses: np.ndarray
    before: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    distances: np.ndarray


@dataclass
class Detections:
    """The movement-sensor detections of some robots (swarm mode), one row per detected robot.

    Attributes
    ----------
    owners : (m,) int ndarray
        Which deciding robot (its row among them) detected it.
    others : (m,) int ndarray
        The detected robot's id.
    distances, angles : (m,) ndarrays
        The sensor's ``[distance, angle]`` (m, rad; the angle from the detected robot towards
        the detecting one).
    headings : (m,) ndarray
        The detected robot's heading then (rad).
    known : (2, m) ndarray
        The command ``[v; w]`` the sensor saw it carry out, unless ``chained``...
    chained : (m,) bool ndarray
        ...when the reading is of this step and the detected robot decides before the detecting
        one: it sees the detected robot's command of this step, being decided.
    """

    owners: np.ndarray
    others: np.ndarray
    distances: np.ndarray
    angles: np.ndarray
    headings: np.ndarray
    known: np.ndarray
    chained: np.ndarray
    towards: np.ndarray = field(init=False)

    @classmethod
    def join(cls, parts: list[tuple[np.ndarray, ...]]) -> Detections:
        """The detections of ``parts``, each a tuple of the fields' values for some robots."""
        empty = (*(np.zeros(0, dtype=np.int64),) * 2, *(np.zeros(0),) * 3, np.zeros((2, 0)), np.zeros(0, dtype=bool))
        return cls(*(np.concatenate(values, axis=-1) for values in zip(empty, *parts)))

    def __post_init__(self) -> None:
        # Where each detected robot is, from the detecting one, as HRVO reads a detection.
        towards = self.angles + np.pi
        self.towards = self.distances[:, None] * np.column_stack((np.cos(towards), np.sin(towards)))

    def offsets(self, rows: np.ndarray) -> np.ndarray:
        """The detecting robot's position less the detected one's ``(k, 2)``, for detections
        ``rows`` ``(k,)``, as the motion guard reads a detection."""
        return self.distances[rows, None] * np.column_stack((np.cos(self.angles[rows]), np.sin(self.angles[rows])))

    def velocity(self, commands: np.ndarray, rows: np.ndarray | slice = slice(None)) -> np.ndarray:
        """The velocities ``(m, 2)`` of the detected robots (of ``rows``) as the sensor estimates
        them (:func:`dream.sensors.seen_velocity`), ``commands`` ``(2, n)`` holding this step's."""
        carried = np.where(self.chained[rows], commands[:, self.others[rows]], self.known[:, rows])
        return np.column_stack(seen_velocity(carried, self.headings[rows]))


def last_detections(sights: dict[int, Sight], delays: np.ndarray, step: int, who: np.ndarray, gap: int) -> Detections:
    """What robots ``who`` ``(k,)`` (ids, increasing; timers' start-up delays ``delays`` ``(k,)``)
    saw at their last movement-sensor reading (every ``gap`` steps) up to ``step``, from the
    readings ``sights`` of the last ``gap`` steps (see :class:`Detections`)."""
    last = timers.last_due(step, delays, gap)
    parts: list[tuple[np.ndarray, ...]] = []
    for when in np.unique(last[last >= 0]):
        sight = sights[int(when)]
        mine = np.flatnonzero(last == when)
        starts, counts = sight.indptr[who[mine]], np.diff(sight.indptr)[who[mine]]
        owners = np.repeat(mine, counts)
        picks = spans(starts, counts)
        others, me = sight.indices[picks], who[owners]
        x = sight.poses
        # Robots of lower id had run their timers, decisions included, before this reading.
        later = others < me
        chained = later & (when == step)
        after = sight.before if when == step else sights[int(when) + 1].before
        known = np.where(later, after[:, others], sight.before[:, others])
        angles = np.arctan2(x[1, me] - x[1, others], x[0, me] - x[0, others])
        parts.append((owners, others, sight.distances[picks], angles, x[2, others], known, chained))
    return Detections.join(parts)


def decide_in_order(
    who: np.ndarray,
    poses: np.ndarray,
    dxi: np.ndarray,
    desired: np.ndarray,
    wanted: np.ndarray,
    settle: np.ndarray,
    seen: Detections,
    commands: np.ndarray,
    *,
    safety: float,
    v_max: float,
    bounds: Bounds,
    limits: RobotSpec,
) -> np.ndarray:
    """The commands of robots ``who`` ``(k,)`` (ids, increasing), written into ``commands``
    ``(2, n)``, and HRVO's choices ``(k, 2)`` (m/s; zero for the robots that settle).

    Each robot believes itself at ``poses`` ``(3, k)`` with last velocity ``dxi`` ``(k, 2)``; a
    robot that ``settle`` ``(k,)`` moves at ``desired`` ``(k, 2)``, the others at HRVO's choice
    for ``wanted`` ``(k, 2)`` among their detections ``seen`` (one :func:`dream.kernels.hrvo` call,
    ``safety``, ``v_max``, ``bounds``); the unicycle command, limited to ``limits``, drives no
    further when the motion guard (:func:`dream.robot.stopping`, :func:`~dream.robot.guard_distance`)
    stops it. A reading
    of this very step saw the new commands of the robots of lower id that decided before it in
    the per-robot mode's order, so such robots decide again until no command they see changes:
    the per-robot mode's decisions, in as many passes as the longest such chain.
    """
    k, n = len(who), commands.shape[1]
    near = guard_distance(limits.diameter, safety)
    own, heading = poses[:2].T, poses[2]
    chosen = np.zeros((k, 2))
    velocity = seen.velocity(commands)
    chained = np.flatnonzero(seen.chained)
    # Only detections this close can stop a robot (robot.stopping): the guard reads no others.
    close = np.flatnonzero(seen.distances < near + limits.v_max * GUARD_HORIZON + 1e-9)
    offsets = seen.offsets(close)
    todo = np.ones(k, dtype=bool)
    while todo.any():
        velocity[chained] = seen.velocity(commands, chained)
        pairs = np.flatnonzero(todo[seen.owners])
        steer = todo & ~settle
        chosen[steer] = _hrvo(own, dxi, wanted, steer, seen, velocity, pairs, safety, v_max, bounds)
        moving = np.where(settle[:, None], desired, chosen)[todo]
        new = kernels.actuator_limit(kernels.dxi_to_dxu(moving.T, poses[:, todo]), limits)
        local = np.cumsum(todo) - 1  # position of each robot of `who` among those of `todo`
        guarded = todo[seen.owners[close]]
        owners = local[seen.owners[close[guarded]]]
        new[0, stopping(new[0], heading[todo], owners, offsets[guarded], near)] = 0.0
        changed = np.zeros(n, dtype=bool)
        changed[who[todo]] = np.any(new != commands[:, who[todo]], axis=0)
        commands[:, who[todo]] = new
        todo = np.bincount(seen.owners[chained[changed[seen.others[chained]]]], minlength=k) > 0
    return chosen


def _hrvo(
    own: np.ndarray,
    dxi: np.ndarray,
    wanted: np.ndarray,
    steer: np.ndarray,
    seen: Detections,
    velocity: np.ndarray,
    pairs: np.ndarray,
    safety: float,
    v_max: float,
    bounds: Bounds,
) -> np.ndarray:
    """HRVO's choice ``(s, 2)`` for the robots ``steer`` ``(k,)`` bool among those at ``own``
    ``(k, 2)`` with velocities ``dxi`` and wishes ``wanted`` ``(k, 2)``, from their detections
    ``seen`` (rows ``pairs``, of the detected robots' ``velocity`` ``(m, 2)``): one
    :func:`dream.kernels.hrvo` call in which every detection is a robot of its own, placed where
    the detection says."""
    pairs = pairs[steer[seen.owners[pairs]]]
    owners = seen.owners[pairs]
    k = int(steer.sum())
    ghosts = own[owners] + seen.towards[pairs]
    counts = np.bincount((np.cumsum(steer) - 1)[owners], minlength=k)
    indptr = np.concatenate(([0], np.cumsum(counts), np.full(len(ghosts), len(ghosts))))
    return kernels.hrvo(
        np.vstack((own[steer], ghosts)),
        np.vstack((dxi[steer], velocity[pairs])),
        np.vstack((wanted[steer], np.zeros_like(ghosts))),
        (indptr, k + np.arange(len(ghosts))),
        safety=safety,
        v_max=v_max,
        bounds=bounds,
    )[:k]
