"""Neighbours within a radius and field of view: positions ``(n, 2)``, results as CSR arrays."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

import dream._reference as _reference
from dream._checks import FloatArray, as_array, as_flags, as_offsets, check_nonnegative, check_robot_id
from dream._reference.draws import Loss
from dream.kernels._dispatch import implementation, kernel_input


def neighbours(
    positions: Any,
    radius: float,
    *,
    headings: Any = None,
    direction: float = 0.0,
    fov: float = 2 * np.pi,
    max_neighbours: int | None = None,
    rows: Any = None,
) -> tuple[np.ndarray, np.ndarray, FloatArray]:
    """Each robot's neighbours within ``radius`` (and field of view) as CSR arrays.

    A uniform grid (cells of the radius) makes this O(n k) in Rust.

    Parameters
    ----------
    positions : (n, 2)
    radius : float
        Inclusive range (m).
    headings : (n,), optional
        Robot headings (rad); with them only robots within ``fov / 2`` of
        ``heading + direction`` are kept (a co-located robot is always kept).
    max_neighbours : int, optional
        Keep only the nearest ones (ties: lower index).
    rows : (n,) bool, optional
        Find only the flagged robots' rows (those whose sensors read this step, say); the
        others' rows are empty, though every robot can be a flagged robot's neighbour.

    Returns
    -------
    indptr : (n + 1,) int64, indices : (m,) int64, distances : (m,) float64
        Robot i's neighbours are ``indices[indptr[i]:indptr[i+1]]``, in increasing order.
        A robot is never its own neighbour; co-located robots are neighbours.
    """
    p = as_array(positions, "positions", (None, 2))
    check_nonnegative(radius, "radius")
    h = None if headings is None else as_array(headings, "headings", (p.shape[0],))
    if not np.isfinite(direction):
        raise ValueError(f"`direction` must be finite, got {direction}")
    check_nonnegative(fov, "fov")
    if max_neighbours is not None and max_neighbours < 0:
        raise ValueError(f"`max_neighbours` must be >= 0, got {max_neighbours}")
    asked = None if rows is None else as_flags(rows, "rows", p.shape[0])
    return implementation("neighbours")(p, radius, h, direction, fov, max_neighbours, asked)


def neighbours_of(
    positions: Any,
    robot_id: int,
    radius: float,
    *,
    heading: float | None = None,
    direction: float = 0.0,
    fov: float = 2 * np.pi,
) -> tuple[np.ndarray, FloatArray]:
    """One robot's neighbours ``(indices, distances)`` among ``positions`` ``(n, 2)``.

    Same rules as :func:`neighbours` for row ``robot_id`` (``heading`` is that robot's); O(n).
    Per-robot sensors and radios use :meth:`dream.World.neighbours_of`, which answers from one
    index per step instead.
    """
    p = as_array(positions, "positions", (None, 2))
    check_robot_id(robot_id, p.shape[0], "positions")
    check_nonnegative(radius, "radius")
    return _reference.neighbours_of(p, robot_id, radius, heading=heading, direction=direction, fov=fov)


def far_from(points: Any, others: Any, distance: float, *, offsets: tuple[Any, Any] | None = None) -> np.ndarray:
    """Which ``points`` lie farther than ``distance`` from every one of ``others``: robots seen that
    no message accounts for, or claims that match no robot seen.

    Parameters
    ----------
    points : (k, 2)
    others : (m, 2)
    distance : float
        Inclusive matching distance (m): a point at exactly ``distance`` from another is matched.
    offsets : (points_offsets (rows + 1,), others_offsets (rows + 1,)), optional
        Several robots at once: row r's points ``points[points_offsets[r]:points_offsets[r + 1]]``
        are matched against its others alone. Without, all are one row.

    Returns
    -------
    far : (k,) bool
    """
    p = as_array(points, "points", (None, 2))
    q = as_array(others, "others", (None, 2))
    check_nonnegative(distance, "distance")
    if offsets is None:
        return implementation("far_from")(p, q, distance)
    if len(offsets) != 2:
        raise ValueError(f"`offsets` must be a pair (points_offsets, others_offsets), got {len(offsets)} arrays")
    cuts = as_offsets(offsets[0], "offsets", len(p), part="[0] (of the points)")
    theirs = as_offsets(offsets[1], "offsets", len(q), len(cuts) - 1, part="[1] (of the others)")
    return implementation("far_from")(p, q, distance, cuts, theirs)


#: What the asked robots see: ``(offsets, ids, distances, bearings, dx, dy, *carried)`` over
#: their rows.
Perceived = tuple[np.ndarray, ...]
#: What they hear: ``(offsets, ids, distances, lost, *summed)`` over their rows (a graph radio's:
#: ``(offsets, ids, distances)``).
Heard = tuple[np.ndarray, ...]


def perceive(
    positions: Any,
    headings: Any,
    rows: Any,
    *,
    sight: tuple[float, float, float] | None = None,
    radio_range: float | None = None,
    talking: Any = None,
    carried: Sequence[Any] = (),
    bearings: bool = True,
    summed: Sequence[Any] | None = None,
    loss: Loss | None = None,
) -> tuple[Perceived, Heard]:
    """Who the robots ``rows`` ``(m,)`` (increasing ids) see and hear, in one neighbour query.

    Robot j is seen by robot i when it is within ``sight = (range, fov, direction)`` (m, rad,
    rad: the field of view about i's heading turned by ``direction``; a co-located robot is
    always seen), and heard when it is within ``radio_range`` (m) and ``talking[j]``. Returns
    ``(seen, heard)``: ``(offsets (m + 1,), ids, distances, bearings, dx, dy)`` and ``(offsets,
    ids, distances, lost)``; row r's entries are ``offsets[r]:offsets[r + 1]``, ids increasing;
    bearings are world-frame directions from the perceiving robot towards the other, ``(dx, dy)``
    the other's position less the perceiving robot's; then one column per array of ``carried``
    (each ``(n,)``, one value per robot, NaN passed on: the velocities a movement sensor reports,
    say), its values at the robots seen. A row does not depend on which other rows are asked.
    Without ``bearings`` the bearings column is empty (an ``atan2`` a robot seen, 15-20 % of a
    crowd's perception, saved where no one reads them).

    Each array of ``summed`` (``(n,)``, one value per robot) is added up over each row heard,
    ``(m,)`` after the heard columns, which are then left empty but for the offsets: a radio's
    inbox that a decision only sums (a consensus) needs no rows. The values add in increasing id
    from +0.0, as :func:`segment_reduce` adds a listed row: the same bits. ``summed=[]`` counts
    each row heard (the offsets) and lists nothing.

    A radio with a ``loss`` (:class:`Loss`) draws each message's fate where it finds it: a lost
    message is not heard (nor summed), and ``lost`` ``(m,)`` counts each row's lost messages
    (empty without a loss).
    """
    p = kernel_input(positions, "positions", (None, 2))
    n = p.shape[0]
    h = kernel_input(headings, "headings", (n,))
    asked = _asked(rows, n)
    if sight is not None:
        check_nonnegative(sight[0], "sensor range")
        check_nonnegative(sight[1], "fov")
    if (radio_range is None) != (talking is None):
        raise ValueError("give both `radio_range` and `talking`, or neither")
    if (summed is not None or loss is not None) and radio_range is None:
        raise ValueError("`summed` and `loss` need a radio: give `radio_range` and `talking`")
    flags = None
    if radio_range is not None:
        check_nonnegative(radio_range, "radio range")
        flags = as_flags(talking, "talking", n)
    columns = [_per_robot(values, n, "carried") for values in carried]
    sums = None if summed is None else [_per_robot(values, n, "summed") for values in summed]
    return implementation("perceive")(
        p,
        h,
        asked,
        sight=sight,
        radio_range=radio_range,
        talking=flags,
        carried=columns or None,
        bearings=bearings,
        summed=sums,
        loss=checked_loss(loss),
    )


def checked_loss(loss: Loss | None) -> Loss | None:
    """``loss`` checked (``keep`` within [0, 1], ``per_metre`` finite and >= 0, integer words),
    its seed as the draws read it (modulo 2^64)."""
    if loss is None:
        return None
    seed, stream, step, keep, per_metre = loss
    for name, word in (("seed", seed), ("stream", stream), ("step", step)):
        if not isinstance(word, (int, np.integer)):
            raise ValueError(f"the loss's {name} must be an integer, got {word!r}")
    if not 0.0 <= keep <= 1.0:
        raise ValueError(f"the loss's `keep` must be within [0, 1], got {keep}")
    if not (np.isfinite(per_metre) and per_metre >= 0):
        raise ValueError(f"the loss's `per_metre` must be finite and >= 0, got {per_metre}")
    return Loss(int(seed) % 2**64, int(stream), int(step), float(keep), float(per_metre))


def linked(rows: Any, graph: tuple[Any, Any], talking: Any, *, positions: Any = None) -> Heard:
    """What the robots ``rows`` ``(m,)`` (increasing ids) hear over a communication ``graph``
    ``(indptr (n + 1,), indices)``, robot i linked to ``indices[indptr[i]:indptr[i + 1]]``
    whatever the distance: each row's links that are ``talking`` ``(n,)`` (bool), not the robot
    itself, in the graph's order. Returns ``(offsets (m + 1,), ids, distances)`` over those rows,
    as :func:`perceive` gives a range radio's: the distances (``hypot``) from the robots'
    ``positions`` ``(n, 2)``, NaN without (they matter only to a loss that grows with distance,
    and cost more than the rest). Only the rows asked for are read of the graph, and checked: a
    swarm's links are most of a step's radio."""
    flags = np.asarray(talking)
    p = None if positions is None else as_array(positions, "positions", (None, 2))
    n = len(flags) if p is None else p.shape[0]
    asked = _asked(rows, n)
    if len(graph) != 2:
        raise ValueError(f"`graph` must be a pair (indptr, indices), got {len(graph)} arrays")
    indptr, indices = (_integers(part, f"`graph` {name}") for part, name in zip(graph, ("indptr", "indices")))
    if indptr.shape != (n + 1,):
        raise ValueError(f"`graph` indptr must have shape ({n + 1},), one row a robot, got {indptr.shape}")
    return implementation("linked")(asked, indptr, indices, as_flags(flags, "talking", n), positions=p)


def _integers(value: Any, what: str) -> np.ndarray:
    """``value`` as a 1-D int64 array (``what``: how an error names it)."""
    array = np.asarray(value)
    if array.ndim != 1 or (array.size and array.dtype.kind not in "iu"):
        raise ValueError(f"{what} must be integers of shape (k,), got dtype {array.dtype} shape {array.shape}")
    return np.ascontiguousarray(array, dtype=np.int64)


def _asked(rows: Any, n: int) -> np.ndarray:
    """``rows`` as the int64 ids ``(m,)`` of robots among ``n``, increasing."""
    array = np.asarray(rows)
    if array.size and array.dtype.kind not in "iu":
        raise ValueError(f"`rows` must hold integer robot ids, got dtype {array.dtype}")
    asked = np.ascontiguousarray(array, dtype=np.int64)
    if asked.ndim != 1 or (len(asked) and (asked[0] < 0 or asked[-1] >= n or np.any(np.diff(asked) <= 0))):
        raise ValueError(f"`rows` must be increasing robot ids in [0, {n}), shape (m,)")
    return asked


def _per_robot(values: Any, n: int, arg: str) -> FloatArray:
    """``values`` as a C-contiguous ``(n,)`` float64 array: data carried to the robots seen or
    summed over those heard, not geometry, so NaN goes through as it is."""
    try:
        array = np.ascontiguousarray(values, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"`{arg}` must hold float arrays of shape ({n},): {err}") from None
    if array.shape != (n,):
        raise ValueError(f"`{arg}` must hold arrays of shape ({n},), one value per robot, got {array.shape}")
    return array
