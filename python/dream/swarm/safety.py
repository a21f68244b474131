"""The engine's safety layer: from the velocities the robots wish to the commands they get.

HRVO on each robot's own detections (rows of one safety radius together, a row's result never
depending on the others'), stepping aside, the single-integrator to unicycle conversion, the
robot's limits and the motion guard. The engine (:class:`~dream.swarm.engine.Engine`) owns the
state these read and write (:class:`Driver`): the last velocities ``dxi`` and the side-step
counters.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from dream import kernels, rules
from dream._csr import spans
from dream.kernels._guard import motion_guard_trusted
from dream.kernels._hrvo import hrvo_rows_trusted
from dream.robot import GUARD_HORIZON, guard_distance
from dream.specs import ArenaSpec, RobotSpec
from dream.swarm.neighbourhood import Neighbourhood
from dream.swarm.robot import SwarmRobot
from dream.swarm.rows import at_rows, put_rows, take_rows


class Driver(Protocol):
    """What the safety layer reads and writes of the engine that runs it."""

    robot: SwarmRobot
    arena: ArenaSpec
    limits: RobotSpec  #: the robot's limits within the simulator's
    dxi: np.ndarray  #: (n, 2) each robot's last chosen velocity (m/s), HRVO's reciprocal term
    sidestep: np.ndarray  #: (n,) int: decisions left stepping aside
    side: np.ndarray  #: (n,) which side each robot steps aside to


#: The columns of a detection that HRVO reads: its distance, offset and velocity.
STEERED_BY = ("distance", "dx", "dy", "vx", "vy")


def drive(
    engine: Driver,
    rows: np.ndarray,
    wished: np.ndarray,
    pose: np.ndarray,
    seen: Neighbourhood,
    straight: np.ndarray | None,
    safety: np.ndarray | None = None,
) -> np.ndarray:
    """The unicycle commands ``(2, k)`` that carry out ``wished`` ``(k, 2)``: through HRVO on the
    robots' own detections (if they avoid, and but for the rows ``straight`` flags), the
    conversion, the limits and the motion guard; ``safety`` ``(k,)``: each row's safety radius
    (m) instead of the Avoid's. Rows of one radius go through the kernels together (a row's
    result never depends on the others')."""
    avoid = engine.robot.avoid
    if avoid is None:
        return _drive_apart(engine, rows, wished, pose, seen, straight, None)
    if safety is None or not len(safety) or (safety == safety[0]).all():  # one radius for all the rows
        radius = avoid.safety if safety is None or not len(safety) else float(safety[0])
        return _drive_apart(engine, rows, wished, pose, seen, straight, radius)
    out = np.empty((2, len(rows)))
    for radius in np.unique(safety):
        part = np.flatnonzero(safety == radius)
        counts = np.diff(seen.offsets)[part]
        hood = Neighbourhood(
            np.concatenate(([0], np.cumsum(counts))),
            {name: seen[name][spans(seen.offsets[:-1][part], counts)] for name in STEERED_BY},
        )
        cut = None if straight is None else straight[part]
        out[:, part] = _drive_apart(engine, rows[part], wished[part], pose[part], hood, cut, float(radius))
    return out


def _drive_apart(
    engine: Driver,
    rows: np.ndarray,
    wished: np.ndarray,
    pose: np.ndarray,
    seen: Neighbourhood,
    straight: np.ndarray | None,
    safety: float | None,
) -> np.ndarray:
    """:func:`drive` for rows that keep one ``safety`` radius (m)."""
    robot, avoid = engine.robot, engine.robot.avoid
    n = len(engine.dxi)
    chosen = wished
    if avoid is not None and safety is not None:
        # The rows that go through HRVO (and step aside); the others drive their wish as it is,
        # read in place by the kernels (no rows gathered out of the detections).
        steer = None if straight is None else ~straight
        asked = wished
        if avoid.sidestep:  # the side-step rule (dream.rules) on the engine's tables, in place
            asked = kernels.sidestep_ask(wished, rows, engine.sidestep, engine.side, steer)
        margin = robot.spec.radius if avoid.margin is None else avoid.margin
        chosen = hrvo_rows_trusted(  # the engine's own perception, and a decision checked in `Engine._apply`
            take_rows(engine.dxi, at_rows(rows, n)),
            np.ascontiguousarray(asked),
            np.ascontiguousarray(pose[:, :2]),
            seen.offsets,
            tuple(np.ascontiguousarray(seen[name]) for name in STEERED_BY),
            safety=safety,
            v_max=robot.spec.v_max,
            bounds=engine.arena.shrunk(margin) if avoid.check_boundaries else None,
            n_angles=avoid.n_angles,
            n_speeds=avoid.n_speeds,
            include_preferred=avoid.include_preferred,
            relative=True,  # the offsets of the robots seen: no angle to turn back into a direction
            steer=steer,
        )
        if avoid.sidestep:
            kernels.sidestep_mark(chosen, wished, rows, engine.sidestep, engine.side, avoid.sidestep, steer)
    put_rows(engine.dxi, at_rows(rows, n), chosen)
    out = kernels.dxi_to_dxu(chosen.T, pose.T, robot.vel_gain, robot.ang_gain)
    if robot.halts:  # no wish, no command (the conversion alone turns some robots at full speed)
        out[:, ~rules.nonzero(chosen)] = 0.0
    out = kernels.actuator_limit(out, engine.limits)
    near = None
    if robot.guard is not None:
        near = robot.guard.near
    elif avoid is not None and safety is not None and avoid.guard:
        near = guard_distance(robot.spec.diameter, safety)
    if near is not None:
        horizon = GUARD_HORIZON if avoid is None else avoid.horizon
        stop = motion_guard_trusted(  # the engine's own commands, poses and perception
            out[0], np.ascontiguousarray(pose[:, 2]), seen.offsets, seen["dx"], seen["dy"], near=near, horizon=horizon
        )
        out[0, stop] = 0.0
    return out
