"""Swarm modes' movement sensors and HRVO decisions, in the per-robot mode's order.

In the per-robot mode robots run their timers one after the other by id, so within a step a
robot's movement sensor sees the commands that robots of lower id have just decided. A swarm
mode that keeps each robot's timer schedule (:func:`dream.timers.due`) keeps this too: it takes
each robot's detections from its last reading (:func:`last_detections`) and lets the robots that
saw a command of this step decide again until none they see changes (:func:`decide_in_order`).
The readings themselves are :class:`~dream.experiments.line_consensus.Sight` and
:class:`~dream.experiments.line_consensus.Detections` (line-consensus's swarm mode, which has its
own copy of these two functions as methods, built them first).
"""

from __future__ import annotations

import numpy as np

from dream import kernels, timers
from dream.experiments.line_consensus import Detections, Sight
from dream.kernels import Bounds
from dream.robot import GUARD_HORIZON, stopping
from dream.specs import RobotSpec


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
        picks = np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
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
    near: float,
) -> np.ndarray:
    """The commands of robots ``who`` ``(k,)`` (ids, increasing), written into ``commands``
    ``(2, n)``, and HRVO's choices ``(k, 2)`` (m/s; zero for the robots that settle).

    Each robot believes itself at ``poses`` ``(3, k)`` with last velocity ``dxi`` ``(k, 2)``; a
    robot that ``settle`` ``(k,)`` moves at ``desired`` ``(k, 2)``, the others at HRVO's choice
    for ``wanted`` ``(k, 2)`` among their detections ``seen`` (one :func:`dream.kernels.hrvo` call,
    ``safety``, ``v_max``, ``bounds``); the unicycle command, limited to ``limits``, drives no
    further when the motion guard (:func:`dream.robot.stopping`, ``near`` m) stops it. A reading
    of this very step saw the new commands of the robots of lower id that decided before it in
    the per-robot mode's order, so such robots decide again until no command they see changes:
    the per-robot mode's decisions, in as many passes as the longest such chain.
    """
    k, n = len(who), commands.shape[1]
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
