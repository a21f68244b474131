"""The public vectorised kernels of DREAM: whole-swarm calls that other projects use directly.

Each function checks its input (shapes, NaN/inf, radii) and raises ``ValueError`` naming the
argument, then runs the Rust kernel of :mod:`dream._core` when it is available, or the NumPy
reference of :mod:`dream._reference` when the extension is missing or the environment
variable ``DREAM_PURE_PYTHON=1`` is set. Both give the same results (the test suite checks).

Shapes: poses ``(3, n)``, unicycle commands and single-integrator velocities ``(2, n)`` in the
Robotarium's layout; positions for geometry kernels ``(n, 2)``. Units: m, s, rad.
"""

from __future__ import annotations

import functools
import os
from types import ModuleType
from typing import Any, NamedTuple

import numpy as np

from dream import _reference
from dream._checks import FloatArray, as_array, as_poses, check_nonnegative, check_robot_id
from dream._reference.voronoi import MAX_COORDINATE
from dream.errors import GeometryError
from dream.specs import GRITSBOT, ONBOARD, ROBOTARIUM, RPS, ArenaSpec, OnboardSpec, RobotSpec, SimulatorSpec

Bounds = tuple[float, float, float, float]


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

    boundary: int  #: robots outside the arena (rps 2.1: 1 if any robot is)
    collision: int  #: pairs of robots whose colliders are within one diameter
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


def threshold_velocities(velocities: Any, spec: SimulatorSpec = RPS) -> FloatArray:
    """Commands ``(2, n)`` clipped as a simulator following ``spec`` clips them.

    rps 0.0.0 (``spec.wheel_thresholding`` off) clips ``v`` and ``w`` to their limits separately;
    rps 2.1 clips each wheel's speed to ``spec.max_wheel`` and converts back to ``(v, w)``.
    """
    u = _commands(velocities, "velocities")
    if spec.wheel_thresholding:
        wheels = {"wheel_radius": spec.wheel_radius, "base_length": spec.base_length, "max_wheel": spec.max_wheel}
        if _core is None:
            return _reference.threshold_wheels(u, **wheels)
        return _core.threshold_wheels(u, **wheels)
    if _core is None:
        return _reference.threshold_velocities(u, spec.max_linear, spec.max_angular)
    return _core.threshold_velocities(u, spec.max_linear, spec.max_angular)


def wheel_speeds(velocities: Any, spec: SimulatorSpec = RPS) -> FloatArray:
    """Left and right wheel speeds ``(2, n)`` (rad/s) of unicycle commands ``(2, n)`` on ``spec``'s robot.

    Elementwise NumPy (nothing for the Rust core to gain): ``(2v -+ L w) / (2 r)``.
    """
    return _reference.wheel_speeds(_commands(velocities, "velocities"), spec.wheel_radius, spec.base_length)


def validate(poses: Any, velocities: Any, arena: ArenaSpec = ROBOTARIUM, spec: SimulatorSpec = RPS) -> Violations:
    """Boundary, collision and actuator counts for one iteration, as a simulator following ``spec`` counts them.

    Collisions are pairs of colliders (``spec.collider_offset`` ahead of the centres) within
    ``spec.diameter``, found with a grid by the Rust kernel (O(n)); robots outside the arena count
    one each, or once per iteration when ``spec.boundary_per_iteration`` (rps 2.1).
    """
    p = as_poses(poses)
    u = _commands(velocities, "velocities", p.shape[1])
    rules = {
        "diameter": spec.diameter,
        "wheel_radius": spec.wheel_radius,
        "base_length": spec.base_length,
        "max_wheel": spec.max_wheel,
        "collider_offset": spec.collider_offset,
        "boundary_per_iteration": spec.boundary_per_iteration,
    }
    if _core is None:
        return Violations(*_reference.validate(p, u, arena.bounds, **rules))
    return Violations(*_core.validate(p, u, arena.bounds, **rules))


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
    if _core is None:
        return _reference.neighbours(p, radius, headings=h, direction=direction, fov=fov, max_neighbours=max_neighbours)
    return _core.neighbours(p, radius, h, direction, fov, max_neighbours)


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


def _checked_bounds(bounds: Any) -> Bounds | None:
    if bounds is None:
        return None
    values = tuple(float(b) for b in bounds)
    if len(values) != 4 or not all(np.isfinite(values)) or values[0] >= values[1] or values[2] >= values[3]:
        raise ValueError(
            f"`bounds` must be finite (xmin, xmax, ymin, ymax) with xmin < xmax and ymin < ymax, got {bounds}"
        )
    return values  # type: ignore[return-value]


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
        self.bounds = _checked_bounds(bounds)
        self.candidates = _checked_grid(v_max, n_angles, n_speeds)
        self.include_preferred = include_preferred
        self._planner = (_reference if _core is None else _core).HrvoPlanner(
            self.candidates, safety=self.safety, v_max=v_max, bounds=self.bounds, include_preferred=include_preferred
        )

    def velocity(
        self, detections: FloatArray, velocity: FloatArray, preferred: FloatArray, position: FloatArray
    ) -> FloatArray:
        """The chosen velocity ``(2,)``.

        ``detections`` ``(k, 4)`` are movement-sensor rows ``[distance, angle, vx, vy]`` (angle
        from the detected robot towards this one); ``velocity`` is the robot's previous
        velocity, ``preferred`` the one it wants, ``position`` where it is (all ``(2,)``, finite
        float64: the caller checks).
        """
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
    pref = as_array(preferred, "preferred", (n, 2))
    check_nonnegative(radius, "radius")
    check_nonnegative(safety, "safety")
    grid = _checked_grid(v_max, n_angles, n_speeds)
    box = _checked_bounds(bounds)
    indptr, indices = (None, None) if neighbours is None else _checked_csr(neighbours, n)
    return (_reference if _core is None else _core).hrvo(
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


def _checked_csr(csr: tuple[Any, Any], n: int) -> tuple[np.ndarray, np.ndarray]:
    indptr = np.ascontiguousarray(csr[0], dtype=np.int64)
    indices = np.ascontiguousarray(csr[1], dtype=np.int64)
    if indptr.shape != (n + 1,) or indptr[0] != 0 or np.any(np.diff(indptr) < 0) or indptr[-1] != len(indices):
        raise ValueError(f"`neighbours` indptr must be non-decreasing of shape ({n + 1},) from 0 to len(indices)")
    if len(indices) and (indices.min() < 0 or indices.max() >= n):
        raise ValueError(f"`neighbours` indices must be robot ids in [0, {n})")
    return indptr, indices


def _within_reach(array: FloatArray, name: str) -> FloatArray:
    """``array`` unless a coordinate exceeds what the Voronoi kernels compute without overflow."""
    if array.size and np.abs(array).max() > MAX_COORDINATE:
        raise ValueError(f"`{name}` must be finite and at most 1e100 in magnitude, got {np.abs(array).max()}")
    return array


class VoronoiCells(NamedTuple):
    """Cells of :func:`voronoi_cells`; ``vertices``/``offsets`` are ``None`` unless requested."""

    centroids: FloatArray  #: (n, 2)
    areas: FloatArray  #: (n,)
    vertices: FloatArray | None  #: (m, 2): robot i's polygon is vertices[offsets[i]:offsets[i+1]]
    offsets: np.ndarray | None  #: (n + 1,) int64


def voronoi_cells(
    positions: Any,
    *,
    radius: float = 1.0,
    bounds: Bounds = ROBOTARIUM.bounds,
    virtual: tuple[Any, Any] | None = None,
    resolution: int = 64,
    polygons: bool = False,
) -> VoronoiCells:
    """Each robot's Voronoi cell within a disc: centroid, area and optionally the polygon.

    Robot i's cell is the disc of ``radius`` (a regular polygon of ``resolution`` vertices)
    intersected with the arena ``bounds``, clipped by the perpendicular bisector of every other
    robot within ``2 radius`` and of each of its virtual agents (exact polygon clipping). An
    empty cell (robot outside the arena) has area 0 and the robot's position as centroid. A
    radius beyond the arena's reach is shrunk to one that still covers it (same cells, no loss
    of precision), so any finite radius works; coordinates are limited to 1e100 in magnitude.

    Parameters
    ----------
    positions : (n, 2)
    virtual : (indptr (n + 1,), points (m, 2)), optional
        Virtual agents per robot, e.g. from :func:`virtual_agents`.
    polygons : bool
        Also return the cells' vertices (counter-clockwise) as CSR.
    """
    p = _within_reach(as_array(positions, "positions", (None, 2)), "positions")
    n = p.shape[0]
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"`radius` must be finite and > 0, got {radius}")
    if resolution < 3:
        raise ValueError(f"`resolution` must be >= 3, got {resolution}")
    box = _checked_bounds(bounds)
    assert box is not None
    _within_reach(np.array(box), "bounds")
    agents = None
    if virtual is not None:
        indptr = np.ascontiguousarray(virtual[0], dtype=np.int64)
        points = _within_reach(as_array(virtual[1], "virtual points", (None, 2)), "virtual points")
        if indptr.shape != (n + 1,) or indptr[0] != 0 or np.any(np.diff(indptr) < 0) or indptr[-1] != len(points):
            raise ValueError(f"`virtual` indptr must be non-decreasing of shape ({n + 1},) from 0 to len(points)")
        agents = (indptr, points)
    vi, vp = (None, None) if agents is None else agents
    centroids, areas, vertices, offsets = (_reference if _core is None else _core).voronoi_cells(
        p, radius=radius, bounds=box, virtual_indptr=vi, virtual_points=vp, resolution=resolution
    )
    return VoronoiCells(centroids, areas, vertices if polygons else None, offsets if polygons else None)


def voronoi_cell(
    position: Any,
    others: Any,
    *,
    radius: float = 1.0,
    bounds: Bounds = ROBOTARIUM.bounds,
    virtual: Any = None,
    resolution: int = 64,
) -> tuple[FloatArray, float, FloatArray]:
    """One robot's cell, as :func:`voronoi_cells` computes it, from what that robot knows.

    Parameters
    ----------
    position : (2,)
    others : (k, 2)
        Positions of the other robots it knows of (those beyond ``2 radius`` change nothing).
    virtual : (j, 2), optional
        Its virtual agents (see :func:`obstacle_agents`).

    Returns
    -------
    centroid : (2,), area : float, vertices : (m, 2)
        The centroid is ``position`` when the cell is empty.
    """
    p = _within_reach(as_array(position, "position", (2,)), "position")
    q = _within_reach(as_array(others, "others", (None, 2)), "others")
    v = np.zeros((0, 2)) if virtual is None else _within_reach(as_array(virtual, "virtual", (None, 2)), "virtual")
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"`radius` must be finite and > 0, got {radius}")
    if not 3 <= resolution <= 2**20:
        raise ValueError(f"`resolution` must be between 3 and 2^20, got {resolution}")
    box = _checked_bounds(bounds)
    assert box is not None
    _within_reach(np.array(box), "bounds")
    if _core is None:
        return _reference.voronoi_cell(p, q, v, radius=radius, bounds=box, resolution=resolution)
    return _core.voronoi_cell(p, q, v, radius=radius, bounds=box, resolution=resolution)


def obstacle_agents(
    position: Any,
    closest_points: Any,
    *,
    robot_radius: float = GRITSBOT.radius,
    margin: float = 0.0,
    mirror_at_surface: bool = False,
) -> FloatArray:
    """One robot's virtual agents ``(k, 2)`` from the closest points ``(k, 2)`` of the obstacles it
    senses (an :class:`~dream.sensors.ObstacleSensor` reading); see :func:`virtual_agents`."""
    p = as_array(position, "position", (2,))
    c = as_array(closest_points, "closest_points", (None, 2))
    offset = (
        0.0
        if mirror_at_surface
        else check_nonnegative(robot_radius, "robot_radius") + check_nonnegative(margin, "margin")
    )
    return _reference.agents_from_closest(p, c, offset)


def virtual_agents(
    positions: Any,
    obstacles: tuple[Any, Any],
    *,
    range: float = 1.0,  # noqa: A002 (a sensor's range, as elsewhere in the API)
    robot_radius: float = GRITSBOT.radius,
    margin: float = 0.0,
    mirror_at_surface: bool = False,
) -> tuple[np.ndarray, FloatArray]:
    """Virtual agents that keep each robot's Voronoi cell off the obstacles it senses.

    For robot p and each convex obstacle whose closest point c is within ``range``, the agent
    is p mirrored across ``c - n (robot_radius + margin)`` (n the unit vector from p to c): the
    cell's boundary then stays ``robot_radius + margin`` before the obstacle, so the robot's
    body does not touch it. A robot already closer than that gets its boundary 1 um ahead of
    itself (its cell keeps to its own side and its centroid leads it away).
    ``mirror_at_surface=True`` mirrors across c itself, as the original did. A robot inside an
    obstacle gets no agent for it.

    Parameters
    ----------
    positions : (n, 2)
    obstacles : (vertices (v, 2), offsets (k + 1,))
        Convex obstacles as CSR: obstacle k is the convex hull of
        ``vertices[offsets[k]:offsets[k + 1]]``.

    Returns
    -------
    indptr : (n + 1,) int64, points : (m, 2)
        Robot i's agents are ``points[indptr[i]:indptr[i + 1]]``, by obstacle.

    Raises
    ------
    GeometryError
        If an obstacle's vertices enclose no area.
    """
    p = as_array(positions, "positions", (None, 2))
    vertices = as_array(obstacles[0], "obstacle vertices", (None, 2))
    offsets = np.ascontiguousarray(obstacles[1], dtype=np.int64)
    if (
        offsets.ndim != 1
        or len(offsets) < 1
        or offsets[0] != 0
        or np.any(np.diff(offsets) < 0)
        or offsets[-1] != len(vertices)
    ):
        raise ValueError("obstacle `offsets` must be non-decreasing from 0 to the number of vertices")
    check_nonnegative(range, "range")
    offset = (
        0.0
        if mirror_at_surface
        else check_nonnegative(robot_radius, "robot_radius") + check_nonnegative(margin, "margin")
    )
    if _core is None:
        return _reference.virtual_agents(p, vertices, offsets, range=range, offset=offset)
    return _core.virtual_agents(p, vertices, offsets, range=range, offset=offset)


def distance_rays(poses: Any, walls: Any = None, *, spec: OnboardSpec = ONBOARD, robots: Any = None) -> FloatArray:
    """Noiseless readings ``(k, n)`` of every robot's infrared distance sensors (rps 2.1's model).

    Ray ``j`` starts at ``spec.rays[:2, j]`` in the body frame of a centre ``spec.centre_offset``
    ahead of the pose and points at ``heading + spec.rays[2, j]``; it reads the distance (m) to
    the nearest line-segment wall or other robot (a disc of ``spec.robot_diameter`` around its
    own offset centre) within ``spec.range``, or -1. The arena's edges are not seen; a robot
    whose disc contains a ray's start is not seen by that ray (as in rps 2.1). A grid makes this
    O(n k m) in Rust (m robots within reach), in parallel over robots.

    Parameters
    ----------
    poses : (3, n)
    walls : (w, 2, 2), optional
        Line segments, ``walls[i, 0]`` start and ``walls[i, 1]`` end (rps 2.1's ``obstacles``).
    spec : OnboardSpec
        The sensor head; its noise settings are not used here (see :class:`dream.DistanceSensor`).
    robots : (b,) int, optional
        Cast only these robots' rays (the others' columns read -1); all by default.
    """
    p = as_poses(poses)
    n = p.shape[1]
    segments = np.zeros((0, 4)) if walls is None else as_array(walls, "walls", (None, 2, 2)).reshape(-1, 4)
    rays = as_array(spec.rays, "spec.rays", (3, None))
    check_nonnegative(spec.robot_diameter, "robot_diameter")
    if not (np.isfinite(spec.range) and spec.range > 0):
        raise ValueError(f"`range` must be finite and > 0, got {spec.range}")
    ids = None
    if robots is not None:
        ids = np.ascontiguousarray(np.atleast_1d(robots), dtype=np.int64)
        if ids.ndim != 1 or (len(ids) and (ids.min() < 0 or ids.max() >= n)):
            raise ValueError(f"`robots` must be robot ids in [0, {n}), got {robots!r}")
    options = {"centre_offset": spec.centre_offset, "robot_diameter": spec.robot_diameter, "range": spec.range}
    if _core is None:
        return _reference.distance_rays(p, segments, rays, robots=ids, **options)
    return _core.distance_rays(p, segments, rays, robots=ids, **options)


__all__ = [
    "IMPLEMENTATION",
    "GeometryError",
    "HrvoPlanner",
    "Violations",
    "VoronoiCells",
    "actuator_limit",
    "distance_rays",
    "dxi_to_dxu",
    "hrvo",
    "neighbours",
    "neighbours_of",
    "threshold_velocities",
    "unicycle_step",
    "validate",
    "wheel_speeds",
    "obstacle_agents",
    "virtual_agents",
    "voronoi_cell",
    "voronoi_cells",
]
