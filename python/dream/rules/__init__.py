"""Decision rules shared by the per-robot classes and the whole-swarm (batch) loops.

Each rule is a small vectorised function: the same code decides for one robot (arrays of
shape ``(2,)`` or ``(1, 2)``, scalars for its counters) and for a whole swarm (``(n, 2)``,
``(n,)``). A per-robot controller calls a rule with its own values; a swarm loop calls it once
with every robot's; so the two modes cannot drift apart. Every rule is distributed: it uses
only what one robot knows (its position, its goal, its counters) and fixed, shared parameters.

The ring's rules (hrvo-circle's barrier, docking, squeezing) live in :mod:`dream.rules.ring`
and are read from here too. Units: metres, metres per second.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dream import kernels
from dream._checks import Bounds, FloatArray
from dream._reference import sidestep as _sidestep
from dream.rules.ring import (  # noqa: F401 (read from dream.rules too)
    BAND_MARGIN,
    arc_merge,
    arc_release,
    clear_way,
    dock,
    goal_taken,
    grow_over,
    outside_ring,
    squeezes,
    stall,
    watch_ends,
)

#: Angle (rad) the roundabout aims ahead of the island's tangent point, so that a robot on
#: the island's edge still has somewhere to go.
ROUNDABOUT_LEAD = np.pi / 6


def _pairs(*values: Any) -> bool:
    """Whether every one of ``values`` is one robot's vector, a float64 ndarray ``(2,)``: the rules
    then take a scalar path, which skips NumPy's per-call cost on tiny arrays (most of a robot's
    decision time) and rounds as the array path (same operations in the same order, and the
    same NumPy functions wherever a result could differ from :mod:`math`'s)."""
    for v in values:  # a loop: a generator would cost as much as the check
        if type(v) is not np.ndarray or v.shape != (2,) or v.dtype is not _FLOAT64:
            return False
    return True


def _row(*values: Any) -> bool:
    """Whether every one of ``values`` is one robot's row, a float64 ndarray ``(1, 2)`` (a swarm
    robot deciding robot by robot): the rules then take their scalar path on it."""
    for v in values:
        if type(v) is not np.ndarray or v.shape != (1, 2) or v.dtype is not _FLOAT64:
            return False
    return True


def _scalars(*values: Any) -> bool:
    """Whether every one of ``values`` is a Python or NumPy number or a 0-d array (a robot's own counter)."""
    for v in values:
        if type(v) is bool or not (isinstance(v, _NUMBERS) or (type(v) is np.ndarray and v.ndim == 0)):
            return False
    return True


_FLOAT64 = np.dtype(np.float64)
_NUMBERS = (int, float, np.integer, np.floating)


def arrival(positions: Any, goals: Any, unreached: Any, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Which robots are at their goal, and which of them reached it just now.

    Parameters
    ----------
    positions, goals : (n, 2) or (2,) array_like
        Where the robots are and where they are heading (m).
    unreached : (n,) or () bool array_like
        Whether each robot's current goal has not been counted as reached yet.
    tolerance : float
        A robot closer than this to its goal has arrived (m).

    Returns
    -------
    arrived, reached : (n,) or () bool ndarray
        ``arrived``: within ``tolerance``; ``reached``: arrived and not counted before (the
        robot raises its state once, then clears ``unreached``).
    """
    if _pairs(positions, goals) and (isinstance(unreached, (bool, np.bool_)) or _scalars(unreached)):
        arrived = np.hypot(float(goals[0]) - float(positions[0]), float(goals[1]) - float(positions[1])) < tolerance
        return arrived, arrived & np.bool_(unreached)
    if _row(positions, goals) and type(unreached) is np.ndarray and unreached.shape == (1,):
        one, now = arrival(positions[0], goals[0], unreached[0], tolerance)
        return np.array([one]), np.array([now])
    offset = np.asarray(goals, dtype=np.float64) - np.asarray(positions, dtype=np.float64)
    arrived = np.hypot(offset[..., 0], offset[..., 1]) < tolerance
    return arrived, arrived & np.asarray(unreached, dtype=bool)


def moves_on(state: Any, everyone_level: Any, unreached: Any, n_goals: int) -> np.ndarray:
    """Whether a robot heads for its next goal: it has reached its current one, it knows that
    every robot has reached as many goals as itself (``everyone_level``), and goals remain."""
    state = np.asarray(state)
    return np.asarray(everyone_level, dtype=bool) & (state < n_goals) & ~np.asarray(unreached, dtype=bool)


def roundabout_aim(positions: Any, goals: Any, semi_axes: tuple[float, float], island: float) -> FloatArray:
    """The point a robot aims at so that every robot turns the same way around the centre.

    HRVO alone lets robots that cross through the centre from all sides meet head-on and
    freeze or circle there. Here the centre is an island, an ellipse of ``island`` times
    ``semi_axes`` about the origin, that every robot keeps on its left (counter-clockwise
    traffic): a robot whose straight way to its goal passes through the island aims instead
    at the island's edge just past its counter-clockwise tangent point. Robots then merge into
    one stream around the centre, leaving it when the goal comes into view, instead of facing
    each other. A robot inside the island that heads outwards goes straight to its goal.

    The tangents are computed after scaling the ellipse to a circle: a linear map keeps lines,
    tangency and the sense of rotation.

    Parameters
    ----------
    positions, goals : (n, 2) or (2,) array_like
        Positions and goals (m), relative to the arena's centre at the origin.
    semi_axes : (float, float)
        Semi-axes ``(a, b)`` of the goals' ring (m); the island is ``island * (a, b)``.
    island : float
        The island's size as a fraction of the ring, in [0, 1); 0 turns the rule off.

    Returns
    -------
    (n, 2) or (2,) ndarray
        The point to head for (m): the goal, or a point on the island's edge.
    """
    if _pairs(positions, goals):
        a, b = float(semi_axes[0]), float(semi_axes[1])
        qx, qy = float(positions[0]) / a, float(positions[1]) / b
        gx, gy = float(goals[0]) / a, float(goals[1]) / b
        wx, wy = gx - qx, gy - qy
        t = -(qx * wx + qy * wy) / max(wx * wx + wy * wy, 1e-300)
        c = min(max(t, 0.0), 1.0)
        if t > 0.0 and np.hypot(qx + c * wx, qy + c * wy) < island:
            r = float(np.hypot(qx, qy))
            turn = np.arccos(min(island / max(r, 1e-300), 1.0)) + ROUNDABOUT_LEAD
            angle = float(np.arctan2(qy, qx) + turn)
            gx, gy = island * float(np.cos(angle)), island * float(np.sin(angle))
        return np.array([gx * a, gy * b])
    if _row(positions, goals):
        return roundabout_aim(positions[0], goals[0], semi_axes, island)[None]
    scale = np.asarray(semi_axes, dtype=np.float64)
    q = np.asarray(positions, dtype=np.float64) / scale
    g = np.asarray(goals, dtype=np.float64) / scale
    way = g - q
    (qx, qy), (wx, wy) = np.moveaxis(q, -1, 0), np.moveaxis(way, -1, 0)
    length2 = np.maximum(wx * wx + wy * wy, 1e-300)
    # Closest approach to the centre along the way, only if it lies ahead of the robot.
    t = -(qx * wx + qy * wy) / length2
    closest = q + np.clip(t, 0.0, 1.0)[..., None] * way
    crosses = (t > 0.0) & (np.hypot(closest[..., 0], closest[..., 1]) < island)
    # The trigonometry only for the robots that go round (element by element, as for one robot),
    # their coordinates read and written one column at a time (NumPy moves a masked row of two
    # values one call a row).
    x, y = q[..., 0][crosses], q[..., 1][crosses]
    radii = np.hypot(x, y)
    # The counter-clockwise tangent point from q is acos(island / r) past q's own angle.
    turns = np.arccos(np.minimum(island / np.maximum(radii, 1e-300), 1.0)) + ROUNDABOUT_LEAD
    angles = np.arctan2(y, x) + turns
    g[..., 0][crosses] = island * np.cos(angles)
    g[..., 1][crosses] = island * np.sin(angles)
    return g * scale


def preferred_velocity(positions: Any, aims: Any, goals: Any, v_max: float, gain: float) -> FloatArray:
    """Towards ``aims``, at a speed that falls in proportion to the distance left to ``goals``.

    Slowing down near the goal lets a robot settle on it instead of stopping anywhere within
    the arrival tolerance, where, off towards a neighbour's goal, it could keep that neighbour
    from arriving.

    Parameters
    ----------
    positions, aims, goals : (n, 2) or (2,) array_like
        Positions, the points the robots head for now, and their goals (m).
    v_max : float
        Top speed (m/s).
    gain : float
        Speed per metre left to the goal (1/s) below ``v_max``.

    Returns
    -------
    (n, 2) or (2,) ndarray
        Preferred single-integrator velocities (m/s); zero at the goal.
    """
    if _pairs(positions, aims, goals):
        px, py = float(positions[0]), float(positions[1])
        ox, oy = float(aims[0]) - px, float(aims[1]) - py
        distance = float(np.hypot(ox, oy))
        speed = min(v_max, gain * float(np.hypot(float(goals[0]) - px, float(goals[1]) - py)))
        factor = speed / max(distance, 1e-300) if distance > 0.0 else 0.0
        return np.array([ox * factor, oy * factor])
    if _row(positions, aims, goals):
        return preferred_velocity(positions[0], aims[0], goals[0], v_max, gain)[None]
    p = np.asarray(positions, dtype=np.float64)
    offset = np.asarray(aims, dtype=np.float64) - p
    left = np.asarray(goals, dtype=np.float64) - p
    distances = np.hypot(offset[..., 0], offset[..., 1])
    speeds = np.minimum(v_max, gain * np.hypot(left[..., 0], left[..., 1]))
    return offset * np.where(distances > 0.0, speeds / np.maximum(distances, 1e-300), 0.0)[..., None]


def sidestep_preference(desired: Any, sidestep: Any, side: Any) -> tuple[FloatArray, Any]:
    """The velocity a robot asks HRVO for, and its side-step counter after this decision.

    A robot with ``sidestep`` decisions left stepping aside asks for its desired velocity
    turned by -90 degrees times ``side`` (1: to its right, -1: to its left).

    Parameters
    ----------
    desired : (n, 2) or (2,) array_like
        Velocity towards the goal (m/s).
    sidestep : (n,) or () int array_like
        Decisions left stepping aside.
    side : (n,) or () float array_like
        1.0 or -1.0.

    Returns
    -------
    wanted : (n, 2) or (2,) ndarray
        Velocity to ask HRVO for (m/s).
    sidestep : (n,) or () int ndarray
        The counter, one decision fewer.
    """
    if _pairs(desired) and _scalars(sidestep, side):
        if sidestep > 0:
            s = float(side)
            wanted = np.array([s * float(desired[1]), s * -float(desired[0])])
        else:
            wanted = desired.copy()
        return wanted, np.int64(max(int(sidestep) - 1, 0))
    return _sidestep.preference(desired, sidestep, side)  # many robots: the array rule


def sidestep_update(chosen: Any, desired: Any, sidestep: Any, side: Any, updates: int) -> tuple[Any, Any]:
    """The side-step counter and side after HRVO chose ``chosen``.

    HRVO stops a robot whose way is blocked by a robot within the safety radius (every free
    velocity points away from its goal). A robot that wants to move but got the zero velocity
    steps aside to its right for the next ``updates`` decisions; blocked again while still
    stepping aside (by a wall, say), it turns to the other side. Robots that all turn the same
    way circulate around each other instead of facing off.

    Parameters
    ----------
    chosen, desired : (n, 2) or (2,) array_like
        HRVO's velocity and the velocity towards the goal (m/s).
    sidestep, side : (n,) or () array_like
        The counter after :func:`sidestep_preference`, and the side (1.0 or -1.0).
    updates : int
        Decisions to step aside for.

    Returns
    -------
    sidestep, side : (n,) or () ndarray
    """
    if _pairs(chosen, desired) and _scalars(sidestep, side):
        if chosen[0] or chosen[1] or not (desired[0] or desired[1]):  # not blocked
            return np.int64(sidestep), np.float64(side)
        return np.int64(updates), np.float64(-float(side) if sidestep > 0 else 1.0)
    return _sidestep.update(chosen, desired, sidestep, side, updates)


def wmsr_keep(values: Any, own: float, trimmed: int) -> np.ndarray:
    """W-MSR's filter for one robot: ``values`` ``(k,)`` without the ``trimmed`` largest of those above
    ``own`` and the ``trimmed`` smallest of those below it (all of them when there are fewer), in
    their order (:func:`wmsr_kept` of one row).

    With at most ``trimmed`` lying neighbours in a robust enough graph, the correct robots still
    reach consensus within the range of their own values (LeBlanc et al., 2013): a liar's value
    outside that range is among the dropped ones.
    """
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    return values[wmsr_kept(values, np.array([0, len(values)]), np.array([own], dtype=np.float64), trimmed)]


def wmsr_kept(values: Any, offsets: Any, own: Any, trimmed: int) -> np.ndarray:
    """W-MSR's filter on ragged rows: ``(e,)`` bool, which of ``values`` ``(e,)`` (NaN-free) row r
    (entries ``offsets[r]:offsets[r + 1]``) keeps when it drops the ``trimmed`` largest of its values
    above ``own[r]`` and the ``trimmed`` smallest below it (all of them when there are fewer).

    Each row is sorted on its own (by row, then value), so a row's flags depend on its entries
    alone: robots filtered one at a time or together keep the same values.
    """
    values = np.asarray(values, dtype=np.float64)
    offsets = np.asarray(offsets, dtype=np.int64)
    keep = np.ones(len(values), dtype=bool)
    if trimmed <= 0 or not len(values):
        return keep
    count = np.diff(offsets)
    row = np.repeat(np.arange(len(count)), count)
    mine = np.asarray(own, dtype=np.float64)[row]
    order = np.lexsort((values, row))
    rank = np.empty(len(values), dtype=np.int64)  # each value's place in its row, smallest first
    rank[order] = np.arange(len(values)) - offsets[row[order]]
    below = np.minimum(np.bincount(row[values < mine], minlength=len(count)), trimmed)
    above = np.minimum(np.bincount(row[values > mine], minlength=len(count)), trimmed)
    # Sorted, a row holds its values below `own` first and those above it last.
    return (rank >= below[row]) & (rank < (count - above)[row])


def seen_positions(position: Any, detections: Any) -> FloatArray:
    """World positions ``(k, 2)`` of the robots in movement-sensor ``detections`` ``(k, 4)`` (rows
    ``[distance, angle, vx, vy]``, ``angle`` pointing from the robot seen to the one at
    ``position`` ``(2,)``, m)."""
    rows = np.asarray(detections, dtype=np.float64).reshape(-1, 4)
    d, angle = rows[:, 0], rows[:, 1]
    return np.column_stack((position[0] - d * np.cos(angle), position[1] - d * np.sin(angle)))


def far_from(points: Any, others: Any, distance: float, *, offsets: tuple[Any, Any] | None = None) -> np.ndarray:
    """``(k,)`` bool: which of ``points`` ``(k, 2)`` lie farther than ``distance`` (m) from every one
    of ``others`` ``(m, 2)`` (all of them when there are none): robots seen that no claimed
    position accounts for, or claims that match no robot seen. Several robots at once: their
    rows cut by ``offsets`` (see :func:`dream.kernels.far_from`)."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    others = np.asarray(others, dtype=np.float64).reshape(-1, 2)
    return kernels.far_from(points, others, distance, offsets=offsets)


def line_places(senders: Any, receivers: Any, x: Any, y: Any, spacing: float) -> FloatArray:
    """Where each line-consensus message puts its receiver ``(m, 2)`` (m): ``spacing`` per id
    difference right of the sender's ``x`` (robot i belongs ``(j - i) spacing`` right of robot
    j), in the sender's row ``y``. ``senders``, ``receivers``, ``x``, ``y``: ``(m,)`` or scalars."""
    offset = (np.asarray(senders) - np.asarray(receivers)) * spacing
    return np.stack(np.broadcast_arrays(np.asarray(x, dtype=np.float64) + offset, np.asarray(y, dtype=np.float64)), -1)


def consensus(values: Any, rows: Any, count: int) -> FloatArray:
    """The consensus update: each of ``count`` robots takes the mean of the values ``(m, 2)`` it
    received (``rows`` ``(m,)``: the receiving robot's row, values in the order received);
    ``(count, 2)``, NaN for a robot that received nothing.

    Robots with as many messages are averaged together, each row as ``numpy.mean`` averages one
    robot's list (pairwise summation), so that a robot and the swarm round alike.
    """
    values = np.asarray(values, dtype=np.float64).reshape(-1, 2)
    rows = np.asarray(rows, dtype=np.int64)
    order = np.argsort(rows, kind="stable")
    heard = np.bincount(rows, minlength=count)
    starts = np.concatenate(([0], np.cumsum(heard)))[:-1]
    out = np.full((count, 2), np.nan)
    for size in np.unique(heard[heard > 0]):
        robots = np.flatnonzero(heard == size)
        picks = order[starts[robots, None] + np.arange(size)]  # (robots, size), in the order received
        out[robots, 0] = values[picks, 0].mean(axis=1)
        out[robots, 1] = values[picks, 1].mean(axis=1)
    return out


def line_goal(
    positions: Any, targets: Any, travelling: Any, spacing: float, lane: float, bounds: Bounds
) -> tuple[FloatArray, np.ndarray]:
    """Where line-consensus robots head for their consensus ``targets``, and whether they travel.

    With a passing lane (``lane`` > 0 m) a robot whose place is more than two spacings away along
    x travels (until it is within one): it heads for the target's x in its own row, at least
    ``lane`` off the line (above it when heading right, below when heading left, if closer). A
    robot that does not travel heads for its target. Goals lie within ``bounds``: the consensus
    line drifts while the team travels, and a robot heading for a place beyond the arena's edge
    would leave what HRVO's boundary check accepts, after which HRVO forbids it every velocity
    (1000 robots: the line's end 0.4 m beyond the edge froze a robot there for good). Waiting at
    the edge, it pulls the line back through the consensus.

    Parameters
    ----------
    positions, targets : (n, 2) or (2,) array_like
        Where the robots are and their consensus targets (m); a NaN target leaves the robot's
        ``travelling`` as it was.
    travelling : (n,) or () bool array_like
        Whether each robot travelled at its last decision.
    bounds : (xmin, xmax, ymin, ymax)
        Where the robots' centres may go (m).

    Returns
    -------
    goals : (n, 2) or (2,) ndarray
    travelling : (n,) or () bool ndarray
    """
    p = np.asarray(positions, dtype=np.float64)
    t = np.asarray(targets, dtype=np.float64)
    dx = t[..., 0] - p[..., 0]
    away = np.abs(dx)
    travelling = np.where((lane > 0) & (away > 2 * spacing), True, np.where(away < spacing, False, travelling))
    off_line = p[..., 1] - t[..., 1]
    off_line = np.where(np.abs(off_line) < lane, np.copysign(lane, dx), off_line)
    beside = np.stack((t[..., 0], t[..., 1] + off_line), axis=-1)
    goals = np.where(travelling[..., None], beside, t)
    xmin, xmax, ymin, ymax = bounds
    return np.stack((goals[..., 0].clip(xmin, xmax), goals[..., 1].clip(ymin, ymax)), axis=-1), travelling


def nonzero(vectors: Any) -> np.ndarray:
    """Which ``vectors`` ``(n, 2)`` or ``(2,)`` are not zero (a NaN component counts, as in
    ``numpy.any``): component by component, six times faster than ``numpy.any(..., axis=-1)``
    over two values a row."""
    v = np.asarray(vectors)
    return (v[..., 0] != 0) | (v[..., 1] != 0)


def each_any(flags: Any) -> np.ndarray:
    """``(k, ...)``: whether any of each row's ``flags`` ``(k, m, ...)`` along axis 1 is set, as
    ``flags.any(axis=1)`` gives, column by column: 5-10 times faster over the few columns of a
    robot's tables (NumPy reduces a short axis slowly)."""
    f = np.asarray(flags, dtype=bool)
    if f.ndim < 2:
        raise ValueError(f"each_any takes flags of shape (k, m, ...), got {f.shape}")
    out = np.zeros((f.shape[0], *f.shape[2:]), dtype=bool)
    for j in range(f.shape[1]):
        out |= f[:, j]
    return out


def length(vectors: Any) -> FloatArray:
    """Lengths ``(n,)`` or ``()`` of ``vectors`` ``(n, 2)`` or ``(2,)``, rounded as :func:`math.hypot`
    rounds them (which can differ from ``numpy.hypot`` in the last bit): a robot's rules and the
    swarm's then round alike, and as the per-robot code always has."""
    v = np.asarray(vectors, dtype=np.float64)
    return kernels.hypot(v[..., 0], v[..., 1])


def squared_length(vectors: Any) -> FloatArray:
    """Squared lengths ``(...)`` of ``vectors`` ``(..., 2)``: to compare with a squared distance
    (a fifth of the cost of :func:`length`'s ``hypot``)."""
    v = np.asarray(vectors, dtype=np.float64)
    return v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1]


def toward(positions: Any, goals: Any, gain: float, v_max: float) -> FloatArray:
    """``gain (goals - positions)`` ``(n, 2)`` or ``(2,)`` (m/s), scaled down to ``v_max`` when faster."""
    return capped(gain * (np.asarray(goals, dtype=np.float64) - np.asarray(positions, dtype=np.float64)), v_max)


def capped(velocities: Any, v_max: float) -> FloatArray:
    """``velocities`` ``(n, 2)`` or ``(2,)`` (m/s) scaled down to ``v_max`` when faster (times
    ``v_max / speed``, as a robot's ``desired *= v_max / speed`` rounds)."""
    v = np.asarray(velocities, dtype=np.float64)
    return v * np.minimum(1.0, v_max / np.maximum(length(v), 1e-300))[..., None]


def stress(positions: Any, others: Any, weights: Any) -> FloatArray:
    """The stress term of the affine-formation law, ``sum_j w_ij (p_i - p_j)`` ``(n, 2)`` or ``(2,)``
    (m), for robots at ``positions`` ``(n, 2)`` or ``(2,)`` that take their formation's robots to be
    at ``others`` ``(n, k, 2)`` or ``(k, 2)`` with weights ``weights`` ``(n, k)`` or ``(k,)``.

    Terms are added in the order of ``others``, and skipped where the weight is 0 or the position
    unknown (NaN: nothing heard yet), so that a robot and the swarm round alike.
    """
    p = np.asarray(positions, dtype=np.float64)
    there = np.asarray(others, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    pull = np.zeros(p.shape)
    for j in range(there.shape[-2]):
        counts = (w[..., j] != 0) & np.isfinite(there[..., j, 0])
        pull = np.where(counts[..., None], pull + w[..., j, None] * (p - there[..., j, :]), pull)
    return pull


def sent_row(own_y: Any, target_y: Any, travelling: Any) -> np.ndarray:
    """The y a line-consensus robot sends: its target's while it travels beside the line (so that
    its detour does not pull the others' line), else its own. A NaN target: its own."""
    target_y = np.asarray(target_y, dtype=np.float64)
    return np.where(np.asarray(travelling, dtype=bool) & np.isfinite(target_y), target_y, own_y)


def settles(desired: Any, nearest: Any, fine: float, clearance: float) -> np.ndarray:
    """Whether a robot moves at ``desired`` ``(n, 2)`` or ``(2,)`` (m/s) without HRVO: slower than
    ``fine`` (m/s) with no robot nearer than ``clearance`` (m; ``nearest`` ``(n,)`` or ``()``,
    inf when none is detected). See :meth:`dream.robot.RobotHRVO.settle_or_steer`."""
    return (length(desired) < fine) & (np.asarray(nearest) >= clearance)


def approach(
    positions: Any, centroids: Any, gain: float, v_max: float, arrival: float, carry: Any = None
) -> FloatArray:
    """Coverage: ``gain`` times the way to the cell's centroid ``(n, 2)`` or ``(2,)`` (m/s), no
    faster than ``v_max``; zero when the way is shorter than ``arrival`` (m).

    ``carry`` ``(n, 2)`` or ``(2,)`` (m), optional, is added to the way: the share of its last step
    a moving robot keeps (heavy-ball). A robot in a slow flow, whose centroid moves ahead of it
    with its neighbours, then keeps moving instead of stopping each time it is just within
    ``arrival`` and starting again when a neighbour's step pushes it out.
    """
    offset = np.asarray(centroids, dtype=np.float64) - np.asarray(positions, dtype=np.float64)
    way = offset if carry is None else offset + np.asarray(carry, dtype=np.float64)
    distance = length(way)
    scale = np.minimum(1.0, v_max / (gain * np.maximum(distance, 1e-300)))
    return np.where((distance >= arrival)[..., None], gain * way * scale[..., None], 0.0)


def momentum(positions: Any, last: Any, moving: Any, share: float) -> FloatArray:
    """``share`` of the step ``positions - last`` ``(n, 2)`` or ``(2,)`` (m) that the robots
    ``moving`` ``(n,)`` or ``()`` (bool: their last decision moved them) took since their last
    decision at ``last``; zero for the others. Coverage adds it to a robot's way to its centroid
    (:func:`approach`'s ``carry``, heavy-ball), and a moving robot sends where it is plus it: where
    it will be at its next decision if it keeps its pace."""
    step = np.asarray(positions, dtype=np.float64) - np.asarray(last, dtype=np.float64)
    return np.where(np.asarray(moving, dtype=bool)[..., None], share * step, 0.0)


def morph(start: Any, goals: Any, done: Any, total: int) -> FloatArray:
    """Where aims stand after ``done`` ``(k,)`` or ``()`` of ``total`` steps from ``start`` to ``goals``
    ``(k, m, 2)`` or ``(m, 2)`` (m): a steady pace along straight lines, then at the goals. Aims
    that all take the same shape keep an affine image of it on the way (affine-formation's leaders)."""
    start = np.asarray(start, dtype=np.float64)
    share = np.minimum(np.asarray(done) / total, 1.0)
    return start + share[..., None, None] * (np.asarray(goals, dtype=np.float64) - start)
