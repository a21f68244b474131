"""The public vectorised kernels of DREAM: whole-swarm calls that other projects use directly.

Each function checks its input (shapes, NaN/inf, radii) and raises ``ValueError`` naming the
argument, then runs the Rust kernel of :mod:`dream._core` when it is available, or the NumPy
reference of :mod:`dream._reference` when the extension is missing or the environment
variable ``DREAM_PURE_PYTHON=1`` is set. Both give the same results (the test suite checks).

Shapes: poses ``(3, n)``, unicycle commands and single-integrator velocities ``(2, n)`` in the
Robotarium's layout; positions for geometry kernels ``(n, 2)``. Units: m, s, rad.
"""

from __future__ import annotations

import os
from types import ModuleType
from typing import Any, NamedTuple

import numpy as np

from dream import _reference
from dream._checks import FloatArray, as_array, as_poses, check_nonnegative, check_robot_id
from dream.specs import GRITSBOT, ROBOTARIUM, RPS, ArenaSpec, RobotSpec, SimulatorSpec


def _load_core() -> ModuleType | None:
    if os.environ.get("DREAM_PURE_PYTHON", "") not in ("", "0"):
        return None
    try:
        from dream import _core
    except ImportError:
        return None
    return _core


_core = _load_core()

#: ``"rust"`` when the compiled kernels are in use, ``"numpy"`` for the reference fallback.
IMPLEMENTATION = "numpy" if _core is None else "rust"


class Violations(NamedTuple):
    """Validation counts of one iteration, by the Robotarium simulator's criteria."""

    boundary: int  #: robots outside the arena
    collision: int  #: pairs of robots whose centres are within one diameter
    actuator: int  #: 1 if any command needs a wheel faster than allowed


def _commands(value: Any, name: str, n: int | None = None) -> FloatArray:
    return as_array(value, name, (2, n))


def unicycle_step(poses: Any, velocities: Any, dt: float = RPS.time_step) -> FloatArray:
    """Poses ``(3, n)`` after one forward-Euler step of the unicycle model (rps's update).

    ``x += dt cos(theta) v``, ``y += dt sin(theta) v``, ``theta += dt w``, then theta is
    wrapped to (-pi, pi] with ``atan2(sin, cos)``.
    """
    p = as_poses(poses)
    u = _commands(velocities, "velocities", p.shape[1])
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"`dt` must be finite and > 0, got {dt}")
    if _core is None:
        return _reference.unicycle_step(p, u, dt)
    return _core.unicycle_step(p, u, dt)


def threshold_velocities(velocities: Any, sim: SimulatorSpec = RPS) -> FloatArray:
    """Commands ``(2, n)`` clipped to the simulator's linear and angular limits (rps ``set_velocities``)."""
    u = _commands(velocities, "velocities")
    if _core is None:
        return _reference.threshold_velocities(u, sim.max_linear, sim.max_angular)
    return _core.threshold_velocities(u, sim.max_linear, sim.max_angular)


def validate(poses: Any, velocities: Any, arena: ArenaSpec = ROBOTARIUM, sim: SimulatorSpec = RPS) -> Violations:
    """Boundary, collision and actuator counts for one iteration, as rps counts them.

    Collisions are pairs within ``sim.diameter`` (found with a grid by the Rust kernel: O(n)).
    """
    p = as_poses(poses)
    u = _commands(velocities, "velocities", p.shape[1])
    wheels = dict(diameter=sim.diameter, wheel_radius=sim.wheel_radius, base_length=sim.base_length, max_wheel=sim.max_wheel)
    if _core is None:
        return Violations(*_reference.validate(p, u, arena.bounds, **wheels))
    return Violations(*_core.validate(p, u, arena.bounds, **wheels))


def dxi_to_dxu(dxi: Any, poses: Any, vel_gain: float = 0.8, ang_gain: float = 3.0) -> FloatArray:
    """Unicycle commands ``(2, n)`` from single-integrator velocities ``(2, n)`` at ``poses`` ``(3, n)``.

    ``v = vel_gain (c dx + s dy)``, ``w = ang_gain atan2(-s dx + c dy, v) / (pi/2)``.
    """
    d = _commands(dxi, "dxi")
    p = as_poses(poses, n=d.shape[1])
    if _core is None:
        return _reference.dxi_to_dxu(d, p, vel_gain, ang_gain)
    return _core.dxi_to_dxu(d, p, vel_gain, ang_gain)


def actuator_limit(dxu: Any, robot: RobotSpec = GRITSBOT) -> FloatArray:
    """Commands ``(2, n)`` within the robot's limits; linear speed is sacrificed before turning."""
    u = _commands(dxu, "dxu")
    limits = dict(
        max_linear=robot.v_max,
        max_angular=robot.w_max,
        wheel_radius=robot.wheel_radius,
        base_length=robot.base_length,
        max_wheel=robot.ac_max,
    )
    if _core is None:
        return _reference.actuator_limit(u, **limits)
    return _core.actuator_limit(u, **limits)


def neighbours(
    positions: Any,
    radius: float,
    *,
    headings: Any = None,
    direction: float = 0.0,
    fov: float = 2 * np.pi,
    max_neighbours: int | None = None,
) -> tuple[np.ndarray, np.ndarray, FloatArray]:
    """Each robot's neighbours within ``radius`` (and field of view) as CSR arrays.

    Parameters
    ----------
    positions : (n, 2)
    radius : float
        Inclusive range (m).
    headings : (n,), optional
        Robot headings (rad); with them only robots within ``fov / 2`` of
        ``heading + direction`` are kept.
    max_neighbours : int, optional
        Keep only the nearest ones.

    Returns
    -------
    indptr : (n + 1,) int64, indices : (m,) int64, distances : (m,) float64
        Robot i's neighbours are ``indices[indptr[i]:indptr[i+1]]``, in increasing order.
        A robot is never its own neighbour; co-located robots are neighbours.
    """
    p = as_array(positions, "positions", (None, 2))
    check_nonnegative(radius, "radius")
    h = None if headings is None else as_array(headings, "headings", (p.shape[0],))
    if max_neighbours is not None and max_neighbours < 0:
        raise ValueError(f"`max_neighbours` must be >= 0, got {max_neighbours}")
    return _reference.neighbours(p, radius, headings=h, direction=direction, fov=fov, max_neighbours=max_neighbours)


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

    Same rules as :func:`neighbours` for row ``robot_id`` (``heading`` is that robot's).
    """
    p = as_array(positions, "positions", (None, 2))
    check_robot_id(robot_id, p.shape[0], "positions")
    check_nonnegative(radius, "radius")
    return _reference.neighbours_of(p, robot_id, radius, heading=heading, direction=direction, fov=fov)


def hrvo_velocity(
    velocity: FloatArray,
    preferred: FloatArray,
    directions: FloatArray,
    distances: FloatArray,
    neighbour_velocities: FloatArray,
    *,
    safety: float = 0.24,
    v_max: float = 0.2,
    position: FloatArray | None = None,
    bounds: tuple[float, float, float, float] | None = None,
    candidates: FloatArray | None = None,
    include_preferred: bool = True,
) -> FloatArray:
    """One robot's HRVO velocity ``(2,)`` from its neighbours' directions ``(k,)`` (rad, from the
    robot towards each), distances ``(k,)`` and velocities ``(k, 2)``; see :func:`hrvo`.

    Inputs are trusted to be finite float64 arrays of those shapes (the per-robot API checks
    them once, upstream).
    """
    return _reference.hrvo_velocity(
        velocity, preferred, directions, distances, neighbour_velocities, safety=safety, v_max=v_max,
        position=position, bounds=bounds, candidates=candidates, include_preferred=include_preferred,
    )


def hrvo(
    positions: Any,
    velocities: Any,
    preferred: Any,
    neighbours: tuple[Any, Any] | None = None,
    *,
    radius: float = 1.0,
    safety: float = 0.24,
    v_max: float = 0.2,
    bounds: tuple[float, float, float, float] | None = None,
    n_angles: int = 20,
    n_speeds: int = 10,
    include_preferred: bool = True,
) -> FloatArray:
    """HRVO velocities ``(n, 2)`` for the whole swarm (single-integrator, m/s).

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
    pref = as_array(preferred, "preferred", (n, 2))
    check_nonnegative(radius, "radius")
    check_nonnegative(safety, "safety")
    check_nonnegative(v_max, "v_max")
    if n_angles < 1 or n_speeds < 1:
        raise ValueError(f"`n_angles` and `n_speeds` must be >= 1, got {n_angles} and {n_speeds}")
    csr = None if neighbours is None else _checked_csr(neighbours, n)
    return _reference.hrvo(
        p, v, pref, csr, radius=radius, safety=safety, v_max=v_max, bounds=bounds,
        n_angles=n_angles, n_speeds=n_speeds, include_preferred=include_preferred,
    )


def _checked_csr(csr: tuple[Any, Any], n: int) -> tuple[np.ndarray, np.ndarray]:
    indptr = np.asarray(csr[0], dtype=np.int64)
    indices = np.asarray(csr[1], dtype=np.int64)
    if indptr.shape != (n + 1,) or indptr[0] != 0 or np.any(np.diff(indptr) < 0) or indptr[-1] != len(indices):
        raise ValueError(f"`neighbours` indptr must be non-decreasing of shape ({n + 1},) from 0 to len(indices)")
    if len(indices) and (indices.min() < 0 or indices.max() >= n):
        raise ValueError(f"`neighbours` indices must be robot ids in [0, {n})")
    return indptr, indices
