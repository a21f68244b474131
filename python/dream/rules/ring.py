"""The ring's rules (hrvo-circle): the arrival barrier of bounded messages, its failure
detector, docking on a packed ring, squeezing and taking a goal a standing robot holds.

Like every rule of :mod:`dream.rules`, each decides for one robot or for many at once from what
those robots alone know. Units: metres, metres per second.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dream import kernels
from dream._checks import FloatArray

_FLOAT64, _INT64 = np.dtype(np.float64), np.dtype(np.int64)


def _alone(*values: Any) -> bool:
    """Whether every one of ``values`` is one robot's row, an ndarray ``(1,)`` (a swarm robot
    deciding robot by robot): a rule then decides in Python, skipping NumPy's per-call cost, with
    the same operations in the same order as its array path."""
    for v in values:
        if type(v) is not np.ndarray or v.shape != (1,):
            return False
    return True


def arc_merge(
    n: int, state: Any, left: Any, right: Any, released: Any, rows: Any, offsets: Any, heard: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One radio round of the arrival barrier: robots merge the arcs of ids they know to have
    arrived, and the highest level known to be complete.

    Robot ``i`` of ``n`` (ids around a ring, cyclic) at level ``state`` (goals reached) knows
    that robots ``i - left, ..., i + right`` (mod ``n``) have reached at least ``state`` goals,
    and that every robot has reached at least ``released`` goals. A message from robot ``j``
    at level ``state_j >= state`` whose arc overlaps or touches robot i's extends it (trying
    ``j``'s arc shifted by ``-n, 0, n`` about the ring); any message raises ``released`` to
    the sender's. Each message is compared with the arc the robot had before the round, so the
    order of messages does not matter. Facts only ever become true (levels never fall), so a
    stale, late or repeated message never makes an arc claim too much.

    Parameters
    ----------
    n : int
        Robots around the ring.
    state, left, right, released : (m,) or () int array_like
        The ``m`` receiving robots' levels, arcs and released levels.
    rows : (k,) int array_like
        Each message's receiving robot (index into the ``m``).
    offsets : (k,) int array_like
        The sender's id less the receiver's, mod ``n``.
    heard : (k, 4) int array_like
        Each message's ``[state, left, right, released]``.

    Returns
    -------
    left, right, released : (m,) or () int64 ndarray
        After the round; an arc covering every robot is capped at ``n - 1`` on either side.
        Complete arcs release their level in :func:`arc_release`.
    """
    state, left, right, released = (np.asarray(v, dtype=np.int64) for v in (state, left, right, released))
    rows = np.asarray(rows, dtype=np.intp)
    heard = np.asarray(heard, dtype=np.int64).reshape(-1, 4)
    offsets = np.asarray(offsets, dtype=np.int64)
    own_left, own_right = left.reshape(-1)[rows], right.reshape(-1)[rows]
    useful = heard[:, 0] >= state.reshape(-1)[rows]  # the sender's arc holds at its level, so at any lower one
    new_left, new_right = own_left.copy(), own_right.copy()
    for shift in (-n, 0, n):
        low, high = offsets + shift - heard[:, 1], offsets + shift + heard[:, 2]
        touch = useful & (low <= own_right + 1) & (high >= -own_left - 1)
        new_left = np.where(touch, np.maximum(new_left, -low), new_left)
        new_right = np.where(touch, np.maximum(new_right, high), new_right)
    out = [left.reshape(-1).copy(), right.reshape(-1).copy(), released.reshape(-1).copy()]
    for total, values in zip(out, (new_left, new_right, heard[:, 3])):
        np.maximum.at(total, rows, values)
    shape = state.shape
    return np.minimum(out[0], n - 1).reshape(shape), np.minimum(out[1], n - 1).reshape(shape), out[2].reshape(shape)


def arc_release(n: int, state: Any, left: Any, right: Any, released: Any) -> np.ndarray:
    """The released level ``(m,)`` or ``()``: a robot whose arc (:func:`arc_merge`) covers all
    ``n`` robots knows that every robot has reached its level, and releases it."""
    full = np.asarray(left) + np.asarray(right) + 1 >= n
    return np.maximum(np.asarray(released, dtype=np.int64), np.where(full, np.asarray(state, dtype=np.int64), -1))


def watch_ends(
    n: int, ids: Any, left: Any, right: Any, watched: Any, ages: Any, rows: Any, senders: Any, relayed: Any
) -> tuple[np.ndarray, np.ndarray]:
    """One round of the barrier's failure detector, bounded whatever ``n``: each robot watches the
    two robots just beyond the ends of its arc (:func:`arc_merge`), the ones its release waits on.

    A watched robot's age counts the rounds since the robot last had news that it was alive: it
    heard it, or heard a robot that watches it too and had news ``a`` rounds old (then ``a + 1``:
    a message is at least a round old, so stale or repeated news never keeps a silent robot
    young). A robot whose arc end moved watches the new one from age 1. A crashed robot's
    messages leave the air, so its age grows by one a round; a live one's stays small while a
    robot near it watches it. The caller takes an age beyond its silence for a crash.

    Parameters
    ----------
    n : int
        Robots around the ring.
    ids, left, right : (k,) int array_like
        The deciding robots' ids and arcs (after this round's merge).
    watched, ages : (k, 2) int array_like
        The robots each watched beyond its left and right ends, and their ages (rounds).
    rows, senders : (e,) int array_like
        Each message's receiving row and its sender.
    relayed : (e, 4) int array_like
        Each message's ``[watched left, its age, watched right, its age]``.

    Returns
    -------
    watched, ages : (k, 2) int64 ndarray
    """
    ids, left, right = (np.asarray(v, dtype=np.int64) for v in (ids, left, right))
    ends = np.stack(((ids - left - 1) % n, (ids + right + 1) % n), axis=-1)
    ages = np.where(ends == np.asarray(watched), np.asarray(ages, dtype=np.int64), 0) + 1
    rows, senders = np.asarray(rows, dtype=np.intp), np.asarray(senders, dtype=np.int64)
    relayed = np.asarray(relayed, dtype=np.int64).reshape(-1, 4)
    for side in (0, 1):
        end = ends[rows, side]
        news = np.where(senders == end, 0, np.iinfo(np.int64).max)
        for at in (0, 2):
            news = np.where(relayed[:, at] == end, np.minimum(news, relayed[:, at + 1] + 1), news)
        np.minimum.at(ages[:, side], rows, news)
    return ends, ages


def grow_over(n: int, left: Any, right: Any, silent: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(left, right, grown)``: each arc (:func:`arc_merge`) grown by one over the robot beyond
    each end flagged ``silent`` ``(k, 2)`` (taken for crashed: the others stop waiting for it),
    never beyond all ``n`` robots (one robot beyond both ends is passed once); ``grown`` ``(k, 2)``
    flags the ends that grew."""
    grown = np.array(silent, dtype=bool, copy=True).reshape(-1, 2)
    left, right = np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)
    grown[:, 0] &= left + right + 1 < n
    left = left + grown[:, 0]
    grown[:, 1] &= left + right + 1 < n
    return left, right + grown[:, 1], grown


def stall(distance: Any, closest: Any, stalled: Any, unreached: Any, progress: float) -> tuple[Any, Any]:
    """``(closest, stalled)`` after a decision ``distance`` (m) from the goal: a robot that has come
    ``progress`` (m) closer than ``closest`` since its last progress starts counting again; one
    that has not counts one more decision stalled; one waiting on a goal reached is not stalled."""
    alone = _alone(distance, closest, stalled, unreached)
    if alone and distance.dtype == closest.dtype == _FLOAT64 and stalled.dtype == _INT64:  # one robot's row
        d, c, waiting = float(distance[0]), float(closest[0]), bool(unreached[0])
        moved = waiting and d < c - progress
        return np.array([d if moved else c]), np.array([stalled[0] + 1 if waiting and not moved else 0])
    distance, closest = np.asarray(distance, dtype=np.float64), np.asarray(closest, dtype=np.float64)
    unreached = np.asarray(unreached, dtype=bool)
    moved = unreached & (distance < closest - progress)
    stalled = np.where(unreached & ~moved, np.asarray(stalled) + 1, 0)
    return np.where(moved, distance, closest), stalled


def squeezes(squeezing: Any, stalled: Any, patience: int, outside: Any, nearest: Any, safety: float) -> np.ndarray:
    """Whether each robot takes its least safety radius: stalled for ``patience`` decisions while
    ``outside`` the ring of parked robots (a wall at the ring's radius), until the ``nearest``
    robot it sees (m, NaN: none) is ``safety`` (the ring's radius) away."""
    if _alone(squeezing, stalled, outside, nearest) and nearest.dtype == _FLOAT64:  # one robot's row
        stuck = bool(stalled[0] >= patience) and bool(outside[0])
        return np.array([stuck or (bool(squeezing[0]) and float(nearest[0]) < safety)])
    clear = ~(np.asarray(nearest, dtype=np.float64) < safety)
    stuck = (np.asarray(stalled) >= patience) & np.asarray(outside, dtype=bool)
    return stuck | (np.asarray(squeezing, dtype=bool) & ~clear)


def goal_taken(here: Any, goals: Any, offsets: Any, seen: Any, speeds: Any, reach: Any, safety: float) -> np.ndarray:
    """``(k,)`` bool: whether a robot standing on each robot's goal holds it: one of the robots seen
    (``seen`` ``(e, 2)``, their offsets from the robot; ``speeds`` ``(e,)`` bool, whether each
    stands still; rows cut by ``offsets``) within ``safety`` (m) of the goal while the robot is
    within ``reach`` ``(k,)`` (m) of it, as close as HRVO lets it come. A crashed robot stops where
    it is and a finished one stays: the goal then counts as reached, or the circles stop."""
    here, goals = np.asarray(here, dtype=np.float64), np.asarray(goals, dtype=np.float64)
    owner = np.repeat(np.arange(len(here)), np.diff(offsets))
    others = here[owner] + np.asarray(seen, dtype=np.float64).reshape(-1, 2)
    on_goal = np.asarray(speeds, dtype=bool) & (np.hypot(*(others - goals[owner]).T) < safety)
    near = np.hypot(*(here - goals).T) <= np.asarray(reach)
    return near & kernels.segment_any(on_goal, np.asarray(offsets, dtype=np.int64))


def outside_ring(positions: Any, semi_axes: tuple[float, float]) -> np.ndarray:
    """Whether each position lies beyond the ring with ``semi_axes`` (m), centred on the origin."""
    if type(positions) is np.ndarray and positions.shape == (1, 2) and positions.dtype == _FLOAT64:  # one robot's row
        x, y = float(positions[0, 0]) / float(semi_axes[0]), float(positions[0, 1]) / float(semi_axes[1])
        return np.array([np.hypot(x, y) > 1.0])
    q = np.asarray(positions, dtype=np.float64) / np.asarray(semi_axes, dtype=np.float64)
    return np.hypot(q[..., 0], q[..., 1]) > 1.0


def dock(
    positions: Any, goals: Any, semi_axes: tuple[float, float], depth: float, width: float, lead: float
) -> tuple[FloatArray, np.ndarray]:
    """Where a robot heads for its goal on a packed ring, reached only from the inside.

    On a ring whose goals are barely a robot's width apart, robots parked at their goals form a
    wall: a robot that meets the ring beside its goal cannot slide along it, and one that slips
    outside is shut out. So each goal has a dock, ``depth`` inside it along the ring's inward
    normal, and a corridor of half-width ``width`` from the dock to the goal. A robot in its
    corridor heads for the goal; one in the ring's band (beyond the ring of docks, through
    ``semi_axes``'s scaling) but out of its corridor first goes back in, towards the docks' ring
    ``lead`` radians ahead counter-clockwise (with the roundabout's traffic); any other heads for
    its dock (through :func:`roundabout_aim`).

    Parameters
    ----------
    positions, goals : (n, 2) or (2,) array_like
        Positions and goals on the ring (m), relative to the arena's centre.
    semi_axes : (float, float)
        Semi-axes of the ring (m).
    depth, width : float
        The dock's depth and the corridor's half-width (m).
    lead : float
        How far ahead (rad, about the centre) a robot in the band aims as it goes back in.

    Returns
    -------
    targets : (n, 2) or (2,) ndarray
        The goal, a point on the docks' ring, or the dock (m).
    band : (n,) or () bool ndarray
        Whether the robot is beyond its dock's ring, where stepping aside pushes it outwards.
    """
    scale = np.asarray(semi_axes, dtype=np.float64)
    p = np.asarray(positions, dtype=np.float64)
    g = np.asarray(goals, dtype=np.float64)
    normal = g / scale**2  # the ring's outward normal at the goal
    normal = normal / np.hypot(normal[..., 0], normal[..., 1])[..., None]
    docks = g - depth * normal
    along = np.sum((p - docks) * normal, axis=-1) / depth  # 0 at the dock, 1 at the goal
    nearest = docks + depth * np.clip(along, 0.0, 1.0)[..., None] * normal
    corridor = (np.hypot(*np.moveaxis(p - nearest, -1, 0)) < width) & (along > -0.5)
    q = p / scale
    radius, dock_radius = np.hypot(q[..., 0], q[..., 1]), np.hypot(*np.moveaxis(docks / scale, -1, 0))
    angle = np.arctan2(q[..., 1], q[..., 0]) + lead
    inwards = dock_radius[..., None] * np.stack((np.cos(angle), np.sin(angle)), axis=-1) * scale
    going_in = ~corridor & (radius > dock_radius + BAND_MARGIN)
    targets = np.where(corridor[..., None], g, np.where(going_in[..., None], inwards, docks))
    return targets, radius > dock_radius


#: How far (in the ring's scaled units) beyond its dock's ring a robot turns back in (:func:`dock`),
#: so that one on that ring does not switch between its dock and the way in.
BAND_MARGIN = 0.02


def clear_way(position: Any, goal: Any, others: Any, clearance: float, offsets: Any = None) -> Any:
    """Whether the straight way from ``position`` to ``goal`` ``(2,)`` keeps ``clearance`` (m) from
    every one of ``others`` ``(e, 2)`` (robots seen, taken as standing); several robots at once
    (positions and goals ``(k, 2)``, their rows of ``others`` cut by ``offsets`` ``(k + 1,)``): ``(k,)``.

    HRVO forbids every velocity that would ever bring a robot within its safety radius of a
    neighbour, even past the goal: a robot a centimetre off its goal, with a parked neighbour
    beyond it, may not move towards it at all. Over a short, clear way the goal is safe to take.
    """
    others = np.asarray(others, dtype=np.float64).reshape(-1, 2)
    p, g = np.asarray(position, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    if offsets is None:
        return bool(clear_way(p[None], g[None], others, clearance, np.array([0, len(others)]))[0])
    owner = np.repeat(np.arange(len(p)), np.diff(offsets))
    way, rel = (g - p)[owner], others - p[owner]
    along = np.clip(np.sum(rel * way, axis=1) / np.maximum(np.sum(way * way, axis=1), 1e-300), 0.0, 1.0)
    close = np.hypot(*(rel - along[:, None] * way).T) < clearance
    return ~kernels.segment_any(close, np.asarray(offsets, dtype=np.int64))
