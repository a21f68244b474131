"""Types of the compiled kernels (dream-py). Poses are (3, n), commands (2, n), float64."""

from collections.abc import Sequence
from typing import Any, final

import numpy as np
from numpy.typing import NDArray

__version__: str
__all__ = [
    "__version__",
    "bursts",
    "draws",
    "unicycle_step",
    "threshold_velocities",
    "threshold_wheels",
    "validate",
    "colliding",
    "dxi_to_dxu",
    "dxu_to_dxi",
    "actuator_limit",
    "hypot",
    "neighbours",
    "far_from",
    "perceive",
    "linked",
    "hrvo",
    "hrvo_rows",
    "HrvoPlanner",
    "voronoi_cells",
    "voronoi_cell",
    "heard_cells",
    "virtual_agents",
    "distance_rays",
    "segment_reduce",
    "segment_any",
    "segment_nearest",
    "segment_nearest_to",
    "motion_guard",
    "sidestep_ask",
    "sidestep_mark",
    "take_rows",
    "put_rows",
]

_Bounds = tuple[float, float, float, float]
_Floats = NDArray[np.float64]
_Ints = NDArray[np.int64]

def unicycle_step(poses: NDArray[np.float64], velocities: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
    """Poses (3, n) after one forward-Euler unicycle step with commands (2, n)."""

def threshold_velocities(velocities: NDArray[np.float64], max_linear: float, max_angular: float) -> NDArray[np.float64]:
    """Commands (2, n) clipped to |v| <= max_linear and |w| <= max_angular, signs kept."""

def threshold_wheels(
    velocities: NDArray[np.float64], *, wheel_radius: float, base_length: float, max_wheel: float
) -> NDArray[np.float64]:
    """Commands (2, n) whose wheel speeds are clipped to max_wheel (rps 2.1)."""

def validate(
    poses: NDArray[np.float64],
    velocities: NDArray[np.float64],
    bounds: tuple[float, float, float, float],
    *,
    diameter: float,
    wheel_radius: float,
    base_length: float,
    max_wheel: float,
    collider_offset: float = 0.0,
    boundary_per_iteration: bool = False,
) -> tuple[int, int, int, NDArray[np.int64]]:
    """(boundary, collision, actuator) counts of one iteration by rps's criteria (0.0.0 by default, 2.1's with the options), and the robots in a collision (ascending)."""

def colliding(poses: NDArray[np.float64], *, diameter: float, collider_offset: float = 0.0) -> NDArray[np.bool_]:
    """(n,) bool: the robots of the pairs validate counts as collisions."""

def dxi_to_dxu(
    dxi: NDArray[np.float64], poses: NDArray[np.float64], vel_gain: float, ang_gain: float
) -> NDArray[np.float64]:
    """Unicycle commands (2, n) from single-integrator velocities (2, n) at poses (3, n)."""

def dxu_to_dxi(dxu: NDArray[np.float64], headings: NDArray[np.float64], projection: float) -> NDArray[np.float64]:
    """Velocities (2, n) of the points projection ahead of robots of headings (n,) driven by commands (2, n)."""

def bursts(
    lossy: NDArray[np.int64], links: NDArray[np.int64], draws: NDArray[np.float64], enter: float, leave: float
) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
    """Whether each message over `links` is sent in a loss burst, and the links in a burst after them
    (strictly increasing, as `lossy`): a link flips where its draw is below `leave` (in one) or `enter`."""

def draws(
    seed: int, stream: int, step: int, keys: Sequence[NDArray[np.int64]], kinds: str, rows: int, columns: int
) -> NDArray[np.float64]:
    """The (rows, columns) uniform draws in [0, 1) of `stream` at `step`: each key a word for every
    draw (kind a), one per row (r) or one per column (c), hashed in order (see dream.swarm.draws)."""

def hypot(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    """math.hypot(x[i], y[i]) for the arrays x, y (n,), to the bit."""

def actuator_limit(
    dxu: NDArray[np.float64],
    *,
    max_linear: float,
    max_angular: float,
    wheel_radius: float,
    base_length: float,
    max_wheel: float,
) -> NDArray[np.float64]:
    """Commands (2, n) within the speed limits, slowed so that no wheel is too fast."""

def neighbours(
    positions: _Floats,
    radius: float,
    headings: _Floats | None = None,
    direction: float = 0.0,
    fov: float = ...,
    max_neighbours: int | None = None,
    rows: NDArray[np.bool_] | None = None,
) -> tuple[_Ints, _Ints, _Floats]:
    """CSR (indptr (n+1,), indices, distances) of every robot's (or each flagged robot's) neighbours
    within radius and field of view."""

def far_from(
    points: _Floats,
    others: _Floats,
    distance: float,
    points_offsets: _Ints | None = None,
    others_offsets: _Ints | None = None,
) -> NDArray[np.bool_]:
    """(k,) bool: points farther than distance from every one of others in the same row."""

def hrvo(
    positions: _Floats,
    velocities: _Floats,
    preferred: _Floats,
    indptr: _Ints | None,
    indices: _Ints | None,
    *,
    radius: float,
    safety: float,
    v_max: float,
    bounds: _Bounds | None,
    candidates: _Floats,
    include_preferred: bool,
) -> _Floats:
    """HRVO velocities (n, 2) of the whole swarm; neighbours from CSR or within radius."""

def hrvo_rows(
    velocities: _Floats,
    preferred: _Floats,
    positions: _Floats,
    offsets: _Ints,
    detections: _Floats | tuple[_Floats, ...],
    *,
    safety: float,
    v_max: float,
    bounds: _Bounds | None,
    candidates: _Floats,
    include_preferred: bool,
    relative: bool = False,
    steer: NDArray[np.bool_] | None = None,
) -> _Floats:
    """HRVO velocities (m, 2) of the deciding robots, each from its own detections (k, 4) or their four columns, cut by
    offsets (m+1,); with `relative`, (k, 5) or five columns: distance, dx, dy, vx, vy; with `steer` (m,), only the rows
    it flags (the others: their preferred velocity)."""

def linked(
    rows: _Ints, indptr: _Ints, indices: _Ints, talking: NDArray[np.bool_], positions: _Floats | None = None
) -> tuple[_Ints, _Ints, _Floats]:
    """(offsets, ids, distances) of what the robots `rows` hear over the graph (indptr, indices) among the
    talking; distances NaN without positions."""

def perceive(
    positions: _Floats,
    headings: _Floats,
    rows: _Ints,
    *,
    sight: tuple[float, float, float] | None = None,
    radio_range: float | None = None,
    talking: NDArray[np.bool_] | None = None,
    carried: Sequence[_Floats] | None = None,
    bearings: bool = True,
    summed: Sequence[_Floats] | None = None,
    loss: tuple[int, int, int, float, float] | None = None,
) -> tuple[tuple[NDArray[Any], ...], tuple[NDArray[Any], ...]]:
    """(seen (offsets, ids, distances, bearings, dx, dy, *carried), heard (offsets, ids, distances,
    lost, *summed)) of the robots `rows`; each of `carried` (n,) is read at the robots seen; bearings
    empty unless `bearings`; each of `summed` (n,) is added up over each row heard, whose ids and
    distances are then left empty (none given: only counted); `lost` counts each row's messages lost
    to `loss` (seed, stream, step, keep, per_metre), empty without."""

def segment_reduce(values: _Floats, offsets: _Ints, op: str, index: _Ints | None = None) -> _Floats:
    """op (sum, mean, min, max) of each row's entries of values (k, w): (m, w)."""

def segment_any(flags: NDArray[np.bool_], offsets: _Ints) -> NDArray[np.bool_]:
    """(m,) bool: whether any entry of each row is set."""

def segment_nearest_to(points: _Floats, offsets: _Ints, origins: _Floats, k: int, index: _Ints | None = None) -> _Ints:
    """Each row's k entries whose point is nearest its origin (m, k), -1 in the slots left."""

def segment_nearest(keys: _Floats, offsets: _Ints, k: int | None = None) -> _Ints:
    """(m,) int: the entry of each row with the smallest key, -1 for none; with k, (m, k): each
    row's k smallest, smallest first, -1 in the slots left."""

def motion_guard(
    speeds: _Floats, headings: _Floats, offsets: _Ints, dx: _Floats, dy: _Floats, *, near: float, horizon: float
) -> NDArray[np.bool_]:
    """(m,) bool: which robots stop short of a robot they see at (dx, dy) (CSR rows by offsets)."""

@final
class HrvoPlanner:
    """One robot's HRVO parameters and candidate grid (m, 2)."""

    def __new__(
        cls, candidates: _Floats, *, safety: float, v_max: float, bounds: _Bounds | None, include_preferred: bool
    ) -> HrvoPlanner: ...
    def velocity(self, detections: _Floats, velocity: _Floats, preferred: _Floats, position: _Floats) -> _Floats:
        """Velocity (2,) for seed-format detections (k, 4) [distance, angle, vx, vy]."""

def voronoi_cells(
    positions: _Floats,
    *,
    radius: float,
    bounds: _Bounds,
    virtual_indptr: _Ints | None = None,
    virtual_points: _Floats | None = None,
    resolution: int = 64,
    neighbours: bool = True,
) -> tuple[_Floats, _Floats, _Floats, _Ints]:
    """(centroids (n, 2), areas (n,), vertices (m, 2), offsets (n+1,)) of disc-bounded Voronoi cells
    (without ``neighbours``, each clipped by its virtual points alone)."""

def heard_cells(
    here: _Floats,
    hearers: _Ints,
    positions: _Floats,
    said: _Floats,
    said_now: _Floats,
    *,
    range: float,
    seen_indptr: _Ints,
    seen_points: _Floats,
    same: float,
    virtual_indptr: _Ints,
    virtual_points: _Floats,
    radius: float,
    bounds: _Bounds,
    resolution: int = 64,
    loss: tuple[int, int, int, float, float] | None = None,
    lost: _Ints | None = None,
) -> tuple[_Floats, _Floats, _Floats, _Ints]:
    """(centroids (k, 2), areas (k,), vertices (m, 2), offsets (k+1,)) of the cells of robots that
    know the others by range radio (through its loss, as perceive draws it, and without the
    links lost, i * n + j, strictly increasing), by sight and by virtual agents."""

def virtual_agents(
    positions: _Floats, vertices: _Floats, offsets: _Ints, *, range: float, offset: float
) -> tuple[_Ints, _Floats]:
    """CSR (indptr (n+1,), points (m, 2)) of every robot's virtual agents for convex obstacles."""

def voronoi_cell(
    position: _Floats, others: _Floats, virtual_points: _Floats, *, radius: float, bounds: _Bounds, resolution: int = 64
) -> tuple[_Floats, float, _Floats]:
    """One robot's cell: (centroid (2,), area, counter-clockwise vertices (m, 2))."""

def distance_rays(
    poses: _Floats,
    walls: _Floats,
    rays: _Floats,
    *,
    centre_offset: float,
    robot_diameter: float,
    range: float,
    robots: _Ints | None = None,
) -> _Floats:
    """Readings (k, n) of the rays (3, k) of every robot (or of `robots`) against walls (m, 4) and the other robots; -1 for nothing."""

def sidestep_ask(
    want: _Floats, rows: _Ints, counters: _Ints, sides: _Floats, steer: NDArray[np.bool_] | None = None
) -> _Floats:
    """What robots `rows` (increasing) ask HRVO for (k, 2): `want` (k, 2), turned to their side while their counter is above zero; counters (n,) int64 counted down in place; with `steer` (k,), only the rows it flags."""

def sidestep_mark(
    chosen: _Floats,
    want: _Floats,
    rows: _Ints,
    counters: _Ints,
    sides: _Floats,
    updates: int,
    steer: NDArray[np.bool_] | None = None,
) -> None:
    """Robots `rows` stopped (`chosen` zero) though they wished to move: counters set to `updates`, sides (n,) set right or flipped, in place; with `steer` (k,), only the rows it flags."""

def take_rows(tables: Sequence[NDArray[np.uint8]], rows: _Ints) -> list[NDArray[np.uint8]]:
    """The rows `rows` (increasing) of each table (n, width) uint8: one (len(rows), width) array each."""

def put_rows(tables: Sequence[NDArray[np.uint8]], rows: _Ints, values: Sequence[NDArray[np.uint8]]) -> None:
    """values[t] (len(rows), width) uint8 written into tables[t] (n, width) at the rows `rows` (increasing)."""
