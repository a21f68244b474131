"""Hybrid Reciprocal Velocity Obstacles: the whole swarm at once (:func:`hrvo`) or one robot (:class:`HrvoPlanner`)."""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

import dream._reference as _reference
from dream._checks import (
    Bounds,
    FloatArray,
    all_finite,
    as_array,
    as_flags,
    as_offsets,
    check_nonnegative,
    checked_bounds,
)
from dream.kernels._dispatch import implementation

#: Preferred speeds above this (m/s) are scaled down to it, keeping their direction: the choice
#: ranks candidates by their squared distance to the preferred velocity, which overflows to inf
#: for every candidate beyond ~1e154 m/s. No candidate is faster than ``v_max``, so a preferred
#: velocity this far away ranks them by its direction alone, as a farther one would.
PREFERRED_LIMIT = 1e6


def _bounded(preferred: FloatArray) -> FloatArray:
    """``preferred`` ``(n, 2)`` with each row no longer than :data:`PREFERRED_LIMIT`."""
    if not preferred.size or max(preferred.max(), -preferred.min()) <= PREFERRED_LIMIT / 2:
        return preferred  # no coordinate above half the limit, so no row near it (NaN: checked below)
    norm = np.hypot(preferred[:, 0], preferred[:, 1])
    huge = norm > PREFERRED_LIMIT
    if not huge.any():
        return preferred
    out = preferred.copy()
    out[huge] *= (PREFERRED_LIMIT / norm[huge])[:, None]
    return out


def _checked_grid(v_max: float, n_angles: int, n_speeds: int) -> FloatArray:
    check_nonnegative(v_max, "v_max")
    if n_angles < 1 or n_speeds < 1:
        raise ValueError(f"`n_angles` and `n_speeds` must be >= 1, got {n_angles} and {n_speeds}")
    return _grid(float(v_max), int(n_angles), int(n_speeds))


@functools.lru_cache(maxsize=16)
def _grid(v_max: float, n_angles: int, n_speeds: int) -> FloatArray:
    """The candidate grid, built once per parameter set: building it costs more than a small swarm's HRVO."""
    grid = _reference.candidate_grid(v_max, n_angles, n_speeds)
    grid.flags.writeable = False  # shared between calls
    return grid


def _check_decision(detections: FloatArray, vectors: dict[str, FloatArray]) -> None:
    """Refuse what the Rust planner refuses, on both paths: a non-finite ``velocity``, ``preferred``
    or ``position`` ``(2,)``, then the first detection row ``(4,)`` that is not finite or lies at a
    negative distance (the NumPy reference would decide from it without a word)."""
    for name, vector in vectors.items():
        if not all_finite(vector):
            raise ValueError(
                f"`{name}` contains a non-finite value (NaN or inf) at index {np.flatnonzero(~np.isfinite(vector))[0]}"
            )
    if all_finite(detections) and not (len(detections) and detections[:, 0].min() < 0):
        return
    for index, row in enumerate(detections.tolist()):
        if not all(map(math.isfinite, row)):
            raise ValueError(f"`detections` contains a non-finite value (NaN or inf) at index {index}")
        if row[0] < 0:
            raise ValueError(f"`detection distance` must be finite and >= 0, got {row[0]}")


def _checked_csr(csr: tuple[Any, Any], n: int) -> tuple[np.ndarray, np.ndarray]:
    indices = np.ascontiguousarray(csr[1], dtype=np.int64)
    indptr = as_offsets(csr[0], "neighbours", len(indices), n, part="indptr")
    if len(indices) and (indices.min() < 0 or indices.max() >= n):
        raise ValueError(f"`neighbours` indices must be robot ids in [0, {n})")
    return indptr, indices


class HrvoPlanner:
    """One robot's HRVO: fixed parameters and candidate grid, one :meth:`velocity` call per decision.

    This is the per-robot path of :class:`dream.RobotHRVO`; see :func:`hrvo` for the algorithm.
    """

    def __init__(
        self,
        *,
        safety: float = 0.24,
        v_max: float = 0.2,
        bounds: Bounds | None = None,
        n_angles: int = 20,
        n_speeds: int = 10,
        include_preferred: bool = True,
    ) -> None:
        self.safety = check_nonnegative(safety, "safety")
        self.v_max = v_max
        self.bounds = checked_bounds(bounds)
        self.candidates = _checked_grid(v_max, n_angles, n_speeds)
        self.include_preferred = include_preferred
        self._planner = self._build()

    def _build(self) -> Any:
        return implementation("HrvoPlanner")(
            self.candidates,
            safety=self.safety,
            v_max=self.v_max,
            bounds=self.bounds,
            include_preferred=self.include_preferred,
        )

    def __getstate__(self) -> dict[str, Any]:
        # The Rust planner holds only scratch space and these parameters: pickles (checkpoints)
        # keep the parameters and build it again.
        return {key: value for key, value in self.__dict__.items() if key != "_planner"}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._planner = self._build()

    def velocity(
        self, detections: FloatArray, velocity: FloatArray, preferred: FloatArray, position: FloatArray
    ) -> FloatArray:
        """The chosen velocity ``(2,)``.

        ``detections`` ``(k, 4)`` are movement-sensor rows ``[distance, angle, vx, vy]`` (angle
        from the detected robot towards this one); ``velocity`` is the robot's previous
        velocity, ``preferred`` the one it wants, ``position`` where it is (all ``(2,)`` float64:
        the caller checks the shapes).

        Raises
        ------
        ValueError
            A non-finite value, or a detection at a negative distance: the same message from the
            Rust and the NumPy paths.
        """
        _check_decision(detections, {"velocity": velocity, "preferred": preferred, "position": position})
        if abs(preferred[0]) + abs(preferred[1]) > PREFERRED_LIMIT:
            preferred = _bounded(preferred.reshape(1, 2))[0]
        return self._planner.velocity(detections, velocity, preferred, position)


def hrvo(
    positions: Any,
    velocities: Any,
    preferred: Any,
    neighbours: tuple[Any, Any] | None = None,
    *,
    radius: float = 1.0,
    safety: float = 0.24,
    v_max: float = 0.2,
    bounds: Bounds | None = None,
    n_angles: int = 20,
    n_speeds: int = 10,
    include_preferred: bool = True,
) -> FloatArray:
    """HRVO velocities ``(n, 2)`` for the whole swarm (single-integrator, m/s).

    For each robot and neighbour: a cone of half-angle ``asin(safety / max(d, safety))`` towards
    the neighbour, with the RVO edge (apex ``(v_A + v_B) / 2``) on the side of the robot's
    velocity and the VO edge (apex ``v_B``) on the other. The result is the candidate closest to
    the preferred velocity that no neighbour forbids and that keeps ``position + v`` strictly
    inside ``bounds``; zero if none does.

    Parameters
    ----------
    positions, velocities, preferred : (n, 2)
        Positions, previous velocities (also the velocities neighbours are assumed to keep),
        and preferred velocities.
    neighbours : (indptr, indices), optional
        CSR neighbour lists; ``None``: every other robot within ``radius``.
    safety : float
        Combined safety radius of two robots (m).
    bounds : (xmin, xmax, ymin, ymax), optional
        Only velocities keeping ``position + v`` strictly inside are chosen.
    n_angles, n_speeds : int
        The candidate grid (see :func:`dream._reference.candidate_grid`).
    include_preferred : bool
        Try the preferred velocity itself (clamped to ``v_max``) first; the original sampled
        only the grid, so it could not move exactly along a free preferred direction.
    """
    p = as_array(positions, "positions", (None, 2))
    n = p.shape[0]
    v = as_array(velocities, "velocities", (n, 2))
    pref = _bounded(as_array(preferred, "preferred", (n, 2)))
    check_nonnegative(radius, "radius")
    check_nonnegative(safety, "safety")
    grid = _checked_grid(v_max, n_angles, n_speeds)
    box = checked_bounds(bounds)
    indptr, indices = (None, None) if neighbours is None else _checked_csr(neighbours, n)
    return implementation("hrvo")(
        p,
        v,
        pref,
        indptr,
        indices,
        radius=radius,
        safety=safety,
        v_max=v_max,
        bounds=box,
        candidates=grid,
        include_preferred=include_preferred,
    )


def hrvo_rows(
    velocities: Any,
    preferred: Any,
    positions: Any,
    offsets: Any,
    detections: Any,
    *,
    safety: float = 0.24,
    v_max: float = 0.2,
    bounds: Bounds | None = None,
    n_angles: int = 20,
    n_speeds: int = 10,
    include_preferred: bool = True,
    relative: bool = False,
    steer: Any = None,
) -> FloatArray:
    """HRVO velocities ``(m, 2)`` of the robots deciding now, each from its own detections.

    Row r's detections are ``detections[offsets[r]:offsets[r + 1]]``, movement-sensor rows
    ``[distance, angle, vx, vy]`` (angle from the detected robot towards this one), or a tuple
    of those four columns (a neighbourhood's, unstacked); with ``relative``, rows ``[distance,
    dx, dy, vx, vy]`` or their five columns, ``(dx, dy)`` the detected robot's offset (a movement
    sensor's neighbourhood holds them: no angle to turn back into a direction). Row r's answer
    is :meth:`HrvoPlanner.velocity`'s for them, with ``velocities``, ``preferred`` and
    ``positions`` ``(m, 2)``: the robots' previous, wanted velocities and believed positions.
    A robot decides from what it perceives, never from the others' true poses (see :func:`hrvo`).
    With ``steer`` ``(m,)`` bool, only the rows it flags go through HRVO; the others get their
    preferred velocity as it is (robots driving straight: no rows to gather out of the inputs).
    """
    pos = as_array(positions, "positions", (None, 2))
    m = pos.shape[0]
    v = as_array(velocities, "velocities", (m, 2))
    pref = as_array(preferred, "preferred", (m, 2))  # bounded by hrvo_rows_trusted
    names = "(distance, dx, dy, vx, vy)" if relative else "(distance, angle, vx, vy)"
    width = 5 if relative else 4
    if isinstance(detections, tuple):
        if len(detections) != width:
            raise ValueError(f"`detections` columns must be {names}, got {len(detections)} columns")
        distance = as_array(detections[0], "detections", (None,))
        seen: Any = (distance, *(as_array(column, "detections", (len(distance),)) for column in detections[1:]))
    else:
        seen = as_array(detections, "detections", (None, width))
        distance = seen[:, 0]
    if len(distance) and distance.min() < 0:
        raise ValueError(f"`detection distance` must be finite and >= 0, got {distance.min()}")
    cuts = as_offsets(offsets, "offsets", len(distance), m)
    return hrvo_rows_trusted(
        v,
        pref,
        pos,
        cuts,
        seen,
        safety=check_nonnegative(safety, "safety"),
        v_max=v_max,
        bounds=bounds,
        n_angles=n_angles,
        n_speeds=n_speeds,
        include_preferred=include_preferred,
        relative=relative,
        steer=None if steer is None else as_flags(steer, "steer", m),
    )


def hrvo_rows_trusted(
    velocities: FloatArray,
    preferred: FloatArray,
    positions: FloatArray,
    offsets: np.ndarray,
    detections: tuple[FloatArray, ...],
    *,
    safety: float,
    v_max: float,
    bounds: Bounds | None,
    n_angles: int,
    n_speeds: int,
    include_preferred: bool,
    relative: bool,
    steer: np.ndarray | None = None,
) -> FloatArray:
    """:func:`hrvo_rows` of arrays its caller built and vouches for: float64 of the right shapes,
    finite, detections at distances >= 0 cut into rows by int64 ``offsets`` (the swarm engine's
    own perception and checked decisions), so that they are not checked again, entry by entry;
    the parameters are. Huge preferred velocities are bounded as :func:`hrvo_rows` bounds them."""
    bounded = _bounded(preferred)
    out: FloatArray = implementation("hrvo_rows")(
        velocities,
        bounded,
        positions,
        offsets,
        detections,
        safety=safety,
        v_max=v_max,
        bounds=checked_bounds(bounds),
        candidates=_checked_grid(v_max, n_angles, n_speeds),
        include_preferred=include_preferred,
        relative=relative,
        steer=steer,
    )
    if steer is not None and bounded is not preferred:  # the rows not steered, as they were given
        np.copyto(out, preferred, where=~steer[:, None])
    return out
